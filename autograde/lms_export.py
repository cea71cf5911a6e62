"""Grades an LMS imports as they are: ``canvas_import.csv`` and ``moodle_import.csv`` next to grades.csv.

    from autograde.lms_export import write_lms_exports
    paths = write_lms_exports(course, report)     # at the end of grade_class, after export(...)

``grades.csv`` is nbgrader's own export (one row per student and assignment, nbgrader's columns):
no LMS imports it unchanged. This module writes, from the same sqlite gradebook, one file in the
layout each LMS documents for a bulk grade import, and ``lms_export_notes.txt``, which names every
student who is NOT in a file and why (no identifier the LMS can match, hand-graded answers not
graded yet, two students claiming one identifier). Nobody is dropped silently and no identifier
is guessed: a student is in a file only under an identifier the LMS itself gave (``report[s]["lms"]``,
filled by intake from the LMS's download) or that course.yaml declares (``student_ids_are``).

What each LMS documents, and what was read to decide the layouts
-----------------------------------------------------------------

Each LMS's import file, with the documents and source read to decide its layout, is in the
docstring of its plug-in: ``autograde/lms/canvas.py`` (Gradebook > Import, a CSV) and
``autograde/lms/moodle.py`` (the assignment's offline grading worksheet, or the gradebook's CSV
import); ``autograde/lms/blackboard.py`` says why Blackboard gets none. This module holds what is
the same for all of them: the settings, the scores read from the gradebook, the notes file.

Others: nbgrader itself has no LMS export (https://github.com/jupyter/nbgrader/issues/530, "LTI/
Canvas Integration", open since 2016; IllumiDesk's Canvas exporter plugin request,
https://github.com/IllumiChat/illumidesk/issues/583). otter-grader's ``otter grade`` writes one
``final_grades.csv`` of per-question scores keyed by file name (its ``otter/grade`` docstring), no
LMS layout either.

Inferred where the documents are silent (and checked against the sources the plug-ins cite):

* Encoding: UTF-8 with a byte-order mark, so spreadsheet programs show non-ASCII names; Moodle
  strips the mark, Canvas's importer matches the header with ``include?("Student")``, which the
  mark does not disturb; the first field is therefore never quoted (a quote after the mark would
  be malformed CSV to Ruby). Line ends CRLF (RFC 4180); both importers accept them.
* Numbers: points with ``.`` and at most 2 decimals (Canvas shows and compares 2), no thousands
  separator, scaled to ``lms.points_possible`` when that is set.
* Pending hand-graded points. Both LMSs treat a blank score as "no grade" and erase a grade they
  hold (above), and both leave a student who is not in the file untouched. So a student with any
  hand-graded answer still ungraded is NOT written into either file: the LMS keeps whatever it has,
  and the notes file lists the student with the answers that wait and the points so far. A student
  is written once every hand-graded answer has a grade (``manual_grades.csv``, re-applied by the
  next ``make grade``); an unanswered one is graded 0 by nbgrader itself ("No response") and is not
  pending. Never is a pending answer counted as 0.
* Names are information only (both LMSs match on the identifier); control characters are removed
  and a name starting with ``= + - @`` gets a leading ``'`` against spreadsheet formulas.
* A Canvas user id or Moodle participant number must be digits (Canvas turns anything else into
  0 and falls back to matching by name); an anonymous Canvas id (``anon_<id>``, what the download
  of an anonymously graded assignment carries) is no user id and is left out with that reason;
  two students claiming one identifier are both left out.

What a pending answer is, read from the gradebook (nbgrader's sqlite database, ``nbgrader.api``):
a grade of a hand-graded cell (a markdown grade cell, a grade cell that is also a solution cell,
or a task cell) with neither a manual nor an automatic score, in a notebook that was graded.
nbgrader's ``determine_grade`` scores an answer cell left as released 0 ("No response") and leaves
an answered one without a score for a person; ``gradebook.record`` copies those automatic scores,
sets the task cells (completion points) and re-applies ``manual_grades.csv``; ``manual_grade.py``
sets ``manual_score``. (``needs_manual_grade`` is not used: ``record`` copies scores without it, so
it stays True on an unanswered cell.) A notebook never graded at all (not handed in, or not
readable) keeps the blank rows nbgrader made for it: it scores 0, as in grades.csv, and the notes
say so.
"""

