"""Canvas: its download read, its students named, its gradebook import and its re-upload of feedback.

Its download
------------
**Canvas** ("Download Submissions", an assignment's page or the gradebook):
``lib/content_zipper.rb`` (https://github.com/instructure/canvas-lms/blob/master/lib/content_zipper.rb)
writes one flat zip. Each uploaded file is
``<name>[_LATE]_<user id>_<file id>_<the file's display name>``:

* ``get_user_name``: the student's *sortable* name ("Lee, Ann"), with ``_<digits>_`` turned into
  ``<digits>`` ("because we use /_\\d+_/ to infer the user/attachment ids when teachers upload
  graded submissions"), lowercased; ``get_filename`` joins it, ``"LATE"`` when
  ``submission.late?``, and the user id with ``_``, then removes every character that is not a
  word character (``[^[[:word:]]]``): ``Lee, Ann`` -> ``leeann``, ``Müller, Zoë`` -> ``müllerzoë``;
* in an anonymously graded assignment there is no name and the id is ``anon_<anonymous id>``;
* ``add_upload_submission``: ``"#{filename}_#{file.id}_#{display_name}"``; the second number is
  the **attachment (file) id**, not a submission id, and the display name has ``\\ / : * ? " < > |``
  and NUL replaced by ``_``; text entries and URLs become ``<name>_<user id>_text.html`` and
  ``_link.html``;
* only the files of each student's *current* submission are zipped
  (``submission.attachment_ids``): earlier submissions are not in the download;
* Canvas's own re-upload of graded files (``app/models/assignment.rb``,
  ``infer_comment_context_from_filename``) reads the first two all-digit ``_`` parts as user id
  and file id;
* an older version of the same file wrote ``<name>-late_<user id>_...``: spaces and
  non-word characters became ``-``, the whole name lowercased, so its late marker is ``-late``.

Display names: a file uploaded where one of the same name already is gets ``-1`` ... ``-7`` and
then a UUID before its extension (``Attachment.make_unique_filename`` in
``app/models/attachment.rb``); so re-submitting ``02_reward.ipynb`` arrives as
``02_reward-1.ipynb`` (inferred from that code and from what students report:
https://github.com/IIC1253/IIC1253-2025-1/issues/34, "11111111-2.zip"; an instructor's example of
the whole name: https://github.com/instructure/canvas-lms/issues/2406,
``studenttest_3143_207797_zipsubmission.zip``; https://github.com/TimHanneman/Canvas_submission_sort
describes the late field and the resubmission number).

Inferred where the sources are silent:

* which of two files of one notebook is newer: the larger file id (Canvas's database ids
  grow with every upload), then the ``-N`` re-upload number; Canvas writes no time and no
  attempt number into a name, so ``submitted_at`` and ``attempt`` are None; ``late`` is True for
  ``LATE``/``-late``, False otherwise. The record's ``attachment_id`` holds the number Canvas
  writes after the user id, which is the *file* id of the newest file graded (the one Canvas's
  re-upload matches a returned file with). A name that Canvas could have written in two ways
  (a sortable name ending in ``_<digits>``, a display name starting with digits) is read the way
  whose file name is one of the assignment's notebooks, then the way the student's other files
  agree on; a file still readable as two different users is graded for nobody.

Its import file
---------------
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

Its feedback package
--------------------
**Canvas** (*Re-Upload Submissions*). Instructure's source, ``app/models/assignment.rb``
(https://github.com/instructure/canvas-lms/blob/master/app/models/assignment.rb, the stored
version read has ``Submission.active`` and ``grants_right?``):
``generate_comments_from_files`` ("Takes a zipped file full of assignment comments/annotated
assignments and generates comments on each assignment's submission. Quietly ignore (for now) files
that don't make sense to us. The convention for file naming ... is
last_name_first_name_user_id_attachment_id") unzips the upload and for every file calls
``infer_comment_context_from_filename``::

    filename = File.basename(fullpath)
    split_filename = filename.split('_')
    user_id, attachment_id = split_filename.grep(/^\\d+$/).take(2)
    attachment_id = nil if split_filename.last =~ /^link/ || filename =~ /^\\._/
    ...
    if !attachment || !submission || !attachment.grants_right?(user, :read) ||
       !submission.attachments.where(:id => attachment_id).exists?
      @ignored_files << fullpath

so a file is matched by the first two ``_``-separated parts that are all digits: the Canvas user
id, then the id of a file (attachment) of that user's *current* submission, exactly the two
numbers Canvas's *Download Submissions* writes (read above: ``<name>[_LATE]_<user id>_<file
id>_<display name>``) and ``intake`` keeps (``ids.user_id``, ``ids.attachment_id``: the newest
graded file). Any other file is ignored (``@ignored_files``, which the method returns beside
the comments made). The files of one user become ONE submission
comment, "See attached files", hidden while the assignment is muted. Each file is attached with
``FileInContext.attach(self, g[:filename], g[:display_name])`` where ``display_name`` is the
*submitted* file's display name: Canvas shows every returned file under the name of the student's
upload whose id it carries (confirmed by https://github.com/instructure/canvas-lms/issues/2406,
2024: a returned ``..._feedback.pdf`` shows as ``zipsubmission.zip``). So this package writes,
per student, ``<name>_<user id>_<attachment id>_summary.html`` and
``<name>_<user id>_<attachment id>_<notebook>.html``: ``<name>`` is Canvas's own (lowercased
word characters as its download wrote it) with every ``_`` and non-word character removed, and
``student`` when nothing is left or when it is all digits (it would be read as the user id); the
record's ``attachment_ids`` ({notebook file name: that upload's file id}, kept by intake) gives
each notebook's page its own notebook's upload id, so it shows under that notebook's name (the
summary goes with the newest upload, ``ids.attachment_id``). Inferred, not verified on a live Canvas: that a ``.html`` shown under an
``.ipynb`` display name opens as a page (``Attachment.mimetype`` is given the extracted file's
own name, ``.html``); README.txt tells the instructor that students see their upload's name.
An anonymous assignment's id (``anon_<id>``) is no user id: those students go to
``feedback_by_student.zip``.
"""

