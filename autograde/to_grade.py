"""The hand-grading sheet, ``to_grade.csv``: every answer a person grades, in one file to fill in.

    from autograde.to_grade import write_to_grade
    path = write_to_grade(course, report)        # after grading: <course>/to_grade.csv

then, once the ``score`` (and ``comment``) cells are filled in a spreadsheet,

    python -m autograde.manual_grade --from-csv course/to_grade.csv

applies every filled row at once (``manual_grade.apply_sheet``). This module is the sheet: its
columns, writing it from the gradebook and the autograded notebooks, and reading it back.

One row per student, notebook and cell a person decides, ordered by question and then by student
(grading one question across the class, as nbgrader's formgrader does): a one-sentence answer (a
markdown grade cell, or a grade cell that is also a solution cell: the same test as
``lms_export.read_standings``), and a test cell whose verdict the tripwire left to a human
(``report[s]["undecided"]``) or that a person already decided (``manual_grades.csv``). A notebook
that was never graded (not handed in) has no rows. Each row carries the student's display name
(the LMS's, ``lms_export.student_label``) beside the id, the answer as written (from
``<course>/autograded/<student>/<assignment>/<notebook>.ipynb``, read without following a link and
size-capped like the class report's notebooks, one line, at most ``ANSWER_CHARS``), the mark scheme
(``mark_scheme.yaml``), the points, the grade and comment already entered, and blank ``score`` and
``comment`` cells. A blank ``score`` is skipped when the sheet is applied, so a half-filled sheet
can be applied and filled further.

Safe in a spreadsheet: UTF-8 with a byte-order mark and CRLF, as the LMS import files
(``text.write_csv``); control characters removed and any cell that starts with ``= + - @``
prefixed with ``'`` (``text.FORMULA``), so a student's answer such as ``=HYPERLINK(...)``
is shown as text, never run as a formula. Reading it back accepts what a spreadsheet may save
instead: no byte-order mark, Windows-1252, ``;`` or tab as separator, a decimal comma in a score.
"""

from __future__ import annotations

import codecs
import csv
import io
import time
from pathlib import Path

import yaml

from .course import ASSIGNMENT, COURSE_ID, HERE
from .lms_export import student_label
from .text import FORMULA, clean_text, num, write_csv

TO_GRADE_FILE = "to_grade.csv"

COLUMNS = ["student_name", "student_id", "notebook", "grade_id", "status", "max_score", "current_score",
           "score", "comment", "answer", "mark_scheme", "current_comment"]
REQUIRED = ("student_id", "notebook", "grade_id", "score")         # what applying the sheet reads

ANSWER_CHARS = 3_000          # of a student's answer in the sheet (a one-sentence answer is ~300)
SHEET_BYTES = 50 << 20        # a sheet read back, at most

TO_GRADE, GRADED, NO_ANSWER, NEEDS_A_HUMAN = "to grade", "graded", "no answer (0)", "NEEDS A HUMAN"


def mark_scheme() -> dict:
    """{grade id: mark scheme text} (``autograde/mark_scheme.yaml``, as ``gradebook.record`` reads it)."""
    path = HERE / "mark_scheme.yaml"
    data = yaml.safe_load(path.read_text()) if path.exists() else {}
    return data if isinstance(data, dict) else {}


def write_to_grade(course: Path, report: dict, log=print) -> Path:
    """Write ``<course>/to_grade.csv`` for ``report``'s students (grade_class's per-student dict;
    ``report[s]["lms"]`` gives the display name, ``report[s]["undecided"]`` the tripwires) from
    the course's gradebook and autograded notebooks; returns its path. Always written, with its
    header, even with nothing to grade. A sheet already there that holds scores not yet applied (an
    instructor filled it in place, then graded again) is never overwritten: it is kept beside it as
    ``to_grade.unapplied-<time>.csv``, and ``log`` says how to apply it."""
    from .gradebook import read_manual

    course = Path(course)
    scheme, manual = mark_scheme(), read_manual(course)
    keep_unapplied(course / TO_GRADE_FILE, manual, log)
    rows = [_row(report, course, scheme, manual, *item) for item in _cells(course, report, set(manual))]
    rows.sort(key=lambda r: (r["notebook"], r["grade_id"], r["student_id"]))
    path = course / TO_GRADE_FILE
    write_csv(path, COLUMNS, [[_cell(r[c]) for c in COLUMNS] for r in rows])
    return path