from __future__ import annotations

from dataclasses import replace
from datetime import datetime, timezone
from pathlib import Path

from .course import ASSIGNMENT, COURSE, COURSE_ID
from .lms import PLUGINS, TITLE
from .lms.base import SheetJob, Standing, lms_record, student_label
from .lms.canvas import IMPORT_FILE as CANVAS_FILE  # noqa: F401  (a public name, moved)
from .lms.moodle import IMPORT_FILE as MOODLE_FILE  # noqa: F401  (a public name, moved)
from .text import count, num, write_atomic, write_csv

NOTES_FILE = "lms_export_notes.txt"

DEFAULTS = {
    "points_possible": None,
    **{lms.name: lms.settings({})[0] for lms in PLUGINS if lms.import_file},
}


# ---------------------------------------------------------------- course.yaml's lms: section ----

def lms_settings(raw: dict | None = None) -> tuple[dict, list[str]]:
    """course.yaml's ``lms:`` section (or ``raw``) over the defaults, and what in it is unusable.

    Returns (settings, warnings); an unusable value is replaced by its default and named in a
    warning, so the files are still written. Each LMS with an import file checks its own section
    (``Lms.settings``)."""
    raw = COURSE.get("lms") if raw is None else raw
    raw = raw if isinstance(raw, dict) else {}
    warnings = []
    out = {"points_possible": raw.get("points_possible")}
    pp = out["points_possible"]
    if pp is not None:
        try:
            pp = float(pp)
        except (TypeError, ValueError):
            pp = None
        if pp is None or not pp > 0 or pp != pp or pp == float("inf"):
            warnings.append(f"lms.points_possible {raw.get('points_possible')!r} is not a positive number: "
                            f"the notebooks' own total is used")
            pp = None
        out["points_possible"] = pp
    for lms in PLUGINS:
        if lms.import_file:
            out[lms.name], said = lms.settings(_mapping(raw.get(lms.name)))
            warnings += said
    return out, warnings


# ------------------------------------------------------------------ what the gradebook holds ----

def read_standings(course: Path, report: dict) -> tuple[dict[str, Standing], float | None]:
    """({student: Standing}, the assignment's total) from ``course``'s gradebook, for ``report``'s
    students; (empty, None) when the course has no gradebook."""
    db = Path(course) / "gradebook.db"
    if not db.is_file():
        return {}, None
    from nbgrader.api import Gradebook, MissingEntry, TaskCell

    standings = {}
    with Gradebook(f"sqlite:///{db}", course_id=COURSE_ID) as gb:
        try:
            assignment = gb.find_assignment(ASSIGNMENT)
        except MissingEntry:
            return {}, None
        total = float(assignment.max_score)
        solutions = {nb.name: {c.name for c in nb.solution_cells} for nb in assignment.notebooks}
        for student in report:
            failed = (report[student] or {}).get("failed") or {}
            try:
                sub = gb.find_submission(ASSIGNMENT, student)
            except MissingEntry:
                standings[student] = Standing(0.0, total, notes=[
                    "no notebook of theirs could be graded (report.csv says why): 0 points, as in grades.csv"])
                continue
            st = Standing(0.0, total)
            undecided = {(nb, g) for nb, g, _ in (report[student] or {}).get("undecided") or ()}
            for nb in sorted(sub.notebooks, key=lambda n: n.name):
                grades = list(nb.grades)
                if not grades:             # a notebook with no graded cell (01_world_model): nothing to say
                    continue
                touched = any(g.auto_score is not None or g.manual_score is not None or not g.needs_manual_grade
                              for g in grades)
                if not touched and f"{nb.name}.ipynb" not in failed:
                    worth = sum(float(g.max_score) for g in grades)
                    st.notes.append(f"{nb.name} was not graded (not handed in, or not readable): "
                                    f"0 of its {num(worth)} points, as in grades.csv")
                    continue
                for g in sorted(grades, key=lambda g: g.name):
                    by_hand = (isinstance(g.cell, TaskCell) or g.cell.cell_type == "markdown"
                               or g.name in solutions.get(nb.name, ()))
                    if by_hand and g.manual_score is None and g.auto_score is None:
                        st.pending.append((nb.name, g.name, float(g.max_score)))
                        continue
                    if (nb.name, g.name) in undecided:     # the tripwire: the instructor decides first
                        st.pending.append((nb.name, g.name, float(g.max_score)))
                        continue
                    if g.manual_score is None and g.auto_score is None:
                        st.notes.append(f"{nb.name} {g.name}: no result (its notebook did not finish): "
                                        f"0 of {num(float(g.max_score))}, as in grades.csv")
                    st.points += float(g.score)
            standings[student] = st
    return standings, total