from __future__ import annotations

import re
import unicodedata
from collections import Counter

from ..text import clean_text, digits, ident, num
from .base import (
    NAME_CHARS,
    SUMMARY,
    Lms,
    LmsFile,
    NotebookParser,
    Sheet,
    SheetJob,
    StudentReturn,
    digits_only,
    lms_record,
    place,
    word_char,
)

IMPORT_FILE = "canvas_import.csv"
FEEDBACK_ZIP = "canvas_feedback_upload.zip"

# Canvas's student columns, in the order its exporter writes them (Integration ID and Root Account
# only exist where an account turns them on; the importer does not need them).
CANVAS_STUDENT_COLUMNS = ["Student", "ID", "SIS User ID", "SIS Login ID", "Section"]
CANVAS_POINTS_ROW = "    Points Possible"            # the exporter's first cell, spaces included
CANVAS_SIS = {"sis_user_id": "SIS User ID", "sis_login_id": "SIS Login ID"}
DEFAULTS = {"assignment_id": None, "assignment_name": None, "student_ids_are": None}


# --- its download ---------------------------------------------------------------------------------
_CANVAS_LOOSE = re.compile(r"^.*?_(?:\d+|anon_[0-9A-Za-z]+)_(?:\d+_.+|text\.html|link\.html)$", re.S)
_CANVAS_ANON = re.compile(r"^(?:(?P<late>LATE)_)?anon_(?P<anon>[0-9A-Za-z]+)_"
                          r"(?:(?P<aid>\d+)_(?P<display>.+)|(?P<made>text|link)\.html)$", re.S)
_CANVAS_UUID = re.compile(r"-[0-9a-f]{8}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{12}(?=\.ipynb$)", re.I)


_CANVAS_IDS = re.compile(r"(?P<uid>\d+)_(?:(?P<aid>\d+)_|(?P<made>text|link)\.html$)")