def keep_unapplied(path: Path, manual: dict, log=print) -> Path | None:
    """Move ``path`` aside when it holds a score that ``manual`` (manual_grades.csv) does not: the
    instructor's work not yet applied. Returns where it went, or None."""
    if not path.is_file():
        return None
    rows, problems = read_sheet(path)
    waiting = 0
    for _, row in rows:
        score = (row.get("score") or "").strip()
        if not score:
            continue
        held = manual.get((row.get("student_id"), (row.get("notebook") or "").removesuffix(".ipynb"),
                           row.get("grade_id")))
        try:
            same = held is not None and float(held["score"]) == float(score.replace(",", "."))
        except ValueError:
            same = False
        waiting += not same
    if not waiting:
        return None
    aside = path.with_name(f"{path.stem}.unapplied-{time.strftime('%Y%m%d-%H%M%S')}{path.suffix}")
    path.replace(aside)
    log(f"WARNING: {path.name} held {waiting} score{'s' * (waiting != 1)} not yet applied: kept as {aside}; apply "
        f"it with: .venv/bin/python -m autograde.manual_grade --from-csv {aside}")
    return aside


def _cells(course: Path, report: dict, manual: set):
    """(student, notebook, grade id, max score, status, score so far) of every cell a person
    decides; ``manual``: the (student, notebook, grade id) of manual_grades.csv."""
    db = course / "gradebook.db"
    if not db.is_file():
        return []
    from nbgrader.api import Gradebook, MissingEntry, TaskCell

    out = []
    with Gradebook(f"sqlite:///{db}", course_id=COURSE_ID) as gb:
        try:
            assignment = gb.find_assignment(ASSIGNMENT)
        except MissingEntry:
            return []
        solutions = {nb.name: {c.name for c in nb.solution_cells} for nb in assignment.notebooks}
        for student in sorted(report):
            rep = report[student] if isinstance(report[student], dict) else {}
            failed = rep.get("failed") or {}
            undecided = {(nb, g) for nb, g, *_ in rep.get("undecided") or ()}
            try:
                sub = gb.find_submission(ASSIGNMENT, student)
            except MissingEntry:
                continue
            for nb in sub.notebooks:
                grades = list(nb.grades)
                touched = any(g.auto_score is not None or g.manual_score is not None or not g.needs_manual_grade
                              for g in grades)
                graded = (course / "autograded" / student / ASSIGNMENT / f"{nb.name}.ipynb").is_file()
                if not (touched or graded or f"{nb.name}.ipynb" in failed):   # not handed in: nothing to read
                    continue
                for g in grades:
                    if isinstance(g.cell, TaskCell):                     # completion points: the receipts decide
                        continue
                    by_hand = g.cell.cell_type == "markdown" or g.name in solutions.get(nb.name, ())
                    if (nb.name, g.name) in undecided:
                        status = NEEDS_A_HUMAN
                    elif not by_hand and (student, nb.name, g.name) not in manual:
                        continue
                    elif g.manual_score is not None:
                        status = GRADED
                    elif g.auto_score is not None:
                        status = NO_ANSWER if by_hand else GRADED
                    else:
                        status = TO_GRADE
                    out.append((student, nb.name, g.name, float(g.max_score), status,
                                g.manual_score if g.manual_score is not None else g.auto_score))
    return out


def _row(report, course, scheme, manual, student, notebook, grade_id, max_score, status, score) -> dict:
    rep = report[student] if isinstance(report[student], dict) else {}
    entered = manual.get((student, notebook, grade_id)) or {}
    if status == NEEDS_A_HUMAN:
        why = next((w for w in rep.get("tripwires") or () if str(w).startswith(f"{notebook} {grade_id}:")), "")
        answer = "(a function: see the student's feedback page)"
        scheme_text = f"NEEDS A HUMAN: {why} Score {num(max_score)} if the function is right, else 0."
    else:
        answer = "" if status == NO_ANSWER else read_answer(course, student, notebook, grade_id)
        scheme_text = str(scheme.get(grade_id) or "")
    return {"student_name": student_label(rep, student), "student_id": student, "notebook": notebook,
            "grade_id": grade_id, "status": status, "max_score": num(max_score),
            "current_score": _shown(entered.get("score")) if entered else (num(score) if score is not None else ""),
            "score": "", "comment": "", "answer": answer, "mark_scheme": scheme_text,
            "current_comment": entered.get("comment") or ""}


def _shown(score) -> str:
    """A score from manual_grades.csv as the sheet shows points ('1.0' -> '1'); as written if not a number."""
    try:
        return num(float(score))
    except (TypeError, ValueError):
        return str(score or "")


