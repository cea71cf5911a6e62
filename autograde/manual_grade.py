"""Enter manual grades headless; they are kept in manual_grades.csv and survive every regrade.

    python -m autograde.manual_grade STUDENT NOTEBOOK GRADE_ID SCORE [--comment "..."]
    python -m autograde.manual_grade --from-csv course/to_grade.csv

e.g. ``python -m autograde.manual_grade s042 04_imagination_gap ex1_sentence 1 --comment "Clear."``
The second form applies every row of the hand-grading sheet (``to_grade.py``) whose ``score`` is
filled, all at once: every row is checked first (student, notebook and grade id known, the score a
number within the cell's points, no two rows disagreeing), and if any row is wrong nothing is
applied and every wrong row is named by its line, with the nearest real ids for a wrong one.
A row whose score and comment are already what is recorded changes nothing, so applying the same
sheet twice is the same as once.

manual_grades.csv is the source of truth: it is written first, then the grades go into the
gradebook (one transaction), then the feedback pages of the students whose grades changed are
made again (one ``generate_feedback`` call for all of them, ``default_jobs()`` processes) and
grades.csv once. The course folder is held meanwhile (``course_lock``), as a grading run holds it.
"""

from __future__ import annotations

import argparse
import csv
import difflib
import io
import json
import math
import sys
from dataclasses import dataclass
from pathlib import Path

from .course import ASSIGNMENT, COURSE_DIR, COURSE_ID, course_lock
from .feedback import generate_feedback

FIELDS = ["student_id", "notebook", "grade_id", "score", "comment"]


@dataclass
class Entry:
    """One grade to enter; ``line`` is its line in the sheet (0 on the command line)."""
    student: str
    notebook: str
    grade_id: str
    score: float
    comment: str = ""
    line: int = 0


def set_manual_grade(student: str, notebook: str, grade_id: str, score: float, comment: str = "",
                     course: Path = COURSE_DIR, jobs: int = 1) -> None:
    """Record one grade in manual_grades.csv and in the gradebook, and refresh that student's pages
    and grades.csv; raise ValueError (naming the nearest real ids) if it cannot be entered."""
    entry = Entry(student, notebook.removesuffix(".ipynb"), grade_id, score, comment)
    _graded_course(Path(course))
    with course_lock(Path(course).resolve(), log=_stderr):
        problems = check(Path(course), [entry])
        if problems:
            raise ValueError("; ".join(problems))
        _apply(Path(course), [entry], jobs=jobs, log=_stderr, unchanged_skip=False)


def apply_sheet(sheet: Path, course: Path = COURSE_DIR, jobs: int | None = None, log=print) -> dict:
    """Apply every filled row of the hand-grading sheet ``sheet`` (to_grade.csv) to ``course``.

    Returns {"applied": [Entry], "unchanged": [Entry], "skipped": [line], "students": [touched],
    "feedback_errors": {student: error}}. Raises ValueError with every problem, one per line,
    when any row is wrong; then nothing is written."""
    from .to_grade import read_sheet

    course = Path(course)
    rows, problems = read_sheet(sheet)
    if problems:
        raise ValueError("\n".join(problems))
    entries, skipped = [], []
    for line, row in rows:
        raw = (row.get("score") or "").strip()
        if not raw:
            skipped.append(line)
            if (row.get("comment") or "").strip():
                log(f"line {line}: a comment without a score is not applied (give a score to apply it)")
            continue
        score = _number(raw)
        if score is None:
            problems.append(f"line {line}: score {raw!r} is not a number")
            score = math.nan
        entries.append(Entry(row["student_id"], row["notebook"].removesuffix(".ipynb"), row["grade_id"],
                             score, (row.get("comment") or "").strip(), line))
    _graded_course(course)
    if jobs is None:
        from .schedule import default_jobs
        jobs = default_jobs()
    with course_lock(course.resolve(), log=log):
        problems += check(course, entries, scores_checked=False)
        if problems:
            problems.sort(key=lambda p: int(p.split(":", 1)[0].split()[-1]) if p.startswith("line ") else 0)
            raise ValueError(f"{sheet}: nothing applied, {len(problems)} problem"
                             f"{'s' if len(problems) != 1 else ''}:\n" + "\n".join(problems))
        out = _apply(course, entries, jobs=jobs, log=log)
    out["skipped"] = skipped
    return out


def _graded_course(course: Path) -> None:
    """ValueError unless ``course`` has a gradebook (before its lock, which would make the folder)."""
    if not (course / "gradebook.db").is_file():
        raise ValueError(f"no gradebook in {course}: grade the class first (make grade), or give --course")


