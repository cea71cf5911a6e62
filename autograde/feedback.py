"""The feedback pages: the autograded notebooks made fit to show (hidden tests out, verdicts in, sizes
capped), then nbgrader's ``generate_feedback`` in several processes at once, each student's pages
under a time limit.

    python -m autograde.feedback ARGS_JSON      (one such process)
"""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import nbformat

from . import cellcode
from .course import ASSIGNMENT, _last_error, nbgrader_api, tool_env


FEEDBACK_OUTPUT_CHARS = 20_000      # per output in a feedback page; the rest is cut with a note


FEEDBACK_NOTEBOOK_CHARS = 2_000_000  # all outputs of one notebook together; all its cells' text too


FEEDBACK_SOURCE_CHARS = 20_000      # per cell's text (markdown or code) in a feedback page


FEEDBACK_TIMEOUT = 120              # seconds one student's feedback pages may take before they are skipped


WIDGET = "application/vnd.jupyter.widget-view+json"


HIDDEN_NOTE = "# (hidden tests: run by the grader; their verdict is printed below)\n"


def generate_feedback(course: Path, students: list[str], jobs: int, log=print,
                      timeout: float = FEEDBACK_TIMEOUT) -> dict:
    """nbgrader's feedback pages for ``students``, ``jobs`` processes at once; {student: error} for
    the students whose pages could not be made (their grades stand).

    Each student's pages depend only on their autograded notebooks and their rows in the gradebook,
    which every process only reads, so they can be made side by side (nbgrader's own
    ``generate_feedback`` makes them one student after another; benchmarks/grading_wallclock.txt
    has what that cost). The pages are the same whichever process makes them.

    A student whose pages take more than ``timeout`` seconds (a submission built to be slow to
    render) loses their pages, not the batch: their process is killed, their half-made pages are
    removed, and the students after them get a new process. The pages are capped in size before
    (``sanitize_feedback_sources``), so a real notebook takes a few seconds at most."""
    students = sorted(students)
    errors: dict = {}
    n = max(1, min(jobs, len(students)))
    with tempfile.TemporaryDirectory(prefix="pusht-feedback-") as tmp:
        queue = [students[i::n] for i in range(n) if students[i::n]]
        running, count = [], 0

        def start(chunk):
            nonlocal count
            count += 1
            done, err = Path(tmp) / f"{count}.jsonl", Path(tmp) / f"{count}.err"
            args = json.dumps({"course": str(course), "students": chunk, "answer": str(done)})
            with open(err, "w") as stderr:       # a file, not a pipe: no process waits on a full one
                proc = subprocess.Popen([sys.executable, "-m", "autograde.feedback", args],
                                        cwd=course, stdout=subprocess.DEVNULL, stderr=stderr, env=tool_env(),
                                        start_new_session=True)
            running.append({"chunk": chunk, "done": done, "err": err, "proc": proc, "seen": 0,
                            "since": time.monotonic()})

        for chunk in queue:
            start(chunk)
        while running:
            time.sleep(0.05)
            for job in list(running):
                finished = []
                for line in job["done"].read_text().splitlines() if job["done"].exists() else []:
                    try:
                        finished.append(json.loads(line))
                    except ValueError:           # a line being written as we read
                        break
                if len(finished) > job["seen"]:
                    job["seen"], job["since"] = len(finished), time.monotonic()
                left = job["chunk"][len(finished):]
                exited = job["proc"].poll() is not None
                late = not exited and time.monotonic() - job["since"] > timeout
                if not (exited or late):
                    continue
                running.remove(job)
                errors.update({f["student"]: f["error"] for f in finished if f["error"]})
                if late:
                    try:
                        os.killpg(job["proc"].pid, signal.SIGKILL)
                    except ProcessLookupError:
                        pass
                    job["proc"].wait()
                if not left:
                    continue
                stuck = left[0]
                errors[stuck] = (f"its feedback pages took more than {timeout:g} s to make and were "
                                 "skipped (the grades are recorded)" if late else
                                 _last_error(job["err"].read_text(errors="replace")))
                shutil.rmtree(course / "feedback" / stuck / ASSIGNMENT, ignore_errors=True)
                if left[1:]:
                    start(left[1:])
    for student, error in sorted(errors.items()):
        log(f"nbgrader generate_feedback failed for {student}: {error}")
    return errors


