"""Moodle: its download read, its students named, its grading worksheet (or gradebook import) and its feedback zip.

Its download
------------
**Moodle** ("Download all submissions", and the preference "Download submissions in folders",
on by default since Moodle 3.1): ``mod/assign/classes/downloader.php``
(https://github.com/moodle/moodle/blob/main/mod/assign/classes/downloader.php, 2022; before it the
same code was ``assign::download_submissions`` in ``mod/assign/locallib.php``):

* ``get_student_prefix``: the student's full name (``fullname()``; "Participant" under blind
  marking) with every ``_`` replaced by a space, then ``_<unique id for the user>``, through
  ``clean_filename``; the unique id is the assignment's participant id
  (``get_uniqueid_for_user``, kept per assignment in ``assign_user_mapping``, so stable across
  downloads of one assignment);
* in folders: ``<prefix>_assignsubmission_file/<the file's path and name, not renamed>`` (the
  help string, commit 381bb72, MDL-62831: "Each submission is then put in a separate folder, with
  the folder structure kept for any subfolders, and files are not renamed"); Moodle 3.1-4.0
  wrote the folder with a trailing ``_`` (``..._assignsubmission_file_/``);
* not in folders: ``<prefix>_assignsubmission_file_<file name>``; other submission plugins write
  ``assignsubmission_onlinetext`` and so on;
* the zip entries are written with the time of the download (``zip_writer``'s
  ``add_file_from_stored_file`` without a ``time`` option), and only each student's latest
  submission is in it; nothing in a name says late (https://docs.moodle.org/310/en/Assignment_settings:
  after the due date "Submissions are still allowed ... but will be marked as late", in Moodle).
* team submissions are named by the group (``<group name>_<group id>``); read here as if the
  group were a participant.

Inferred where the sources are silent: the name has no ``_`` (Moodle replaced them), so the first
``_<digits>_assignsubmission_`` ends it, whatever the student named their file; several uploads of
one notebook are ordered by their re-upload number (the zip's times are all the download's);
``late``, ``submitted_at`` and ``attempt`` are None.

Its import file
---------------
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

Its feedback package
--------------------
**Moodle** (*Upload multiple feedback files in a zip*). Source
``mod/assign/feedback/file/importziplib.php``
(https://github.com/moodle/moodle/blob/main/mod/assign/feedback/file/importziplib.php),
``is_valid_filename_for_import``: every part of the member's path is split with
``explode('_', $pathpart, 5)``; "Expected format for the directory names in $pathpart is
fullname_userid_plugintype_pluginname (as created by zip export in Moodle >= 4.1) resp.
fullname_userid_plugintype_pluginname_ (as created by earlier versions)"; ``$info[1]`` must be a
participant id (``get_uniqueid_for_user``, the number of the download, kept by intake as
``ids.participant_id``) of a participant of the group shown, ``$info[2]``/``$info[3]`` a plugin
of the assignment (``get_plugin_by_type``), and what follows is the file name; names starting with
``.`` or ``~`` are skipped. Moodle's own test (``tests/importziplib_test.php``) accepts
``'Student Name_' . $studentid . '_assignsubmission_file_My_cool_filename.txt'`` as the file
``My_cool_filename.txt``. A file that differs from the one of that name already there (content
hash, ``is_file_modified``) is stored as the student's feedback file and the student is notified
(``notify_grade_modified``); an unchanged one is skipped. The help string (``lang/en``,
``feedbackzip_help``): "Feedback files will be assigned to students based on the participant id
which should be the second part of each filename immediately after the users full name." So each
member here is ``<full name>_<participant id>_assignsubmission_file_<file>`` (flat: the folder
form's path is joined back with a leading ``/``), with ``<full name>`` Moodle's download name with
``_`` and control characters made spaces (Moodle's ``get_student_prefix`` also turns ``_`` into
spaces, ``downloader.php``), the characters that ``clean_param($name, PARAM_FILE)`` removes
removed (``lib/moodlelib.php``: ``preg_replace('~[[:cntrl:]]|[&<>"`\\|\\':\\\\\\\\/]~u', '', $param)``,
a path separator among them), and no leading ``.``/``~``.
"""

from __future__ import annotations

import re
import unicodedata
from datetime import timezone

