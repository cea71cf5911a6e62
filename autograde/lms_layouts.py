"""The bulk downloads of Canvas, Moodle and Blackboard: how each names its files, read back.

``intake`` uses this module when a class download is in one LMS's own layout; it decides which
student a file belongs to by the LMS's id of that student (Canvas user id, Moodle participant id,
Blackboard username), never by free text, and keeps the LMS's identifiers in ``Intake.lms``.
Every name here comes from an untrusted archive and is only ever parsed, never used as a path
(``intake`` has already refused hostile names before any of this runs).

What each LMS documents, and where
----------------------------------
The naming is read from each LMS's own source code where it is open (Canvas, Moodle): that code
is what writes the zip, so it is the documentation that cannot be out of date. Instructure's
and Anthology's help pages for "Download Submissions" / "Download Assignment" were searched for
and are not in the reference store this was written from; what they would add is which menu to
use, not the names.

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

**Blackboard Learn, Original courses** (Grade Center > column menu > "Assignment File
Download", a zip ``gradebook_<course>_<assignment>_<YYYY-MM-DD-HH-MM-SS>.zip``). Blackboard's code
is closed and its help page was not found, so this is what tools that read these downloads
agree on: https://github.com/vangef/BBGradebookOrganiser (``utils/organiser.py``),
https://github.com/timdrysdale/parselearn and https://github.com/timdrysdale/gradex-cli (the
receipt, quoted below), https://github.com/jeroendoggen/blackboard-analysis-tools (receipts in the
institution's language: ``Naam:``, ``Opdracht:``, ``Bestandsnaam:``):

* each file of each attempt: ``<assignment name>_<username>_attempt_<YYYY-MM-DD-HH-MM-SS>_<original
  file name>``, flat; one receipt per attempt, ``<assignment name>_<username>_attempt_<same
  time>.txt``::

      Name: Demonstrator Alpha (s0000000)
      Assignment: Demo
      Date Submitted: Tuesday, 21 April 2020 06:34:13 o'clock BST
      Current Mark: Needs Marking

      Submission Field:
      There is no student submission text data for this assignment.

      Comments:
      There are no student comments for this assignment.

      Files:
      	Original filename: something from my computer.pdf
      	Filename: Demo_s0000000_attempt_2020-04-21-06-34-13_something from my computer.pdf

  (US English sites write ``Monday, February 3, 2020 10:15:45 AM EST``.) The student writes the
  submission field and the comments, so only the header above the first empty line is read.

What is inferred where the sources are silent
---------------------------------------------
* Canvas: which of two files of one notebook is newer: the larger file id (Canvas's database ids
  grow with every upload), then the ``-N`` re-upload number; Canvas writes no time and no
  attempt number into a name, so ``submitted_at`` and ``attempt`` are None; ``late`` is True for
  ``LATE``/``-late``, False otherwise. The record's ``attachment_id`` holds the number Canvas
  writes after the user id, which is the *file* id of the newest file graded (the one Canvas's
  re-upload matches a returned file with). A name that Canvas could have written in two ways
  (a sortable name ending in ``_<digits>``, a display name starting with digits) is read the way
  whose file name is one of the assignment's notebooks, then the way the student's other files
  agree on; a file still readable as two different users is graded for nobody.
* Moodle: the name has no ``_`` (Moodle replaced them), so the first ``_<digits>_assignsubmission_``
  ends it, whatever the student named their file; several uploads of one notebook are ordered by
  their re-upload number (the zip's times are all the download's); ``late``, ``submitted_at``
  and ``attempt`` are None.
* Blackboard: the assignment name is the same in every file of a download; it is what is left of
  the name before ``_<username>`` when a receipt names the username (the ``(username)`` at the
  end of its first line), else the longest ``_``-separated start that all files share (with a
  single student, the username is then the last ``_`` part, as BBGradebookOrganiser assumes).
  The time in the name is the attempt's, in the server's time zone, which is not written:
  ``submitted_at`` is that local time without a zone (the receipt's own "Date Submitted" when it
  can be read, English month names only). ``attempt`` counts the attempts *in this download*,
  oldest first: a download of the last attempts only has attempt 1 everywhere. Nothing marks an
  attempt late: ``late`` is None. Of several attempts, each notebook is graded from the latest
  attempt that holds it. Blackboard Ultra's downloads are named differently and are not read.
* In every layout, a student's own file name that is itself an LMS name of *another* student of
  the same LMS (``bob_999_888_02_reward.ipynb`` in Canvas, ``Bob_999_assignsubmission_file_...`` in
  Moodle, ``<assignment>_bob_attempt_..._...`` in Blackboard) is graded for nobody, as intake does
  with ``<folder>/<other>_<notebook>.ipynb``; any other start of the name (``s042_02_reward.ipynb``)
  is the student's own naming and is ignored.
"""

