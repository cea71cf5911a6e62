"""The class report: one page that says what to re-teach, ``course/class_report.html``.

    write_class_report(course, report, submitted=None) -> Path

``grade_class`` calls it last, after the gradebook's export. The page is self-contained (figures are
PNGs made with matplotlib and embedded as ``data:`` URLs; nothing is fetched, no script runs: the
first element of its ``<head>`` is a Content-Security-Policy that allows none) and shows:

* first, the run's guarantees (``guarantees``, where ``grade_class`` passes them): which of the
  sandbox's protections held, and what a student's code could do where one did not;
* the score distribution: students per total score (nbgrader's score of each student's submission in
  ``gradebook.db``, manual grades included; a student of the report without a submission scores 0,
  as in ``report.csv``);
* per graded cell (hidden tests, completion points, one-sentence answers): of the students whose
  notebook was graded, how many earned its full points, and the most common hint among those who did
  not. A hint is the grader's own words only: the failing case's hint from ``checks.TESTS`` (never
  its probe), or the fixed part of a receipts message; what a student's code printed or raised is
  left out (it is in ``report.csv``);
* per predict-then-run exercise, the letters the class locked (the ``[prediction locked] ex1: (b)``
  receipt) beside the letters the students' own runs measured (``Reconcile ex1: you predicted (b);
  the measurement says (c)``), read from the outputs of the notebooks as handed in, and how many were
  surprised (a locked letter and a measured one that differ); counts, percentages and the
  predicted x measured table, no per-student list;
* the completion points' receipts missing or out of order, by the grader's reason;
* what needs a human, by student: answer-key copies, look-alike ids, graded functions the grader
  could not follow or could not run, notebooks the grader could not finish, late LMS submissions,
  uploaded files that their names did not place (graded by their content, or not graded at all:
  ``report[s]["human"]``, from ``intake.Intake.human``);
* how long each student's grading took (``report[s]["seconds"]``): a histogram, total and mean.

Student ids appear only in the flags, each with the name the LMS wrote beside it (:func:`display_name`). Every string a student could have made (an id, an LMS name, a
note quoting their file or their output) is escaped, with invisible and direction-changing
characters spelled as code points. No cell source is read into the page, and the gradebook's
``source_cell`` table (which holds the hidden tests) is never queried.

Where the notebooks as handed in come from: ``submitted`` ({student: {notebook file name: notebook
as JSON dict or ``NotebookNode``}}, e.g. ``grade_class``'s prepared notebooks), else nbgrader's
``<course>/submitted/<student>/<assignment>/<notebook>.ipynb`` where such files exist (read without
following links, at most ``MAX_NOTEBOOK_BYTES``). The autograded notebooks are no use here: nbgrader
clears the outputs and runs the notebooks again at the grading config, so their receipts are the
grader's run, not the student's.
"""

from __future__ import annotations

import base64
import html
import io
import json
import math
import os
import re
import sqlite3
import statistics
import unicodedata
from collections import Counter
from datetime import datetime, timezone
from pathlib import Path

from . import cellcode, checks, receipts
from .files import read_capped
from .course import ASSIGNMENT, EXERCISES

REPORT_FILE = "class_report.html"
MAX_NOTEBOOK_BYTES = 32 << 20          # a notebook on disk read for its receipts, at most
MAX_TEXT = 300                         # characters of any one student-made string shown

CSP = "; ".join(["default-src 'none'", "script-src 'none'", "object-src 'none'", "style-src 'unsafe-inline'",
                 "img-src data:", "base-uri 'none'", "form-action 'none'"])

# Printed by pusht.predict.reconcile (its format string, kept stable for the autograder).
RECONCILE_RE = re.compile(r"Reconcile (?P<ex>ex\d): you predicted \((?P<predicted>[a-z])\); the measurement says "
                          r"\((?P<measured>[a-z])\), which (?:matches|differs from) your prediction\.")

# What a completion verdict's message says (autograde/receipts.py, after "exN: "): the grader's
# fixed words, and whether the receipts are missing or out of order. Anything else is "other".
RECEIPT_REASONS = [
    ("prediction in order", "in order", "prediction locked at "),
    ("missing", "the prediction cell (with lock_prediction) is missing or no longer locks",
     "the prediction cell (with lock_prediction) is missing"),
    ("missing", "no prediction receipt in the output of the prediction cell", "no prediction receipt"),
    ("missing", "no experiment receipt in the notebook", "no experiment receipt"),
    ("missing", "receipts there, but the cells have no execution record (outputs pasted in?)",
     "the receipts are there but the cells have no execution record"),
    ("out of order", "the prediction cell says the experiment had already run when it locked",
     "your prediction cell says the experiment had already run"),
    ("out of order", "the experiment ran before the prediction was locked",
     "the experiment ran before the prediction was locked"),
    ("out of order", "the experiment's functions ran directly before the prediction was locked",
     "the experiment's functions ran directly"),
    ("out of order", "the experiment used a prediction the prediction cell never showed (locked again after?)",
     "the experiment used a prediction that this notebook's prediction cell never showed"),
    ("unreadable", "the receipts are unreadable (edited?)", "the receipts are unreadable"),
]

# checks.judge's messages other than a failing case: (starts with, what the page says)
_JUDGE_FIXED = [
    ("no credit: your", "no credit: the graded function reaches the package's own implementation"),
    ("this test was not checked", "not checked: the notebook holding it was not graded"),
    ("could not be checked", "could not be checked: the function was not defined, or defining it failed"),
    ("did not finish the checks in time", "did not finish the checks in time"),
    ("returned far more numbers", "returned far more numbers than the checks need"),
]
_FAILED_CASE = re.compile(r"^\d+ of \d+ checks passed; first failure: check (?P<i>\d+): ")