# ------------------------------------------------------------------------- the export itself ----

def write_lms_exports(course: Path, report: dict, *, settings: dict | None = None, log=print,
                      now: datetime | None = None) -> list[Path]:
    """Write canvas_import.csv, moodle_import.csv and lms_export_notes.txt into ``course``.

    ``report``: grade_class's per-student dict; ``report[s]["lms"]`` is None/absent or
    ``{"system", "name", "ids", "late", "submitted_at", "attempt"}``. ``settings``: an ``lms:``
    mapping to use instead of course.yaml's. Returns the paths written.

    An import file is written only for an LMS it can serve (:func:`systems_served`): the LMS the
    download came from, or one whose ``student_ids_are`` in course.yaml says what the ids of a
    generic download are. Another LMS's file left by an earlier run in the same course folder is
    removed (it would hold another class's scores); the notes file says which files were written,
    which were not and why."""
    course = Path(course)
    cfg, warnings = lms_settings(settings)
    now = now or datetime.now(timezone.utc)
    standings, total = read_standings(course, report)
    if total is None:
        warnings.append(f"no gradebook with assignment {ASSIGNMENT!r} in {course}: no scores to export")
    lms_max = cfg["points_possible"] or total
    scale = (lms_max / total) if (total and lms_max) else 1.0

    def lms_points(st: Standing) -> str:
        return num(st.points * scale)

    served = systems_served(report, cfg)
    job = SheetJob(report, standings, {}, lms_max, lms_points, now, ASSIGNMENT, lambda s: TITLE.get(s, s))
    sheets = [lms.import_sheet(replace(job, settings=cfg[lms.name]))
              for lms in PLUGINS if lms.import_file and lms.name in served]
    paths = []
    for sheet in sheets:
        paths.append(course / sheet.file)
        write_csv(paths[-1], sheet.header, [*sheet.lead, *(r for _, r in sheet.rows)])
    for lms in PLUGINS:
        if lms.import_file and lms.name not in served:
            if (course / lms.import_file).is_file():
                (course / lms.import_file).unlink()
                warnings.append(f"removed {lms.import_file}, left by an earlier grading in this course folder: this "
                                f"download is not {lms.title}'s")
    if not sheets:
        warnings.append("no import file written: the download is in no LMS's own layout (Canvas, Moodle, Blackboard) "
                        "and course.yaml's lms.canvas.student_ids_are / lms.moodle.student_ids_are do not say "
                        "what its student ids are")
    for lms in PLUGINS:
        if lms.no_import and lms.name in served:
            warnings.append(lms.no_import)
    notes = _notes(report, standings, total, lms_max, warnings, sheets, now, course)
    paths.append(course / NOTES_FILE)
    write_atomic(paths[-1], notes.encode("utf-8"))
    for line in warnings:
        log(f"WARNING: lms export: {line}")
    for sheet in sheets:
        left = len(sheet.pending) + sum(map(len, sheet.missing.values())) + sum(len(s) for s, _ in sheet.conflicts)
        waiting = f", {len(sheet.pending)} of them waiting for hand-graded answers" if sheet.pending else ""
        log(f"{sheet.file}: {count(len(sheet.rows))}" +
            (f"; {left} not in it{waiting}: see {NOTES_FILE}" if left else ""))
    return paths