def _number(text: str) -> float | None:
    """A score as typed in a spreadsheet: '1', '0.5', '0,5' (a decimal comma); None if not a number."""
    text = text.strip()
    if text.count(",") == 1 and "." not in text:
        text = text.replace(",", ".")
    try:
        x = float(text)
    except ValueError:
        return None
    return x if math.isfinite(x) else None


def check(course: Path, entries: list[Entry], scores_checked: bool = True) -> list[str]:
    """Every problem with ``entries`` against the course's gradebook, in words (empty: all can be
    entered): an unknown student, notebook or grade id (with the nearest real ones), a student with
    no graded submission, a score outside the cell's points, two rows for one cell that disagree."""
    from nbgrader.api import Gradebook, MissingEntry

    db = course / "gradebook.db"
    if not db.is_file():
        return [f"no gradebook in {course}: grade the class first (make grade)"]
    problems, seen = [], {}
    with Gradebook(f"sqlite:///{db}", course_id=COURSE_ID) as gb:
        try:
            assignment = gb.find_assignment(ASSIGNMENT)
        except MissingEntry:
            return [f"the gradebook in {course} has no assignment {ASSIGNMENT!r}: grade the class first"]
        students = {s.id for s in gb.students}
        cells = {nb.name: {c.name: float(c.max_score) for c in [*nb.grade_cells, *nb.task_cells]}
                 for nb in assignment.notebooks}
        for e in entries:
            where = f"line {e.line}: " if e.line else ""
            wrong = []
            if e.student not in students:
                wrong.append(f"no student {e.student!r}{_nearest(e.student, students, 'ids')}")
            if e.notebook not in cells:
                wrong.append(f"no notebook {e.notebook!r}{_nearest(e.notebook, cells, 'notebooks')}")
            elif e.grade_id not in cells[e.notebook]:
                wrong.append(f"no graded cell {e.grade_id!r} in {e.notebook}"
                             f"{_nearest(e.grade_id, cells[e.notebook], 'cells')}")
            if not wrong and e.student in students:
                try:
                    gb.find_grade(e.grade_id, e.notebook, ASSIGNMENT, e.student)
                except MissingEntry:
                    wrong.append(f"student {e.student!r} has no graded submission of {ASSIGNMENT} "
                                 f"(grade the class first)")
            if not math.isfinite(e.score):
                if scores_checked:
                    wrong.append(f"score {e.score!r} is not a number")
            elif e.notebook in cells and e.grade_id in cells[e.notebook]:
                top = cells[e.notebook][e.grade_id]
                if not 0 <= e.score <= top:
                    wrong.append(f"score {e.score:g} is outside 0..{top:g} for {e.grade_id}")
            key = (e.student, e.notebook, e.grade_id)
            if not wrong and key in seen and (seen[key].score, seen[key].comment) != (e.score, e.comment):
                wrong.append(f"{e.student} {e.notebook} {e.grade_id} is also on line {seen[key].line} "
                             f"with another score or comment")
            seen.setdefault(key, e)
            problems += [where + w for w in wrong]
    return problems


def _nearest(name: str, known, what: str) -> str:
    """': the nearest are a, b' (or why there is none), for an unknown ``name``."""
    known = sorted(known)
    if not known:
        return f" (there are no {what} in the gradebook yet)"
    folded = {k.casefold(): k for k in known}
    near = [folded[k] for k in difflib.get_close_matches(name.casefold(), list(folded), n=3, cutoff=0.6)]
    if near:
        return f": the nearest {what} are {', '.join(near)}" if len(near) > 1 else f": did you mean {near[0]}?"
    return f" (nothing close; {len(known)} {what}, e.g. {', '.join(known[:3])})"