FLAG_KINDS = {                         # kind: what the instructor should do
    "answer key": "a graded function holds the package's own implementation: read it (the score stands)",
    "look-alike id": "two ids that look the same: check in the LMS that both are real students",
    "delegation unclear": "the grader cannot tell whether a graded function reaches the package's own: read it",
    "not finished": "nbgrader could not finish a notebook: points from the tests that ran are kept",
    "late": "handed in after the deadline, says the LMS",
    "grader could not run it": "a graded function ran in the student's kernel, but the grader could not run it: "
                               "0 points for it until you decide",
    "file not graded": "an uploaded file that neither its name nor its content places in the assignment: "
                       "read it, and tell the student (their page says it was not graded)",
    "file graded by content": "a file whose name did not say which notebook it is, graded as the notebook it "
                              "holds: check it is the one the student meant",
}


# --- reading ---------------------------------------------------------------------------------------
def _num(x) -> float | None:
    return float(x) if isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) else None


def gradebook_rows(course: Path, students) -> tuple[dict, list, float]:
    """({student: total score}, [(student, notebook, cell, kind, max, score or None, by_hand_pending,
    comment)], the assignment's maximum) from the course's gradebook, read-only. ``kind``: "task"
    (a completion point), "markdown" or "code" (a grade cell). A score is nbgrader's: the manual
    score where there is one, else the automatic one; None where neither was given."""
    db = course / "gradebook.db"
    totals, rows = {}, []
    if not db.is_file():
        return totals, rows, 0.0
    con = sqlite3.connect(f"{db.resolve().as_uri()}?mode=ro", uri=True)
    try:
        q = """
        SELECT sa.student_id, n.name, b.name, CASE WHEN tc.id IS NULL THEN gc.cell_type ELSE 'task' END,
               COALESCE(gc.max_score, tc.max_score),
               g.auto_score, g.manual_score, g.extra_credit, g.needs_manual_grade,
               (SELECT c.manual_comment FROM comment c JOIN base_cell cb ON cb.id = c.cell_id
                 WHERE c.notebook_id = sn.id AND cb.name = b.name AND cb.notebook_id = b.notebook_id
                   AND c.manual_comment IS NOT NULL LIMIT 1)
          FROM grade g
          JOIN submitted_notebook sn ON sn.id = g.notebook_id
          JOIN submitted_assignment sa ON sa.id = sn.assignment_id
          JOIN assignment a ON a.id = sa.assignment_id
          JOIN base_cell b ON b.id = g.cell_id
          JOIN notebook n ON n.id = b.notebook_id
          LEFT JOIN grade_cells gc ON gc.id = b.id
          LEFT JOIN task_cells tc ON tc.id = b.id
         WHERE a.name = ?"""
        want = set(students)
        for sid, nb, cell, kind, mx, auto, manual, extra, pending, comment in con.execute(q, (ASSIGNMENT,)):
            if sid not in want:
                continue
            if manual is not None:
                score = manual
            elif auto is not None:
                score = auto
            else:
                score = None
            totals[sid] = totals.get(sid, 0.0) + (score or 0.0) + (extra or 0.0)
            rows.append((sid, nb, cell, kind, float(mx or 0.0), score, bool(pending) and manual is None, comment))
        maximum = con.execute("""SELECT COALESCE(SUM(COALESCE(gc.max_score, tc.max_score)), 0) FROM base_cell b
                                  JOIN notebook n ON n.id = b.notebook_id JOIN assignment a ON a.id = n.assignment_id
                                  LEFT JOIN grade_cells gc ON gc.id = b.id LEFT JOIN task_cells tc ON tc.id = b.id
                                 WHERE a.name = ? AND b.type IN ('GradeCell', 'TaskCell')""",
                              (ASSIGNMENT,)).fetchone()[0]
    finally:
        con.close()
    return totals, rows, float(maximum or 0.0)


def _read_json_notebook(path: Path):
    """A notebook on disk as a dict, or None: no link followed, no more than MAX_NOTEBOOK_BYTES."""
    data = read_capped(path, MAX_NOTEBOOK_BYTES)
    if data is None:
        return None
    for enc in ("utf-8-sig", "utf-16", "utf-32"):
        try:
            obj = json.loads(data.decode(enc))
            return obj if isinstance(obj, dict) else None
        except (UnicodeDecodeError, ValueError, RecursionError):
            continue
    return None


def _notebook(course: Path, submitted: dict | None, student: str, name: str):
    if submitted is not None:
        return (submitted.get(student) or {}).get(name)
    folder = course / "submitted"
    if not folder.is_dir() or student in ("", ".", "..") or "/" in student or "\0" in student:
        return None
    return _read_json_notebook(folder / student / ASSIGNMENT / name)


