"""Enter a manual grade headless; it is kept in manual_grades.csv and survives every regrade.

    python -m autograde.manual_grade STUDENT NOTEBOOK GRADE_ID SCORE [--comment "..."]

e.g. ``python -m autograde.manual_grade s042 04_imagination_gap ex1_sentence 1 --comment "Clear."``
The CSV is the source of truth; this also writes the grade into the gradebook now and refreshes
the student's feedback and grades.csv.
"""

from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path

from .course import ASSIGNMENT, COURSE_ID, HERE, nbgrader
from .feedback import generate_feedback

FIELDS = ["student_id", "notebook", "grade_id", "score", "comment"]


def set_manual_grade(student: str, notebook: str, grade_id: str, score: float, comment: str = "",
                     course: Path = HERE) -> None:
    """Record the grade in manual_grades.csv and in the gradebook; raise ValueError if unknown."""
    from nbgrader.api import Gradebook, MissingEntry

    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb:
        try:
            grade = gb.find_grade(grade_id, notebook, ASSIGNMENT, student)
        except MissingEntry:
            raise ValueError(f"no graded cell {grade_id!r} in {notebook} for student {student!r}: "
                             f"check the names (and that the class has been graded)") from None
        if not 0 <= score <= grade.max_score:
            raise ValueError(f"score must be between 0 and {grade.max_score} for {grade_id}")
        grade.manual_score = score
        try:            # a test cell (a tripwire's decision, say) has no comment of its own
            gb.find_comment(grade_id, notebook, ASSIGNMENT, student).manual_comment = comment
        except MissingEntry:
            pass
        gb.db.commit()
    path = course / "manual_grades.csv"
    rows = list(csv.DictReader(open(path, newline=""))) if path.exists() else []
    rows = [r for r in rows if (r["student_id"], r["notebook"], r["grade_id"]) != (student, notebook, grade_id)]
    rows.append({"student_id": student, "notebook": notebook, "grade_id": grade_id,
                 "score": score, "comment": comment})
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, FIELDS)
        w.writeheader()
        w.writerows(sorted(rows, key=lambda r: (r["student_id"], r["notebook"], r["grade_id"])))
    # the same pages, exporter and time limit as grading's (feedback.py); a page that cannot be made is said, not silent
    generate_feedback(course, [student], jobs=1, log=lambda line: print(line, file=sys.stderr))
    nbgrader(course, "export", f"--to={course / 'grades.csv'}")


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("student")
    p.add_argument("notebook", help="e.g. 04_imagination_gap")
    p.add_argument("grade_id", help="e.g. ex1_sentence")
    p.add_argument("score", type=float)
    p.add_argument("--comment", default="")
    p.add_argument("--course", type=Path, default=HERE)
    args = p.parse_args(argv)
    try:
        set_manual_grade(args.student, args.notebook.removesuffix(".ipynb"), args.grade_id, args.score,
                         args.comment, args.course)
    except ValueError as e:
        p.error(str(e))
    print(f"{args.student} {args.notebook} {args.grade_id}: {args.score} (kept in manual_grades.csv)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