from ..text import clean_text, digits, ident, num
from .base import (
    NAME_CHARS,
    Lms,
    LmsFile,
    NotebookParser,
    Sheet,
    SheetJob,
    StudentReturn,
    digits_only,
    lms_record,
    place,
)

IMPORT_FILE = "moodle_import.csv"
FEEDBACK_ZIP = "moodle_feedback_files.zip"

# Moodle's offline grading worksheet: the three columns its importer looks for by title (plus two
# it ignores, for the instructor's eyes), and the gradebook import's user fields ("Map to").
MOODLE_WORKSHEET_COLUMNS = ["Identifier", "Full name", "Grade", "Maximum grade", "Last modified (grade)"]
MOODLE_PARTICIPANT = "Participant "
MOODLE_USER_FIELDS = {"username": "Username", "useridnumber": "ID number", "useremail": "Email address",
                      "userid": "User ID"}
MOODLE_IDENTIFIERS = ("participant", *MOODLE_USER_FIELDS)
DEFAULTS = {"identifier": "participant", "grade_item": None, "student_ids_are": None}

MOODLE_PLUGIN = "assignsubmission_file"
MOODLE_DROPPED = "&<>\"`|':\\/"   # what Moodle's clean_param(PARAM_FILE) removes from a file name


# --- its download ---------------------------------------------------------------------------------
_MOODLE_PREFIX = r"(?P<name>[^_]*)_(?P<pid>\d+)_assignsubmission_(?P<plugin>[a-z0-9]+)"
_MOODLE_FOLDER = re.compile(rf"^{_MOODLE_PREFIX}_?$", re.S)
MOODLE_FLAT = re.compile(rf"^{_MOODLE_PREFIX}_(?P<file>.+)$", re.S)


def _read_moodle(members: list[list[str]], parse_notebook: NotebookParser) -> tuple[list, list[str]]:
    out = []
    for p in members:
        folder = _MOODLE_FOLDER.match(p[0]) if len(p) >= 2 else None
        flat = MOODLE_FLAT.match(p[0]) if len(p) == 1 else None
        m = folder or flat
        if not m:
            out.append("it is not named as Moodle names the files of a download (<full name>_<participant "
                       "id>_assignsubmission_file/<file> or <full name>_<participant id>_assignsubmission_"
                       "file_<file>), so it names no Moodle participant")
            continue
        f = LmsFile("moodle", m["pid"], m["name"].strip(), p[-1] if folder else m["file"], label=repr("/".join(p)))
        for sub in p[1:-1]:                      # a subfolder named as another participant's folder
            c = _MOODLE_FOLDER.match(sub) or MOODLE_FLAT.match(sub)
            if c and c["pid"] != f.lms_id:
                f.claims = c["pid"]
        c = MOODLE_FLAT.match(f.original)
        if c and c["pid"] != f.lms_id:
            f.claims = c["pid"]
        elif c:
            f.original = c["file"]               # their own file, downloaded from Moodle and uploaded again
        out.append(f)
    return out, []


def looks_like(parts: list[str]) -> bool:
    return bool((len(parts) >= 2 and _MOODLE_FOLDER.match(parts[0])) or
                (len(parts) == 1 and MOODLE_FLAT.match(parts[0])))


# --- one student's record -------------------------------------------------------------------------
def summarise(newest: LmsFile) -> tuple[dict, list[str]]:
    return ({"system": "moodle", "name": newest.name, "ids": {"participant_id": newest.lms_id},
             "late": None, "submitted_at": None, "attempt": None}, [])


# --- its import file ------------------------------------------------------------------------------
def settings(raw: dict) -> tuple[dict, list[str]]:
    """course.yaml's ``lms.moodle`` over the defaults, and what in it is unusable (replaced by its default)."""
    moodle = {**DEFAULTS, **raw}
    warnings = []
    if moodle["identifier"] not in MOODLE_IDENTIFIERS:
        warnings.append(f"lms.moodle.identifier {moodle['identifier']!r} is not one of "
                        f"{', '.join(MOODLE_IDENTIFIERS)}: participant is used")
        moodle["identifier"] = "participant"
    if moodle["student_ids_are"] not in (None, *MOODLE_USER_FIELDS):
        warnings.append(f"lms.moodle.student_ids_are {moodle['student_ids_are']!r} is not one of "
                        f"{', '.join(MOODLE_USER_FIELDS)} (or null): treated as null")
        moodle["student_ids_are"] = None
    v = moodle["grade_item"]
    moodle["grade_item"] = clean_text(str(v)) if v not in (None, "") else None
    return moodle, warnings


