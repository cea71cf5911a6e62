"""Intake: turn the LMS download (a .zip or a folder) into one notebook per student and notebook.

This is the first step of grading, and the only one that looks at what students uploaded before
anything is run. Uploads are untrusted: a file name can try to escape the course folder
(``../x_02_reward.ipynb``), claim another student (``alice/bob_02_reward.ipynb``) or be a zip bomb.
Nothing here ever writes a file, and no name from the archive is ever used as a path: members are
read into memory and every decision is recorded in words an instructor can read in report.csv.

    from intake import collect, decode_notebook
    intake = collect(Path("class.zip"), ["01_world_model.ipynb", "02_reward.ipynb", ...])
    for student, uploads in intake.students.items():      # student: a folder-safe id
        for name, upload in uploads.items():               # name: "02_reward.ipynb"
            nb = decode_notebook(upload.data)              # ValueError: tell the student why

Layouts accepted (after one optional wrapper folder that holds the whole class, as LMSs add):

* flat:   ``<student>_<notebook>.ipynb``       e.g. ``s042_02_reward.ipynb``, ``john_doe_02_reward.ipynb``
* folder: ``<student>/<notebook>.ipynb``       e.g. ``s042/02_reward.ipynb``
          ``<student>/<student>_<notebook>.ipynb`` (the same student twice) is fine too.

LMS layouts (``autograde/lms_layouts.py`` quotes where each LMS documents its naming, and says
what is inferred): a download that Canvas ("Download Submissions"), Moodle ("Download all
submissions", in folders or not) or Blackboard Learn Original ("Assignment File Download") made
is read in that LMS's own naming, and only in it:

* Canvas:     ``leeann_1001_40002_02_reward.ipynb``, ``müllerzoë_LATE_1002_40004_02_reward-1.ipynb``
* Moodle:     ``Zoë Müller_5301277_assignsubmission_file/02_reward.ipynb`` (or ``..._file_02_reward.ipynb``)
* Blackboard: ``Chapter 3_jdoe_attempt_2026-03-02-09-30-15_02_reward.ipynb``, and its receipt
              ``Chapter 3_jdoe_attempt_2026-03-02-09-30-15.txt``

There the LMS's id of the student decides whose a file is (Canvas user id, Moodle participant
id, Blackboard username; never the free-text name), the folder-safe id is ``<lms>_<that id>``
(``canvas_1001``, ``moodle_5301277``, ``blackboard_jdoe``: the same in every download, whatever
the student's name becomes), and ``Intake.lms`` keeps the LMS's identifiers, Canvas's late
marker and Blackboard's attempt times for matching grades back. Of several uploads of one
notebook, the LMS's own order decides (Canvas's file ids, Blackboard's attempt times); the
student's notes say which was graded and which were set aside, that Canvas marked them late, and
which Blackboard attempt was graded (its receipt's date when it has one). A file that does not
follow the LMS's naming names no student of it and is graded for nobody; a download that mixes
two LMSs' layouts is refused (ValueError). A download is taken for an LMS's when more than half
its files follow that LMS's naming; otherwise the generic layouts below apply.

The notebook part must be one of the assignment's notebooks (its two-digit number AND its name,
in any letter case), at the END of the name, so a student id may itself contain underscores.
It may carry a re-upload suffix, which also counts as "how many times re-uploaded" when two uploads
have the same time: ``02_reward (1)``, ``02_reward(2)``, ``02_reward-1``, ``02_reward_2``,
``02_reward_v2``, ``02_reward-Copy1`` (Jupyter's duplicate) all mean 02_reward. Colab's
``Copy of 02_reward`` is accepted as well. Anything else after the name (``02_reward_final``,
``02_reward_solution``) names no notebook of this assignment: with the release at hand
(``collect(release=...)``, as grading calls it) such a file of a known student is identified by
its content (``identify``) and graded as what it holds, and so is a file whose name says one
notebook and whose content is another; without it, the file is refused.

Student ids (see :func:`normalise_student_id`): the id the LMS wrote is kept for the report
(``Intake.display_names``) and turned into ONE folder-safe form that nbgrader uses as folder name
and gradebook key: ``Ann Lee`` -> ``Ann_Lee``, ``Zoë`` -> ``Zoë``. Two different ids that would
become the same folder (``Ann Lee`` and ``Ann_Lee``, or ``Ann_Lee`` and ``ann_lee``, which are one
folder on macOS and Windows) are never merged: both are graded separately, the second one as
``Ann_Lee~2``, and both students' notes say so. The same name typed in two Unicode forms (``Chloé``
composed or decomposed, as macOS writes it) is the same student.

Look-alike ids (see :func:`_note_lookalikes`): ``victim2`` and ``vіctim2`` (a Cyrillic ``і``) are
two students to the computer and one to the eye. Ids whose Unicode confusable skeletons (UTS #39,
computed by ICU through PyICU) are equal are graded separately as always, and both students' notes
name the other id, with the code points of any character outside ASCII spelled out. Without PyICU
the check cannot run: grading goes on, ``Intake.lookalikes_checked`` is False and
``Intake.warnings`` says how to enable it.
"""

from __future__ import annotations

import codecs
import json
import os
import re
import stat
import unicodedata
import zipfile
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path
from typing import Callable

import nbformat

from . import lms_layouts
from .identify import Identifier
from .lms import plugin as lms_plugin
from .lms_layouts import LayoutError

MB = 2 ** 20
MAX_NOTEBOOK_BYTES = 50 * MB     # a chapter notebook with outputs is < 5 MB; 50 MB is surely wrong
MAX_TOTAL_BYTES = 2048 * MB      # everything read from one class download, all students together
MAX_MEMBERS = 100_000            # entries in the archive (or files in the folder) looked at
MAX_FILES_PER_NOTEBOOK = 4      # uploads of one notebook read per student when notebooks are known by content
MAX_ID_CHARS = 64                # nbgrader's gradebook holds 128; folders hold 255 bytes
MAX_ID_BYTES = 200
REDOWNLOAD = ("Open the notebook in Jupyter or Colab, use File > Download > Download .ipynb, and "
              "upload the .ipynb file that this saves.")
LOOKALIKES_NOT_CHECKED = (
    "look-alike student ids (e.g. 'victim2' and 'v\u0456ctim2', with a Cyrillic i) were NOT checked: "
    "PyICU cannot be imported ({why}). To check them, install ICU's development files (Debian/Ubuntu: "
    "sudo apt-get install libicu-dev pkg-config; macOS: brew install icu4c pkg-config, and add "
    "$(brew --prefix)/opt/icu4c/lib/pkgconfig to PKG_CONFIG_PATH), run `make icu` (it installs the "
    "PyICU pinned in requirements.txt) and grade again")

# Names of files and folders that operating systems and Jupyter add: ignored, never graded.
_JUNK = {"__macosx", "thumbs.db", "desktop.ini", "__pycache__"}
# Invisible characters that reverse the direction of text: a name containing them can look like
# another one in a listing, so such a member is refused.
_BIDI = set("\u200e\u200f\u202a\u202b\u202c\u202d\u202e\u2066\u2067\u2068\u2069\u061c")
_WINDOWS_RESERVED = {"con", "prn", "aux", "nul", *(f"com{i}" for i in range(10)),
                     *(f"lpt{i}" for i in range(10))}
