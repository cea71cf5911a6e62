"""The learner's path, in a real browser: open the student release in JupyterLab, answer, run, save,
hand in, and be graded.

For notebooks 02 and 04 of the student release (notebooks/), as a learner does it:

1. the two notebooks are copied into a fresh folder of the learner's own, and a real JupyterLab
   server (the main venv's ``jupyter lab``) serves that folder, with a configuration, data, runtime,
   settings and workspaces folder of its own (nothing of the user's leaks in), no news, no update
   check, no extension manager calls, every notebook cell kept in the DOM (``windowingMode`` none),
   and the nbgrader extensions off (a learner's install does not need them). The kernel is the
   venv's ``python3``;
2. headless Chromium (Playwright; tests/browser_support.py) opens each notebook in JupyterLab's UI
   and, in the editor of each cell: sets the parameters cell to the smoke config (``SMOKE = True``),
   types the instructor's solution into every answer cell (the solution cell's full source, matched
   by nbgrader ``grade_id``), for notebook 04 locks a prediction (a letter and a sentence of why)
   and writes the one-sentence answer; it puts the exact text in the editor (select all, then
   ``insert_text``: typed key by key, CodeMirror would indent and close brackets) and checks that
   the editor holds exactly that text. Then Run > Run All Cells, a wait until the kernel is idle
   and every code cell has run, and Ctrl+S, with a wait until the file on disk is the saved one;
3. the saved notebooks, as the learner's folder holds them, are handed to the grader as a class of
   one (``<student>/<notebook>.ipynb``) and graded by ``python -m autograde.grade`` in a fresh course
   folder; the learner must earn every automatic and every completion point of both notebooks (in
   the gradebook, against its maximum per cell; and in grades.csv, the export). The written answer
   is graded by hand, so it is not part of that total: it must reach the grader as written and wait
   there for the instructor's grade.

Screenshots of each notebook after Run All (and the save) go to ``$LANE_ARTIFACTS`` (else the test's tmp folder);
on a failure, a screenshot and the notebook's errors are saved beside them and named in the message.

The browser actions go through the UI (clicks, keys); the page's JupyterLab application object
(``window.jupyterapp``, exposed by ``LabApp.expose_app_in_browser`` as JupyterLab's own UI tests do)
is only read, to wait for conditions (kernel idle, cells run, model saved) instead of sleeping.

Where Playwright or /usr/bin/chromium is missing the tests are skipped with the reason; with
``REQUIRE_BROWSER=1`` they fail instead.
"""

from __future__ import annotations

import csv
import json
import os
import re
import secrets
import shutil
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import nbformat
import pytest

import browser_support

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = ("02_reward", "04_imagination_gap")
STUDENT = "learner"
RUN_TIMEOUT = int(os.environ.get("LEARNER_PATH_RUN_TIMEOUT", "300"))   # seconds for Run All, per notebook
UI_TIMEOUT = 60_000                     # ms: page load, kernel start, an editor, a save
MAX_SHOT = 16_000                       # px: the tallest screenshot (Chromium draws no taller page)
GRADE_TIMEOUT = 900                     # seconds for the grader on the class of one
# What the learner writes where the release asks them to write (the code answers are the solutions').
REASON = ("The actor only ever trains inside the model's dreams, so it will learn motions that the "
          "model rates highly even where the real block does not move.")
WRITTEN_ANSWER = ("The actor got good at raising the reward the world model dreams, choosing motions "
                  "after which the model decodes the block nearer the target; that skill is worth "
                  "nothing in reality wherever the model's picture of the block is wrong.")

pytestmark = pytest.mark.lane


# --- the edits a learner makes ---------------------------------------------------------------------
def gid(cell) -> str | None:
    return cell.metadata.get("nbgrader", {}).get("grade_id")


STUB = re.compile(r"^[ \t]*# YOUR CODE HERE\n[ \t]*raise NotImplementedError\(\)\n?", re.M)


