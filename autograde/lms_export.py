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

Canvas, Gradebook > Import (a CSV):

* Guides: "How do I import grades in the Gradebook?" (Instructure's Instructor Guide,
  https://community.canvaslms.com/t5/Instructor-Guide/How-do-I-import-grades-in-the-Gradebook/ta-p/807;
  its text was not in the stored corpus, so its content was not read) and two universities'
  copies of its rules that were: https://teaching.resources.osu.edu/toolsets/carmencanvas/guides/calculating-final-grades/import-csv-file-carmen-grades
  (required columns: Student name OR Student ID OR SIS User ID; SIS Login ID; Section; one column
  per assignment; "If a score already exists ... the uploaded grade ... will overwrite" it; a
  column that names no assignment creates a new one) and
  https://ts.vcu.edu/askit/teaching-and-learning/canvas/faculty/grading-faculty/gradebook-action-menu-faculty/
  (read-only total columns are ignored on import).
* Canvas's source, which is the format's only exact statement:
  ``lib/gradebook_exporter.rb`` (https://github.com/instructure/canvas-lms/blob/master/lib/gradebook_exporter.rb):
  header ``Student, ID, [SIS User ID], SIS Login ID, [Integration ID], [Root Account], Section``,
  then one column per assignment titled ``Title (assignment_id)``; second row ``"    Points Possible"``
  with the assignments' points; numbers with at most 2 decimals; UTF-8, comma, a byte-order mark
  when the user's "include BOM" feature is on (``lib/csv_with_i18n.rb``); a name starting with
  ``=`` is written as ``="name"`` against spreadsheet formulas.
  ``lib/gradebook_importer.rb`` (https://github.com/instructure/canvas-lms/blob/master/lib/gradebook_importer.rb):
  the header must start with a cell containing "Student" and one containing "ID", the student
  columns must end with "Section", an SIS User ID column must be followed by SIS Login ID; a
  student is found by ID (Canvas user id), else SIS User ID, else SIS Login ID, else by name,
  else reported as unknown; an assignment column by the id in ``(…)``, else by exact title, else
  it becomes a NEW assignment; a row whose first cell contains "Points Possible" is not a student
  (it sets the points of a new assignment); ``;`` or ``,`` separators; decimal commas accepted;
  a blank or ``-`` cell is "no score".
  ``ui/features/gradebook_uploads/jquery/process_gradebook_upload.js``: a cell whose value differs
  from Canvas's current score is posted as that student's grade, so a BLANK cell where Canvas
  already has a score ERASES it; only a student absent from the file is left untouched.

Moodle, two documented ways in:

* Gradebook > Import > CSV file (https://docs.moodle.org/311/en/Grade_import, same text on the
  4.x page https://docs.moodle.org/405/en/Grade_import): the file is the CSV export's format;
  on the preview page "Map from" picks the identifier column and "Map to" the user field
  (userid, username, useridnumber = ID number, useremail; email is case-sensitive), and each
  other column is mapped to a grade item, a new item, feedback or "Ignore"; encoding and
  separator are chosen on upload. Source ``grade/import/csv/classes/load_data.php``
  (https://github.com/moodle/moodle/blob/main/grade/import/csv/classes/load_data.php): a user value
  that matches nobody aborts the whole import; a row with a blank identifier is not rejected but
  keeps the previous row's user (the user is not reset between rows), so no row here ever lacks
  its identifier; a grade cell
  ``''`` or ``'-'`` becomes "no grade" and ``update_final_grade`` then stores NULL and marks the
  grade overridden (``lib/grade/grade_item.php``), i.e. a blank ERASES an existing grade;
  decimal separators are unformatted with ``unformat_float``; grades above 100 need the site's
  ``unlimitedgrades``. ``lib/csvlib.class.php`` converts from the chosen encoding, strips a UTF-8
  byte-order mark and accepts CRLF, CR or LF.
* The assignment's "Offline grading worksheet" (Assignment settings > Feedback types; then
  View all submissions > Grading action > Upload grading worksheet; https://docs.moodle.org/401/en/Assignment_settings).
  Source ``mod/assign/feedback/offline/importgradeslib.php`` and ``locallib.php``: columns are
  found by their titles ``Identifier``, ``Grade`` and ``Last modified (grade)``, all three
  required, in any order, compared with the strings of the uploading user's language (English here:
  "Identifierare" in Swedish, so a teacher whose Moodle is not in English switches it to English for
  the upload, inferred from ``get_string`` and the language packs); ``Identifier`` is ``Participant <n>``; a row whose grade is blank
  is SKIPPED (nothing changes), as is one above the assignment's maximum grade, and one whose
  grade Moodle changed more than 60 s after "Last modified (grade)" (unless the instructor ticks
  "Allow updating records that have been modified more recently in Moodle than in the
  spreadsheet"). <n> is the number Moodle puts in each download folder name
  (``mod/assign/classes/downloader.php``: ``fullname . '_' . get_uniqueid_for_user(userid)``),
  a per-assignment participant number from ``assign_user_mapping``, NOT the user id: written into
  a gradebook import mapped to "userid" it would grade whichever user has that id. So a Moodle
  download's students can only go back through the worksheet, and that is this module's default
  (``lms.moodle.identifier: participant``); the gradebook layout is written when course.yaml
  names a user field and the ids are known to be that field.

Others: nbgrader itself has no LMS export (https://github.com/jupyter/nbgrader/issues/530, "LTI/
Canvas Integration", open since 2016; IllumiDesk's Canvas exporter plugin request,
https://github.com/IllumiChat/illumidesk/issues/583). otter-grader's ``otter grade`` writes one
``final_grades.csv`` of per-question scores keyed by file name (its ``otter/grade`` docstring), no
LMS layout either.

Inferred where the documents are silent (and checked against the sources above):

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

from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path

from .course import ASSIGNMENT, COURSE, COURSE_ID
from .lms_layouts import TITLE
from .text import clean_text, count, digits, ident, num, spreadsheet_text, write_atomic, write_csv

CANVAS_FILE = "canvas_import.csv"
MOODLE_FILE = "moodle_import.csv"
NOTES_FILE = "lms_export_notes.txt"

# Canvas's student columns, in the order its exporter writes them (Integration ID and Root Account
# only exist where an account turns them on; the importer does not need them).
CANVAS_STUDENT_COLUMNS = ["Student", "ID", "SIS User ID", "SIS Login ID", "Section"]
CANVAS_POINTS_ROW = "    Points Possible"            # the exporter's first cell, spaces included
CANVAS_SIS = {"sis_user_id": "SIS User ID", "sis_login_id": "SIS Login ID"}

# Moodle's offline grading worksheet: the three columns its importer looks for by title (plus two
# it ignores, for the instructor's eyes), and the gradebook import's user fields ("Map to").
MOODLE_WORKSHEET_COLUMNS = ["Identifier", "Full name", "Grade", "Maximum grade", "Last modified (grade)"]
MOODLE_PARTICIPANT = "Participant "
MOODLE_USER_FIELDS = {"username": "Username", "useridnumber": "ID number", "useremail": "Email address",
                      "userid": "User ID"}
MOODLE_IDENTIFIERS = ("participant", *MOODLE_USER_FIELDS)

DEFAULTS = {
    "points_possible": None,
    "canvas": {"assignment_id": None, "assignment_name": None, "student_ids_are": None},
    "moodle": {"identifier": "participant", "grade_item": None, "student_ids_are": None},
}


# ---------------------------------------------------------------- course.yaml's lms: section ----

def lms_settings(raw: dict | None = None) -> tuple[dict, list[str]]:
    """course.yaml's ``lms:`` section (or ``raw``) over the defaults, and what in it is unusable.

    Returns (settings, warnings); an unusable value is replaced by its default and named in a
    warning, so the files are still written."""
    raw = COURSE.get("lms") if raw is None else raw
    raw = raw if isinstance(raw, dict) else {}
    warnings = []
    out = {"points_possible": raw.get("points_possible"),
           "canvas": {**DEFAULTS["canvas"], **_mapping(raw.get("canvas"))},
           "moodle": {**DEFAULTS["moodle"], **_mapping(raw.get("moodle"))}}
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
    canvas, moodle = out["canvas"], out["moodle"]
    aid = canvas["assignment_id"]
    if aid is not None:
        aid = str(aid).strip()
        if not digits(aid):
            warnings.append(f"lms.canvas.assignment_id {canvas['assignment_id']!r} is not a Canvas assignment id "
                            f"(digits): it is left out of the column title")
            aid = None
    canvas["assignment_id"] = aid
    if canvas["student_ids_are"] not in (None, *CANVAS_SIS):
        warnings.append(f"lms.canvas.student_ids_are {canvas['student_ids_are']!r} is not one of "
                        f"{', '.join(CANVAS_SIS)} (or null): treated as null")
        canvas["student_ids_are"] = None
    if moodle["identifier"] not in MOODLE_IDENTIFIERS:
        warnings.append(f"lms.moodle.identifier {moodle['identifier']!r} is not one of "
                        f"{', '.join(MOODLE_IDENTIFIERS)}: participant is used")
        moodle["identifier"] = "participant"
    if moodle["student_ids_are"] not in (None, *MOODLE_USER_FIELDS):
        warnings.append(f"lms.moodle.student_ids_are {moodle['student_ids_are']!r} is not one of "
                        f"{', '.join(MOODLE_USER_FIELDS)} (or null): treated as null")
        moodle["student_ids_are"] = None
    for part, key in (("canvas", "assignment_name"), ("moodle", "grade_item")):
        v = out[part][key]
        out[part][key] = clean_text(str(v)) if v not in (None, "") else None
    return out, warnings


# ------------------------------------------------------------------ what the gradebook holds ----

@dataclass
class Standing:
    """One student's score as the gradebook has it."""
    points: float                                   # every graded point (pending answers not counted)
    max_points: float                               # the assignment's total
    pending: list[tuple[str, str, float]] = field(default_factory=list)   # (notebook, grade id, max)
    notes: list[str] = field(default_factory=list)  # what the instructor should know about the score

    @property
    def pending_points(self) -> float:
        return sum(m for _, _, m in self.pending)


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

@dataclass
class _Sheet:
    """One import file being assembled."""
    file: str
    header: list[str] = field(default_factory=list)
    lead: list[list[str]] = field(default_factory=list)                # rows before the students'
    rows: list[tuple[str, list[str]]] = field(default_factory=list)   # (student, row)
    pending: list[str] = field(default_factory=list)
    missing: dict[str, list[str]] = field(default_factory=dict)        # reason -> students
    conflicts: list[tuple[list[str], str]] = field(default_factory=list)   # (students, why)
    info: list[str] = field(default_factory=list)


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
    sheets = []
    if "canvas" in served:
        sheets.append(_canvas_sheet(report, standings, cfg, lms_max, lms_points))
    if "moodle" in served:
        sheets.append(_moodle_sheet(report, standings, cfg, lms_max, lms_points, now))
    paths = []
    for sheet in sheets:
        paths.append(course / sheet.file)
        write_csv(paths[-1], sheet.header, [*sheet.lead, *(r for _, r in sheet.rows)])
    for system, file in (("canvas", CANVAS_FILE), ("moodle", MOODLE_FILE)):
        if system not in served:
            if (course / file).is_file():
                (course / file).unlink()
                warnings.append(f"removed {file}, left by an earlier grading in this course folder: this "
                                f"download is not {TITLE[system]}'s")
    if not sheets:
        warnings.append("no import file written: the download is in no LMS's own layout (Canvas, Moodle, Blackboard) "
                        "and course.yaml's lms.canvas.student_ids_are / lms.moodle.student_ids_are do not say "
                        "what its student ids are")
    if "blackboard" in served:
        warnings.append("Blackboard: no import file is written (grades.csv has every score; Blackboard's "
                        "Grade Center takes them by hand or by its own upload)")
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
    for system in ("canvas", "moodle"):
        if cfg[system].get("student_ids_are"):
            served.add(system)
    return served


def _canvas_sheet(report, standings, cfg, lms_max, lms_points) -> _Sheet:
    c = cfg["canvas"]
    title = c["assignment_name"] or ASSIGNMENT
    column = f"{title} ({c['assignment_id']})" if c["assignment_id"] else title
    sheet = _Sheet(CANVAS_FILE, header=[*CANVAS_STUDENT_COLUMNS, column],
                   lead=[[CANVAS_POINTS_ROW, "", "", "", "", num(lms_max) if lms_max else ""]])
    if not c["assignment_id"]:
        sheet.info.append(f"lms.canvas.assignment_id is not set: the column is titled {column!r} without an id, "
                          f"so Canvas matches it by exact title or offers to create a NEW assignment")
    claims = {}
    for s in sorted(report):
        lms = lms_record(report[s])
        key, why = None, None
        if lms and lms["system"] == "canvas":
            uid = ident(lms["ids"].get("user_id"))
            if uid is None:
                why = "the Canvas download gave no Canvas user id"
            elif uid.startswith("anon_"):
                why = ("anonymous grading: Canvas's download names the student only by an anonymous id, "
                       "which its gradebook import cannot match (grade in SpeedGrader, or import after "
                       "anonymity is lifted and the submissions are downloaded again)")
            elif not digits(uid):
                why = f"its Canvas user id {uid!r} is not a number"
            else:
                key = ("ID", uid)
        elif lms:
            why = f"no Canvas user id: the hand-in came from {TITLE.get(lms['system'], lms['system'])}"
        elif c["student_ids_are"]:
            key = (CANVAS_SIS[c["student_ids_are"]], s)
            if "~" in s:
                key, why = None, (f"its student id was renamed by intake to keep two students apart, so it "
                                  f"is no {CANVAS_SIS[c['student_ids_are']]}")
        else:
            why = ("no Canvas identifier: the file name carried only a student id (set "
                   "lms.canvas.student_ids_are if these ids are Canvas SIS ids)")
        if key is None:
            sheet.missing.setdefault(why, []).append(s)
            continue
        claims.setdefault(key, []).append(s)
    _place(sheet, claims, report, standings, lms_points, lambda key, s, name, pts: [
        name, key[1] if key[0] == "ID" else "", key[1] if key[0] == "SIS User ID" else "",
        key[1] if key[0] == "SIS Login ID" else "", "", pts])
    return sheet


def _moodle_sheet(report, standings, cfg, lms_max, lms_points, now) -> _Sheet:
    m = cfg["moodle"]
    user_field = m["identifier"]
    sheet = _Sheet(MOODLE_FILE)
    stamp = now.astimezone(timezone.utc).replace(microsecond=0).isoformat()
    if user_field == "participant":
        sheet.header = list(MOODLE_WORKSHEET_COLUMNS)
        sheet.info.append("the assignment's offline grading worksheet: upload it under the assignment "
                          "(View all submissions > Upload grading worksheet), not in the gradebook, with your "
                          "Moodle language set to English (its column titles are matched in your language)")
    else:
        sheet.header = [MOODLE_USER_FIELDS[user_field], "Full name", m["grade_item"] or ASSIGNMENT]
        sheet.info.append(f"the gradebook's CSV import: map from {MOODLE_USER_FIELDS[user_field]!r} to {user_field}, "
                          f"{sheet.header[2]!r} to the assignment's grade item, 'Full name' to Ignore")
        if lms_max and lms_max > 100:
            sheet.info.append(f"grades above 100 ({num(lms_max)} possible) are refused unless the site allows "
                              f"them (Site administration > Grades > General settings: unlimitedgrades)")
    claims = {}
    for s in sorted(report):
        lms = lms_record(report[s])
        key, why = None, None
        if user_field == "participant":
            if lms and lms["system"] == "moodle":
                pid = ident(lms["ids"].get("participant_id"))
                if pid is None:
                    why = "the Moodle download gave no participant number"
                elif not digits(pid):
                    why = f"its participant number {pid!r} is not a number"
                else:
                    key = ("participant", pid)
            elif lms:
                why = f"no Moodle participant number: the hand-in came from {TITLE.get(lms['system'], lms['system'])}"
            else:
                why = ("no Moodle participant number: the file name carried only a student id (the worksheet "
                       "needs Moodle's own download; or set lms.moodle.identifier to the user field these ids are)")
        else:
            label = MOODLE_USER_FIELDS[user_field]
            if lms and lms["system"] == "moodle":
                value = ident(lms["ids"].get(user_field))
                if value is not None:
                    key = (user_field, value)
                else:
                    why = (f"no Moodle {label}: Moodle's download names a student by participant number, which "
                           f"the gradebook import cannot match (it is not the user id); set "
                           f"lms.moodle.identifier: participant to write the assignment's grading worksheet")
            elif lms:
                why = f"no Moodle {label}: the hand-in came from {TITLE.get(lms['system'], lms['system'])}"
            elif m["student_ids_are"] == user_field:
                key = (user_field, s)
                if "~" in s:
                    key, why = None, (f"its student id was renamed by intake to keep two students apart, so it "
                                      f"is no Moodle {label}")
            else:
                why = (f"no Moodle {label}: the file name carried only a student id (set "
                       f"lms.moodle.student_ids_are: {user_field} if these ids are Moodle {label}s)")
        if key is None:
            sheet.missing.setdefault(why, []).append(s)
            continue
        claims.setdefault(key, []).append(s)
    maximum = num(lms_max) if lms_max else ""
    if user_field == "participant":
        row = lambda key, s, name, pts: [MOODLE_PARTICIPANT + key[1], name, pts, maximum, stamp]   # noqa: E731
    else:
        row = lambda key, s, name, pts: [key[1], name, pts]                                        # noqa: E731
    _place(sheet, claims, report, standings, lms_points, row)
    return sheet


def _place(sheet: _Sheet, claims: dict, report: dict, standings: dict, lms_points, make_row) -> None:
    """Rows for every identifier claimed by exactly one student whose score is final."""
    for key, students in sorted(claims.items(), key=lambda kv: kv[1][0]):
        if len(students) > 1:
            sheet.conflicts.append((students, f"{', '.join(students)}: all claim {key[0]} {key[1]!r}; none is "
                                              f"exported (check in the LMS which hand-in is whose)"))
            continue
        s = students[0]
        st = standings.get(s)
        if st is None:
            sheet.missing.setdefault("no score: the course has no gradebook entry for this student", []).append(s)
            continue
        if st.pending:
            sheet.pending.append(s)
            continue
        sheet.rows.append((s, make_row(key, s, student_label(report[s], s), lms_points(st))))


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

def lms_record(rep) -> dict | None:
    """``rep["lms"]`` when it is a usable identity, else None."""
    lms = (rep or {}).get("lms") if isinstance(rep, dict) else None
    if not isinstance(lms, dict) or not isinstance(lms.get("system"), str):
        return None
    ids = lms.get("ids")
    return {**lms, "ids": ids if isinstance(ids, dict) else {}}


def _mapping(value) -> dict:
    return value if isinstance(value, dict) else {}


def student_label(rep, student: str) -> str:
    """The student's name for a file: the LMS's, else the id; no control characters, no formula."""
    lms = lms_record(rep)
    name = clean_text(str(lms.get("name") or "")) if lms else ""
    return spreadsheet_text(name or student)