def systems_served(report: dict, cfg: dict) -> set[str]:
    """The LMSs an import file can serve: those of the students' own records (the download's
    layout), and Canvas or Moodle where course.yaml says what a generic download's ids are."""
    served = {lms["system"] for lms in map(lms_record, report.values()) if lms}
    for lms in PLUGINS:
        if lms.import_file and cfg[lms.name].get("student_ids_are"):
            served.add(lms.name)
    return served


# ------------------------------------------------------------------------------ the notes file ----

def _notes(report, standings, total, lms_max, warnings, sheets, now, course) -> str:
    out = [f"LMS import files for assignment {ASSIGNMENT} ({course}), written "
           f"{now.astimezone(timezone.utc).replace(microsecond=0).isoformat()}",
           f"Scores: {num(total) if total else '?'} points in the notebooks" +
           (f", written out of {num(lms_max)} (lms.points_possible): set the LMS assignment to that maximum"
            if total and lms_max != total else
            ": set the LMS assignment's points (Canvas) or maximum grade (Moodle) to the same number"),
           "A student is in a file only when every hand-graded answer has a grade; the LMS keeps what it has "
           "for everyone not in the file (a blank cell would erase it in both LMSs)."]
    if warnings:
        out += ["", "Settings (course.yaml, lms:):", *[f"  {w}" for w in warnings]]
    for sheet in sheets:
        out += ["", f"== {sheet.file}: {count(len(sheet.rows))} ==", *[f"  {i}" for i in sheet.info]]
        if sheet.pending:
            out.append(f"  Not exported yet, hand-graded answers to grade ({len(sheet.pending)}):")
            out += [f"    {_pending_line(s, report, standings[s], total)}" for s in sheet.pending]
        if sheet.conflicts:
            out.append(f"  Not exported, one identifier claimed twice ({sum(len(s) for s, _ in sheet.conflicts)}):")
            out += [f"    {why}" for _, why in sheet.conflicts]
        if sheet.missing:
            out.append(f"  Not exported, no identifier this file can use "
                       f"({sum(map(len, sheet.missing.values()))}):")
            for why, students in sorted(sheet.missing.items()):
                out.append(f"    {why} ({len(students)}): {', '.join(students)}")
        remarks = [(s, n) for s, _ in sheet.rows for n in standings[s].notes]
        if remarks:
            out.append("  About scores in the file:")
            out += [f"    {s}: {n}" for s, n in remarks]
    late = [s for s in sorted(report) if (lms_record(report[s]) or {}).get("late")]
    if late:
        out += ["", "Late hand-ins, as the LMS marked them (scores are exported without any penalty):"]
        for s in late:
            lms = lms_record(report[s])
            when = f", submitted {lms['submitted_at']}" if lms.get("submitted_at") else ""
            att = f", attempt {lms['attempt']}" if lms.get("attempt") is not None else ""
            out.append(f"  {s} ({student_label(report[s], s)}){when}{att}")
    out += ["", "To export a student who waits: python -m autograde.manual_grade STUDENT NOTEBOOK GRADE_ID SCORE "
            "for each answer named above, then run make grade again (unchanged students are not regraded; "
            "manual grades are re-applied) and upload the new file."]
    return "\n".join(out) + "\n"


def _pending_line(s, report, st: Standing, total) -> str:
    cells = "; ".join(f"{nb} {g} ({num(m)} point{'s' if m != 1 else ''})" for nb, g, m in st.pending)
    extra = f"; also: {'; '.join(st.notes)}" if st.notes else ""
    return (f"{s} ({student_label(report[s], s)}): not graded yet: {cells}. So far {num(st.points)} of "
            f"{num(total or 0)} points, {num(st.pending_points)} still to grade{extra}")


# -------------------------------------------------------------------------------------- helpers ----

def _mapping(value) -> dict:
    return value if isinstance(value, dict) else {}