def learner_edits(name: str) -> list[dict]:
    """[{index, cell_type, grade_id, text, what}]: every cell of the release's ``name`` the learner
    edits, with the whole text it holds afterwards. Fails if the release asks for an answer this
    list does not give (a stub or a "YOUR ANSWER HERE" left unanswered)."""
    release = nbformat.read(ROOT / "notebooks" / f"{name}.ipynb", as_version=4)
    solution = {gid(c): c for c in nbformat.read(ROOT / "solutions" / f"{name}.ipynb", as_version=4).cells if gid(c)}
    edits = []
    for i, cell in enumerate(release.cells):
        g = gid(cell)
        if "parameters" in cell.metadata.get("tags", []):
            # False -> True, one space added before a comment so that it stays in its column
            text, n = re.subn(r"^SMOKE = False(?=( ?))", lambda m: "SMOKE = True" + m.group(1), cell.source,
                              flags=re.M)
            assert n == 1, f"{name}: the parameters cell has no `SMOKE = False` line:\n{cell.source}"
            edits.append(dict(index=i, cell_type="code", grade_id=None, text=text, what="parameters: SMOKE = True"))
        elif g in solution and cell.cell_type == "code" and "### BEGIN SOLUTION" in solution[g].source:
            if "lock_prediction(" in cell.source:
                edits.append(dict(index=i, cell_type="code", grade_id=g,
                                  text=lock_cell(cell.source, solution[g].source), what="the prediction, locked"))
            else:
                edits.append(dict(index=i, cell_type="code", grade_id=g, text=solution[g].source,
                                  what="the solution, typed in"))
        elif g and cell.cell_type == "markdown" and cell.metadata["nbgrader"].get("solution"):
            edits.append(dict(index=i, cell_type="markdown", grade_id=g, text=WRITTEN_ANSWER,
                              what="the written answer (graded by hand)"))
    edited = {e["index"] for e in edits}
    left = [i for i, c in enumerate(release.cells) if i not in edited
            and ("raise NotImplementedError" in c.source or "YOUR ANSWER HERE" in c.source)]
    assert not left, f"{name}: cells {left} ask for an answer this test does not give"
    return edits


def lock_cell(release_src: str, solution_src: str) -> str:
    """The lock cell as the learner fills it: a letter (one the instructor did not pick: the point is
    for locking before running, not for the letter) and a sentence of why, the stub removed."""
    from pusht.predict import choices_of

    options = choices_of("ex1")
    picked = re.search(r'^PREDICTION = "([a-z])"', solution_src, re.M)
    letter = options[(options.index(picked.group(1)) + 1) % len(options)] if picked else options[-1]
    text = STUB.sub("", release_src, count=1)
    text, n1 = re.subn(r'^PREDICTION = ""', f'PREDICTION = "{letter}"', text, count=1, flags=re.M)
    text, n2 = re.subn(r'^REASON = ""', f"REASON = {REASON!r}", text, count=1, flags=re.M)
    assert n1 == n2 == 1 and "NotImplementedError" not in text, f"the lock cell changed shape:\n{release_src}"
    return text


# --- a JupyterLab server on the learner's folder ---------------------------------------------------
def clean_env(drop=("PUSHT_", "NBGRADER_"), extra: dict | None = None) -> dict:
    """This environment without the chapter's and nbgrader's variables (a learner has none; the
    grader sets its own), and without any other names starting with ``drop``; PUSHT_WORKERS (how
    many cores the chapter's sweeps use) is kept."""
    env = {k: v for k, v in os.environ.items() if not k.startswith(drop) or k == "PUSHT_WORKERS"}
    return {**env, **(extra or {})}