def _apply(course: Path, entries: list[Entry], jobs: int, log, unchanged_skip: bool = True) -> dict:
    """Write checked ``entries``: manual_grades.csv once, the gradebook once, then one feedback
    run for the students touched and grades.csv once."""
    from nbgrader.api import Gradebook, MissingEntry

    from .gradebook import export_csv, read_manual
    from .text import write_atomic
    from .to_grade import mark_scheme

    manual = read_manual(course)
    scheme = mark_scheme()
    final = {}                                     # the last row for a cell wins (equal ones, checked)
    for e in entries:
        final[(e.student, e.notebook, e.grade_id)] = e
    applied, unchanged = [], []
    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb:
        grades = {k: gb.find_grade(k[2], k[1], ASSIGNMENT, k[0]) for k in final}
        for key, e in final.items():
            row = manual.get(key)
            same = (row is not None and _number(row.get("score") or "") == e.score
                    and (row.get("comment") or "") == e.comment and grades[key].manual_score == e.score)
            (unchanged if same and unchanged_skip else applied).append(e)
        if not applied:
            return {"applied": [], "unchanged": unchanged, "students": [], "feedback_errors": {}}
        for e in applied:                          # the source of truth first
            manual[(e.student, e.notebook, e.grade_id)] = {
                "student_id": e.student, "notebook": e.notebook, "grade_id": e.grade_id,
                "score": str(float(e.score)), "comment": e.comment}
        buf = io.StringIO()
        w = csv.DictWriter(buf, FIELDS, extrasaction="ignore")
        w.writeheader()
        w.writerows(manual[k] for k in sorted(manual))
        write_atomic(course / "manual_grades.csv", buf.getvalue().encode("utf-8"))
        for e in applied:
            grade = grades[(e.student, e.notebook, e.grade_id)]
            grade.manual_score = e.score
            grade.needs_manual_grade = False
            comment = e.comment
            if e.grade_id in scheme:                # as gradebook.record composes it on every regrade
                comment = comment + (f"\n\nMark scheme: {scheme[e.grade_id]}")
            try:            # a test cell (a tripwire's decision, say) has no comment of its own
                gb.find_comment(e.grade_id, e.notebook, ASSIGNMENT, e.student).manual_comment = comment
            except MissingEntry:
                pass
        gb.db.commit()
    students = sorted({e.student for e in applied})
    # the same pages, exporter and time limit as grading's (feedback.py); a page that cannot be made is said, not silent
    errors = generate_feedback(course, students, jobs=jobs, log=log)
    export_csv(course, course / "grades.csv")
    refresh_returns(course, log=log)
    return {"applied": applied, "unchanged": unchanged, "students": students, "feedback_errors": errors}


def refresh_returns(course: Path, log=print) -> list[Path]:
    """The LMS import file and the feedback packages, made again from the report the last grading
    saved (``lms_feedback``'s report.json), so that hand grades reach them without grading again.
    A tripwire decision now in manual_grades.csv no longer waits. Nothing where no grading saved
    a report (a course graded before this existed: ``make grade`` again does it)."""
    from .gradebook import read_manual
    from .lms_export import write_lms_exports
    from .lms_feedback import REPORT_JSON, RETURN_DIR, write_feedback_return

    saved = course / RETURN_DIR / REPORT_JSON
    if not saved.is_file():
        log(f"note: {saved} does not exist, so the import file and the feedback packages were not made again: "
            f"run make grade again (nothing is regraded)")
        return []
    report = json.loads(saved.read_text(encoding="utf-8"))
    decided = read_manual(course)
    for s, rep in report.items():
        rep["undecided"] = [u for u in rep.get("undecided") or () if (s, u[0], u[1]) not in decided]
    return write_lms_exports(course, report, log=log) + write_feedback_return(course, report, log=log)


def _stderr(line: str) -> None:
    print(line, file=sys.stderr)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("student", nargs="?")
    p.add_argument("notebook", nargs="?", help="e.g. 04_imagination_gap")
    p.add_argument("grade_id", nargs="?", help="e.g. ex1_sentence")
    p.add_argument("score", nargs="?", type=float)
    p.add_argument("--comment", default="")
    p.add_argument("--from-csv", type=Path, metavar="TO_GRADE_CSV",
                   help="apply every row of this sheet whose score is filled (to_grade.csv)")
    p.add_argument("--jobs", type=int, default=None, help="feedback processes at once (default: one per core)")
    p.add_argument("--course", type=Path, default=COURSE_DIR, help="the graded course folder (default: course/)")
    args = p.parse_args(argv)
    if args.from_csv is not None:
        if args.student is not None:
            p.error("give either --from-csv or STUDENT NOTEBOOK GRADE_ID SCORE, not both")
        try:
            out = apply_sheet(args.from_csv, args.course, jobs=args.jobs, log=_stderr)
        except ValueError as e:
            print(f"manual_grade: {e}", file=sys.stderr)
            return 2
        print(f"{len(out['applied'])} grade{'s' if len(out['applied']) != 1 else ''} applied for "
              f"{len(out['students'])} student{'s' if len(out['students']) != 1 else ''} (kept in "
              f"manual_grades.csv); {len(out['unchanged'])} unchanged; {len(out['skipped'])} rows without "
              f"a score skipped")
        if out["feedback_errors"]:
            print(f"feedback pages not made for: {', '.join(sorted(out['feedback_errors']))} "
                  f"(their grades are recorded)", file=sys.stderr)
        return 0
    if args.score is None:
        p.error("give STUDENT NOTEBOOK GRADE_ID SCORE, or --from-csv TO_GRADE_CSV")
    try:
        set_manual_grade(args.student, args.notebook, args.grade_id, args.score, args.comment, args.course,
                         jobs=args.jobs or 1)
    except ValueError as e:
        p.error(str(e))
    print(f"{args.student} {args.notebook} {args.grade_id}: {args.score} (kept in manual_grades.csv)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
