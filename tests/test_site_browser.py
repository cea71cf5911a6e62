"""The chapter site in a real browser (headless Debian Chromium through Playwright): a lane.

The site is the smoke run's (``make site-smoke``; ``make lanes`` passes ``SITE_HTML``), or, when
that is not given, built here from a fresh smoke run. It is served on 127.0.0.1 and:

* the landing page loads with no console error, no failed request and no request to any other host,
  at a phone width and a desktop width (screenshots of both go to ``$LANE_ARTIFACTS``);
* with JavaScript off, the headline numbers are on the page and equal ``meta.yaml``'s;
* the chart's reading (which evaluation it is, and its two lessons) is on the page with JavaScript off;
* moving the scrubber shows that iteration's numbers and "what to notice" lines (computed from
  ``scrubber.json``), and redraws both worlds, the spawn pose's ghost included;
* every image on every notebook page loads.
"""

from __future__ import annotations

import functools
import http.server
import json
import os
import subprocess
import sys
import threading
from pathlib import Path

import pytest
import yaml

from browser_support import chromium, skip_or_fail

ROOT = Path(__file__).resolve().parents[1]
pytestmark = pytest.mark.lane
WIDTHS = {"phone": 390, "desktop": 1280}


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    given = os.environ.get("SITE_HTML")
    if given:
        html = Path(given).resolve()
        assert (html / "index.html").exists(), f"SITE_HTML={given} holds no built site (make site-smoke)"
        return html
    if not Path(sys.executable).with_name("jupyter-book").exists():
        skip_or_fail("Jupyter Book is not installed (make site-deps), and SITE_HTML names no built site")
    tmp = tmp_path_factory.mktemp("site")
    subprocess.run([sys.executable, "-m", "scripts.chapter", "--smoke", "--out", str(tmp / "run")], cwd=ROOT, check=True,
                   capture_output=True)
    subprocess.run([sys.executable, "-m", "chapter_site", "--run", str(tmp / "run"), "--out", str(tmp / "site")],
                   cwd=ROOT, check=True, capture_output=True)
    return tmp / "site" / "html"


class _Quiet(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):
        pass


@pytest.fixture(scope="module")
def served(site):
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), functools.partial(_Quiet, directory=str(site)))
    threading.Thread(target=server.serve_forever, daemon=True).start()
    yield f"http://127.0.0.1:{server.server_port}"
    server.shutdown()


@pytest.fixture(scope="module")
def browser():
    with chromium() as b:
        yield b


@pytest.fixture(scope="module")
def artifacts(tmp_path_factory) -> Path:
    path = Path(os.environ.get("LANE_ARTIFACTS") or tmp_path_factory.mktemp("artifacts"))
    path.mkdir(parents=True, exist_ok=True)
    return path


def _watch(page, base: str) -> dict:
    """Collect what would make a page unfit: console errors, uncaught exceptions, failed
    requests, error responses, and any request that leaves ``base``."""
    seen = {"console": [], "pageerror": [], "failed": [], "status": [], "foreign": [], "bytes": 0}
    page.on("console", lambda m: seen["console"].append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: seen["pageerror"].append(str(e)))
    page.on("requestfailed", lambda r: seen["failed"].append(r.url))
    page.on("request", lambda r: seen["foreign"].append(r.url)
            if not (r.url.startswith(base) or r.url.startswith("data:")) else None)

    def response(r):
        if r.status >= 400:
            seen["status"].append((r.status, r.url))
        else:
            try:
                seen["bytes"] += len(r.body())
            except Exception:  # noqa: BLE001 - a redirect has no body
                pass
    page.on("response", response)
    return seen


def _clean(seen: dict) -> dict:
    return {k: v for k, v in seen.items() if k != "bytes" and v}


@pytest.mark.parametrize("width", WIDTHS)
def test_landing_page_loads_clean(browser, served, artifacts, width):
    ctx = browser.new_context(viewport={"width": WIDTHS[width], "height": 900})
    page = ctx.new_page()
    seen = _watch(page, served)
    page.goto(f"{served}/index.html")
    page.wait_for_load_state("networkidle")
    assert page.locator("#two-worlds").is_visible()
    assert page.locator("#scrub").is_visible()             # JavaScript on: the slider is there
    page.screenshot(path=str(artifacts / f"site_landing_{width}.png"), full_page=True)
    (artifacts / f"site_landing_{width}_weight.json").write_text(json.dumps({"bytes_loaded": seen["bytes"]}))
    # nothing wider than the screen at a phone width: the reader never scrolls sideways
    overflow = page.evaluate("document.documentElement.scrollWidth - document.documentElement.clientWidth")
    ctx.close()
    assert not _clean(seen), _clean(seen)
    assert overflow <= 1, f"the page is {overflow} px wider than a {WIDTHS[width]} px screen"