def predictions_of(nb, exercise: str) -> dict | None:
    """What the student's own run printed for ``exercise`` in notebook ``nb`` (a dict): {"locked":
    the letter of the lock receipt or None, "measured": the letter of the reconcile line or None,
    "reconciled_predicted": the letter the reconcile line says was predicted}. Only receipts printed
    by a cell that calls ``lock_prediction`` (a reconcile line: ``reconcile``) count, as for the
    completion point. None when there is no notebook."""
    from pusht.predict import choices_of

    cells = nb.get("cells") if isinstance(nb, dict) else None
    if not isinstance(cells, list):
        return None
    options = choices_of(exercise)
    locked = measured = said = None
    for cell in cells:
        if not isinstance(cell, dict) or cell.get("cell_type") != "code":
            continue
        src = cellcode.source(cell)
        has_lock, has_rec = "lock_prediction" in src, "reconcile" in src
        if not (has_lock or has_rec):
            continue
        for line in receipts._stdout(cell):
            if has_lock and locked is None:
                m = receipts.LOCK_RE.search(line)
                if m and m["ex"] == exercise and m["choice"] in options:
                    locked = m["choice"]
            if has_rec:
                m = RECONCILE_RE.search(line)
                if m and m["ex"] == exercise and m["measured"] in options:
                    measured, said = m["measured"], m["predicted"]      # the last one printed counts
    return {"locked": locked, "measured": measured, "reconciled_predicted": said}


def hint_of(test_id: str, message: str) -> str:
    """The grader's own words for a failing hidden test's message (checks.judge): the failing case's
    hint, or the fixed part of the message; never what the student's code printed or raised."""
    message = message if isinstance(message, str) else ""
    m = _FAILED_CASE.match(message)
    test = checks.TESTS.get(test_id)
    if m:
        i = int(m["i"])
        if test is not None and 1 <= i <= len(test.cases) and message[m.end():].startswith(test.cases[i - 1].hint):
            return f"check {i}: {test.cases[i - 1].hint}"
        return f"check {i} failed"
    for start, words in _JUDGE_FIXED:
        if message.startswith(start) or f" {start}" in message[:120]:
            return words
    return "other (see report.csv)"


def receipt_reason(message: str) -> tuple[str, str]:
    """(category, the grader's fixed words) of a completion verdict's message (receipts.py)."""
    message = message if isinstance(message, str) else ""
    body = message.split(": ", 1)[1] if re.match(r"ex\d+: ", message) else message
    for category, words, start in RECEIPT_REASONS:
        if body.startswith(start):
            return category, words
    return "other", "other (see report.csv)"


def _pairs(value):
    if isinstance(value, (list, tuple)) and len(value) >= 2:
        return value
    return None


def gather(course: Path, report: dict, submitted: dict | None = None) -> dict:
    """Every number the page shows, from the gradebook, the report and the notebooks as handed in."""
    course = Path(course)
    students = sorted(report)
    totals, rows, maximum = gradebook_rows(course, students)
    scores = [totals.get(s, 0.0) for s in students]

    # per graded cell
    graded_nb = {(s, nb) for s, nb, _, _, _, score, _, _ in rows if score is not None}
    cells: dict = {}
    for s, nb, cell, kind, mx, score, pending, comment in rows:
        key = (nb, cell)
        c = cells.setdefault(key, {"notebook": nb, "cell": cell, "max": mx, "graded": 0, "full": 0, "partial": 0,
                                   "zero": 0, "pending": 0, "not_graded": 0, "hints": Counter(),
                                   "kind": ("hidden test" if cell in checks.TESTS else
                                            "completion point" if kind == "task" else
                                            "graded by hand" if kind == "markdown" else "test")})
        if (s, nb) not in graded_nb:
            c["not_graded"] += 1
            continue
        if score is None:
            c["pending"] += 1 if pending else 0
            c["not_graded"] += 0 if pending else 1
            continue
        c["graded"] += 1
        if score >= mx:
            c["full"] += 1
            continue
        c["partial" if score > 0 else "zero"] += 1
        rep = report.get(s) or {}
        hint = None
        if c["kind"] == "hidden test":
            v = _pairs((rep.get("verdicts") or {}).get(cell))
            if v is not None and _num(v[0]) is not None and _num(v[1]) is not None and v[0] >= v[1]:
                hint = "the checks passed; a manual grade gave fewer points"
            elif v is not None:
                hint = hint_of(cell, v[2] if len(v) > 2 else "")
        elif c["kind"] == "completion point":
            ex = cell[:-len("_order")] if cell.endswith("_order") else cell
            v = _pairs((rep.get("completion") or {}).get(ex))
            message = v[1] if v is not None else (comment or "").split("\n\n")[-1]
            category, words = receipt_reason(message)
            hint = None if category == "prediction in order" else words
        if hint is None and c["kind"] != "graded by hand":
            hint = "no message from the grader (a manual grade?)"
        if hint:
            c["hints"][hint] += 1
    for s in students:          # students of the report with no submission in the gradebook
        if s not in totals:
            for c in cells.values():
                c["not_graded"] += 1
    cell_list = sorted(cells.values(), key=lambda c: (c["notebook"], c["kind"] == "graded by hand", c["cell"]))

    # predictions and receipts, per exercise
    from pusht.predict import choices_of

    exercises = {}
    for ex, stem in EXERCISES.items():
        letters = list(choices_of(ex))
        e = {"exercise": ex, "notebook": stem, "letters": letters, "locked": Counter(), "measured": Counter(),
             "cross": Counter(), "n_notebooks": 0, "n_locked": 0, "n_measured": 0, "n_both": 0, "surprised": 0,
             "disagree": 0, "receipts": Counter(), "reasons": Counter()}
        for s in students:
            p = predictions_of(_notebook(course, submitted, s, f"{stem}.ipynb"), ex)
            if p is not None:
                e["n_notebooks"] += 1
                if p["locked"]:
                    e["n_locked"] += 1
                    e["locked"][p["locked"]] += 1
                if p["measured"]:
                    e["n_measured"] += 1
                    e["measured"][p["measured"]] += 1
                if p["locked"] and p["measured"]:
                    e["n_both"] += 1
                    e["cross"][(p["locked"], p["measured"])] += 1
                    e["surprised"] += p["locked"] != p["measured"]
                    e["disagree"] += bool(p["reconciled_predicted"]) and p["reconciled_predicted"] != p["locked"]
            v = _pairs(((report.get(s) or {}).get("completion") or {}).get(ex))
            if v is None:
                e["receipts"]["not graded"] += 1
                continue
            category, words = receipt_reason(v[1])
            e["receipts"][category] += 1
            if category != "prediction in order":
                e["reasons"][(category, words)] += 1
        e["options"] = _options(ex)
        exercises[ex] = e

    # what needs a human
    flags = []
    for s in students:
        rep = report.get(s) or {}
        for note in rep.get("notes") or ():
            note = note if isinstance(note, str) else str(note)
            if "answer key, for the instructor" in note:
                flags.append(("answer key", s, note))
            elif "UTS #39" in note and "looks like" in note:
                flags.append(("look-alike id", s, note))
            elif "for the instructor: the grader cannot tell" in note:
                flags.append(("delegation unclear", s, note))
        for name, error in sorted((rep.get("failed") or {}).items()):
            flags.append(("not finished", s, f"{name}: {_error_line(error)}"))
        for line in rep.get("tripwires") or ():      # the kernel ran it, the grader could not: 0 until decided
            flags.append(("grader could not run it", s, str(line)))
        for h in rep.get("human") or ():           # intake: files their names did not place (identify.py)
            if isinstance(h, dict):
                kind = "file graded by content" if h.get("graded") else "file not graded"
                flags.append((kind, s, f"{h.get('file')}: " + (f"graded as {h['graded']}: " if h.get("graded") else "")
                               + str(h.get("why"))))
        lms = rep.get("lms")
        if isinstance(lms, dict) and lms.get("late"):
            who = " ".join(str(lms.get(k)) for k in ("name",) if lms.get(k))
            when = lms.get("submitted_at")
            flags.append(("late", s, f"{who + ': ' if who else ''}submitted {when if when else '(time not given)'}"
                                     f"{' (' + str(lms.get('system')) + ')' if lms.get('system') else ''}"))

    seconds = [_num((report.get(s) or {}).get("seconds")) for s in students]
    timed = [x for x in seconds if x is not None and x >= 0]
    return {"students": len(students), "max": maximum, "scores": scores, "cells": cell_list,
            "exercises": exercises, "flags": flags, "names": {s: display_name(report.get(s)) for s in students},
            "seconds": timed, "untimed": len(students) - len(timed),
            "notebook_source": "given" if submitted is not None else (
                "course/submitted" if (course / "submitted").is_dir() else "none")}