def write_lab_config(home: Path) -> dict:
    """JupyterLab's config, data, runtime, settings and workspaces folders under ``home``; returns
    the environment variables that point the server at them."""
    config, settings = home / "config", home / "settings"
    (config / "labconfig").mkdir(parents=True)
    # server side: no news feed, no update check, no extension-manager index (each a call out),
    # the application object readable by the test, nbgrader's and the LSP server extensions off
    off = ["nbgrader.server_extensions.formgrader", "nbgrader.server_extensions.validate_assignment",
           "nbgrader.server_extensions.assignment_list", "nbgrader.server_extensions.course_list", "jupyter_lsp"]
    server = {"LabApp": {"news_url": None, "check_for_updates_class": "jupyterlab.NeverCheckForUpdate",
                         "extension_manager": "readonly", "expose_app_in_browser": True},
              "ServerApp": {"jpserver_extensions": {e: False for e in off}}}
    for name in ("jupyter_server_config.json", "jupyter_lab_config.json"):
        (config / name).write_text(json.dumps(server, indent=1))
    # front-end plugins off: the news prompt, nbgrader's lab extension, the LSP client (its server is off)
    (config / "labconfig" / "page_config.json").write_text(json.dumps({"disabledExtensions": {
        "@jupyterlab/apputils-extension:announcements": True, "@jupyter/nbgrader": True,
        "@jupyterlab/lsp-extension": True}}, indent=1))
    user = {
        # every cell attached to the DOM, off-screen ones too (JupyterLab 4 windows them by default)
        "@jupyterlab/notebook-extension/tracker": {"windowingMode": "none"},
        # no "would you like to receive official Jupyter news?" toast, no update check
        "@jupyterlab/apputils-extension/notification": {"fetchNews": "false", "checkForUpdates": False},
    }
    for plugin, values in user.items():
        path = settings / f"{plugin}.jupyterlab-settings"
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(values, indent=1))
    return {"JUPYTER_CONFIG_DIR": str(config), "JUPYTER_DATA_DIR": str(home / "data"),
            "JUPYTER_RUNTIME_DIR": str(home / "runtime"), "JUPYTERLAB_SETTINGS_DIR": str(settings),
            "JUPYTERLAB_WORKSPACES_DIR": str(home / "workspaces"), "IPYTHONDIR": str(home / "ipython"),
            "JUPYTER_PLATFORM_DIRS": "1"}


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_until(condition, timeout: float, what: str, every: float = 0.2):
    """Poll ``condition()`` until it returns something true (returned), or fail saying ``what``."""
    end = time.monotonic() + timeout
    while True:
        got = condition()
        if got:
            return got
        if time.monotonic() > end:
            pytest.fail(f"timed out after {timeout:.0f} s waiting for {what}")
        time.sleep(every)


class Lab:
    def __init__(self, root: Path, home: Path):
        self.root, self.home = root, home
        self.token = secrets.token_hex(16)
        self.log = home / "jupyterlab.log"
        # nothing of the user's Jupyter or IPython set-up: every folder Jupyter reads is under ``home``
        env = clean_env(("PUSHT_", "NBGRADER_", "JUPYTER", "IPYTHON"), write_lab_config(home))
        cmd = [sys.executable, "-m", "jupyterlab", "--no-browser", f"--port={free_port()}",
               "--ServerApp.port_retries=50", "--ServerApp.ip=127.0.0.1", f"--IdentityProvider.token={self.token}",
               f"--ServerApp.root_dir={root}"]
        if hasattr(os, "geteuid") and os.geteuid() == 0:      # containers and CI runners
            cmd.append("--allow-root")
        self.proc = subprocess.Popen(cmd, cwd=root, env=env, stdout=self.log.open("w"), stderr=subprocess.STDOUT)
        # the server writes its address (the port it really got) into its runtime file once it listens
        info = wait_until(self._info, 60, f"JupyterLab to start (its log: {self.log})")
        self.url = f"http://127.0.0.1:{info['port']}/"
        wait_until(lambda: self._get("api/status") is not None, 30, f"JupyterLab to answer (its log: {self.log})")

    def _info(self):
        if self.proc.poll() is not None:
            pytest.fail(f"JupyterLab exited with {self.proc.returncode}:\n{self.log.read_text()[-3000:]}")
        for f in (self.home / "runtime").glob(f"jpserver-{self.proc.pid}.json"):
            try:
                return json.loads(f.read_text())
            except ValueError:          # being written
                return None
        return None

    def _get(self, path: str, method: str = "GET"):
        req = urllib.request.Request(self.url + path, method=method, headers={"Authorization": f"token {self.token}"})
        try:
            with urllib.request.urlopen(req, timeout=10) as r:
                body = r.read()
                return json.loads(body) if body else {}
        except OSError:
            return None

    def shut_down_kernels(self):
        for s in self._get("api/sessions") or []:
            self._get(f"api/sessions/{s['id']}", method="DELETE")

    def close(self):
        self.proc.terminate()
        try:
            self.proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()