def _feedback_for(course: Path, students: list[str], answer: Path | None = None) -> dict:
    """Feedback for each of ``students`` in this process; returns {student: error} for failures.
    With ``answer``, each student's outcome is also appended to that file as one JSON line the
    moment it is known (the parent's clock runs per student)."""
    api = nbgrader_api(course)
    errors = {}
    for student in students:
        res = api.generate_feedback(ASSIGNMENT, student_id=student, force=True)
        error = None if res.get("success") else _last_error(res.get("error") or res.get("log") or "")
        if error:
            errors[student] = error
        if answer is not None:
            with open(answer, "a") as f:
                f.write(json.dumps({"student": student, "error": error}) + "\n")
    return errors


SUMMARY_TITLE = "What the grader found"


def sanitize_feedback_sources(course: Path, report: dict) -> None:
    """Before feedback: hidden tests out, each test's verdict in (the first of its cell's outputs),
    long outputs cut, the Colab install cell out (it does nothing but on Colab), and on top of the
    page one cell that names each test that lost points with the grader's hint (:func:`summary_cell`)."""
    for student, rep in report.items():
        folder = course / "autograded" / student / ASSIGNMENT
        for path in folder.glob("*.ipynb"):
            nb = nbformat.read(path, as_version=4)
            nb.metadata.pop("widgets", None)
            budget = text_budget = FEEDBACK_NOTEBOOK_CHARS
            verdicts = []
            nb.cells = [c for i, c in enumerate(nb.cells) if i != install_cell_index(nb.cells)]
            for cell in nb.cells:
                g = cellcode.gid(cell)
                if cell.cell_type == "code" and "### BEGIN HIDDEN TESTS" in cell.source:
                    cell.source = _strip_hidden(cell.source)
                text_budget = _cap_source(cell, text_budget)
                verdict = None
                if g in rep["verdicts"]:
                    score, max_score, msg = rep["verdicts"][g]
                    verdicts.append((g, score, max_score, msg))
                    cell.outputs = _without_grader_lines(cell.get("outputs", []))
                    verdict = nbformat.v4.new_output("stream", name="stdout",
                                                     text=f"[grader] {g}: {score:g} of {max_score:g} points: {msg}\n")
                if cell.cell_type == "code":
                    # widgets (progress bars) are live views with random ids: nothing in a static page
                    cell.outputs = _coalesce_streams([o for o in cell.get("outputs", []) if WIDGET not in o.get("data", {})])
                    if verdict is not None:         # the grader's word first, above what the cell printed
                        cell.outputs.insert(0, verdict)
                    budget = _cap_outputs(cell, budget)
                elif verdict is not None:               # as before: what nbgrader's page does with it
                    cell.outputs.append(verdict)
            if verdicts:
                nb.cells.insert(0, summary_cell(verdicts))
            nbformat.write(nb, path)


def install_cell_index(cells) -> int | None:
    """The Colab install cell's index (its first ungraded code cell that mentions ``google.colab``,
    as scripts/release.py writes it), or None."""
    return next((i for i, c in enumerate(cells) if c.cell_type == "code" and "google.colab" in c.source
                 and not cellcode.gid(c)), None)


_MARKDOWN_SPECIAL = re.compile(r"([\\`*_{}\[\]()#+\-.!|<>$~&])")


def _plain(text: str) -> str:
    """``text`` as markdown that shows it as it is (a hint may quote the student's exception)."""
    return _MARKDOWN_SPECIAL.sub(r"\\\1", " ".join(text.split()))


def summary_cell(verdicts) -> nbformat.NotebookNode:
    """The page's first cell: each graded cell by its name (a link to it), its points, and for each
    that lost points the grader's hint, so the one line a student needs comes first."""
    lines = [f"## {SUMMARY_TITLE}", ""]
    for g, score, max_score, msg in verdicts:
        lost = score < max_score
        lines.append(f"* [{_plain(g)}](#{g}): **{score:g} of {max_score:g} points**" + (f": {_plain(msg)}" if lost else ""))
    if all(score >= max_score for _, score, max_score, _ in verdicts):
        lines += ["", "Every test passed."]
    return nbformat.v4.new_markdown_cell("\n".join(lines))