def test_headline_reads_without_javascript_and_equals_meta(browser, served):
    from chapter_site.landing import HEADLINE

    seed0 = yaml.safe_load((ROOT / "meta.yaml").read_text())["seeds"][0]
    ctx = browser.new_context(java_script_enabled=False)
    page = ctx.new_page()
    page.goto(f"{served}/index.html")
    shown = {el.get_attribute("data-key"): el.inner_text() for el in page.locator("#two-worlds [data-key]").all()}
    assert set(shown) == {k for k, _, _ in HEADLINE}
    for key, text in shown.items():
        value = float(text.rstrip("%")) / (100 if text.endswith("%") else 1)
        assert value == pytest.approx(seed0[key], abs=0.0005 if not text.endswith("%") else 0.005), key
    assert page.locator("#two-worlds svg").count() == 1                   # the bars are static SVG
    assert page.locator("#curves svg").count() == 2
    assert page.locator("#curves .reading").inner_text().strip()              # which evaluation the chart is
    assert page.locator("#curves ul.lessons li").count() == 2
    assert page.locator("#scrubber ul.notice li").count() == 2                # what to notice, last iteration
    assert not page.locator("#scrub").is_visible()                        # the slider needs JavaScript
    assert page.locator("#scrubber svg").count() == 2                     # both worlds drawn anyway
    assert "pending" in page.locator("#wallclock").inner_text()
    ctx.close()


def _data(site: Path) -> dict:
    return json.loads((site / "_static" / "scrubber.json").read_text())


FIELDS = ("iteration", "dream-reward", "real-reward", "dream-dist", "real-dist", "drift", "leaving")


def test_scrubber_moves_figure_and_numbers(browser, served, site):
    from chapter_site import landing, svg

    data = _data(site)
    frames = data["frames"]
    page = browser.new_page()
    page.goto(f"{served}/index.html")
    slider = page.locator("#scrub")
    slider.wait_for(state="visible")

    def attr(world, part, name):
        return page.locator(f'#scrubber svg[data-world="{world}"] .{part}').get_attribute(name)

    def state():
        return ({f: page.locator(f'#scrubber [data-field="{f}"]').inner_text() for f in FIELDS},
                [attr(w, p, a) for w in ("in the dream", "in reality")
                 for p, a in (("tee0", "points"), ("pusher-path", "points"), ("pusher", "cx"))])

    last_numbers, last_drawing = state()
    assert last_numbers["iteration"] == str(frames[-1]["iteration"])
    for w in ("in the dream", "in reality"):
        assert page.locator(f'#scrubber svg[data-world="{w}"] .ghost0').count() == 1   # the spawn pose, drawn
    scale = 240 / (2 * svg.ARENA_HALF)
    for index in (0, len(frames) // 2):
        slider.fill(str(index))
        numbers, drawing = state()
        f = frames[index]
        expected = landing._readout(f, data)
        assert numbers == {k: expected[k] for k in FIELDS}
        assert drawing != last_drawing, f"iteration {f['iteration']}: the worlds were not redrawn"
        for world, name in (("dream", "in the dream"), ("real", "in reality")):
            ghost = svg.tee_points(*f[world]["block_mm_deg"][0], scale, 240)
            assert [attr(name, "ghost0", "points"), attr(name, "ghost1", "points")] == ghost
    page.close()


def test_every_notebook_page_loads_its_images(browser, served, site):
    pages = sorted((site / "notebooks").glob("*.html"))
    assert len(pages) == 6
    for html in pages:
        page = browser.new_page()
        seen = _watch(page, served)
        page.goto(f"{served}/notebooks/{html.name}")
        page.wait_for_load_state("networkidle")
        images = page.locator("img").all()
        assert images, f"{html.name} shows no figure"
        broken = [img.get_attribute("src") for img in images
                  if not img.evaluate("i => i.complete && i.naturalWidth > 0")]
        page.close()
        assert not broken, f"{html.name}: images that did not load: {broken}"
        assert not _clean(seen), (html.name, _clean(seen))