_ANSI = re.compile(r"\x1b\[[0-9;]*[A-Za-z]")
_CODE_LINE = re.compile(r"^\s*(-+>|\d+\s|File \"|Cell In\b)|\^\^\^")
_EXCEPTION = re.compile(r"^([A-Za-z_][\w.]*(?:Error|Exception|Interrupt|Exit|Timeout)):")


def _error_line(error) -> str:
    """nbgrader's last error line for a notebook it could not finish (``course._last_error``), as
    the flag shows it: only the exception's type (``ValueError``, ``CellTimeoutError``), never its
    message or any other line, which can be the student's own words or code."""
    line = _ANSI.sub("", error if isinstance(error, str) else str(error)).strip()
    if _CODE_LINE.search(line):
        return "nbgrader stopped (its last error line quotes code: see report.csv)"
    kind = _EXCEPTION.match(line)
    if kind is None:       # not "SomeError: ...": it may be any line of the student's traceback
        return "nbgrader stopped (see report.csv for its last error line)"
    return f"{kind.group(1)} (the message is in report.csv)"   # the type only: the message can be the student's


def _options(exercise: str) -> dict:
    """The option texts of an exercise (``EX1_OPTIONS``...: the notebook's own words, markdown bold
    dropped), from the module ``python -m pusht.exercise`` shows them from; {} where they cannot be
    had. Notebooks 04-06's modules import numpy, not torch (0.15 s); notebook 07's imports torch."""
    try:
        from pusht.exercise import EXERCISES as TERMINAL

        value = TERMINAL[exercise].texts()[1]
    except Exception:      # noqa: BLE001  the page goes on without the option texts
        return {}
    return {k: str(v).replace("**", "") for k, v in value.items()} if isinstance(value, dict) else {}


# --- the page --------------------------------------------------------------------------------------
def page_text(value, cap: int = MAX_TEXT) -> str:
    """Any text for the page: capped, invisible and control characters spelled as code points, escaped."""
    s = value if isinstance(value, str) else str(value)
    if len(s) > cap:
        s = s[:cap] + "…"
    out = []
    for ch in s:
        cat = unicodedata.category(ch)
        if cat in ("Cc", "Cf", "Cs", "Co", "Cn", "Zl", "Zp") and ch not in "\n\t":
            out.append(f"<U+{ord(ch):04X}>")
        else:
            out.append(ch)
    return html.escape("".join(out), quote=True)


def _id(student: str) -> str:
    """A student id as the page shows it: escaped, isolated from the text around it, and spelled
    as code points when it holds anything but printable ASCII."""
    shown = f'<bdi class="id">{page_text(student, 128)}</bdi>'
    if all(" " < ch < "\x7f" for ch in student):
        return shown
    spelled = "".join(ch if " " < ch < "\x7f" else f"[U+{ord(ch):04X}]" for ch in student[:128])
    return f'{shown} <span class="spelled">({page_text(spelled, 1200)})</span>'