def canvas_splits(base: str, anonymous: bool) -> list[dict]:
    """Every way Canvas could have written ``base``: [{name, uid, aid, display, made, late, marker}].

    A name Canvas wrote is lowercased word characters (``-`` too in the old format) and never
    holds ``_<digits>_`` (Canvas removes those so that the ids can be found); linear in the
    length of ``base``, which the archive chooses."""
    if anonymous:
        m = _CANVAS_ANON.match(base)
        return [{"name": None, "uid": f"anon_{m['anon']}", "aid": m["aid"], "display": m["display"],
                 "made": m["made"], "late": bool(m["late"]), "marker": "LATE" if m["late"] else ""}] if m else []
    bad = next((i for i, c in enumerate(base) if not (word_char(c) or c == "-") or "A" <= c <= "Z"), len(base))
    ids_inside = re.search(r"_\d+_", base)
    limit = min(bad, ids_inside.end() - 1 if ids_inside else len(base))   # a name ends before both
    out = []
    for i, c in enumerate(base):
        if c != "_" or i + 1 >= len(base) or not base[i + 1].isdigit():
            continue
        name, late, marker = base[:i], False, ""
        if name.endswith("_LATE"):
            name, late, marker = name[:-len("_LATE")], True, "LATE"
        elif name.endswith("-late"):
            name, late, marker = name[:-len("-late")], True, "-late"
        if not name or len(name) > limit:
            continue
        r = _CANVAS_IDS.match(base, i + 1)
        # database ids never start with 0: "leeann_1001_40001_01_world_model_final.ipynb" is user 1001's
        # file 40001, not user 40001's file "01"
        if r and (r["uid"].startswith("0") or (r["aid"] or "1").startswith("0")):
            continue
        if r:
            out.append({"name": name, "uid": r["uid"], "aid": r["aid"], "made": r["made"],
                        "display": base[r.end():] if r["aid"] else None, "late": late, "marker": marker})
    return out


def _canvas_display(display: str) -> str:
    """The student's file name, less the UUID Canvas adds after its seventh same-named upload."""
    return _CANVAS_UUID.sub("", display)


def _read_canvas(members: list[list[str]], parse_notebook: NotebookParser) -> tuple[list, list[str]]:
    bases = [p[-1] for p in members]
    # An anonymously graded assignment names every file anon_<id>; a student called "Anon" does not.
    canvas_like = [b for p, b in zip(members, bases) if len(p) == 1 and _CANVAS_LOOSE.match(b)]
    anonymous = 2 * sum(bool(_CANVAS_ANON.match(b)) for b in canvas_like) > len(canvas_like)

    def score(s):
        if s["made"]:
            return 1
        nb = parse_notebook(_canvas_display(s["display"]))
        return 2 if nb and nb[0] is None else 1 if nb else 0

    splits = [canvas_splits(b, anonymous) if len(p) == 1 else [] for p, b in zip(members, bases)]
    # The students' own files vouch for a reading: a (user id, name) that other files read the same way.
    support = Counter()
    provisional = []
    for ss in splits:
        scores = [score(s) for s in ss]
        best = [s for s, x in zip(ss, scores) if x == max(scores)]
        one = {(s["uid"], s["name"]) for s in best}
        provisional.append(one.pop() if len(one) == 1 else None)
        if provisional[-1]:
            support[provisional[-1]] += 1
    out = []
    for p, base, ss, own in zip(members, bases, splits, provisional):
        if len(p) != 1:
            out.append("Canvas puts every file at the top of its download; this one is in a folder")
            continue
        if not ss:
            out.append("it is not named as Canvas names the files of a download "
                       "(<name>_<user id>_<file id>_<file name>), so it names no Canvas user")
            continue

        def key(s, own=own):
            return (score(s), support[(s["uid"], s["name"])] - ((s["uid"], s["name"]) == own))
        top = max(map(key, ss))
        best = [s for s in ss if key(s) == top]
        if len({s["uid"] for s in best}) > 1:
            users = " or ".join(sorted({s["uid"] for s in best}))
            out.append(f"Canvas could have written this name for user {users}: it cannot be told whose it is, "
                       f"so it is graded for nobody")
            continue
        s = best[0]
        f = LmsFile("canvas", s["uid"], s["name"], None, late=s["late"], marker=s["marker"])
        if s["made"]:
            f.made_by_lms = {"text": "text entry", "link": "URL"}[s["made"]]
            f.label = repr(base)
        else:
            f.original = _canvas_display(s["display"])
            f.file_id = s["aid"]
            f.rank = (int(s["aid"]),)
            f.label = f"{base!r} (Canvas file id {s['aid']})"
            # their file's own name, read as Canvas's name of a notebook of somebody else's
            named = {t["uid"] for t in canvas_splits(f.original, anonymous=False) if score(t) == 2}
            if named and s["uid"] not in named:
                f.claims = sorted(named)[0]
        out.append(f)
    return out, []