# --- in the browser --------------------------------------------------------------------------------
# Reading the page's JupyterLab (never acting through it): the notebook panel of a path.
PANEL_JS = """(path) => {
  const app = window.jupyterapp;
  if (!app) return null;
  for (const w of app.shell.widgets('main')) if (w.context && w.context.path === path) return w;
  return null;
}"""


def js(body: str) -> str:
    """A page function of ``path`` (and an optional second argument) with ``panel`` found first."""
    return f"""([path, arg]) => {{ const panel = ({PANEL_JS})(path); {body} }}"""


KERNEL_READY = js("""
  const dialog = document.querySelector('.jp-Dialog');
  if (dialog) return 'dialog';
  if (!panel || !panel.sessionContext.session || !panel.sessionContext.session.kernel) return false;
  // JupyterLab adds the cells in batches: all of them (arg) must be there
  const kernel = panel.sessionContext.session.kernel;
  return kernel.status === 'idle' && panel.content.widgets.length === arg ? 'idle' : false;""")
CELL_TEXT = js("""
  const cell = panel.content.widgets[arg];
  const view = cell.editor && cell.editor.editor;             // CodeMirror's EditorView
  return {editor: view && view.state ? view.state.doc.toString() : null,
          model: cell.model.sharedModel.getSource(), type: cell.model.type, id: cell.model.id};""")
RUN_STATE = js("""
  const kernel = panel.sessionContext.session && panel.sessionContext.session.kernel;
  const code = panel.content.widgets.filter(c => c.model.type === 'code');
  const pending = code.filter(c => c.model.executionState === 'running'
                                   || (c.promptNode && c.promptNode.textContent.includes('*'))).length;
  return {kernel: kernel ? kernel.status : null, pending, code: code.length,
          counted: code.filter(c => c.model.executionCount !== null).length};""")
RUN_RESULT = js("""
  const errors = c => c.model.type !== 'code' ? [] : c.model.outputs.toJSON()
    .filter(o => o.output_type === 'error').map(o => ({ename: o.ename, evalue: o.evalue, traceback: o.traceback}));
  return panel.content.widgets.map((c, i) => ({index: i, type: c.model.type, count: c.model.executionCount,
                                               errors: errors(c)}));""")
KERNEL_NAME = js("return panel.sessionContext.session.kernel.name;")
CLEAN = js("return !!panel && panel.context.model.dirty === false;")


def artifacts_dir(tmp: Path) -> Path:
    out = Path(os.environ["LANE_ARTIFACTS"]) if os.environ.get("LANE_ARTIFACTS") else tmp
    out.mkdir(parents=True, exist_ok=True)
    return out


ANSI = re.compile(r"\x1b\[[0-9;]*m")