def display_name(rep) -> str | None:
    """The student's name as the LMS (or the download) wrote it: ``report[s]["name"]``, else the LMS
    record's name; None where neither says one. Shown beside the id, never used as a key."""
    rep = rep if isinstance(rep, dict) else {}
    lms = rep.get("lms") if isinstance(rep.get("lms"), dict) else {}
    for name in (rep.get("name"), lms.get("name")):
        if isinstance(name, str) and name.strip():
            return name.strip()
    return None


def _who(student: str, name: str | None) -> str:
    """The id, and the name beside it where there is one (both escaped)."""
    return _id(student) + (f' <span class="name">{page_text(name, 128)}</span>' if name and name != student else "")


def _n(n: int, word: str) -> str:
    return f"{n} {word}{'' if n == 1 else 's'}"


def _pct(n: int, d: int) -> str:
    return f"{100 * n / d:.0f}%" if d else "–"


def _png(fig) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _img(fig, alt: str, name: str) -> str:
    return f'<img class="figure" data-figure="{name}" alt="{page_text(alt, 1000)}" src="data:image/png;base64,{_png(fig)}">'


def _figure(w: float, h: float, left: float = 0.6, bottom: float = 0.55, right: float = 0.15, top: float = 0.25,
            wspace: float | None = None):
    """A matplotlib figure of ``w`` x ``h`` inches with fixed margins (inches): no layout engine,
    which would draw every figure twice (the report's figures cost 0.1 s each with one, 0.05 without)."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(w, h))
    fig.subplots_adjust(left=left / w, right=1 - right / w, bottom=bottom / h, top=1 - top / h, wspace=wspace)
    return fig


def _score_section(d: dict) -> str:
    scores, mx = d["scores"], d["max"]
    top = int(math.floor(mx)) if mx else int(math.floor(max(scores, default=0)))
    bins = Counter(min(int(math.floor(x)), top) for x in scores)
    fig = _figure(7.5, 3.0)
    ax = fig.add_subplot()
    xs = list(range(0, top + 1))
    ys = [bins.get(x, 0) for x in xs]
    bars = ax.bar(xs, ys, width=0.85, color="#4477aa")
    if len(xs) <= 40:
        ax.bar_label(bars, labels=[str(y) if y else "" for y in ys], fontsize=8)
    ax.set_xlabel(f"total score (points, of {mx:g}; a bar holds scores from its value up to the next)")
    ax.set_ylabel("students")
    ax.set_xlim(-0.7, top + 0.7)
    ax.yaxis.get_major_locator().set_params(integer=True)
    alt = f"Histogram: students per total score, {d['students']} students, scores 0 to {mx:g} points"
    rows = "".join(f'<tr data-score-bin="{x}" data-count="{bins.get(x, 0)}"><td>{x}</td><td>{bins.get(x, 0)}</td></tr>'
                   for x in xs if bins.get(x, 0))
    stats = (f"mean {statistics.fmean(scores):.1f}, median {statistics.median(scores):g}, lowest {min(scores):g}, "
             f"highest {max(scores):g} points of {mx:g}") if scores else "no scores"
    return (f'<section id="scores"><h2>Scores</h2><p>{d["students"]} students: {stats}.</p>'
            f'{_img(fig, alt, "scores")}'
            f'<details><summary>the histogram as numbers</summary><table class="num"><tr><th>score from (points)</th>'
            f'<th>students</th></tr>{rows}</table></details></section>')


def _cells_section(d: dict) -> str:
    cells = d["cells"]
    if not cells:
        return '<section id="tests"><h2>Tests and completion points</h2><p>The gradebook holds no grades.</p></section>'
    body = []
    for c in cells:
        failing = c["partial"] + c["zero"]
        top = c["hints"].most_common(1)
        hint = (f'{page_text(top[0][0], 600)} <span class="muted">({top[0][1]} of {failing} who lost points)</span>'
                if top and failing else "")
        if c["kind"] == "graded by hand":
            hint = f'{c["pending"]} awaiting a manual grade' if c["pending"] else ""
        body.append(
            f'<tr data-notebook="{page_text(c["notebook"])}" data-cell="{page_text(c["cell"])}" data-graded="{c["graded"]}" '
            f'data-full="{c["full"]}" data-pending="{c["pending"]}" data-not-graded="{c["not_graded"]}">'
            f'<td><span class="cell">{page_text(c["cell"])}</span><br><span class="muted">{page_text(c["notebook"])}, '
            f'{c["kind"]}, {c["max"]:g} pt</span></td>'
            f'<td>{c["graded"]}</td><td class="rate">{_bar(c)}{c["full"]} ({_pct(c["full"], c["graded"])})</td>'
            f'<td>{c["partial"] + c["zero"]}</td><td>{c["not_graded"]}</td><td class="hint">{hint}</td></tr>')
    return (f'<section id="tests"><h2>Tests and completion points</h2>'
            f'<p>Per graded cell: of the students whose notebook was graded, how many have all its points '
            f'(the bar: their share). Completion points are earned by locking the prediction before the '
            f'experiment. The hint is the grader\'s own words for the first failing check, and how many of '
            f'those who lost points got it; what a student\'s code printed is in <code>report.csv</code>.</p>'
            f'<table class="wide"><tr><th>graded cell</th><th>graded</th><th>full points</th><th>lost points</th>'
            f'<th>not graded</th><th>most common hint (the grader\'s words)</th></tr>'
            f'{"".join(body)}</table></section>')


def _bar(c: dict) -> str:
    """The share of full points as a bar of the table's cell (CSS only: no figure to draw)."""
    if not c["graded"]:
        return ""
    share = 100 * c["full"] / c["graded"]
    return (f'<span class="bar" title="{share:.0f}% with full points"><span class="fill {c["kind"].split()[0]}" '
            f'style="width:{share:.1f}%"></span></span>')