def _moodle_sheet(job: SheetJob) -> Sheet:
    report, lms_max = job.report, job.lms_max
    m = job.settings
    user_field = m["identifier"]
    sheet = Sheet(IMPORT_FILE)
    stamp = job.now.astimezone(timezone.utc).replace(microsecond=0).isoformat()
    if user_field == "participant":
        sheet.header = list(MOODLE_WORKSHEET_COLUMNS)
        sheet.info.append("the assignment's offline grading worksheet: upload it under the assignment "
                          "(View all submissions > Upload grading worksheet), not in the gradebook, with your "
                          "Moodle language set to English (its column titles are matched in your language)")
    else:
        sheet.header = [MOODLE_USER_FIELDS[user_field], "Full name", m["grade_item"] or job.assignment]
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
                why = f"no Moodle participant number: the hand-in came from {job.title(lms['system'])}"
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
                why = f"no Moodle {label}: the hand-in came from {job.title(lms['system'])}"
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
    place(sheet, claims, report, job.standings, job.points, row)
    return sheet


# --- its feedback package -------------------------------------------------------------------------
def moodle_full_name(name) -> str:
    """The full-name part of a Moodle feedback-zip member: ``_`` made a space (Moodle splits on it;
    its download does the same), what ``clean_param(PARAM_FILE)`` removes (``& < > " ` | ' : \\ /``)
    removed, control characters made spaces, no leading ``.``/``~`` (Moodle skips such files)."""
    text = unicodedata.normalize("NFC", str(name or "")).replace("_", " ")
    text = "".join(" " if unicodedata.category(c)[0] == "C" else "" if c in MOODLE_DROPPED else c for c in text)
    text = " ".join(text.split()).lstrip(".~ ")[:NAME_CHARS].rstrip()
    return text or "Participant"


def moodle_entries(r: StudentReturn) -> list[tuple[str, bytes]] | str:
    pid = ident(((r.lms or {}).get("ids") or {}).get("participant_id"))
    if pid is None or not digits_only(pid):
        return f"no Moodle participant id usable by the feedback zip ({pid!r})"
    prefix = f"{moodle_full_name(r.lms.get('name'))}_{pid}_{MOODLE_PLUGIN}_"
    out = [(prefix + file, data) for file, data in r.files()]
    for member, _ in out:            # read back as Moodle's download naming is read (above)
        m = MOODLE_FLAT.match(member)
        if not m or m["pid"] != pid or m["file"] != member[len(prefix):]:
            return f"its Moodle name {member!r} would not read back as participant {pid}"
    return out


FEEDBACK_README = [
    "  Moodle: Assignment settings > Feedback types > tick Feedback files; then View all submissions >",
    "  Grading action > Upload multiple feedback files in a zip > choose this zip > Confirm. Show all",
    "  participants (no group selected) first: Moodle imports only the participants shown. Each file",
    "  becomes the student's feedback file and the student is notified; a file unchanged since the last",
    "  upload is skipped."]


class Moodle(Lms):
    """Moodle, behind the protocol of ``base.Lms``."""
    name, title, id_key = "moodle", "Moodle", "participant_id"
    newest = "the newest"
    import_file, feedback_zip = IMPORT_FILE, FEEDBACK_ZIP

    def looks_like(self, parts, parse_notebook):
        return looks_like(parts)

    def read(self, members, parse_notebook, read_text):
        return _read_moodle(members, parse_notebook)

    def summarise(self, files, graded, newest):
        return summarise(newest)

    def settings(self, raw):
        return settings(raw)

    def import_sheet(self, job: SheetJob) -> Sheet:
        return _moodle_sheet(job)

    def feedback_entries(self, r: StudentReturn):
        return moodle_entries(r)

    def feedback_readme(self, n):
        return [f"== {FEEDBACK_ZIP}: {n} students ==", *FEEDBACK_README, ""]


MOODLE = Moodle()