def looks_like(parts: list[str], parse_notebook: NotebookParser) -> bool:
    """Whether this member follows Canvas's naming. Canvas's names are only ``_``-separated parts,
    so a reading must leave a file name that is a notebook of the assignment or no notebook at all
    (``s1_2_02_reward.ipynb`` is student ``s1_2``'s, not Canvas user 2's "reward.ipynb")."""
    def canvas_file(x):
        if x["made"]:
            return True
        display = _canvas_display(x["display"])
        return not display.casefold().endswith(".ipynb") or parse_notebook(display) is not None

    return bool(len(parts) == 1 and _CANVAS_LOOSE.match(parts[0]) and
                any(map(canvas_file, canvas_splits(parts[0], False) + canvas_splits(parts[0], True))))


def _canvas_vouched(parts: list[list[str]], looks: list[set[str]], parse_notebook: NotebookParser) -> list[int]:
    """Members named ``<name>_<user id>_<file id>_<file>`` whose own file part names no notebook (a
    student's renaming, ``05_horizon_final.ipynb``, which intake identifies by its content) that
    follow Canvas's naming all the same: those whose (user id, name) reading is also the reading of
    a member that follows it in full (the student's other files vouch for the reading), and those
    that have Canvas's full shape with a file id while their whole name reads as no generic
    ``<student>_<notebook>.ipynb`` (a student who renamed every file, or one who uploaded only
    files of their own, cannot turn the class's download into a generic one). A generic
    ``s1_2_02_reward.ipynb`` reads as student ``s1_2``'s notebook 02 and has no voucher, so it stays
    what ``looks_like`` says."""
    def readings(base, strict):
        out = set()
        for anonymous in (False, True):
            for x in canvas_splits(base, anonymous):
                if x["made"] or not strict or parse_notebook(_canvas_display(x["display"])) is not None:
                    out.add((x["uid"], x["name"]))
        return out

    vouchers = set()
    for p, one in zip(parts, looks):
        if "canvas" in one:
            vouchers |= readings(p[0], strict=True)
    def shaped(base):        # <name>_<user id>_<file id>_<file>, whose whole name reads as no <student>_<notebook>
        return parse_notebook(base) is None and any(
            x["aid"] for anonymous in (False, True) for x in canvas_splits(base, anonymous))

    return [i for i, (p, one) in enumerate(zip(parts, looks))
            if "canvas" not in one and len(p) == 1 and _CANVAS_LOOSE.match(p[0])
            and ((vouchers and readings(p[0], strict=False) & vouchers) or shaped(p[0]))]


# --- one student's record -------------------------------------------------------------------------
def summarise(files: list[LmsFile], graded: list[LmsFile], newest: LmsFile) -> tuple[dict, list[str]]:
    notes: list[str] = []
    late = any(f.late for f in files)
    names = sorted({f.name for f in files if f.name is not None})
    if len(names) > 1:
        notes.append(f"Canvas wrote different names for user {newest.lms_id}: "
                     f"{', '.join(map(repr, names))}: check in Canvas that these files are all theirs")
    if late:
        marker = next(f.marker for f in files if f.late)
        notes.append(f"Canvas marked this submission late ({marker!r} in its file names)")
    file_id = newest.file_id or next((f.file_id for f in files if f.file_id), None)
    return ({"system": "canvas", "name": newest.name, "ids": {"user_id": newest.lms_id, "attachment_id": file_id},
             "late": late, "submitted_at": None, "attempt": None}, notes)


# --- its import file ------------------------------------------------------------------------------
def settings(raw: dict) -> tuple[dict, list[str]]:
    """course.yaml's ``lms.canvas`` over the defaults, and what in it is unusable (replaced by its default)."""
    canvas = {**DEFAULTS, **raw}
    warnings = []
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
    v = canvas["assignment_name"]
    canvas["assignment_name"] = clean_text(str(v)) if v not in (None, "") else None
    return canvas, warnings