def _predictions_section(d: dict) -> str:
    exs = list(d["exercises"].values())
    fig = _figure(3.4 * len(exs), 3.5, left=0.6, right=0.1, top=0.55, wspace=0.35)
    axes = fig.subplots(1, len(exs), squeeze=False)[0]
    parts, handles = [], ()
    for ax, e in zip(axes, exs):
        L = e["letters"]
        xs = range(len(L))
        lk = [e["locked"].get(x, 0) for x in L]
        ms = [e["measured"].get(x, 0) for x in L]
        b1 = ax.bar([x - 0.2 for x in xs], lk, width=0.4, color="#4477aa", label="locked prediction")
        b2 = ax.bar([x + 0.2 for x in xs], ms, width=0.4, color="#ddaa33", label="own run measured")
        ax.bar_label(b1, labels=[f"{n}\n{_pct(n, e['n_locked'])}" if n else "" for n in lk], fontsize=7)
        ax.bar_label(b2, labels=[f"{n}\n{_pct(n, e['n_measured'])}" if n else "" for n in ms], fontsize=7)
        ax.set_xticks(list(xs), [f"({x})" for x in L])
        ax.set_xlabel("answer letter")
        ax.set_ylabel("students")
        ax.set_ylim(0, max(lk + ms + [1]) * 1.3)
        ax.yaxis.get_major_locator().set_params(integer=True)
        ax.set_title(f"{e['exercise']} ({e['notebook'][:2]}): {e['surprised']} of {e['n_both']} surprised",
                     fontsize=9, loc="left")
        handles = (b1, b2)
        rows = []
        for x in L:
            option = e["options"].get(x, "")
            rows.append(f'<tr data-ex="{e["exercise"]}" data-letter="{x}" data-locked="{e["locked"].get(x, 0)}" '
                        f'data-measured="{e["measured"].get(x, 0)}"><td>({x})</td>'
                        f'<td class="option">{page_text(option, 400)}</td>'
                        f'<td>{e["locked"].get(x, 0)} ({_pct(e["locked"].get(x, 0), e["n_locked"])})</td>'
                        f'<td>{e["measured"].get(x, 0)} ({_pct(e["measured"].get(x, 0), e["n_measured"])})</td></tr>')
        head = "".join(f"<th>measured ({m})</th>" for m in L)
        cross = "".join(
            f'<tr><th>predicted ({p})</th>' + "".join(
                f'<td data-ex="{e["exercise"]}" data-predicted="{p}" data-measured="{m}" '
                f'data-count="{e["cross"].get((p, m), 0)}"{" class=diag" if p == m else ""}>'
                f'{e["cross"].get((p, m), 0)}</td>' for m in L) + "</tr>" for p in L)
        no_lock = e["n_notebooks"] - e["n_locked"]
        parts.append(
            f'<div class="exercise" data-ex="{e["exercise"]}" data-notebooks="{e["n_notebooks"]}" '
            f'data-n-locked="{e["n_locked"]}" data-n-measured="{e["n_measured"]}" data-n-both="{e["n_both"]}" '
            f'data-surprised="{e["surprised"]}"><h3>{e["exercise"]} ({page_text(e["notebook"])})</h3>'
            f'<p>{e["n_notebooks"]} notebooks read: {e["n_locked"]} show a locked prediction '
            f'({no_lock} none), {e["n_measured"]} a measurement of their own run. Of the {e["n_both"]} with both, '
            f'<strong>{e["surprised"]} ({_pct(e["surprised"], e["n_both"])}) were surprised</strong> (the '
            f'measurement differs from the prediction).'
            + (f' In {e["disagree"]} the reconcile line names another prediction than the lock receipt '
               f'(edited outputs?).' if e["disagree"] else "") + '</p>'
            f'<table><tr><th>letter</th><th>option</th><th>locked prediction (% of locked)</th>'
            f'<th>own run measured (% of measured)</th></tr>{"".join(rows)}</table>'
            f'<details><summary>predicted × measured</summary><table class="num cross"><tr><th></th>{head}</tr>'
            f'{cross}</table></details></div>')
    if handles:
        fig.legend(handles, ["locked prediction (% of locked)", "own run measured (% of measured)"], loc="upper center",
                   ncols=2, fontsize=8, frameon=False)
    alt = ("Grouped bar charts, one per exercise: students per answer letter, the locked predictions beside "
           "what the students' own runs measured")
    source = {"given": "the notebooks as handed in",
              "course/submitted": "the notebooks as handed in (course/submitted)",
              "none": "no notebooks as handed in were available, so nothing is counted"}[d["notebook_source"]]
    return (f'<section id="predictions"><h2>Predict, then run</h2><p>Read from {source}: the lock receipt '
            f'(<code>[prediction locked] ex1: (b)</code>) and the reconcile line of the student\'s own run '
            f'(<code>Reconcile ex1: … the measurement says (c)</code>). A class whose measurements differ from '
            f'its predictions is where the chapter\'s point landed as a surprise: worth discussing.</p>'
            f'{_img(fig, alt, "predictions")}{"".join(parts)}</section>')