class Learner:
    """One notebook, worked through in one browser tab."""

    def __init__(self, browser, lab: Lab, name: str, tmp: Path, artifacts: Path):
        self.lab, self.name, self.path, self.tmp, self.artifacts = lab, name, f"{name}.ipynb", tmp, artifacts
        self.context = browser.new_context(viewport={"width": 1400, "height": 1000})
        self.off_host = []
        # nothing leaves the machine: a request for anything but the server is answered with an
        # error, and noted (the notebooks' own content asks for some: the release's Colab and Binder
        # badges are images on the web, matplotlib's animation controls a stylesheet on a CDN)
        self.context.route("**/*", self._route)
        self.page = self.context.new_page()
        self.page.set_default_timeout(UI_TIMEOUT)
        self.console_errors = []
        self.page.on("pageerror", lambda e: self.console_errors.append(str(e)))

    def _route(self, route):
        if route.request.url.startswith(self.lab.url):
            route.continue_()
        else:
            self.off_host.append((route.request.resource_type, route.request.url))
            route.abort()

    def state(self, script, arg=None):
        return self.page.evaluate(script, [self.path, arg])

    def fail(self, message: str):
        """Fail with ``message``, a screenshot and the notebook's errors saved (and named)."""
        pytest.fail(self.evidence(message), pytrace=False)

    def evidence(self, message: str) -> str:
        """``message``, with a screenshot and the notebook's errors (and the server's log) saved to
        the test's tmp folder (and to $LANE_ARTIFACTS where set) and named."""
        shot = self.tmp / f"FAILED_{self.name}.png"
        errors = self.tmp / f"FAILED_{self.name}_errors.txt"
        try:
            self.page.screenshot(path=str(shot))
        except Exception as e:  # noqa: BLE001
            shot = f"(no screenshot: {e})"
        lines = [message, ""]
        try:
            for c in self.state(RUN_RESULT) or []:
                for err in c["errors"]:
                    lines += [f"cell {c['index']} (In [{c['count']}]): {err['ename']}: {err['evalue']}",
                              *(ANSI.sub("", t) for t in err["traceback"]), ""]
        except Exception as e:  # noqa: BLE001
            lines.append(f"(could not read the notebook's outputs: {e})")
        lines += ["page errors:", *self.console_errors, "", "JupyterLab log (end):", self.lab.log.read_text()[-4000:]]
        errors.write_text("\n".join(lines))
        if self.artifacts != self.tmp:
            for f in (shot, errors):
                if isinstance(f, Path) and f.is_file():
                    shutil.copy(f, self.artifacts / f.name)
        return f"{self.name}: {message}\nscreenshot: {shot}\nerrors and logs: {errors}"

    # the steps --------------------------------------------------------------------------------------
    def open(self):
        # a workspace of its own per notebook: only this notebook is open in the tab
        self.page.goto(f"{self.lab.url}lab/workspaces/{self.name}/tree/{self.path}?reset&token={self.lab.token}")
        n = len(nbformat.read(ROOT / "notebooks" / self.path, as_version=4).cells)
        self.wait_for_kernel(n)
        cells = self.cells()
        if cells.count() != n:
            self.fail(f"{cells.count()} cells in the DOM, the notebook has {n} (is windowing still on?)")

    def cells(self):
        panel_id = self.page.evaluate(f"(path) => ({PANEL_JS})(path).id", self.path)
        return self.page.locator(f"[id='{panel_id}'] .jp-Notebook .jp-WindowedPanel-viewport > .jp-Cell")

    def wait_for_kernel(self, n_cells: int):
        """Until the notebook's ``n_cells`` cells are there and its kernel is idle; a "Select Kernel"
        dialog, if JupyterLab asks, is answered with its default (the notebook's own python3)."""
        for _ in range(3):
            try:
                got = self.page.wait_for_function(KERNEL_READY, arg=[self.path, n_cells], polling=200,
                                                  timeout=UI_TIMEOUT).json_value()
            except Exception:  # noqa: BLE001
                self.fail("the notebook's kernel did not start (no idle kernel within "
                          f"{UI_TIMEOUT // 1000} s)")
            if got == "idle":
                return
            dialog = self.page.locator(".jp-Dialog")
            title = dialog.locator(".jp-Dialog-header").inner_text()
            if "kernel" not in title.lower():
                self.fail(f"an unexpected dialog: {title!r}: {dialog.inner_text()[:500]}")
            dialog.locator(".jp-Dialog-button.jp-mod-accept").click()
            dialog.wait_for(state="detached")
        self.fail("JupyterLab kept asking for a kernel")

    def set_text(self, index: int, text: str, cell_type: str):
        """Replace cell ``index``'s text with ``text`` through its editor, and check the editor holds
        exactly ``text``."""
        cell = self.cells().nth(index)
        cell.scroll_into_view_if_needed()
        if cell_type == "markdown":                # a rendered markdown cell: double-click to edit it
            cell.locator(".jp-MarkdownOutput").dblclick()
        editor = cell.locator(".cm-content")
        editor.click()
        cell.locator(".cm-editor.cm-focused").wait_for()
        self.page.keyboard.press("Control+a")
        self.page.keyboard.insert_text(text)
        try:        # CodeMirror takes the inserted text in from the DOM: until its state has it
            self.page.wait_for_function(js(f"return ({CELL_TEXT})([path, arg[0]]).editor === arg[1];"),
                                        arg=[self.path, [index, text]], polling=100, timeout=5000)
        except Exception:  # noqa: BLE001
            pass          # said below, with the difference
        got = self.state(CELL_TEXT, index)
        if got["editor"] != text or got["model"] != text:
            self.fail(f"cell {index}: the editor does not hold the text put in it:\n--- wanted\n{text}\n"
                      f"--- editor\n{got['editor']}\n--- model\n{got['model']}")
        self.page.keyboard.press("Escape")          # back to command mode

    def run_all(self):
        """Run > Run All Cells, then until the kernel is idle and no cell waits to run; fails unless
        every code cell ran, without an error. Returns (seconds, each cell's execution count)."""
        if self.state(RUN_STATE)["counted"]:
            self.fail("cells carry execution counts before Run All (the release should have none)")
        self.page.locator(".lm-MenuBar-item", has_text=re.compile(r"^Run$")).click()
        self.page.locator(".lm-Menu-item").filter(
            has=self.page.locator(".lm-Menu-itemLabel", has_text=re.compile(r"^Run All Cells$"))).click()
        start = time.monotonic()
        try:
            self.page.wait_for_function(js(f"""
              const s = ({RUN_STATE})([path, arg]);
              return (s.kernel === 'idle' && s.pending === 0 && s.counted > 0) || s.kernel === 'dead';"""),
                arg=[self.path, None],
                polling=250, timeout=RUN_TIMEOUT * 1000)
        except Exception:  # noqa: BLE001
            s = self.state(RUN_STATE)
            self.fail(f"Run All did not finish in {RUN_TIMEOUT} s (LEARNER_PATH_RUN_TIMEOUT): kernel "
                      f"{s['kernel']}, {s['counted']} of {s['code']} code cells run, {s['pending']} pending")
        cells = self.state(RUN_RESULT)
        kernel = self.state(RUN_STATE)["kernel"]
        if kernel != "idle":
            self.fail(f"the kernel is {kernel} after Run All (out of memory?)")
        errors = [c for c in cells if c["errors"]]
        unrun = [c["index"] for c in cells if c["type"] == "code" and c["count"] is None]
        if errors or unrun:
            first = errors[0] if errors else None
            self.fail("Run All stopped: " + (f"cell {first['index']} raised {first['errors'][0]['ename']}: "
                                              f"{first['errors'][0]['evalue']}; " if first else "")
                      + f"cells {unrun} did not run")
        return time.monotonic() - start, [c["count"] for c in cells]

    def screenshot(self) -> Path:
        """The whole notebook as one tall picture: the tab made as tall as the notebook's cells (up
        to MAX_SHOT px; a longer notebook is shown from its top), then back to its size."""
        size = self.page.evaluate(f"""(path) => {{
            const outer = ({PANEL_JS})(path).content.node.querySelector('.jp-WindowedPanel-outer');
            outer.scrollTop = 0;
            return {{content: outer.scrollHeight, shown: outer.clientHeight}};
        }}""", self.path)
        view = self.page.viewport_size
        tall = int(min(view["height"] - size["shown"] + size["content"], MAX_SHOT))
        self.page.set_viewport_size({"width": view["width"], "height": max(tall, view["height"])})
        path = self.artifacts / f"learner_path_{self.name}.png"
        try:
            self.page.screenshot(path=str(path))
        finally:
            self.page.set_viewport_size(view)
        return path

    def save(self, counts: list):
        """Ctrl+S, then until JupyterLab has the model clean and the file on disk is what was run
        (``counts``: each cell's execution count in the browser)."""
        file = self.lab.root / self.path
        # the notebook focused in command mode: a click on the last cell's prompt area (never on
        # its content: the first cell's badges are links), then Escape
        self.cells().last.locator(".jp-InputPrompt").click()
        self.page.keyboard.press("Escape")
        self.page.keyboard.press("Control+s")
        try:
            self.page.wait_for_function(CLEAN, arg=[self.path, None], polling=200, timeout=UI_TIMEOUT)
        except Exception:  # noqa: BLE001
            self.fail("the notebook was not saved (the model stayed dirty after Ctrl+S)")

        def saved():
            try:
                nb = nbformat.read(file, as_version=4)
            except Exception:  # noqa: BLE001        # being written
                return None
            return nb if [c.get("execution_count") for c in nb.cells] == counts else None
        return wait_until(saved, 30, f"{file} on disk to hold the notebook as run (execution counts {counts})")

    def close(self):
        self.context.close()