from __future__ import annotations

import re
import unicodedata
from collections import Counter
from dataclasses import dataclass, field
from datetime import datetime
from typing import Callable

SYSTEMS = ("canvas", "moodle", "blackboard")
TITLE = {"canvas": "Canvas", "moodle": "Moodle", "blackboard": "Blackboard"}
RECEIPT_BYTES = 64 * 1024      # a receipt is a few hundred bytes; a bigger .txt is not one

# parse_notebook(file name) -> (prefix or None, notebook, re-upload counter) or None: intake's _Names.parse
NotebookParser = Callable[[str], "tuple[str | None, str, int] | None"]


class LayoutError(ValueError):
    """The class download as a whole cannot be read (e.g. it mixes two LMSs' layouts): nothing is
    graded, and the message says what to do instead."""


@dataclass
class LmsFile:
    """One member of an LMS download as the LMS named it: whose, and what the student uploaded."""
    system: str
    lms_id: str                   # Canvas user id ("12345", "anon_x1Y2z"), Moodle participant id, Blackboard username
    name: str | None              # the student's name as the LMS wrote it (None where it wrote none)
    original: str | None          # the name the student gave the file; None for a file the LMS made
    made_by_lms: str = ""         # for such a file: "receipt", "text entry", "URL"
    late: bool | None = None
    rank: tuple = ()              # the LMS's own order of uploads: larger is newer
    when: datetime | None = None  # Blackboard: the attempt's time from the name
    file_id: str | None = None    # Canvas: the attachment id
    marker: str = ""              # Canvas: how the late marker was written ("LATE", "-late")
    label: str = ""               # how a note names this upload
    claims: str | None = None     # another student's LMS id that the student's own file name claims
    receipt: dict = field(default_factory=dict)   # Blackboard receipts: name, username, submitted, submitted_text


def word_char(c: str) -> bool:
    """Ruby's [[:word:]]: letters, marks, digits, connector punctuation (``_``)."""
    return c.isalnum() or c == "_" or unicodedata.category(c)[0] in "MN" or unicodedata.category(c) == "Pc"


# --- Canvas --------------------------------------------------------------------------------------
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


# --- Moodle --------------------------------------------------------------------------------------
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


# --- Blackboard ----------------------------------------------------------------------------------
_BB = re.compile(r"^(?P<head>.+?)_attempt_(?P<ts>\d{4}-\d\d-\d\d-\d\d-\d\d-\d\d)(?:_(?P<orig>.+)|(?P<receipt>\.txt))$",
                 re.S)
_MONTHS = {m: i + 1 for i, m in enumerate(["january", "february", "march", "april", "may", "june", "july",
                                            "august", "september", "october", "november", "december"])}
_DATE_DMY = re.compile(r"(?P<d>\d{1,2})\s+(?P<mon>[A-Za-z]+)\s+(?P<y>\d{4}),?\s+(?P<H>\d{1,2}):(?P<M>\d\d):(?P<S>\d\d)"
                       r"\s*(?P<ampm>[AaPp][Mm])?")
_DATE_MDY = re.compile(r"(?P<mon>[A-Za-z]+)\s+(?P<d>\d{1,2}),\s*(?P<y>\d{4}),?\s+(?P<H>\d{1,2}):(?P<M>\d\d):(?P<S>\d\d)"
                       r"\s*(?P<ampm>[AaPp][Mm])?")