def _receipts_section(d: dict) -> str:
    rows = []
    for e in d["exercises"].values():
        r = e["receipts"]
        reasons = "; ".join(f'{page_text(w)}: <span data-ex="{e["exercise"]}" data-reason="{page_text(w)}">{n}</span>'
                            for (cat, w), n in sorted(e["reasons"].items(), key=lambda kv: -kv[1]))
        rows.append(f'<tr data-ex="{e["exercise"]}" data-in-order="{r["prediction in order"]}" '
                    f'data-missing="{r["missing"]}" data-out-of-order="{r["out of order"]}" '
                    f'data-other="{r["unreadable"] + r["other"]}" data-not-graded="{r["not graded"]}">'
                    f'<td>{e["exercise"]} ({page_text(e["notebook"])})</td><td>{r["prediction in order"]}</td>'
                    f'<td>{r["missing"]}</td><td>{r["out of order"]}</td><td>{r["unreadable"] + r["other"]}</td>'
                    f'<td>{r["not graded"]}</td><td class="hint">{reasons}</td></tr>')
    return ('<section id="receipts"><h2>Receipts missing or out of order</h2><p>The completion points\' verdicts '
            '(<code>autograde/receipts.py</code>), counted by the grader\'s reason. "Not graded": no notebook '
            'of that exercise was graded for the student.</p><table><tr><th>exercise</th><th>in order</th>'
            '<th>missing</th><th>out of order</th><th>unreadable, other</th><th>not graded</th><th>reasons</th></tr>'
            f'{"".join(rows)}</table></section>')


def _flags_section(d: dict) -> str:
    by_kind: dict = {}
    for kind, s, text in d["flags"]:
        by_kind.setdefault(kind, []).append((s, text))
    if not by_kind:
        return '<section id="flags"><h2>Needs a human</h2><p>Nothing.</p></section>'
    out = []
    for kind, what in FLAG_KINDS.items():
        items = by_kind.get(kind, [])
        if not items:
            continue
        names = d.get("names") or {}
        rows = "".join(f'<tr class="flag" data-kind="{kind}"><td>{_who(s, names.get(s))}</td><td>{page_text(text, 800)}</td></tr>'
                       for s, text in items)
        students = len({s for s, _ in items})
        out.append(f'<details{" open" if len(items) <= 25 else ""} data-kind="{kind}" data-count="{len(items)}">'
                   f'<summary><strong>{kind}</strong>: {_n(len(items), "flag")}, {_n(students, "student")}. '
                   f'{what}</summary>'
                   f'<table class="flags"><tr><th>student</th><th>what</th></tr>{rows}</table></details>')
    return ('<section id="flags"><h2>Needs a human</h2><p>Ids are shown as the LMS wrote them; any character '
            'outside printable ASCII is also spelled as a code point.</p>' + "".join(out) + "</section>")


def _time_section(d: dict) -> str:
    xs = d["seconds"]
    if not xs:
        return ('<section id="time"><h2>Grading time</h2><p>No grading times were recorded'
                f'{" for " + str(d["untimed"]) + " students" if d["untimed"] else ""}.</p></section>')
    import numpy as np

    fig = _figure(7.5, 2.8)
    ax = fig.add_subplot()
    counts, edges = np.histogram(xs, bins=max(5, min(30, round(2 * len(xs) ** (1 / 3)))))   # Rice's rule
    ax.bar(edges[:-1], counts, width=np.diff(edges), align="edge", color="#228833", edgecolor="white")
    ax.set_xlabel("grading time per student (s, wall clock)")
    ax.set_ylabel("students")
    ax.yaxis.get_major_locator().set_params(integer=True)
    total, mean = sum(xs), statistics.fmean(xs)
    alt = f"Histogram of per-student grading time, {len(xs)} students, mean {mean:.1f} s"
    return (f'<section id="time" data-total="{total:.3f}" data-mean="{mean:.3f}" data-n="{len(xs)}">'
            f'<h2>Grading time</h2>'
            f'<p>{len(xs)} students: total {total:.1f} s, mean {mean:.1f} s, median {statistics.median(xs):.1f} s, '
            f'longest {max(xs):.1f} s per student'
            + (f' ({d["untimed"]} students without a time)' if d["untimed"] else "")
            + '. The total adds each student\'s time; with several grading tasks at once the batch took less '
              'wall-clock time.</p>' + _img(fig, alt, "time") + "</section>")


def _glance(d: dict) -> str:
    """The few lines to read first: where the class lost most, where it was surprised, what to check."""
    items = []
    auto = [c for c in d["cells"] if c["kind"] != "graded by hand" and c["graded"]]
    for c in sorted(auto, key=lambda c: c["full"] / c["graded"])[:2]:
        top = c["hints"].most_common(1)
        items.append(f'<li><code>{page_text(c["cell"])}</code> ({page_text(c["notebook"])}): {_pct(c["full"], c["graded"])} of '
                     f'{c["graded"]} with full points'
                     + (f'; most often: {page_text(top[0][0], 300)}' if top else "") + "</li>")
    for e in d["exercises"].values():
        if e["n_both"]:
            lk, ms = e["locked"].most_common(1), e["measured"].most_common(1)
            items.append(f'<li>{e["exercise"]}: {_pct(e["surprised"], e["n_both"])} of {e["n_both"]} surprised; most '
                         f'predicted ({lk[0][0]}), most measured ({ms[0][0]})</li>')
    bad = {k: sum(e["receipts"][k] for e in d["exercises"].values()) for k in ("missing", "out of order")}
    if any(bad.values()):
        items.append(f'<li>receipts: {bad["missing"]} missing, {bad["out of order"]} out of order '
                     f'(all exercises together)</li>')
    kinds = Counter(k for k, _, _ in d["flags"])
    items.append("<li>needs a human: " + (", ".join(f"{n} {k}" for k, n in kinds.items()) or "nothing") + "</li>")
    return f'<section id="glance"><h2>At a glance</h2><ul class="glance">{"".join(items)}</ul></section>'