# After the notebook's name: " (1)", "(2)", "-1", "_2", " 3", "_v2", "-Copy1", "v2".
_SUFFIX = r"(?:\s*\(\s*(?P<n1>\d{1,4})\s*\)|[-_ ]?(?:v|copy)?(?P<n2>\d{1,4}))?"


@dataclass
class Upload:
    """One uploaded file: its bytes (never written anywhere by intake), the name it had in the
    archive or folder (``member``), and when it was saved (``mtime``: the zip entry's date, or
    the file's modification time for a folder; local time, no time zone)."""
    data: bytes
    member: str
    mtime: datetime


@dataclass
class Intake:
    """What was found in a class download.

    ``students``: folder-safe student id -> {notebook file name, e.g. "02_reward.ipynb": Upload}.
        Every student the download names is here, even one whose every file was refused (an
        empty dict: grade them 0 and show their notes).
    ``notes``: student id -> lines for that student's row in report.csv (which upload was graded
        and which ignored, what was refused and why).
    ``rejected``: one line per file that was graded for nobody: which member and why.
    ``display_names``: student id -> the id exactly as the LMS wrote it (Unicode NFC), for the
        report and for matching grades back to the LMS; in an LMS layout ``<lms>_<LMS id>``
        (the LMS's own identity is in ``lms``).
    ``lookalikes_checked``: whether look-alike ids were looked for (False when PyICU is missing).
    ``warnings``: lines for the instructor about the whole class download (e.g. that look-alike
        ids were not checked, and how to enable the check); print them where grading is logged.
    ``lms``: for a download in Canvas's, Moodle's or Blackboard's own layout, student id -> the
        LMS's identity of that student, to match grades back (students of the generic layouts
        have no entry)::

            {"system": "canvas" | "moodle" | "blackboard",
             "name": the student's name as the LMS wrote it (Canvas: the sortable name as its
                     file names write it, "leeann"; None for an anonymous Canvas assignment;
                     Blackboard: the receipt's name, else the username),
             "ids": {"user_id": "12345", "attachment_id": "678"}   (Canvas; user_id is
                        "anon_<id>" when anonymous; attachment_id is the number Canvas writes
                        after the user id: the file (attachment) id of the newest file graded;
                        Canvas writes no submission id into its file names)
                    | {"participant_id": "1234567"}                (Moodle)
                    | {"username": "jdoe"},                         (Blackboard)
             "late": True | False (Canvas's LATE marker) | None (Moodle, Blackboard: not in the names),
             "submitted_at": ISO 8601 local time without zone (Blackboard) | None,
             "attempt": the graded attempt's number among this student's attempts in the
                        download, oldest first (Blackboard) | None,
             "attachment_ids": {"02_reward.ipynb": "678", ...}: the file id of each graded
                        notebook's upload (Canvas) | None}

    ``human``: with the release to identify notebooks by (``collect(release=...)``), one entry per
        file whose name did not decide what it is, for the class report's "needs a human": a
        renamed file graded by its content, one that matches no notebook, two files that are one
        notebook (the newest graded). ``{"student": id, "file": the name as uploaded, "graded":
        the notebook it was graded as, or None, "why": words}``; the student's notes say the same.
    """
    students: dict[str, dict[str, Upload]] = field(default_factory=dict)
    notes: dict[str, list[str]] = field(default_factory=dict)
    rejected: list[str] = field(default_factory=list)
    display_names: dict[str, str] = field(default_factory=dict)
    lookalikes_checked: bool = False
    warnings: list[str] = field(default_factory=list)
    lms: dict[str, dict] = field(default_factory=dict)
    human: list[dict] = field(default_factory=list)


class _Refused(Exception):
    """A member that cannot be placed; the message says why."""


# --- student ids ---------------------------------------------------------------------------------
def _id_char_ok(c: str) -> bool:
    """Letters and digits of any script, their accents, and ``- . _``."""
    return c.isalnum() or c in "-._" or unicodedata.category(c).startswith("M")


def normalise_student_id(raw: str) -> str:
    """The folder-safe form of a student id as the LMS wrote it, or ValueError.

    The rule, in order:

    1. Unicode NFC (so a name typed with a composed ``é`` and one with ``e`` + accent are one),
       then leading and trailing spaces are removed;
    2. every run of spaces or of characters other than letters, digits, accents, ``-``, ``.`` and
       ``_`` becomes one ``_``: ``Ann Lee`` -> ``Ann_Lee``, ``Lee, Ann`` -> ``Lee_Ann``; letters
       keep their case and accents (``Zoë``, ``Chloé``), so the folder reads like the name;
    3. leading ``.`` and ``-`` (hidden files, command-line options) and trailing ``.`` (dropped by
       Windows) are removed; a Windows device name (``CON``, ``NUL``, ``COM1``...) gets a ``_`` in
       front; more than 64 characters are cut to 64.

    What comes out is one path component on Linux, macOS and Windows (no ``/ \\ :``, no control
    characters, never ``.``, ``..`` or empty) and a valid nbgrader student id: nbgrader strips
    spaces from ids, uses the id as a file glob (so ``* ? [ ]`` are replaced), splits
    ``--student_id_exclude`` at commas and the exchange at ``+`` (both replaced), and its gradebook
    column holds 128 characters. An id with no letter or digit at all (``..``, ``___``) is refused.
    """
    s = unicodedata.normalize("NFC", raw).strip()
    out, run = [], False
    for c in s:
        if _id_char_ok(c):
            out.append(c)
            run = False
        elif not run:
            out.append("_")
            run = True
    s = "".join(out).lstrip(".-").rstrip(".")
    if s.split(".")[0].casefold() in _WINDOWS_RESERVED:
        s = "_" + s
    if len(s) > MAX_ID_CHARS:
        s = s[:MAX_ID_CHARS]
    while len(s.encode("utf-8")) > MAX_ID_BYTES:
        s = s[:-1]
    s = s.rstrip(".")
    if not any(c.isalnum() for c in s):
        raise ValueError(f"student id {raw!r} has no letter or digit that could name a folder")
    return s


def _id_key(safe: str) -> str:
    """Two ids with the same key would be the same folder somewhere (case-insensitive disks)."""
    return unicodedata.normalize("NFC", safe.casefold())