def parse_receipt_date(text: str) -> datetime | None:
    """A receipt's "Date Submitted" (``Tuesday, 21 April 2020 06:34:13 o'clock BST`` or ``Monday,
    February 3, 2020 10:15:45 AM EST``) as a naive local time, or None."""
    for rx in (_DATE_DMY, _DATE_MDY):
        m = rx.search(text)
        if not m or m["mon"].casefold() not in _MONTHS:
            continue
        hour = int(m["H"])
        if m["ampm"]:
            hour = hour % 12 + (12 if m["ampm"].upper() == "PM" else 0)
        try:
            return datetime(int(m["y"]), _MONTHS[m["mon"].casefold()], int(m["d"]), hour, int(m["M"]), int(m["S"]))
        except ValueError:
            return None
    return None


def parse_receipt(text: str) -> dict:
    """What a Blackboard receipt's header says: {name, username, submitted (datetime or None),
    submitted_text}. Only the lines before the first empty line are read: below it the student
    wrote (the submission field, the comments)."""
    header = []
    for line in text.lstrip("\ufeff").splitlines():
        if not line.strip():
            if header:
                break
            continue
        header.append(line.strip())
    out = {"name": None, "username": None, "submitted": None, "submitted_text": None}
    if header:
        m = re.match(r"^[^:]{1,40}:\s*(?P<name>.*?)\s*\((?P<user>[^()]+)\)\s*$", header[0])
        if m:
            out["name"], out["username"] = m["name"], m["user"].strip()
    for line in header[1:]:
        label, _, value = line.partition(":")
        if not value.strip():
            continue
        when = parse_receipt_date(value)
        if label.strip().casefold() == "date submitted" or (when and out["submitted_text"] is None):
            out["submitted"], out["submitted_text"] = when, value.strip()
            if label.strip().casefold() == "date submitted":
                break
    return out


def _bb_assignment(heads: list[str], receipts: list[tuple[str, str]]) -> tuple[str, str]:
    """(the assignment name that starts every file's name, how it was found)."""
    from_receipts = Counter(h[:-len(u) - 1] for h, u in receipts if h.endswith(f"_{u}"))
    if from_receipts:
        return from_receipts.most_common(1)[0][0], "receipt"
    tokens = [h.split("_") for h in set(heads)]
    if not tokens:
        return "", "none"
    k = 0
    while all(len(t) > k + 1 for t in tokens) and len({tuple(t[:k + 1]) for t in tokens}) == 1:
        k += 1
    return "_".join(tokens[0][:k]), ("shared" if len(tokens) > 1 else "single")


def _read_blackboard(members: list[list[str]], parse_notebook: NotebookParser,
                     read_text: Callable[[int], bytes]) -> tuple[list, list[str]]:
    warnings: list[str] = []
    parsed = [(_BB.match(p[-1]) if len(p) == 1 else None) for p in members]
    receipts: dict[int, dict] = {}
    for i, m in enumerate(parsed):
        if m and m["receipt"]:
            try:
                data = read_text(i)
            except ValueError as why:
                receipts[i] = {"error": str(why)}
                continue
            receipts[i] = parse_receipt(data.decode("utf-8", errors="replace"))
    heads = [m["head"] for m in parsed if m]
    named = [(parsed[i]["head"], r["username"]) for i, r in receipts.items() if r.get("username")]
    assignment, how = _bb_assignment(heads, named)
    if how == "single":
        warnings.append(f"Blackboard download without a receipt (.txt): the username was read as the last '_' "
                        f"part of {heads[0]!r}; check it in Blackboard")

    def user(head: str) -> str | None:
        if not assignment:
            return head
        return head[len(assignment) + 1:] if head.startswith(f"{assignment}_") and \
            len(head) > len(assignment) + 1 else None

    out = []
    for i, (p, m) in enumerate(zip(members, parsed)):
        if len(p) != 1:
            out.append("Blackboard puts every file at the top of its download; this one is in a folder")
            continue
        if not m:
            out.append("it is not named as Blackboard names the files of a download (<assignment>_<username>_"
                       "attempt_<YYYY-MM-DD-HH-MM-SS>_<file name>), so it names no Blackboard user")
            continue
        username = user(m["head"])
        if username is None:
            out.append(f"it does not start with the assignment name {assignment!r} that the download's other "
                       f"files start with, so it names no Blackboard user of this assignment")
            continue
        try:
            when = datetime.strptime(m["ts"], "%Y-%m-%d-%H-%M-%S")
        except ValueError:
            out.append(f"its attempt time {m['ts']!r} is not a date")
            continue
        f = LmsFile("blackboard", username, None, m["orig"], rank=(when,), when=when,
                    label=f"{p[-1]!r} (Blackboard attempt of {when:%Y-%m-%d %H:%M:%S})")
        if m["receipt"]:
            f.made_by_lms, f.original = "receipt", None
            f.receipt = receipts.get(i, {})
        else:
            c = _BB.match(m["orig"])
            other = c and user(c["head"])
            if other and other != username:
                f.claims = other
        out.append(f)
    return out, warnings