# --- the fixtures ----------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def browser():
    with browser_support.chromium() as b:
        yield b


@pytest.fixture(scope="module")
def learner_folder(browser, tmp_path_factory):
    """The learner's folder after working through both notebooks in JupyterLab, and per notebook
    what happened: {name: {"error": message or None, "edits", "seconds", "screenshot", "off_host"}}."""
    try:
        import jupyterlab  # noqa: F401
    except ImportError:
        browser_support.skip_or_fail("JupyterLab is not installed in this environment")
    tmp = tmp_path_factory.mktemp("learner_path")
    root = tmp / "learner"
    root.mkdir()
    for name in NOTEBOOKS:
        shutil.copy(ROOT / "notebooks" / f"{name}.ipynb", root)
    lab = Lab(root, tmp / "jupyter")
    artifacts = artifacts_dir(tmp)
    done = {}
    try:
        for name in NOTEBOOKS:
            t0 = time.monotonic()
            learner = Learner(browser, lab, name, tmp, artifacts)
            record = done[name] = {"error": None, "edits": learner_edits(name), "off_host": learner.off_host}
            try:
                learner.open()
                record["kernel"] = learner.state(KERNEL_NAME)
                for edit in record["edits"]:
                    learner.set_text(edit["index"], edit["text"], edit["cell_type"])
                record["run_seconds"], counts = learner.run_all()
                record["saved"] = learner.save(counts)
                record["screenshot"] = learner.screenshot()
            except pytest.fail.Exception as e:      # said, with its evidence: the other notebook still runs
                record["error"] = str(e)
            except Exception as e:  # noqa: BLE001   # a Playwright step that timed out, say
                record["error"] = learner.evidence(f"{type(e).__name__}: {e}")
            finally:
                learner.close()
                lab.shut_down_kernels()
            record["seconds"] = time.monotonic() - t0
    finally:
        lab.close()
    return root, done, tmp