# --- member names --------------------------------------------------------------------------------
def _member_parts(name: str) -> list[str]:
    """The components of a member's name, or _Refused for a name that is hostile or broken.

    Both ``/`` and ``\\`` separate components (Windows zip tools write ``\\``); ``.`` and empty
    components are dropped; the name is only ever split into strings, never used as a path.
    """
    if "\x00" in name:
        raise _Refused("its name contains a NUL character (a trick to hide the real name)")
    if any(unicodedata.category(c) == "Cc" for c in name):
        raise _Refused("its name contains control characters")
    if any(c in _BIDI for c in name):
        raise _Refused("its name contains invisible text-direction characters")
    if any(0xD800 <= ord(c) <= 0xDFFF for c in name):
        raise _Refused("its name is not valid UTF-8 text")
    if name.startswith(("/", "\\")):
        raise _Refused("it has an absolute path (starts with / or \\)")
    if re.match(r"[A-Za-z]:", name):
        raise _Refused("it has a Windows drive letter (an absolute path)")
    if ":" in name:
        raise _Refused("its name contains ':' (a drive letter or a Windows alternate data stream)")
    raw_parts = re.split(r"[/\\]", name)
    for p in raw_parts:
        if p.strip(" ") and set(p.strip(" ")) == {"."} and len(p.strip(" ")) >= 2:
            raise _Refused("its path contains '..' (it tries to leave the submissions folder)")
    parts = [unicodedata.normalize("NFC", p) for p in raw_parts if p.strip() not in ("", ".")]
    if not parts:
        raise _Refused("its name is empty once '.' and '/' are removed")
    return parts


def _is_junk(parts: list[str]) -> bool:
    return any(p.startswith(".") or p.casefold() in _JUNK for p in parts)


class NotebookNames:
    """Parses the file-name part of a member against the assignment's notebooks."""

    identifier: Identifier | None = None     # set by collect when it has the release

    def __init__(self, notebooks: list[str]):
        bad = [n for n in notebooks if not n.endswith(".ipynb")]
        if bad or not notebooks:
            raise ValueError(f"notebooks must be file names ending in .ipynb, got {notebooks!r}")
        self.canonical = {n[:-len(".ipynb")].casefold(): n for n in notebooks}
        stems = sorted((n[:-len(".ipynb")] for n in notebooks), key=len, reverse=True)
        alts = "|".join(re.escape(s) for s in stems)
        self.re = re.compile(rf"^(?:(?P<prefix>.+?)_)??(?:copy of\s*)*(?P<nb>{alts}){_SUFFIX}\.ipynb$",
                             re.IGNORECASE)
        # Only to say whose file it was when the notebook part matches nothing.
        self.loose = re.compile(r"^(?P<prefix>.+?)_(?P<nb>\d\d_.*)$")
        self.expected = ", ".join(notebooks)

    def parse(self, base: str) -> tuple[str | None, str, int] | None:
        """(student prefix or None, notebook file name, re-upload counter), or None."""
        m = self.re.match(base)
        if not m:
            return None
        counter = int(m["n1"] or m["n2"] or 0)
        return m["prefix"], self.canonical[m["nb"].casefold()], counter

    def loose_prefix(self, base: str) -> str | None:
        m = self.loose.match(Path(base).stem)
        return m["prefix"] if m else None


# --- reading the download ------------------------------------------------------------------------
@dataclass
class _Entry:
    member: str
    size: int
    mtime: datetime
    read: Callable[[int], bytes]     # read(cap) -> bytes, or raises _Refused
    parts: list[str] = field(default_factory=list)


def _size(n: int) -> str:
    return f"{n / MB:.0f} MB" if n >= MB else f"{n / 1024:.0f} kB" if n >= 1024 else f"{n} bytes"


def _read_capped(f, cap: int) -> bytes:
    """Read at most ``cap`` bytes; a member that inflates past its declared size stops here."""
    chunks, total = [], 0
    while True:
        chunk = f.read(min(MB, cap + 1 - total))
        if not chunk:
            return b"".join(chunks)
        chunks.append(chunk)
        total += len(chunk)
        if total > cap:
            raise _Refused(f"it unpacks to more than {_size(cap)} (a zip bomb, or not a notebook)")


def _zip_name(info: zipfile.ZipInfo) -> str:
    """The member's name as its author meant it: many zip tools write UTF-8 without saying so."""
    name = info.orig_filename
    if not info.flag_bits & 0x800:
        try:
            name = name.encode("cp437").decode("utf-8")
        except (UnicodeEncodeError, UnicodeDecodeError):
            pass
    return name


def _zip_entries(zf: zipfile.ZipFile, rejected: list[str], max_members: int):
    infos = zf.infolist()
    if len(infos) > max_members:
        rejected.append(f"{len(infos) - max_members} archive entries after the first {max_members}: "
                        f"not looked at (too many entries)")
        infos = infos[:max_members]
    for info in infos:
        name = _zip_name(info)
        mode = info.external_attr >> 16
        if info.is_dir() or stat.S_ISDIR(mode):
            continue
        if stat.S_ISLNK(mode):
            rejected.append(f"{name!r}: refused: it is a symbolic link, not a file")
            continue
        if stat.S_IFMT(mode) not in (0, stat.S_IFREG):
            rejected.append(f"{name!r}: refused: it is not a regular file")
            continue
        try:
            when = datetime(*info.date_time)
        except (TypeError, ValueError):
            when = datetime(1980, 1, 1)

        def read(cap, info=info):
            if info.flag_bits & 0x1:
                raise _Refused("it is password-protected in the zip")
            try:
                with zf.open(info) as f:
                    return _read_capped(f, cap)
            except _Refused:
                raise
            except Exception as e:  # noqa: BLE001  bad CRC, truncated archive, unsupported compression
                raise _Refused(f"it could not be read from the zip ({type(e).__name__}: {e})") from None
        yield _Entry(name, info.file_size, when, read)


def _read_file(path: str, cap: int) -> bytes:
    flags = os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_BINARY", 0)
    try:
        fd = os.open(path, flags)
    except OSError as e:
        raise _Refused(f"it could not be opened ({e.strerror})") from None
    with os.fdopen(fd, "rb") as f:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise _Refused("it is not a regular file")
        return _read_capped(f, cap)


def _folder_entries(root: Path, rejected: list[str], max_members: int):
    """Every regular file under ``root``, without following symbolic links."""
    count = 0
    stack: list[tuple[str, tuple[str, ...]]] = [(str(root), ())]
    while stack:
        folder, rel = stack.pop()
        try:
            with os.scandir(folder) as it:
                entries = sorted(it, key=lambda e: e.name)
        except OSError as e:
            rejected.append(f"{'/'.join(rel) or '.'}/: could not be listed ({e.strerror})")
            continue
        for e in entries:
            member = "/".join(rel + (e.name,))
            if e.is_symlink():
                rejected.append(f"{member!r}: refused: it is a symbolic link (never followed)")
            elif e.is_dir(follow_symlinks=False):
                if e.name.startswith(".") or e.name.casefold() in _JUNK:
                    rejected.append(f"{member!r}/: ignored: hidden or system folder")
                elif len(rel) >= 8:
                    rejected.append(f"{member!r}/: ignored: nested too deep")
                else:
                    stack.append((e.path, rel + (e.name,)))
            elif e.is_file(follow_symlinks=False):
                count += 1
                if count > max_members:
                    rejected.append(f"{member!r}: not looked at (more than {max_members} files)")
                    continue
                st = e.stat(follow_symlinks=False)
                yield _Entry(member, st.st_size, datetime.fromtimestamp(st.st_mtime),
                             lambda cap, p=e.path: _read_file(p, cap))
            else:
                rejected.append(f"{member!r}: refused: it is not a regular file")