STYLE = """
body { font: 15px/1.45 system-ui, -apple-system, "Segoe UI", sans-serif; margin: 2em auto; max-width: 72em;
       padding: 0 1em; color: #222; }
h1 { font-size: 1.6em; } h2 { border-bottom: 1px solid #ccc; margin-top: 2em; } h3 { margin-bottom: .3em; }
nav a { margin-right: 1em; } ul.glance li { margin: .2em 0; }
table { border-collapse: collapse; margin: .6em 0; } table.wide { width: 100%; }
td, th { border: 1px solid #ddd; padding: .25em .5em; vertical-align: top; text-align: left; }
td { overflow-wrap: break-word; } th { background: #f4f4f4; }
table.num td { text-align: right; } td.diag { background: #eef5ee; font-weight: bold; }
table.flags { table-layout: fixed; width: 100%; }
table.flags td:first-child, table.flags th:first-child { width: 28%; }
img.figure { max-width: 100%; height: auto; display: block; margin: .6em 0; }
.muted, .spelled { color: #666; } td.hint { min-width: 16em; } td.option { max-width: 34em; font-size: .9em; }
span.cell { font-family: ui-monospace, monospace; overflow-wrap: anywhere; }
td.rate { white-space: nowrap; }
span.bar { display: inline-block; width: 5em; height: .8em; background: #eee; margin-right: .4em; }
span.fill { display: block; height: 100%; background: #4477aa; }
span.fill.completion { background: #cc6677; } span.fill.graded { background: #999; }
bdi.id { font-family: ui-monospace, monospace; background: #f6f6f6; padding: 0 .2em; }
"""


def render(d: dict, title: str) -> str:
    now = datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    n_flags = len(d["flags"])
    nav = " ".join(f'<a href="#{a}">{b}</a>' for a, b in (
        ("scores", "Scores"), ("tests", "Tests"), ("predictions", "Predictions"), ("receipts", "Receipts"),
        ("flags", f"Needs a human ({n_flags})"), ("time", "Grading time")))
    return ("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n"
            f'<meta http-equiv="Content-Security-Policy" content="{CSP}">\n<meta charset="utf-8">\n'
            '<meta name="viewport" content="width=device-width, initial-scale=1">\n'
            '<link rel="icon" href="data:,">\n'
            f"<title>{page_text(title)}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n"
            f'<h1>{page_text(title)}</h1><p class="muted">{d["students"]} students; made {now} by '
            f'<code>autograde/class_report.py</code> from the gradebook and the notebooks as handed in. It holds '
            f'no student code and no hidden test.</p><nav>{nav}</nav>\n'
            + _guarantees_section(d.get("guarantees"))
            + _glance(d) + _score_section(d) + _cells_section(d) + _predictions_section(d) + _receipts_section(d)
            + _flags_section(d) + _time_section(d) + "\n</body>\n</html>\n")


def _guarantees_section(held) -> str:
    """The run's guarantees (``guarantees.of_run``), above everything else: which held, and for those
    that did not, why and what a student's code could do there. Nothing where the run gave none."""
    if not held:
        return ""
    off = [g for g in held if not g.held]
    rows = "".join(f'<tr><td>{page_text(g.name)}</td><td>{"held" if g.held else "<strong>NOT held</strong>"}</td>'
                   f'<td>{page_text(g.detail, 2000)}</td></tr>' for g in held)
    return ('<section id="guarantees"><h2>Guarantees of this run</h2><p>'
            + ("All of the sandbox\'s guarantees held." if not off else
               f'<strong>{len(off)} of {len(held)} did not hold</strong> ({page_text(", ".join(g.name for g in off))}): '
               f'read what a student\'s code could do there.')
            + ' They are also the first lines of the run\'s output and of <code>report.csv</code>.</p>'
              f'<table class="wide"><tr><th>guarantee</th><th></th><th>what holds, or why not and what a student '
              f'could do</th></tr>{rows}</table></section>')


def write_class_report(course: Path, report: dict, submitted: dict | None = None, out: Path | None = None,
                       guarantees: list | None = None) -> Path:
    """Write ``<course>/class_report.html`` (or ``out``) for the per-student ``report`` of
    ``grade_class``; returns its path. ``submitted``: the notebooks as handed in, {student: {file
    name: notebook}} (default: nbgrader's ``<course>/submitted/`` folders, where they exist).
    ``guarantees``: the run's (``guarantees.of_run``), shown first."""
    course = Path(course)
    out = Path(out) if out else course / REPORT_FILE
    d = gather(course, report, submitted)
    d["guarantees"] = guarantees
    page = render(d, f"Class report: {ASSIGNMENT}")
    tmp = out.with_name(out.name + ".tmp")
    tmp.write_text(page, encoding="utf-8")
    os.replace(tmp, out)
    return out
