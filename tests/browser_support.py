"""Headless Chromium for the tests that need a real browser, launched one way.

Debian's Chromium (/usr/bin/chromium) through the Playwright Python package: Playwright never
fetches a browser of its own here (``make browser`` installs both). Where either is missing, or
the browser does not start, a test is skipped with the reason; with ``REQUIRE_BROWSER=1`` (CI) it
fails instead::

    from browser_support import chromium

    @pytest.fixture(scope="module")
    def browser():
        with chromium() as b:
            yield b

(tests/test_feedback_browser.py, test_site_browser.py and test_learner_path.py launch it this way.)
"""

from __future__ import annotations

import contextlib
import os

import pytest

CHROMIUM = "/usr/bin/chromium"     # Debian's package
# quiet and self-contained: no sandbox (containers, CI runners as root), no GPU, no calls home
CHROMIUM_ARGS = ("--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync", "--disable-default-apps", "--no-first-run",
                 "--no-default-browser-check", "--metrics-recording-only", "--mute-audio")


def required() -> bool:
    return bool(os.environ.get("REQUIRE_BROWSER"))


def skip_or_fail(why: str):
    """Skip the test with ``why``, or fail it where REQUIRE_BROWSER is set."""
    if required():
        pytest.fail(f"REQUIRE_BROWSER is set, but {why}")
    pytest.skip(why)


def unavailable() -> str | None:
    """Why no browser test can run here, or None."""
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        return "the Python package playwright is not installed (make browser)"
    if not os.access(CHROMIUM, os.X_OK):
        return f"{CHROMIUM} is not installed (make browser, or: apt-get install chromium)"
    return None


@contextlib.contextmanager
def chromium(**launch):
    """A started headless Chromium (a Playwright ``Browser``), closed on exit; skips (or fails,
    REQUIRE_BROWSER) where there is none. Its profile is fresh: ``launch`` gives every browser a
    new temporary user-data-dir of its own (Playwright refuses ``--user-data-dir`` in ``args``),
    removed when it closes."""
    why = unavailable()
    if why:
        skip_or_fail(why)
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        args = [*CHROMIUM_ARGS, *launch.pop("args", ())]
        try:
            browser = p.chromium.launch(executable_path=CHROMIUM, headless=True, args=args, **launch)
        except Exception as e:
            if required():
                raise
            pytest.skip(f"{CHROMIUM} does not start under Playwright: {e}")
        try:
            yield browser
        finally:
            browser.close()


def watch(page, base: str, js: bool = True) -> dict:
    """Collect what would make a page unfit: console errors, uncaught exceptions, failed
    requests, error responses, and any request that leaves ``base``. With JavaScript off
    (``js=False``) the browser refuses to fetch the scripts the page preloads: not a failure.
    ``bytes`` counts the bodies received."""
    seen = {"console": [], "pageerror": [], "failed": [], "status": [], "foreign": [], "bytes": 0}
    page.on("console", lambda m: seen["console"].append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: seen["pageerror"].append(str(e)))

    def failed(r):
        if js or r.resource_type != "script":
            seen["failed"].append(f"{r.url} ({r.failure})")
    page.on("requestfailed", failed)
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


def problems(seen: dict) -> dict:
    """What :func:`watch` saw that is wrong (all but the byte count)."""
    return {k: v for k, v in seen.items() if k != "bytes" and v}


# Measures of any page, run in it by Playwright with the page's own scripts on or off (issue 42):
# the smallest text drawn (CSS px, times an SVG's scale), what sticks out past the screen's right
# edge outside a box that scrolls, the buttons shown (with JavaScript off a button does nothing), the
# search boxes shown, and the body text the back-to-top pill covers where it is shown.
PAGE_MEASURE = """() => {
  const vw = document.documentElement.clientWidth, vh = window.innerHeight;
  const shown = e => {
    for (let a = e; a && a.nodeType === 1; a = a.parentElement) {
      const s = getComputedStyle(a);
      if (s.display === 'none' || s.visibility === 'hidden' || Number(s.opacity) === 0) return false;
      if (a.tagName === 'DETAILS' && !a.open && a !== e && !e.closest('summary')) return false;
    }
    const r = e.getBoundingClientRect();
    return r.width > 1 && r.height > 1 && r.right > 0 && r.left < vw;
  };
  const name = e => e.tagName.toLowerCase() + (e.getAttribute('class') ? '.' + e.getAttribute('class').trim().split(/\\s+/).join('.') : '')
    + (e.id ? '#' + e.id : '');
  const sizes = [];
  const walk = document.createTreeWalker(document.body, NodeFilter.SHOW_TEXT);
  const texts = [];
  while (walk.nextNode()) {
    const t = walk.currentNode, e = t.parentElement;
    if (!t.textContent.trim() || !e || e.closest('script, style, noscript, title') || !shown(e)) continue;
    texts.push(t);
    let size = parseFloat(getComputedStyle(e).fontSize);
    if (e instanceof SVGElement) { const m = e.getScreenCTM(); size *= Math.hypot(m.a, m.b); }
    sizes.push([Math.round(size * 10) / 10, name(e) + ': ' + t.textContent.trim().slice(0, 40)]);
  }
  sizes.sort((a, b) => a[0] - b[0]);
  const wide = [];
  for (const e of document.querySelectorAll('body *')) {
    const r = e.getBoundingClientRect();
    if (r.width === 0 || r.right <= vw + 1 || !shown(e)) continue;
    let scrolls = false;
    for (let a = e.parentElement; a; a = a.parentElement) {
      if (['auto', 'scroll', 'hidden', 'clip'].includes(getComputedStyle(a).overflowX) && a !== document.body
          && a !== document.documentElement) { scrolls = true; break; }
    }
    if (!scrolls) wide.push(name(e) + ' right edge ' + Math.round(r.right));
  }
  const buttons = [...document.querySelectorAll('button, [role=button]')].filter(shown).map(name);
  const search = [...document.querySelectorAll('input[type=search], .search-button-field')].filter(shown).map(name);
  const covered = [];
  const pill = document.getElementById('pst-back-to-top');
  if (pill && shown(pill)) {
    const p = pill.getBoundingClientRect();
    for (const t of texts) {
      if (pill.contains(t)) continue;
      const range = document.createRange(); range.selectNodeContents(t);
      for (const r of range.getClientRects())
        if (r.right > p.left && r.left < p.right && r.bottom > p.top && r.top < p.bottom && r.top < vh) {
          covered.push(t.textContent.trim().slice(0, 40)); break; }
    }
  }
  return {smallest: sizes.slice(0, 5), wide: wide.slice(0, 10), buttons, search, covered,
          page_overflow: document.documentElement.scrollWidth - document.documentElement.clientWidth};
}"""