# --- collect -------------------------------------------------------------------------------------
@dataclass
class _Candidate:
    entry: _Entry
    original: str        # the student id as written (NFC, stripped); "<system>_<LMS id>" in an LMS layout
    notebook: str
    counter: int
    order: int
    lms: lms_layouts.LmsFile | None = None     # in an LMS layout: what the LMS's name says
    by_name: str | None = None     # the notebook its file name names (None: it names none)
    data: bytes | None = None      # read ahead to identify it by content (``_identify``)
    error: str = ""                # why it could not be read, when read ahead
    renamed: str = ""              # why its content, not its name, decided its notebook (said if graded)
    blank: bool = False            # its answers are all as released: a copy of the hand-out, not the work

    def newness(self) -> tuple:
        """Larger is newer: the LMS's own order first (Canvas's file id, Blackboard's attempt
        time), then the file's time, the re-upload counter, the place in the archive."""
        return (self.lms.rank if self.lms else (), self.entry.mtime, self.counter, self.order)

    def short(self) -> str:
        return self.lms.label if self.lms else _short(self.entry)


def collect(submissions: Path, notebooks: list[str], *, release: dict | None = None,
            max_member_bytes: int = MAX_NOTEBOOK_BYTES,
            max_total_bytes: int = MAX_TOTAL_BYTES,
            max_members: int = MAX_MEMBERS) -> Intake:
    """Find each student's upload of each notebook in a class download; read, never extract.

    ``submissions``: the LMS's .zip, or a folder (symbolic links in it are never followed).
    ``notebooks``: the assignment's notebook file names, e.g. ``["01_world_model.ipynb", ...]``.
    ``max_member_bytes``: a file larger than this (as the zip declares it, and as it really
    unpacks) is refused; ``max_total_bytes``: all files read together stop there (zip bombs).

    Rules (every refusal is a line in ``rejected``, and a note for the student when it is clear
    whose file it was):

    * hostile names are refused and never used as paths: absolute (``/x``, ``C:\\x``,
      ``\\\\server\\x``), any ``..``, NUL or control characters, symbolic links;
    * system files (``__MACOSX/``, ``.DS_Store``, ``.ipynb_checkpoints/``, hidden files) are ignored;
    * one top-level folder holding the whole class (student folders, or the flat files of several
      students) is a wrapper and is skipped; deeper nesting than ``<student>/<file>`` is refused;
    * ``<folder>/<other>_02_reward.ipynb``, a file that names a student other than its folder,
      is graded for NOBODY: the folder decides who uploaded it, the name claims someone else, and
      neither can be trusted; the folder's student is told to rename it;
    * several uploads of one notebook by one student: the newest is graded (modification time;
      on a tie the larger re-upload counter, ``(2)`` over ``(1)`` over none; then the later entry
      in the archive); the note names the one graded and those ignored. If the newest cannot be
      read at all (too big, corrupt), the next newest is graded and the note says so;
    * a download in Canvas's, Moodle's or Blackboard's own layout is read by that LMS's ids
      (module docstring; ``Intake.lms``); one that mixes two of them raises ValueError;
    * with ``release`` (``{file name: released notebook}``), every notebook is identified by its
      content (``identify``), so a student's file is graded as what it is whatever it is called:
      ``05_horizon_final.ipynb`` is graded as 05_horizon, a file named 04 that holds 05 as 05. Its
      name decides only where its content does not (a notebook too damaged to tell); a file that
      neither its name nor its content places, and two files that are one notebook by content
      under different names (the newest is graded, but the student's work before a newer copy of
      the hand-out with no answer in it), go to ``Intake.human`` and the student's notes. A flat
      name whose student part cannot be read (``s042_my horizon.ipynb``) is the longest known
      student id's it starts with. A student's files are read newest first, at most
      ``MAX_FILES_PER_NOTEBOOK`` uploads of each notebook, so that no hand-in spends the class's
      byte limit.
    """
    submissions = Path(submissions)
    names = NotebookNames(notebooks)
    names.identifier = Identifier(release) if release else None
    intake = Intake()
    rejected = intake.rejected
    if submissions.is_dir():
        entries = list(_folder_entries(submissions, rejected, max_members))
        return _collect(entries, names, intake, max_member_bytes, max_total_bytes)
    try:
        zf = zipfile.ZipFile(submissions)
    except (zipfile.BadZipFile, OSError) as e:
        raise LayoutError(f"{submissions} is neither a folder nor a readable .zip file ({e})") from None
    with zf:
        entries = list(_zip_entries(zf, rejected, max_members))
        return _collect(entries, names, intake, max_member_bytes, max_total_bytes)


