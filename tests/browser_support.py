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