def _canvas_sheet(job: SheetJob) -> Sheet:
    report, lms_max = job.report, job.lms_max
    c = job.settings
    title = c["assignment_name"] or job.assignment
    column = f"{title} ({c['assignment_id']})" if c["assignment_id"] else title
    sheet = Sheet(IMPORT_FILE, header=[*CANVAS_STUDENT_COLUMNS, column],
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
            why = f"no Canvas user id: the hand-in came from {job.title(lms['system'])}"
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
    place(sheet, claims, report, job.standings, job.points, lambda key, s, name, pts: [
        name, key[1] if key[0] == "ID" else "", key[1] if key[0] == "SIS User ID" else "",
        key[1] if key[0] == "SIS Login ID" else "", "", pts])
    return sheet


# --- its feedback package -------------------------------------------------------------------------
def canvas_name_part(name) -> str:
    """The name part of a Canvas re-upload file name: word characters only, no ``_`` (the ids are
    found as the first all-digit ``_`` parts), never empty, never all digits."""
    text = "".join(c for c in unicodedata.normalize("NFC", str(name or "")).lower() if word_char(c) and c != "_")
    text = text[:NAME_CHARS]           # a member name stays far below the 255 bytes a file name may hold
    return text if text and not text.isdigit() else "student"


def canvas_entries(r: StudentReturn) -> list[tuple[str, bytes]] | str:
    """[(member name, bytes)] of this student in the Canvas re-upload zip, or why none."""
    ids = (r.lms or {}).get("ids") or {}
    uid, aid = ident(ids.get("user_id")), ident(ids.get("attachment_id"))
    if uid is None or not digits_only(uid):
        return ("anonymous grading: Canvas's download names the student by an anonymous id, which Re-Upload "
                "Submissions cannot match" if uid and uid.startswith("anon_") else
                f"no Canvas user id usable by Re-Upload Submissions ({uid!r})")
    kept = (r.lms or {}).get("attachment_ids")
    per_nb = kept if isinstance(kept, dict) else {}
    if aid is None or not digits_only(aid):
        aid = next((v for v in map(ident, per_nb.values()) if v and digits_only(v)), None)
    if aid is None:
        return "no Canvas file id of their submission (Re-Upload Submissions matches a file of it)"
    name = canvas_name_part(r.lms.get("name"))
    out = []
    for file, data in r.files():
        own = ident(per_nb.get(file[:-len(".html")] + ".ipynb")) if file != SUMMARY else None
        member = f"{name}_{uid}_{own if own and digits_only(own) else aid}_{file}"
        # the name must read back as Canvas's download naming does (read above), with these ids first
        if not any(x["uid"] == uid and x["aid"] == member.split("_")[2] for x in canvas_splits(member, False)):
            return f"its Canvas name {member!r} would not read back as user {uid}"
        out.append((member, data))
    return out


FEEDBACK_README = [
    "  Canvas: the assignment > Re-Upload Submissions (or the Gradebook column's menu) > choose this zip.",
    "  Each file is named <name>_<user id>_<file id>_<page>: Canvas attaches a student's files to ONE comment",
    "  'See attached files' on their submission (hidden while the assignment is muted). Canvas shows each",
    "  file under the name of the student's own upload with that file id (e.g. 02_reward.ipynb); it is",
    "  the HTML page: tell students to open it in a browser. Files Canvas cannot match are ignored: a",
    "  student who submitted again since the download is one (download and grade again first)."]


class Canvas(Lms):
    """Canvas, behind the protocol of ``base.Lms``."""
    name, title, id_key = "canvas", "Canvas", "user_id"
    newest = "the newest (Canvas numbers the files it keeps in the order they were uploaded)"
    import_file, feedback_zip = IMPORT_FILE, FEEDBACK_ZIP

    def looks_like(self, parts, parse_notebook):
        return looks_like(parts, parse_notebook)

    def vouched(self, parts, looks, parse_notebook):
        return _canvas_vouched(parts, looks, parse_notebook)

    def read(self, members, parse_notebook, read_text):
        return _read_canvas(members, parse_notebook)

    def summarise(self, files, graded, newest):
        return summarise(files, graded, newest)

    def notebook_ids(self, graded):
        # each graded notebook's own upload, for returning its page under its name (lms_feedback)
        return {nb: f.file_id for nb, f in graded if f.file_id}

    def settings(self, raw):
        return settings(raw)

    def import_sheet(self, job: SheetJob) -> Sheet:
        return _canvas_sheet(job)

    def feedback_entries(self, r: StudentReturn):
        return canvas_entries(r)

    def feedback_readme(self, n):
        return [f"== {FEEDBACK_ZIP}: {n} students ==", *FEEDBACK_README, ""]


CANVAS = Canvas()