def _collect(entries: list[_Entry], names: NotebookNames, intake: Intake,
             max_member_bytes: int, max_total_bytes: int) -> Intake:
    rejected = intake.rejected
    pending_notes: list[tuple[str, str]] = []   # (student as written, note)
    known: set[str] = set()                     # students as written, who get a report row

    # 1. hostile and system names out
    usable: list[_Entry] = []
    for e in entries:
        try:
            e.parts = _member_parts(e.member)
        except _Refused as why:
            rejected.append(f"{e.member!r}: refused: {why}")
            continue
        if _is_junk(e.parts):
            rejected.append(f"{e.member!r}: ignored: a system or hidden file, not a submission")
            continue
        usable.append(e)

    # 1b. a download in an LMS's own layout (Canvas, Moodle, Blackboard): that LMS's ids decide
    system, wrapped, why = lms_layouts.detect([e.parts for e in usable], names.parse)   # ValueError: two LMSs mixed
    if why:
        intake.warnings.append(why)
    if system:
        return _collect_lms(usable, system, wrapped, names, intake, max_member_bytes, max_total_bytes)

    # 2. a wrapper folder around the whole class?
    tops = {e.parts[0] for e in usable if len(e.parts) > 1}
    if len(tops) == 1 and all(len(e.parts) > 1 for e in usable):
        wrapper = tops.pop()
        inner = [e for e in usable if len(e.parts) == 2]
        claimed = set()
        for e in inner:
            parsed = names.parse(e.parts[1])
            if parsed and parsed[0]:
                try:
                    claimed.add(_id_key(normalise_student_id(parsed[0])))
                except ValueError:
                    pass
        try:
            own = _id_key(normalise_student_id(wrapper))
        except ValueError:
            own = None
        if any(len(e.parts) > 2 for e in usable) or (len(claimed) >= 2 and own not in claimed):
            for e in usable:
                e.parts = e.parts[1:]

    # 3. who and which notebook
    candidates: list[_Candidate] = []
    orphans: list[tuple[int, _Entry]] = []      # flat names with no readable student part (content known)
    for order, e in enumerate(usable):
        parts, base = e.parts, e.parts[-1]
        if len(parts) > 2:
            rejected.append(f"{e.member!r}: refused: nested too deep; expected <student>_<notebook>.ipynb "
                            f"or <student>/<notebook>.ipynb")
            continue
        folder = parts[0].strip() if len(parts) == 2 else None
        if folder is not None:
            try:
                normalise_student_id(folder)
            except ValueError as why:
                rejected.append(f"{e.member!r}: refused: {why}")
                continue
            known.add(unicodedata.normalize("NFC", folder))
        if not base.casefold().endswith(".ipynb"):
            who = folder or names.loose_prefix(base)
            rejected.append(f"{e.member!r}: refused: not a .ipynb notebook file")
            if who:
                pending_notes.append((who, f"{base}: not a .ipynb notebook, not graded. {REDOWNLOAD}"))
            continue
        parsed = names.parse(base)
        if parsed is None and names.identifier is not None and (folder or names.loose_prefix(base)):
            parsed = (None if folder else names.loose_prefix(base), None, 0)     # its content will tell
        if parsed is None and names.identifier is not None and folder is None:
            orphans.append((order, e))        # whose, once every student is known (below)
            continue
        if parsed is None:
            who = folder or names.loose_prefix(base)
            if folder is None and who is None:
                rejected.append(f"{e.member!r}: refused: the name is not <student>_<notebook>.ipynb "
                                f"with a notebook of this assignment ({names.expected})")
            else:
                rejected.append(f"{e.member!r}: refused: names no notebook of this assignment "
                                f"(expected one of {names.expected})")
                pending_notes.append((who, f"{base}: names no notebook of this assignment, not graded; "
                                           f"the notebooks are {names.expected}"))
            continue
        prefix, notebook, counter = parsed
        if folder is None:
            if prefix is None:
                rejected.append(f"{e.member!r}: refused: no student id in the name; expected "
                                f"<student>_{notebook} or <student>/{notebook}")
                continue
            student = prefix
        else:
            student = folder
            if prefix is not None and _same_student(prefix, folder) is False:
                rejected.append(f"{e.member!r}: refused: the file name names student {prefix.strip()!r} but "
                                f"it is in the folder of {folder!r}; graded for nobody")
                pending_notes.append((folder, f"{base}: its name says it belongs to {prefix.strip()!r}, not to "
                                              f"you, so it was not graded for anyone; rename it "
                                              f"{notebook} and upload it again"))
                continue
        original = unicodedata.normalize("NFC", student).strip()
        try:
            normalise_student_id(original)
        except ValueError as why:
            rejected.append(f"{e.member!r}: refused: {why}")
            continue
        if e.size > max_member_bytes:
            rejected.append(f"{e.member!r}: refused: it is {_size(e.size)}, more than the "
                            f"{_size(max_member_bytes)} limit for one file")
            pending_notes.append((original, f"{base}: {_size(e.size)}, too big to be this notebook; "
                                            f"not graded. Clear the outputs, save, and upload it again"))
            known.add(original)
            continue
        known.add(original)
        candidates.append(_Candidate(e, original, notebook, counter, order, by_name=notebook))

    # 3b. a flat name whose student part could not be read (``s042_Copy of Copy of 05_horizon.ipynb``,
    # ``ann_horizon.ipynb``) is the longest known student's whose id, and "_", it starts with; its
    # content tells which notebook. A name that starts with no known id is graded for nobody.
    for order, e in orphans:
        base = e.parts[-1]
        who = max((k for k in known if base.casefold().startswith(k.casefold() + "_")), key=len, default=None)
        if who is None or e.size > max_member_bytes:
            rejected.append(f"{e.member!r}: refused: the name is not <student>_<notebook>.ipynb with a notebook of "
                            f"this assignment ({names.expected}), and it starts with no student's id")
            continue
        candidates.append(_Candidate(e, who, None, 0, order, by_name=None))

    # 4. one folder-safe id per student as written; collisions are told, never merged
    ids = _assign_ids(known, intake)
    # 5. what each file is, by its content; then the newest readable upload of each notebook
    candidates, total = _identify(candidates, ids, names, intake, max_member_bytes, max_total_bytes)
    _pick_newest(candidates, ids, intake, max_member_bytes, max_total_bytes, total=total)
    return _finish(intake, ids, pending_notes)


def _identify(candidates: list[_Candidate], ids: dict[str, str], names: NotebookNames, intake: Intake,
              max_member_bytes: int, max_total_bytes: int, total: int = 0) -> tuple[list[_Candidate], int]:
    """Read every candidate ahead and decide which notebook it is by its content (``identify``;
    ``collect``'s rules); ``total``: bytes already read. Returns the candidates that are some
    notebook (``notebook`` set: by content where it tells, else by name) and the bytes read."""
    if names.identifier is None:
        return candidates, total
    kept = []
    # One student's files are read newest first, within a budget of their own: as many files, and as
    # many bytes, as MAX_FILES_PER_NOTEBOOK uploads of each notebook, so that no hand-in can spend the
    # class's byte limit (which, read ahead, would leave later students' notebooks unread).
    per_files = MAX_FILES_PER_NOTEBOOK * len(names.canonical)
    per_bytes = per_files * max_member_bytes // MAX_FILES_PER_NOTEBOOK
    spent: dict[str, list[int]] = {}
    order = {id(c): i for i, c in enumerate(candidates)}
    for c in sorted(candidates, key=lambda c: (ids[c.original], c.newness()), reverse=True):
        base, sid = _base(c), ids[c.original]
        files, used = spent.setdefault(sid, [0, 0])
        if files >= per_files or used + c.entry.size > per_bytes:
            c.error = (f"this hand-in has more files than {MAX_FILES_PER_NOTEBOOK} uploads of each notebook "
                       f"({per_files} files, {_size(per_bytes)}): only the newest were read")
        elif total + c.entry.size > max_total_bytes:
            c.error = f"the class download passed the {_size(max_total_bytes)} limit for all files together"
        else:
            spent[sid] = [files + 1, used + c.entry.size]
            try:
                c.data = c.entry.read(min(max_member_bytes, max_total_bytes - total))
                total += len(c.data)
            except _Refused as why:
                c.error = str(why)
        match, nb = None, None
        if c.data is not None:
            try:
                nb = decode_notebook(c.data, max_member_bytes)
                match = names.identifier.identify(nb)
            except ValueError:
                pass                          # prepare tells the student why it cannot be read
        if match is not None and match.notebook and match.notebook != c.by_name:
            c.notebook = match.notebook
            if c.by_name is None:
                c.counter = reupload(base)[1]     # "_final (2)" is newer than "_final" on a tie
                c.renamed = f"its name names no notebook of this assignment, but {match.words()}"
            else:
                c.renamed = f"its name says {c.by_name}, but {match.words()}"
        elif c.by_name is None:
            if c.error:
                why = f"it could not be read ({c.error})"
            elif match is None:
                why = "it is not a notebook that can be read (decoding failed)"
            else:
                why = match.words()
            intake.rejected.append(f"{c.entry.member!r}: refused: names no notebook of this assignment, and by "
                                   f"its content it is none of them either: {why}")
            intake.notes.setdefault(sid, []).append(
                f"{base}: not graded: its name names no notebook of this assignment and {why}; the notebooks "
                f"are {names.expected}. Upload the notebook you worked in, as it was released")
            intake.human.append({"student": sid, "file": base, "graded": None, "why": why})
            continue
        elif match is not None and not match.notebook:      # its content places it nowhere, or two places
            why = f"its name says {c.by_name}, but {match.words()}"
            intake.notes.setdefault(sid, []).append(f"{base}: graded as {c.by_name} by its name only: {why}; "
                                                    f"if this is not the notebook you worked in, upload that one")
            intake.human.append({"student": sid, "file": base, "graded": c.by_name,
                                 "why": why + ": check it is the notebook the student meant"})
        if nb is not None and c.notebook:
            c.blank = names.identifier.unworked(nb, c.notebook)
        kept.append(c)
    kept.sort(key=lambda c: order[id(c)])
    return kept, total