# --- the whole download --------------------------------------------------------------------------
def looks_like(parts: list[str], parse_notebook: NotebookParser) -> set[str]:
    """The LMSs whose naming this member's path (components) follows. For Canvas, whose names are
    only ``_``-separated parts, a reading must leave a file name that is a notebook of the
    assignment or no notebook at all (``s1_2_02_reward.ipynb`` is student ``s1_2``'s, not Canvas
    user 2's "reward.ipynb")."""
    s = set()

    def canvas_file(x):
        if x["made"]:
            return True
        display = _canvas_display(x["display"])
        return not display.casefold().endswith(".ipynb") or parse_notebook(display) is not None

    if len(parts) == 1 and _CANVAS_LOOSE.match(parts[0]) and \
            any(map(canvas_file, canvas_splits(parts[0], False) + canvas_splits(parts[0], True))):
        s.add("canvas")
    if (len(parts) >= 2 and _MOODLE_FOLDER.match(parts[0])) or (len(parts) == 1 and MOODLE_FLAT.match(parts[0])):
        s.add("moodle")
    if len(parts) == 1 and _BB.match(parts[0]):
        s.add("blackboard")
    return s


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


def detect(members: list[list[str]], parse_notebook: NotebookParser) -> tuple[str | None, bool, str]:
    """(the LMS whose layout the download is in, or None; whether one folder around everything is
    to be skipped; a line for the instructor when the answer is not clear-cut, else "").

    A download is an LMS's when more than half its files follow that LMS's naming (an LMS names
    every file it puts in the zip). Raises ValueError when files follow two LMSs' namings that
    no one file shares: two downloads merged into one, which cannot be graded as one class.
    """
    variants = [(False, members)]
    if members and all(len(p) >= 2 for p in members) and len({p[0] for p in members}) == 1:
        variants.append((True, [p[1:] for p in members]))
    note = ""
    for wrapper, parts in variants:
        looks = [looks_like(p, parse_notebook) for p in parts]
        for i in _canvas_vouched(parts, looks, parse_notebook):
            looks[i] = looks[i] | {"canvas"}
        count = Counter(s for one in looks for s in one)
        only = {s: [p for p, one in zip(parts, looks) if one == {s}] for s in SYSTEMS}
        mixed = [s for s in SYSTEMS if only[s]]
        if len(mixed) >= 2:
            examples = "; ".join(f"{len(only[s])} named as {TITLE[s]} names them, e.g. {'/'.join(only[s][0])!r}"
                                 for s in mixed)
            raise LayoutError(f"this download mixes the layouts of {' and '.join(TITLE[s] for s in mixed)} "
                             f"({examples}): download each LMS's submissions on their own and grade them "
                             f"one at a time")
        if count:
            best = max(SYSTEMS, key=lambda s: count[s])
            if 2 * count[best] > len(parts):
                return best, wrapper, ""
            note = note or (f"{count[best]} of {len(parts)} files are named as {TITLE[best]} names them, the "
                            f"rest are not: the download is read as <student>_<notebook>.ipynb and "
                            f"<student>/<notebook>.ipynb files")
    return None, False, note