def read_answer(course: Path, student: str, notebook: str, grade_id: str) -> str:
    """The text of the cell ``grade_id`` in the student's autograded notebook, on one line and at
    most ANSWER_CHARS long (a note says when it was cut), or a note in brackets when there is none."""
    from .cellcode import gid
    from .class_report import _read_json_notebook

    if any(p in ("", ".", "..") or "/" in p or "\0" in p for p in (student, notebook)):
        return "(no autograded notebook)"
    nb = _read_json_notebook(Path(course) / "autograded" / student / ASSIGNMENT / f"{notebook}.ipynb")
    if nb is None:
        return "(no autograded notebook)"
    cells = nb.get("cells") if isinstance(nb.get("cells"), list) else []
    for cell in cells:
        if isinstance(cell, dict) and gid(cell) == grade_id:
            src = cell.get("source", "")
            src = "".join(s for s in src if isinstance(s, str)) if isinstance(src, list) else str(src)
            text = clean_text(src[:ANSWER_CHARS * 4])
            if len(text) > ANSWER_CHARS:
                text = text[:ANSWER_CHARS] + f" [... cut at {ANSWER_CHARS} characters: the feedback page has it all]"
            return text
    return "(no cell with this grade id in the autograded notebook)"


def _cell(value) -> str:
    """A value as a spreadsheet shows it: one line, no control characters, never a formula."""
    text = clean_text(str(value))
    return "'" + text if text.startswith(FORMULA) else text


def _uncell(text: str) -> str:
    """What ``_cell`` wrote, back (the id columns: ``'`` before a formula character comes off)."""
    text = text.strip()
    return text[1:] if text.startswith("'") and text[1:].startswith(FORMULA) else text


def read_sheet(path: Path) -> tuple[list[tuple[int, dict]], list[str]]:
    """The filled sheet: ([(line, row)], problems). ``line`` is the line of the file where the row
    starts (the spreadsheet's row number, the header being 1); ``row`` has every column of the
    header, the id columns as ``_cell`` wrote them back to the ids. ``problems`` is not empty when
    the file cannot be read as a sheet at all (then no row is returned)."""
    path = Path(path)
    try:
        with open(path, "rb") as f:
            data = f.read(SHEET_BYTES + 1)
    except OSError as e:
        return [], [f"{path}: cannot be read ({e.strerror or e})"]
    if len(data) > SHEET_BYTES:
        return [], [f"{path}: more than {SHEET_BYTES >> 20} MB: not a grading sheet"]
    legacy = False
    if data.startswith((codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)):   # Excel's "Unicode Text": UTF-16, tabs
        text = data.decode("utf-16")
    else:
        try:
            text = data.decode("utf-8-sig")
        except UnicodeDecodeError:     # Excel's "CSV (comma delimited)" is the system code page
            text, legacy = data.decode("cp1252", errors="replace"), True
    if legacy and "\ufffd" in text:   # not Windows-1252 either (MacRoman, say): comments would be garbled
        return [], [f"{path}: neither UTF-8 nor Windows-1252: save it again as 'CSV UTF-8' (Excel: File > Save "
                    f"As > CSV UTF-8) so that comments reach students as written"]
    first = text.split("\n", 1)[0]
    delimiter = max((",", ";", "\t"), key=first.count)
    reader = csv.reader(io.StringIO(text, newline=""), delimiter=delimiter)
    try:
        header = [h.strip().lstrip("\ufeff") for h in next(reader)]
    except StopIteration:
        return [], [f"{path}: empty (the sheet's header is {', '.join(COLUMNS)})"]
    except csv.Error as e:
        return [], [f"{path}: not a CSV file ({e})"]
    missing = [c for c in REQUIRED if c not in header]
    if missing:
        return [], [f"{path}: no column {', '.join(map(repr, missing))} in its first line "
                    f"(the sheet's columns are {', '.join(COLUMNS)}; write a new one with make grade)"]
    rows, start = [], reader.line_num + 1
    try:
        for values in reader:
            if any(v.strip() for v in values):
                row = {h: (values[i] if i < len(values) else "") for i, h in enumerate(header) if h}
                for key in ("student_id", "notebook", "grade_id"):
                    row[key] = _uncell(row[key])
                rows.append((start, row))
            start = reader.line_num + 1
    except csv.Error as e:
        return [], [f"{path}: line {start}: not readable as CSV ({e})"]
    return rows, []