def _pick_newest(candidates: list[_Candidate], ids: dict[str, str], intake: Intake,
                 max_member_bytes: int, max_total_bytes: int, total: int = 0) -> dict[tuple[str, str], _Candidate]:
    """Grade the newest readable upload of each student's notebook (``_Candidate.newness``);
    the note names the one graded and those ignored. ``total``: bytes already read from the
    download. Returns {(student id, notebook): graded}."""
    rejected = intake.rejected
    groups: dict[tuple[str, str], list[_Candidate]] = {}
    for c in candidates:
        groups.setdefault((ids[c.original], c.notebook), []).append(c)
    chosen = {}
    for (sid, notebook), group in sorted(groups.items()):
        # the student's work before a copy of the hand-out (``blank``), then the newest
        group.sort(key=lambda c: (not c.blank, c.newness()), reverse=True)
        graded, failed = None, []
        for c in group:
            if c.data is not None or c.error:        # read ahead by _identify
                if c.data is not None:
                    graded = (c, c.data)
                    break
                why = c.error
            elif total + c.entry.size > max_total_bytes:
                why = f"the class download passed the {_size(max_total_bytes)} limit for all files together"
            else:
                try:
                    data = c.entry.read(min(max_member_bytes, max_total_bytes - total))
                    total += len(data)
                    graded = (c, data)
                    break
                except _Refused as e:
                    why = str(e)
            rejected.append(f"{c.entry.member!r}: refused: {why}")
            failed.append(f"{c.short()} could not be read ({why})")
        notes = intake.notes.setdefault(sid, [])
        if graded is None:
            notes.append(f"{notebook}: not graded: " + "; ".join(failed))
            continue
        c, data = graded
        chosen[(sid, notebook)] = c
        if c.renamed:                  # graded as what it holds (_identify): said to the student and to a human
            intake.notes.setdefault(sid, []).append(f"{_base(c)}: graded as {notebook}: {c.renamed}")
            if len({_stem(x) for x in group}) == 1:      # else the entry for two files of one notebook says it
                intake.human.append({"student": sid, "file": _base(c), "graded": notebook, "why": c.renamed})
        intake.students.setdefault(sid, {})[notebook] = Upload(data, c.entry.member, c.entry.mtime)
        ignored = group[group.index(c) + 1:]     # older than the graded one
        if len(group) > 1:
            newest = "the newest" if c.lms is None else lms_plugin(c.lms.system).newest
            blanks = [x for x in group if x.blank and x is not c]
            if not c.blank and any(x.newness() > c.newness() for x in blanks):
                newest = ("the newest that holds answers; " + ", ".join(x.short() for x in blanks)
                          + " holds the notebook as handed out, with no answer in it")
            line = f"{notebook}: {len(group)} uploads; graded {c.short()}, {newest}"
            if failed:
                line += " that could be read; " + "; ".join(failed)
            if ignored:
                line += "; ignored the older " + ", ".join(x.short() for x in ignored)
            notes.append(line)
            if len({_stem(x) for x in group}) > 1:   # differently named files, one notebook by content
                intake.human.append({"student": sid, "file": ", ".join(_base(x) for x in group), "graded": notebook,
                                     "why": f"{len(group)} files are {notebook} by their content; {_base(c)} was "
                                            f"graded ({newest}): check it is the one the student meant"})
    return chosen


def _base(c: _Candidate) -> str:
    return c.lms.original if c.lms else c.entry.parts[-1]


_REUPLOAD = re.compile(rf"^(?:copy of\s*)*(?P<stem>.*?){_SUFFIX}(?:\.ipynb)?$", re.IGNORECASE)


def reupload(base: str) -> tuple[str, int]:
    """(the name less an upload's re-upload marks, its counter): ``Copy of x (2).ipynb`` -> ("x", 2),
    as ``NotebookNames.parse`` reads a notebook's name, for any name."""
    m = _REUPLOAD.match(base.strip())
    return m["stem"].strip().casefold(), int(m["n1"] or m["n2"] or 0)


def _stem(c: _Candidate) -> str:
    """One name for a file and its re-uploads: the notebook its name names, else its own name less
    the re-upload marks (``05_horizon_final-1.ipynb`` and ``05_horizon_final.ipynb`` are one)."""
    return c.by_name or reupload(_base(c))[0]


def _finish(intake: Intake, ids: dict[str, str], pending_notes: list[tuple[str, str]]) -> Intake:
    """Every student the download names gets a row (and their notes), in order."""
    for who, note in pending_notes:
        sid = ids.get(unicodedata.normalize("NFC", who).strip())
        if sid:
            intake.notes.setdefault(sid, []).append(note)
    for sid in ids.values():
        intake.students.setdefault(sid, {})
        intake.notes.setdefault(sid, [])
    intake.students = dict(sorted(intake.students.items()))
    intake.notes = dict(sorted(intake.notes.items()))
    intake.lms = dict(sorted(intake.lms.items()))
    return intake