def _without_grader_lines(outputs: list) -> list:
    """A test cell's outputs without the kernel's own grading lines (the verdict replaces them).
    Line by line, after joining the streams: where the kernel cut the printed text into messages
    depends on timing, so a student's line can share a message with a grading line."""
    out = []
    for o in _coalesce_streams(outputs):
        if o.get("output_type") == "stream":
            lines = [line for line in _text(o).splitlines(keepends=True)
                     if "[graded outside this kernel]" not in line and not line.startswith("[grader] ")]
            if not lines:
                continue
            o["text"] = "".join(lines)
        out.append(o)
    return out


def _coalesce_streams(outputs: list) -> list:
    """Consecutive stdout (or stderr) outputs joined into one, as Jupyter displays them. Where the
    kernel cut a cell's printed text into messages depends on timing (it flushes on a clock), so
    without this two gradings of the same notebook could give different feedback pages."""
    out = []
    for o in outputs:
        if (o.get("output_type") == "stream" and out and out[-1].get("output_type") == "stream"
                and out[-1].get("name") == o.get("name")):
            out[-1]["text"] = _text(out[-1]) + _text(o)
        else:
            out.append(o)
    return out


def _text(o) -> str:
    t = o.get("text", "")
    return "".join(t) if isinstance(t, list) else t


def _strip_hidden(src: str) -> str:
    out, hidden = [], False
    for line in src.splitlines(keepends=True):
        if line.strip() == "### BEGIN HIDDEN TESTS":
            hidden = True
            out.append(HIDDEN_NOTE)
        elif line.strip() == "### END HIDDEN TESTS":
            hidden = False
        elif not hidden:
            out.append(line)
    return "".join(out)


def _cap_source(cell, budget: int) -> int:
    """A cell's text cut at FEEDBACK_SOURCE_CHARS, or removed once the notebook's texts have used
    ``budget``; returns what is left of it. Rendering is linear but not fast (nbconvert's markdown
    took about 7 s per million characters of the slowest text tried), and a hand-in may be 50 MB."""
    source = cell.get("source", "")
    if len(source) <= min(FEEDBACK_SOURCE_CHARS, budget):
        return budget - len(source)
    note = (f"[... this cell's text is cut at {FEEDBACK_SOURCE_CHARS} characters in the feedback page]"
            if budget >= FEEDBACK_SOURCE_CHARS else
            "[... this cell's text is left out of the feedback page: the page is capped in size]")
    keep = source[:FEEDBACK_SOURCE_CHARS] if budget >= FEEDBACK_SOURCE_CHARS else ""
    cell.source = keep + (f"\n# {note}\n" if cell.cell_type == "code" else f"\n\n*{note}*\n")
    return max(budget - len(keep), 0)


def _cap_outputs(cell, budget: int) -> int:
    kept = []
    for o in cell.get("outputs", []):
        for key in ("text",):
            if isinstance(o.get(key), str) and len(o[key]) > FEEDBACK_OUTPUT_CHARS:
                o[key] = o[key][:FEEDBACK_OUTPUT_CHARS] + f"\n[... output cut at {FEEDBACK_OUTPUT_CHARS} characters]\n"
        if o.get("output_type") == "error":
            o["traceback"] = [t[:FEEDBACK_OUTPUT_CHARS] for t in o.get("traceback", [])[:50]]
        size = len(json.dumps(o))
        if size > budget:
            kept.append(nbformat.v4.new_output("stream", name="stdout",
                                               text="[... further output removed: the page is capped in size]\n"))
            break
        budget -= size
        kept.append(o)
    cell.outputs = kept
    return budget


def main(argv=None) -> int:
    """``python -m autograde.feedback ARGS_JSON``: one ``generate_feedback`` process (``_feedback_for``)."""
    a = json.loads((sys.argv[1:] if argv is None else argv)[0])
    _feedback_for(Path(a["course"]), a["students"], Path(a["answer"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