@pytest.fixture(scope="module")
def graded(learner_folder):
    """The saved notebooks, handed in as a class of one and graded: (course folder, grader output)."""
    root, done, tmp = learner_folder
    handed = [n for n in NOTEBOOKS if done[n]["error"] is None]
    if not handed:
        pytest.fail("no notebook was saved in the browser: " + "; ".join(d["error"] for d in done.values()))
    # The grader reads the receipts from the notebooks' outputs (autograde/receipts.py), never the
    # learner's .pusht_predictions.json, so the hand-in is the notebooks alone, as an LMS takes it.
    subs = tmp / "class" / STUDENT
    subs.mkdir(parents=True)
    for name in handed:
        shutil.copy(root / f"{name}.ipynb", subs / f"{name}.ipynb")
    course = tmp / "course"
    course.mkdir()
    out = subprocess.run([sys.executable, "-m", "autograde.grade", str(subs.parent), "--course", str(course),
                          "--timeout", "120"], cwd=ROOT, env=clean_env(), capture_output=True, text=True,
                         timeout=GRADE_TIMEOUT)
    assert out.returncode == 0, f"the grader failed:\n{out.stdout[-3000:]}\n{out.stderr[-3000:]}"
    return course, out.stdout + out.stderr


# --- the tests -------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", NOTEBOOKS)
def test_a_learner_answers_runs_and_saves_in_jupyterlab(learner_folder, name):
    root, done, _ = learner_folder
    record = done[name]
    assert record["error"] is None, record["error"]
    saved = record["saved"]
    release = nbformat.read(ROOT / "notebooks" / f"{name}.ipynb", as_version=4)
    assert [c.get("id") for c in saved.cells] == [c.get("id") for c in release.cells]
    for edit in record["edits"]:           # the saved file holds what the learner put in the editor
        assert saved.cells[edit["index"]].source == edit["text"], edit["what"]
    assert not [o for c in saved.cells if c.cell_type == "code" for o in c.outputs if o.output_type == "error"]
    assert record["screenshot"].is_file()
    # JupyterLab made no call out (news, update check, extension index are off): what was asked of
    # another host (and refused) is the notebook's content (images, stylesheets, fonts), no fetch,
    # XHR, script or page
    calls = [(kind, url) for kind, url in record["off_host"] if kind not in ("image", "stylesheet", "font")]
    assert not calls, calls
    # the release's own kernelspec: jupyter_client starts it with the server's interpreter, the venv's
    assert record["kernel"] == release.metadata.kernelspec.name == "python3"
    if name == "04_imagination_gap":       # the lock went to the learner's own folder, as the kernel ran there
        store = json.loads((root / ".pusht_predictions.json").read_text())
        assert store["ex1"]["reason"] == REASON
    print(f"{name}: {record['seconds']:.1f} s in the browser ({record['run_seconds']:.1f} s of Run All)")