def _collect_lms(usable: list[_Entry], system: str, wrapped: bool, names: NotebookNames, intake: Intake,
                 max_member_bytes: int, max_total_bytes: int) -> Intake:
    """A download in ``system``'s own layout (``lms_layouts``): the LMS's id of each student decides
    whose a file is; their folder-safe id is ``<system>_<LMS id>`` (``canvas_12345``,
    ``moodle_1234567``, ``blackboard_jdoe``), the same in every download of the assignment, since
    names can change in the LMS and ids cannot; their LMS identity goes to ``Intake.lms``."""
    rejected = intake.rejected
    title = lms_layouts.TITLE[system]
    pending_notes: list[tuple[str, str]] = []
    files_of: dict[str, list[lms_layouts.LmsFile]] = {}    # "<system>_<LMS id>" -> their files
    candidates: list[_Candidate] = []

    read_so_far = 0                                 # receipts count towards the class's byte limit

    def read_text(i: int) -> bytes:
        nonlocal read_so_far
        size = usable[i].size
        if size > lms_layouts.RECEIPT_BYTES:
            raise ValueError(f"it is {_size(size)}, more than a receipt can be")
        if read_so_far + size > max_total_bytes:
            raise ValueError(f"the class download passed the {_size(max_total_bytes)} limit for all files together")
        try:
            data = usable[i].read(min(lms_layouts.RECEIPT_BYTES, max_total_bytes - read_so_far))
        except _Refused as why:
            raise ValueError(str(why)) from None
        read_so_far += len(data)
        return data

    members = [e.parts[1:] if wrapped else e.parts for e in usable]
    found, warnings = lms_layouts.read(system, members, names.parse, read_text)
    intake.warnings += warnings
    for order, (e, f) in enumerate(zip(usable, found)):
        if isinstance(f, str):
            rejected.append(f"{e.member!r}: refused: {f}")
            continue
        who = f"{system}_{f.lms_id}"
        try:
            normalise_student_id(who)
        except ValueError as why:
            rejected.append(f"{e.member!r}: refused: {why}")
            continue
        files_of.setdefault(who, []).append(f)
        if f.made_by_lms == "receipt":             # read: its name and date are in the student's record
            if f.receipt.get("error"):
                rejected.append(f"{e.member!r}: refused: a {title} receipt that could not be read "
                                f"({f.receipt['error']})")
            continue
        if f.original is None:
            rejected.append(f"{e.member!r}: refused: {title} made it for a {f.made_by_lms}, not a notebook")
            pending_notes.append((who, f"a {f.made_by_lms} ({f.label}): not a .ipynb notebook, not graded. "
                                       f"{REDOWNLOAD}"))
            continue
        base = f.original
        if f.claims:
            rejected.append(f"{e.member!r}: refused: it is {title} user {f.lms_id}'s upload, but its own name "
                            f"{base!r} is how {title} names a file of {title} user {f.claims}; graded for nobody")
            pending_notes.append((who, f"{base}: its name says it belongs to {title} user {f.claims}, not to you, "
                                       f"so it was not graded for anyone; rename it to the notebook's name "
                                       f"and upload it again"))
            continue
        if not base.casefold().endswith(".ipynb"):
            rejected.append(f"{e.member!r}: refused: not a .ipynb notebook file")
            pending_notes.append((who, f"{base}: not a .ipynb notebook, not graded. {REDOWNLOAD}"))
            continue
        parsed = names.parse(base)
        if parsed is None and names.identifier is not None:
            parsed = (None, None, 0)                  # its content will tell
        if parsed is None:
            rejected.append(f"{e.member!r}: refused: names no notebook of this assignment "
                            f"(expected one of {names.expected})")
            pending_notes.append((who, f"{base}: names no notebook of this assignment, not graded; "
                                       f"the notebooks are {names.expected}"))
            continue
        _prefix, notebook, counter = parsed      # the student's own prefix: their naming, not who they are
        if e.size > max_member_bytes:
            rejected.append(f"{e.member!r}: refused: it is {_size(e.size)}, more than the "
                            f"{_size(max_member_bytes)} limit for one file")
            pending_notes.append((who, f"{base}: {_size(e.size)}, too big to be this notebook; "
                                       f"not graded. Clear the outputs, save, and upload it again"))
            continue
        candidates.append(_Candidate(e, who, notebook, counter, order, lms=f, by_name=notebook))

    ids = _assign_ids(set(files_of), intake)
    candidates, read_so_far = _identify(candidates, ids, names, intake, max_member_bytes, max_total_bytes,
                                        total=read_so_far)
    chosen = _pick_newest(candidates, ids, intake, max_member_bytes, max_total_bytes, total=read_so_far)
    for who, sid in ids.items():
        graded = [c.lms for (s, _), c in chosen.items() if s == sid]
        record, notes = lms_layouts.summarise(system, files_of[who], graded)
        # Canvas: each graded notebook's own upload, for returning its page under its name (lms_feedback);
        # None for an LMS that returns no page by its upload
        record["attachment_ids"] = lms_plugin(system).notebook_ids(
            [(nb, c.lms) for (s, nb), c in sorted(chosen.items()) if s == sid])
        intake.lms[sid] = record
        intake.notes.setdefault(sid, [])[:0] = notes
    return _finish(intake, ids, pending_notes)


def _same_student(a: str, b: str) -> bool:
    try:
        return _id_key(normalise_student_id(a)) == _id_key(normalise_student_id(b))
    except ValueError:
        return False


def _short(e: _Entry) -> str:
    return f"{e.member!r} ({e.mtime:%Y-%m-%d %H:%M:%S})"


def _assign_ids(originals: set[str], intake: Intake) -> dict[str, str]:
    """{student as written: folder-safe id}. When different ids would make the same folder, the
    one already folder-safe (else the first in alphabetical order) keeps it, the others get
    ``~2``, ``~3``... (``~`` never appears in a normalised id, so these cannot collide)."""
    by_key: dict[str, list[str]] = {}
    for o in originals:
        by_key.setdefault(_id_key(normalise_student_id(o)), []).append(o)
    ids = {}
    for group in by_key.values():
        group.sort(key=lambda o: (normalise_student_id(o) != o, o))
        base = normalise_student_id(group[0])
        for i, o in enumerate(group):
            sid = base if i == 0 else f"{base}~{i + 1}"
            ids[o] = sid
            intake.display_names[sid] = o
            notes = intake.notes.setdefault(sid, [])
            if len(group) > 1:
                others = ", ".join(repr(x) for x in group if x != o)
                notes.append(f"student id {o!r} and {others} would be the same folder {base!r}; they are "
                             f"graded as different students, this one as {sid!r}: check that this is right")
            if len(o) > MAX_ID_CHARS or len(o.encode("utf-8")) > MAX_ID_BYTES:
                notes.append(f"student id {o!r} is longer than {MAX_ID_CHARS} characters; graded as {sid!r}")
    _note_lookalikes(ids, intake)
    return ids


def _skeleton_function() -> tuple[Callable[[str], set[str]] | None, str]:
    """(text -> its UTS #39 skeletons, "") or (None, why PyICU cannot be used).

    The skeleton is ICU's (``SpoofChecker.getSkeleton``; its first argument has been ignored since
    ICU 58, which has one table for all scripts). Two strings that look the same have the same
    skeleton: ``vіctim2`` (Cyrillic і) and ``victim2``, ``bοb`` (Greek omicron) and ``bob``,
    ``rn`` and ``m``, ``l``, ``I`` and ``1``. Two steps that ICU 72's getSkeleton leaves out are
    added: Default_Ignorable characters are removed first (zero-width space, soft hyphen:
    invisible, so ``vic<U+200B>tim2`` looks like ``victim2``; the skeleton of the current UTS #39
    removes them too), and the skeleton of the NFKC form is taken as well (fullwidth ``ｖｉｃｔｉｍ２``,
    superscript ``²``: compatibility variants that the confusables data mostly leaves to NFKC).
    The import is here, not at the top, so that intake works (and says so) without PyICU.
    """
    try:
        import icu
    except ImportError as e:
        return None, f"{type(e).__name__}: {e}"
    checker = icu.SpoofChecker()
    ignorable = icu.UnicodeSet("[:Default_Ignorable_Code_Point:]")

    def skeletons(text: str) -> set[str]:
        visible = "".join(c for c in text if not ignorable.contains(c))
        return {checker.getSkeleton(0, visible),
                checker.getSkeleton(0, unicodedata.normalize("NFKC", visible))}
    return skeletons, ""


