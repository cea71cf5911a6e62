"""Blackboard Learn (Original courses): its download read, its students named, its feedback folder; no import file.

Its download
------------
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

Inferred where the sources are silent:

* the assignment name is the same in every file of a download; it is what is left of
  the name before ``_<username>`` when a receipt names the username (the ``(username)`` at the
  end of its first line), else the longest ``_``-separated start that all files share (with a
  single student, the username is then the last ``_`` part, as BBGradebookOrganiser assumes).
  The time in the name is the attempt's, in the server's time zone, which is not written:
  ``submitted_at`` is that local time without a zone (the receipt's own "Date Submitted" when it
  can be read, English month names only). ``attempt`` counts the attempts *in this download*,
  oldest first: a download of the last attempts only has attempt 1 everywhere. Nothing marks an
  attempt late: ``late`` is None. Of several attempts, each notebook is graded from the latest
  attempt that holds it. Blackboard Ultra's downloads are named differently and are not read.

Its import file
---------------
None is written: ``grades.csv`` has every score, and Blackboard's Grade Center takes them by hand
or by its own upload (Work Offline > Upload, keyed by the student's user name).

Its feedback package
--------------------
**Blackboard Learn, Original courses.** No bulk return of feedback files was found: Anthology's
help pages describe feedback files attached one attempt at a time on the Grade Attempt page
(https://help.blackboard.com/Learn/Instructor/Grade/Grading_Tasks/Assign_Grades) and a bulk upload
of *grades* only (Work Offline > Upload: "The unique identifier used for each Student is the
Student's User Name", http://library.blackboard.com/ref/3ea64795-6ecc-4abd-b595-0a9a8dfdec94/Content/_instructor_grade_center/grade_center_upload_download.htm).
Blackboard's code is closed, so this is what could be verified, not a proof. The package is a
folder of ``<username>_summary.html`` and ``<username>_<notebook>.html`` (and the same as a zip),
with README.txt saying to attach them on each student's attempt (Grade Center > the column >
View Grade Details > Grade Attempt > Attach File).
"""

from __future__ import annotations

import re
from collections import Counter
from datetime import datetime
from typing import Callable

from ..text import ident
from .base import Lms, LmsFile, NotebookParser, StudentReturn, safe_id

FEEDBACK_ZIP = "blackboard_feedback.zip"
FEEDBACK_DIR = "blackboard_feedback"


# --- its download ---------------------------------------------------------------------------------
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


# --- one student's record -------------------------------------------------------------------------
def _t(when: datetime) -> str:
    return f"{when:%Y-%m-%d %H:%M:%S}"


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


# --- its feedback package -------------------------------------------------------------------------
def blackboard_entries(r: StudentReturn) -> list[tuple[str, bytes]] | str:
    user = ident(((r.lms or {}).get("ids") or {}).get("username"))
    if user is None or not safe_id(user) or user.startswith((".", "~")):
        return f"no Blackboard username usable as a file name ({user!r})"
    return [(f"{user}_{file}", data) for file, data in r.files()]


FEEDBACK_README = [
    "  Blackboard Learn Original has no bulk upload of feedback files: for each student, Grade Center >",
    "  the assignment's column > View Grade Details > Grade Attempt > Feedback to Learner > attach",
    "  <username>_summary.html and their <username>_<notebook>.html pages."]


class Blackboard(Lms):
    """Blackboard Learn Original, behind the protocol of ``base.Lms``: no import file."""
    name, title, id_key = "blackboard", "Blackboard", "username"
    newest = "from the latest attempt that holds it"
    no_import = ("Blackboard: no import file is written (grades.csv has every score; Blackboard's "
                 "Grade Center takes them by hand or by its own upload)")
    feedback_zip, feedback_folder = FEEDBACK_ZIP, FEEDBACK_DIR

    def looks_like(self, parts, parse_notebook):
        return bool(len(parts) == 1 and _BB.match(parts[0]))

    def read(self, members, parse_notebook, read_text):
        return _read_blackboard(members, parse_notebook, read_text)

    def summarise(self, files, graded, newest):
        return _blackboard_summary(files, graded, newest.lms_id)

    def feedback_entries(self, r: StudentReturn):
        return blackboard_entries(r)

    def feedback_readme(self, n):
        return [f"== {FEEDBACK_DIR}/ ({FEEDBACK_ZIP}): {n} students ==", *FEEDBACK_README, ""]


BLACKBOARD = Blackboard()