def gradebook(course: Path) -> tuple[dict, dict]:
    """({notebook: {cell: (score, needs manual grade)}}, {notebook: {cell: (max, kind)}}) for the
    student, kind: "automatic" (a graded code cell: hidden tests), "completion" (a task cell: the
    receipts) or "manual" (a graded markdown cell: a written answer)."""
    from nbgrader.api import Gradebook

    from autograde.course import ASSIGNMENT, COURSE_ID

    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb:
        top = {}
        for nb in gb.find_assignment(ASSIGNMENT).notebooks:
            top[nb.name] = {c.name: (c.max_score, "automatic" if c.cell_type == "code" else "manual")
                            for c in nb.grade_cells}
            top[nb.name].update({c.name: (c.max_score, "completion") for c in nb.task_cells})
        got = {nb.name: {g.name: (g.score, g.needs_manual_grade) for g in nb.grades}
               for nb in gb.find_submission(ASSIGNMENT, STUDENT).notebooks}
    return got, top


@pytest.mark.parametrize("name", NOTEBOOKS)
def test_the_saved_notebook_earns_every_automatic_and_completion_point(learner_folder, graded, name):
    """Every automatic point (the hidden tests) and every completion point (the prediction locked
    before the experiment ran) of the notebook. The written answer (04's ``ex1_sentence``) is graded
    by hand: the grader leaves it at 0, marked "needs manual grade", until the instructor's grade in
    manual_grades.csv is applied (autograde/manual_grade.py); it is not part of this total, only
    checked to have reached the grader as the learner wrote it."""
    from autograde.course import ASSIGNMENT

    _, done, _ = learner_folder
    assert done[name]["error"] is None, f"not handed in: the browser steps failed: {done[name]['error']}"
    course, log = graded
    got, top = gradebook(course)
    cells = {g: v for g, v in top[name].items() if v[1] in ("automatic", "completion")}
    assert cells, f"{name} has no automatic or completion points in the gradebook"
    earned = {g: got[name][g][0] for g in cells}
    maximum = {g: v[0] for g, v in cells.items()}
    report = {r["student_id"]: r["notes"] for r in csv.DictReader(open(course / "report.csv", newline=""))}
    assert earned == maximum, f"{name}: earned {earned} of {maximum}\nreport: {report.get(STUDENT)}\n{log[-2000:]}"
    for g, (_, kind) in top[name].items():
        if kind == "manual":
            assert got[name][g][1], f"{g}: the written answer is not waiting for the instructor"
            autograded = nbformat.read(course / "autograded" / STUDENT / ASSIGNMENT / f"{name}.ipynb", as_version=4)
            assert [c.source for c in autograded.cells if gid(c) == g] == [WRITTEN_ANSWER], g
    print(f"{name}: {sum(earned.values()):g} of {sum(maximum.values()):g} automatic and completion points")


def test_grades_csv_gives_the_learner_every_automatic_and_completion_point(learner_folder, graded):
    """The export an instructor uploads agrees: the learner's score is the automatic and completion
    points of both notebooks (the written answer waits for its manual grade, and the four notebooks
    not handed in score 0)."""
    _, done, _ = learner_folder
    assert all(done[n]["error"] is None for n in NOTEBOOKS), "not every notebook was handed in"
    course, _ = graded
    _, top = gradebook(course)
    total = sum(m for n in NOTEBOOKS for m, kind in top[n].values() if kind in ("automatic", "completion"))
    rows = [r for r in csv.DictReader(open(course / "grades.csv", newline="")) if r["student_id"] == STUDENT]
    assert len(rows) == 1, rows
    assert float(rows[0]["score"]) == total, (rows[0], total)