def _spelled(o: str) -> str:
    """An id for a note: as written, and when it holds anything beyond printable ASCII, each
    character again with the code point of every one that is not: 'vіctim2' (v U+0456 c t i m 2)."""
    if all(" " <= c < "\x7f" for c in o):
        return repr(o)
    return f"{o!r} (" + " ".join(c if " " < c < "\x7f" else f"U+{ord(c):04X}" for c in o) + ")"


def _note_lookalikes(ids: dict[str, str], intake: Intake) -> None:
    """Ids that look the same but are different students: a note for each, naming the others.

    Two ids (as the LMS wrote them, NFC) look alike when a skeleton (:func:`_skeleton_function`)
    of one equals one of the other's, or when their folder-safe forms do (``vіctim 2`` and
    ``victim_2`` differ by a space in report.csv but are two identical-looking folders). Not
    noted: ids that become one folder (:func:`_assign_ids` has already said so), and ids that
    differ by a visible accent (``Zoë`` and ``Zoe``, ``José`` and ``Jose``): UTS #39 keeps
    accents in the skeleton, and such ids are usually two real students with similar names. Ids
    only alike through different skeletons are not chained: ``ſam`` (long s) looks like ``fam``
    and like ``sam``, but ``fam`` and ``sam`` do not look alike. One NFC id is one student
    already (composed and decomposed ``Chloé``), never two.
    """
    skeletons, why = _skeleton_function()
    if skeletons is None:
        intake.lookalikes_checked = False
        intake.warnings.append(LOOKALIKES_NOT_CHECKED.format(why=why))
        return
    folder = {o: normalise_student_id(o) for o in ids}
    by_skeleton: dict[str, set[str]] = {}
    for o in ids:
        for k in skeletons(o) | skeletons(folder[o]):
            by_skeleton.setdefault(k, set()).add(o)
    alike: dict[str, set[str]] = {}
    for group in by_skeleton.values():
        for o in group:
            alike.setdefault(o, set()).update(
                x for x in group if _id_key(folder[x]) != _id_key(folder[o]))
    for o in sorted(ids):
        others = sorted(alike.get(o, ()))
        if others:
            intake.notes.setdefault(ids[o], []).append(
                f"student id {_spelled(o)} looks like {' and '.join(_spelled(x) for x in others)} "
                f"(characters that look alike, Unicode UTS #39); they are graded as different students, "
                f"this one as {ids[o]!r}: check in the LMS that these are different real students and "
                f"not one posing as another; the id as the LMS wrote it, character by character, "
                f"decides who is who")
    intake.lookalikes_checked = True


# --- decode --------------------------------------------------------------------------------------
_BOMS = [(codecs.BOM_UTF32_LE, "utf-32-le"), (codecs.BOM_UTF32_BE, "utf-32-be"),
         (codecs.BOM_UTF8, "utf-8"), (codecs.BOM_UTF16_LE, "utf-16-le"), (codecs.BOM_UTF16_BE, "utf-16-be")]


def _magic_hint(data: bytes) -> str:
    head = data.lstrip()[:16]
    if head.startswith(b"PK\x03\x04"):
        return "it is a zip archive, not a notebook"
    if head.startswith(b"%PDF"):
        return "it is a PDF, not a notebook"
    if head.startswith((b"\x89PNG", b"\xff\xd8\xff", b"GIF8")):
        return "it is an image, not a notebook"
    if head[:1] == b"<":
        return "it is a web page (HTML), not a notebook: the browser saved the page, not the file"
    return ""


def _detect_encoding(data: bytes) -> tuple[str, bytes]:
    """(encoding, bytes without BOM): a byte-order mark, else the pattern of NUL bytes around the
    first character (a notebook starts with '{' or a space, plain ASCII), else UTF-8."""
    for bom, enc in _BOMS:
        if data.startswith(bom):
            return enc, data[len(bom):]
    h = data[:4]
    if len(h) == 4 and h[:3] == b"\0\0\0" and h[3]:
        return "utf-32-be", data
    if len(h) == 4 and h[0] and h[1:] == b"\0\0\0":
        return "utf-32-le", data
    if len(h) >= 2 and h[0] == 0 and h[1]:
        return "utf-16-be", data
    if len(h) >= 2 and h[0] and h[1] == 0:
        return "utf-16-le", data
    return "utf-8", data


def _parse(text: str) -> nbformat.NotebookNode:
    """The notebook in ``text``, or ValueError saying what is wrong with it."""
    text = text.lstrip("\ufeff")
    try:
        obj = json.loads(text)
    except json.JSONDecodeError as e:
        raise ValueError(f"it is not valid JSON (line {e.lineno}, column {e.colno}: {e.msg})") from None
    except RecursionError:
        raise ValueError("it is JSON nested too deep to be a notebook") from None
    if not isinstance(obj, dict) or "nbformat" not in obj:
        raise ValueError("it is JSON but not a Jupyter notebook (no 'nbformat' field)")
    version = obj.get("nbformat")
    if not isinstance(version, int) or not 1 <= version <= 4:
        raise ValueError(f"it says it is notebook format {version!r}; this course reads formats 1 to 4")
    try:
        return nbformat.reads(text, as_version=4)
    except Exception as e:  # noqa: BLE001  schema or conversion problems: not a notebook we can grade
        raise ValueError(f"it is not a readable notebook ({type(e).__name__}: {str(e)[:120]})") from None


def decode_notebook(data: bytes, max_bytes: int = MAX_NOTEBOOK_BYTES) -> nbformat.NotebookNode:
    """The notebook in an uploaded file, as nbformat 4, or ValueError with a message for the student.

    Read as UTF-8 (with or without a byte-order mark), UTF-16 or UTF-32 (little or big endian,
    with or without a byte-order mark, told apart by where the NUL bytes are), and, only when
    none of these works, as Windows-1252 or Latin-1 if that gives a notebook. Old notebooks
    (format 3 and before) are converted. The message of the ValueError says what the file is
    instead (empty, HTML, PDF, zip, not JSON, JSON but not a notebook, too big) and ends with
    what to do about it.
    """
    try:
        if len(data) > max_bytes:
            raise ValueError(f"the file is {_size(len(data))}, more than the {_size(max_bytes)} a "
                             f"notebook can be; clear the outputs (Edit > Clear all outputs), save")
        if not data.strip():
            raise ValueError("the file is empty")
        enc, body = _detect_encoding(data)
        try:
            text = body.decode(enc)
        except UnicodeDecodeError:
            if enc != "utf-8":
                raise ValueError(f"it looks like {enc.upper()} text but is not valid {enc.upper()}") from None
            hint = _magic_hint(data)
            if hint:
                raise ValueError(hint) from None
            for legacy in ("cp1252", "latin-1"):
                try:
                    return _parse(body.decode(legacy))
                except (UnicodeDecodeError, ValueError):
                    pass
            raise ValueError("it is not text in a known encoding (UTF-8, UTF-16, UTF-32)") from None
        try:
            return _parse(text)
        except ValueError as e:
            hint = _magic_hint(data)
            raise ValueError(hint or str(e)) from None
    except ValueError as e:
        raise ValueError(f"not a notebook: {e}. {REDOWNLOAD}") from None