def read(system: str, members: list[list[str]], parse_notebook: NotebookParser,
         read_text: Callable[[int], bytes]) -> tuple[list, list[str]]:
    """([LmsFile, or why the member names no student of this LMS], warnings for the instructor),
    one per member (its path components, any wrapper folder removed). ``read_text(i)`` returns at
    most RECEIPT_BYTES of member i (for Blackboard's receipts) or raises ValueError."""
    if system == "canvas":
        return _read_canvas(members, parse_notebook)
    if system == "moodle":
        return _read_moodle(members, parse_notebook)
    return _read_blackboard(members, parse_notebook, read_text)


# --- one student's record ------------------------------------------------------------------------
def _t(when: datetime) -> str:
    return f"{when:%Y-%m-%d %H:%M:%S}"


def summarise(system: str, files: list[LmsFile], graded: list[LmsFile]) -> tuple[dict, list[str]]:
    """(the student's ``Intake.lms`` record, notes in words) from all their files in the download
    and those graded."""
    newest = max(graded or [f for f in files if f.made_by_lms != "receipt"] or files, key=lambda f: f.rank)
    notes: list[str] = []
    if system == "canvas":
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
    if system == "moodle":
        return ({"system": "moodle", "name": newest.name, "ids": {"participant_id": newest.lms_id},
                 "late": None, "submitted_at": None, "attempt": None}, notes)
    return _blackboard_summary(files, graded, newest.lms_id)


def _blackboard_summary(files: list[LmsFile], graded: list[LmsFile], username: str) -> tuple[dict, list[str]]:
    """Blackboard's attempts are told apart by their time; the graded one is the latest that a
    graded notebook comes from (else the latest), and its receipt, if readable, gives the name
    and the date submitted."""
    notes: list[str] = []
    attempts = sorted({f.when for f in files})
    used = sorted({f.when for f in graded})
    chosen = used[-1] if used else attempts[-1]
    receipts = {f.when: f.receipt for f in files if f.made_by_lms == "receipt"}
    trusted = {}
    for when, info in sorted(receipts.items()):
        if info.get("error"):
            notes.append(f"the receipt of the attempt of {_t(when)} could not be read ({info['error']})")
        elif info.get("username") not in (None, username):
            notes.append(f"the receipt of the attempt of {_t(when)} names {info['username']!r}, not {username!r}: "
                         f"its name and date are not used")
        else:
            trusted[when] = info
    names = [trusted[w]["name"] for w in sorted(trusted, key=lambda w: w != chosen) if trusted[w].get("name")]
    submitted, said = chosen, ""
    info = trusted.get(chosen, {})
    if info.get("submitted"):
        submitted, said = info["submitted"], f" (its receipt says submitted {info['submitted_text']!r})"
    elif info.get("submitted_text"):
        said = f" (its receipt's date {info['submitted_text']!r} could not be read; the file name's time is used)"
    line = (f"Blackboard: {len(attempts)} attempt{'s' * (len(attempts) != 1)} in this download "
            f"({', '.join(map(_t, attempts))}); ")
    if used:
        line += f"graded from the attempt of {_t(chosen)}{said}"
        if len(used) > 1:
            line += (f"; notebooks also come from the attempt{'s' * (len(used) > 2)} of "
                     + ", ".join(_t(w) for w in used if w != chosen) + " (the latest attempt holding each notebook)")
        aside = [w for w in attempts if w not in used]
        if aside:
            line += "; set aside: the attempt" + "s" * (len(aside) > 1) + " of " + ", ".join(map(_t, aside))
    else:
        line += f"no notebook of this assignment was graded from any; the latest is of {_t(chosen)}{said}"
    notes.append(line)
    return ({"system": "blackboard", "name": names[0] if names else username, "ids": {"username": username},
             "late": None, "submitted_at": submitted.isoformat(), "attempt": attempts.index(chosen) + 1}, notes)
