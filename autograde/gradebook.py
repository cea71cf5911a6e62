"""The course's gradebook: every student's scores written into it (by this process alone), manual grades
re-applied, and its exports, ``grades.csv`` and ``report.csv``."""

from __future__ import annotations

import csv
import warnings
from pathlib import Path

import yaml

from . import checks
from .course import ASSIGNMENT, COURSE_ID, HERE


def export_csv(course: Path, filename: Path) -> None:
    """``nbgrader export`` (its CSV plugin) of the course gradebook into ``filename``, in this process."""
    from nbgrader.api import Gradebook
    from nbgrader.plugins import CsvExportPlugin
    from traitlets.config import Config

    config = Config()
    config.CsvExportPlugin.to = str(filename)      # the plugin's destination trait is `to`
    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb:
        CsvExportPlugin(config=config).export(gb)


def record(course: Path, report: dict, results: dict) -> None:
    """Write every student's scores into the course gradebook (this process is its only writer)."""
    from nbgrader.api import Gradebook, MissingEntry

    scheme = yaml.safe_load((HERE / "mark_scheme.yaml").read_text()) if (HERE / "mark_scheme.yaml").exists() else {}
    manual = read_manual(course)
    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb:
        for student, rep in report.items():
            res = results.get(student, {})
            if not res:
                continue
            with warnings.catch_warnings():
                # nbgrader's add_submission builds its rows before adding them to the session, which
                # SQLAlchemy 2 reports once per process ("Object of type <SubmittedAssignment> not in
                # session"); the rows are added right after, so it is noise on the instructor's screen
                warnings.filterwarnings("ignore", message=r"Object of type <\w+> not in session")
                # when the student handed in, as the download says (grade.submitted_at); nbgrader's own
                # default, the grading time, where it says nothing
                when = rep.get("submitted_at")
                gb.add_submission(ASSIGNMENT, student, **({"timestamp": when} if when else {}))
            for name, entry in res.items():
                nb_id = name[:-len(".ipynb")]
                if entry.get("note"):
                    rep["notes"].append(f"{name}: {entry['note']}")
                if not entry["ok"]:
                    rep["failed"][name] = entry["error"]
                    rep["notes"].append(f"{name}: nbgrader could not finish this notebook ({entry['error']}); "
                                        f"points from the tests that had already run are kept")
                sub = gb.find_submission_notebook(nb_id, ASSIGNMENT, student)
                for grade in sub.grades:
                    g = grade.name
                    comment = None
                    if g in entry["scores"] and entry["scores"][g] is not None:
                        grade.auto_score = entry["scores"][g]
                    if g in entry["verdicts"]:
                        v = entry["verdicts"][g]
                        found = rep["delegated"].get(g)
                        if found:
                            v = vars(checks.judge(checks.TESTS[g], "", delegation=found))
                        grade.manual_score = grade.max_score if v["passed"] else 0.0
                        grade.needs_manual_grade = False
                        message = v["message"]
                        if v.get("tripwire") and not found:
                            decided = (student, nb_id, g) in manual
                            message += f" NOTE: {v['tripwire']}" if not decided else \
                                " NOTE: the grader could not run your function again; your instructor looked at it."
                            if not decided:          # the instructor's call (manual_grade), not a silent 0
                                rep.setdefault("tripwires", []).append(f"{nb_id} {g}: {v['tripwire']}")
                                rep.setdefault("undecided", []).append((nb_id, g, float(grade.max_score)))
                                rep["notes"].append(f"NEEDS A HUMAN: {nb_id} {g}: {v['tripwire']} (manual_grade "
                                                    f"{student} {nb_id} {g} SCORE decides it)")
                        rep["verdicts"][g] = (grade.manual_score, grade.max_score, message)
                    ex = g[:-len("_order")] if g.endswith("_order") else None
                    if ex in rep["completion"]:
                        ok, why = rep["completion"][ex]
                        grade.manual_score = grade.max_score if ok else 0.0
                        grade.needs_manual_grade = False
                        comment = why
                    elif g in scheme:
                        comment = f"Mark scheme: {scheme[g]}"
                    row = manual.get((student, nb_id, g))
                    if row:
                        try:
                            score = float(row["score"])
                        except ValueError:
                            score = float("nan")
                        if 0 <= score <= grade.max_score:
                            grade.manual_score = score
                            grade.needs_manual_grade = False
                            if g in rep["verdicts"]:        # the instructor's decision is the score shown
                                rep["verdicts"][g] = (score,) + tuple(rep["verdicts"][g][1:])
                            comment = (row.get("comment") or "") + (f"\n\n{comment}" if comment else "")
                        else:
                            rep["notes"].append(f"manual grade {row['score']!r} for {nb_id} {g} refused: "
                                                f"outside 0..{grade.max_score}")
                    if comment is not None:
                        try:
                            gb.find_comment(g, nb_id, ASSIGNMENT, student).manual_comment = comment
                        except MissingEntry:
                            pass
            gb.db.commit()


def clear_submissions(course: Path, report: dict) -> None:
    """Every student of ``report`` in the gradebook, with their name (``report[s]["name"]``: grades.csv's
    last_name, the whole name as the LMS wrote it, fit for a spreadsheet) and no submission, so that
    :func:`record` writes each afresh."""
    from nbgrader.api import Gradebook

    from .text import spreadsheet_text

    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb:
        for s, rep in report.items():
            name = (rep or {}).get("name")
            gb.update_or_create_student(s, last_name=spreadsheet_text(name) if name else None)
            try:
                gb.remove_submission(ASSIGNMENT, s)
            except Exception:  # noqa: BLE001  nbgrader's MissingEntry, or a half-made row: nothing to remove
                pass
        gb.db.commit()


def read_manual(course: Path) -> dict:
    manual = {}
    if (course / "manual_grades.csv").exists():
        with open(course / "manual_grades.csv", newline="") as f:
            for row in csv.DictReader(f):
                manual[(row["student_id"], row["notebook"], row["grade_id"])] = row
    return manual


def export(course: Path, report: dict, rejected: list[str] = (), held: list = ()) -> None:
    """grades.csv (nbgrader's export of the gradebook) and report.csv (what happened to each file).
    ``held``: the run's guarantees (``guarantees.of_run``), written first, one row each, under the
    student_id ``guarantees.RUN_ROW``."""
    export_csv(course, course / "grades.csv")
    from nbgrader.api import Gradebook, MissingEntry

    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb, \
            open(course / "report.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["student_id", "score", "max_score", "notes"])
        if held:
            from .guarantees import csv_rows
            w.writerows(csv_rows(held))
        for student in sorted(report):
            try:
                sub = gb.find_submission(ASSIGNMENT, student)
                score, max_score = sub.score, sub.max_score
            except MissingEntry:
                score, max_score = 0.0, gb.find_assignment(ASSIGNMENT).max_score
            rep = report[student]
            notes = rep["notes"] + [why for _, why in rep["completion"].values()]
            notes += [f"{g}: {s:g}/{m:g}: {msg}" for g, (s, m, msg) in sorted(rep["verdicts"].items())]
            w.writerow([student, round(score, 3), round(max_score, 3), " | ".join(notes)])
        for line in rejected:          # files that could not be placed to any student
            w.writerow(["(not graded)", "", "", line])
