"""Feedback returned the way the LMS of the download takes it back: one package per LMS, one summary page per student.

    from autograde.lms_feedback import write_feedback_return
    paths = write_feedback_return(course, report)   # at the end of grade_class, after the feedback pages

    python -m autograde.lms_feedback [--course DIR]  # again, on a course already graded (after manual_grade)

Grading writes nbgrader's feedback pages, one per student per notebook
(``<course>/feedback/<student>/<assignment>/<notebook>.html``), and nothing returns them. This
module writes, under ``<course>/feedback_return/``, what each LMS takes back in one upload, for
the LMS the download came from (``report[s]["lms"]["system"]``, filled by ``intake`` from the
download's own names, ``lms_layouts.summarise``), and nothing for an LMS no student came from:

* ``canvas_feedback_upload.zip``: for Canvas's *Re-Upload Submissions* (Grades or the assignment
  page > Re-Upload Submissions);
* ``moodle_feedback_files.zip``: for Moodle's *Upload multiple feedback files in a zip* (the
  assignment's View all submissions > Grading action; Feedback types > Feedback files on);
* ``blackboard_feedback/`` and ``blackboard_feedback.zip``: one file per student and page, named by
  Blackboard username, to attach by hand (Blackboard Learn Original has no bulk return);
* ``feedback_by_student.zip``: ``<student id>/...`` folders for every student no LMS package can
  address (a generic ``<student>_<notebook>.ipynb`` download, an anonymous Canvas assignment, an
  id two students claim);
* ``README.txt``: for the instructor: how to upload each file, who is in which, who is not and why;
* ``report.json``: the per-student report these were made from, so that
  ``python -m autograde.lms_feedback`` can make them again after hand grading without grading.

Each student gets ``summary.html`` (name and id, total and maximum, each notebook's points, each
note and hint, each failing test's hint, the hand-graded comments of ``manual_grades.csv``, and the
list of their notebook pages, or why there are none) plus the notebook pages as grading made them.
Scores come from the gradebook, read as the import files read it (``lms_export.read_standings``:
an answer still to be graded by hand is "not graded yet", never 0) and per cell as the class report
reads it (``class_report.gradebook_rows``). A note meant for the instructor (``for the
instructor`` in it, as ``gradescope`` also leaves out) is not on the student's page; README.txt
counts them.

The page is safe to open: every string a student could have made (their name, a note quoting
their file, a comment) is escaped with the class report's ``page_text`` (control and invisible
characters spelled as code points); no script; the first element of ``<head>`` is the class
report's Content-Security-Policy (no script, no fetch, no form); readable on a phone (viewport
meta, no fixed widths) and in dark mode (``prefers-color-scheme``). Every zip is written whole to
a temporary file, then renamed over the old one.

What each LMS takes back, and where that was read
-------------------------------------------------

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
numbers Canvas's *Download Submissions* writes (``lms_layouts``: ``<name>[_LATE]_<user id>_<file
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

import argparse
import json
import os
import shutil
import stat
import sys
import tempfile
import time
import unicodedata
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

from .class_report import CSP, display_name, gradebook_rows, hint_of, page_text
from .course import ASSIGNMENT, COURSE_DIR, NOTEBOOKS
from .files import read_capped
from .gradebook import read_manual
from .lms_export import lms_record, lms_settings, read_standings
from .lms_layouts import MOODLE_FLAT, TITLE, canvas_splits, word_char
from .text import ident, num, write_atomic

RETURN_DIR = "feedback_return"
CANVAS_ZIP = "canvas_feedback_upload.zip"
MOODLE_ZIP = "moodle_feedback_files.zip"
BLACKBOARD_DIR = "blackboard_feedback"
BLACKBOARD_ZIP = "blackboard_feedback.zip"
GENERIC_ZIP = "feedback_by_student.zip"
README = "README.txt"
REPORT_JSON = "report.json"
SUMMARY = "summary.html"
PACKAGES = {"canvas": CANVAS_ZIP, "moodle": MOODLE_ZIP, "blackboard": BLACKBOARD_ZIP}
MAX_PAGE_BYTES = 32 << 20            # a feedback page read from disk, at most (pages are capped far below)
INSTRUCTOR_ONLY = "for the instructor"
MOODLE_PLUGIN = "assignsubmission_file"
NAME_CHARS = 60                      # of a student's name in a member name (the ids decide, the name only reads)
MOODLE_DROPPED = "&<>\"`|':\\/"   # what Moodle's clean_param(PARAM_FILE) removes from a file name


@dataclass
class StudentReturn:
    """One student's files: the summary first, then the notebook pages ({file name: its path}, read
    only when a package is written, one at a time, so a large class is never all in memory)."""
    student: str
    lms: dict | None
    summary: bytes
    pages: dict[str, Path] = field(default_factory=dict)
    withheld: int = 0                 # notes for the instructor left off the page

    def files(self) -> list[tuple[str, bytes | Path]]:
        return [(SUMMARY, self.summary), *sorted(self.pages.items())]


# --- the summary page -----------------------------------------------------------------------------
STYLE = """
:root { color-scheme: light dark; }
body { font: 16px/1.5 system-ui, -apple-system, "Segoe UI", sans-serif; margin: 0 auto; max-width: 50em;
       padding: 1em; color: #1d1d1d; background: #fff; overflow-wrap: anywhere; }
h1 { font-size: 1.5em; margin: .2em 0 .4em; } h2 { font-size: 1.2em; margin-top: 1.6em; border-bottom: 1px solid #ccc; }
table { border-collapse: collapse; width: 100%; margin: .5em 0; }
td, th { border: 1px solid #ccc; padding: .3em .5em; text-align: left; vertical-align: top; }
th { background: #f2f2f2; } td.num { text-align: right; white-space: nowrap; }
.total { font-size: 1.25em; font-weight: bold; } .muted { color: #555; }
bdi.id, code { font-family: ui-monospace, monospace; background: #f2f2f2; padding: 0 .2em; }
li { margin: .25em 0; } .comment { white-space: pre-wrap; }
@media (prefers-color-scheme: dark) {
  body { color: #e6e6e6; background: #141414; } th, bdi.id, code { background: #2a2a2a; }
  td, th { border-color: #555; } h2 { border-color: #555; } .muted { color: #b0b0b0; }
}
"""


def _who(student: str, lms: dict | None, name: str | None = None) -> str:
    name = name or (lms or {}).get("name")
    lms_ids = ""
    if lms:
        ids = lms.get("ids") or {}
        pairs = [(k, ids.get(k)) for k in ("user_id", "participant_id", "username") if ids.get(k)]
        lms_ids = ", ".join(f"{TITLE.get(lms['system'], lms['system'])} {k.replace('_', ' ')} "
                          f"<bdi class=\"id\">{page_text(v, 128)}</bdi>" for k, v in pairs)
    head = f"<bdi>{page_text(name, 200)}</bdi> " if name else ""
    return (f'{head}(student id <bdi class="id">{page_text(student, 128)}</bdi>' + (f"; {lms_ids}" if lms_ids else "") + ")")


def _summary(student: str, rep: dict, standing, total, cells: list, manual: dict, pages: list[str],
             why_no_pages: str | None) -> tuple[bytes, int]:
    """(the page, how many instructor notes were left off)."""
    lms = lms_record(rep)
    notes = [n if isinstance(n, str) else str(n) for n in (rep.get("notes") or ())]
    withheld = sum(INSTRUCTOR_ONLY in n for n in notes)
    notes = [n for n in notes if INSTRUCTOR_ONLY not in n]
    out = [f"<h1>Feedback: {page_text(ASSIGNMENT)}</h1>", f"<p>{_who(student, lms, display_name(rep))}</p>"]

    # total
    pending = standing.pending if standing else []
    if standing is None or total is None:
        out.append('<p class="total">No score yet: the course has no gradebook entry for you.</p>')
    else:
        out.append(f'<p class="total">Total: {num(standing.points)} of {num(total)} points</p>')
        lms_max = lms_settings()[0]["points_possible"]
        if lms_max and total and lms_max != total:
            out.append(f"<p>In the LMS, where the assignment is out of {num(lms_max)}: "
                       f"{num(standing.points * lms_max / total)} of {num(lms_max)}.</p>")
        if pending:
            out.append(f"<p>{num(standing.pending_points)} point{'s' * (standing.pending_points != 1)} "
                       f"of answers graded by hand {'are' if len(pending) > 1 else 'is'} not graded yet and not "
                       f"counted above (never as 0): " + "; ".join(f"{page_text(nb)} {page_text(g)}" for nb, g, _ in pending)
                       + ".</p>")
        if standing.notes:
            out.append("<ul>" + "".join(f"<li>{page_text(n, 2000)}</li>" for n in standing.notes) + "</ul>")

    # files whose names did not say what they are (intake.Intake.human): said first, not buried in the notes
    files = [h for h in rep.get("human") or () if isinstance(h, dict)]
    if files:
        out.append('<h2>Your files</h2><p>Files whose names did not settle which notebook they are, and what '
                   'became of each (every file is read for what it holds):</p><ul class="files">' + "".join(
                       f"<li><code>{page_text(h.get('file'), 300)}</code>: "
                       + (f"graded as <code>{page_text(h['graded'])}</code>" if h.get("graded") else "<strong>not graded</strong>")
                       + f" ({page_text(h.get('why'), 600)})</li>" for h in files) + "</ul>")

    # per notebook
    waiting = {(nb, g) for nb, g, _ in pending}
    per_nb: dict[str, dict] = {}
    for nb, cell, mx, score in cells:
        d = per_nb.setdefault(nb, {"points": 0.0, "max": 0.0, "scored": 0, "waiting": 0})
        d["max"] += mx
        if (nb, cell) in waiting:
            d["waiting"] += 1
        elif score is not None:
            d["points"] += score
            d["scored"] += 1
    rows = []
    for name in NOTEBOOKS:
        nb = name[:-len(".ipynb")]
        d = per_nb.get(nb)
        page = f"{nb}.html" in pages
        if d is None or d["max"] == 0:
            continue
        if not d["scored"] and not d["waiting"]:
            status = "not graded (not handed in, or not readable: see the notes)"
        elif d["waiting"]:
            status = f"{d['waiting']} answer{'s' * (d['waiting'] > 1)} still to be graded by hand"
        else:
            status = "graded"
        rows.append(f"<tr><td>{page_text(nb)}</td><td class=\"num\">{num(d['points'])} / {num(d['max'])}</td>"
                    f"<td>{page_text(status)}</td><td>{'<code>' + page_text(nb + '.html') + '</code>' if page else '—'}</td></tr>")
    if rows:
        out.append("<h2>Notebooks</h2><table><tr><th>notebook</th><th>points</th><th>status</th>"
                   "<th>its feedback page</th></tr>" + "".join(rows) + "</table>")

    # hints: failing hidden tests, completion points not earned
    hints = []
    where = {cell: nb for nb, cell, _, _ in cells}
    for g, v in sorted((rep.get("verdicts") or {}).items()):
        if isinstance(v, (list, tuple)) and len(v) >= 2 and isinstance(v[0], (int, float)) \
                and isinstance(v[1], (int, float)) and v[0] < v[1]:
            msg = v[2] if len(v) > 2 else ""
            hints.append(f"{where.get(g, '')} {g}: {hint_of(g, msg)}".strip())
    for ex, v in sorted((rep.get("completion") or {}).items()):
        if isinstance(v, (list, tuple)) and len(v) >= 2 and not v[0]:
            hints.append(f"{ex}: {v[1]}")
    judged = bool(rep.get("verdicts") or rep.get("completion"))
    out.append("<h2>Hints from the grader</h2>" + (
        "<ul>" + "".join(f"<li>{page_text(h, 2000)}</li>" for h in hints) + "</ul>" if hints else
        "<p>None: every hidden test and completion point of yours that was graded passed.</p>" if judged else
        "<p>None: no hidden test or completion point of yours was graded (the notes say why).</p>"))

    # hand-graded comments
    # (the score the gradebook holds: a manual grade outside the cell's range was refused there)
    held = {(nb, cell): (mx, score) for nb, cell, mx, score in cells}
    mine = sorted((k, r) for k, r in manual.items() if k[0] == student and (k[1], k[2]) in held)
    if mine:
        items = []
        for (_, nb, g), r in mine:
            mx, score = held[(nb, g)]
            pts = "not graded yet" if score is None or (nb, g) in waiting else f"{num(score)} of {num(mx)} points"
            comment = (r.get("comment") or "").strip()
            items.append(f"<li><strong>{page_text(nb)} {page_text(g)}</strong>: {pts}"
                         + (f'<div class="comment">{page_text(comment, 4000)}</div>' if comment else "") + "</li>")
        out.append("<h2>Graded by hand</h2><ul>" + "".join(items) + "</ul>")

    # notes
    if notes:
        out.append("<h2>Notes on your hand-in</h2><ul>" + "".join(f"<li>{page_text(n, 2000)}</li>" for n in notes) + "</ul>")

    # pages
    if pages:
        out.append("<h2>Your notebooks' feedback pages</h2><p>Sent with this page: each notebook as graded, "
                   "with every test's verdict. Open them in a browser.</p><ul>"
                   + "".join(f"<li><code>{page_text(p)}</code></li>" for p in pages) + "</ul>")
    else:
        out.append(f"<h2>Your notebooks' feedback pages</h2><p>There are none: {page_text(why_no_pages or '', 2000)}</p>")

    page = ("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n"
            f'<meta http-equiv="Content-Security-Policy" content="{CSP}">\n'
            '<meta charset="utf-8">\n<meta name="viewport" content="width=device-width, initial-scale=1">\n'
            '<meta name="referrer" content="no-referrer">\n<link rel="icon" href="data:,">\n'
            f"<title>Feedback: {page_text(ASSIGNMENT)}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n"
            + "\n".join(out) + "\n</body>\n</html>\n")
    return page.encode("utf-8"), withheld


# --- reading what grading made ----------------------------------------------------------------------
def _safe_id(student: str) -> bool:
    return bool(student) and student not in (".", "..") and not any(c in student for c in "/\\\0") and \
        not any(unicodedata.category(c)[0] == "C" for c in student)


def _read_page(path: Path) -> bytes | None:
    """A feedback page as bytes: no link followed, a regular file, at most MAX_PAGE_BYTES."""
    return read_capped(path, MAX_PAGE_BYTES)


def _pages(course: Path, student: str) -> dict[str, Path]:
    """The student's feedback pages that can be sent: regular files (no link), not too large."""
    if not _safe_id(student):
        return {}
    folder = course / "feedback" / student / ASSIGNMENT
    out = {}
    for name in NOTEBOOKS:
        page = f"{name[:-len('.ipynb')]}.html"
        try:
            st = os.lstat(folder / page)
        except OSError:
            continue
        if stat.S_ISREG(st.st_mode) and st.st_size <= MAX_PAGE_BYTES:
            out[page] = folder / page
    return out


UNREADABLE = (b"<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>page missing</title></head><body><p>"
              b"This feedback page could not be read when the feedback was packaged: ask your instructor."
              b"</p></body></html>\n")


def _content(source: bytes | Path) -> bytes:
    if isinstance(source, bytes):
        return source
    data = _read_page(source)
    return UNREADABLE if data is None else data


def _why_no_pages(rep: dict, standing) -> str:
    for n in rep.get("notes") or ():
        if isinstance(n, str) and n.startswith("no feedback pages:"):
            return n
    if standing is not None and standing.notes and standing.notes[0].startswith("no notebook of theirs"):
        return "no notebook of yours could be graded (the notes above say why)."
    return "no feedback page was made for you (the notes above say why, if they know)."


def gather(course: Path, report: dict) -> list[StudentReturn]:
    """Every student's summary page and notebook pages, from the gradebook and the feedback folder."""
    course = Path(course)
    standings, total = read_standings(course, report)
    _, rows, _ = gradebook_rows(course, list(report))
    cells: dict[str, list] = {}
    for sid, nb, cell, _kind, mx, score, _pending, _comment in rows:
        cells.setdefault(sid, []).append((nb, cell, mx, score))
    manual = read_manual(course)
    out = []
    for s in sorted(report):
        rep = report[s] if isinstance(report[s], dict) else {}
        pages = _pages(course, s)
        st = standings.get(s)
        summary, withheld = _summary(s, rep, st, total, sorted(cells.get(s, [])), manual, sorted(pages),
                                     None if pages else _why_no_pages(rep, st))
        out.append(StudentReturn(s, lms_record(rep), summary, pages, withheld))
    return out


# --- the packages -----------------------------------------------------------------------------------
def _digits(text) -> bool:
    return isinstance(text, str) and text.isascii() and text.isdigit()


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
    if uid is None or not _digits(uid):
        return ("anonymous grading: Canvas's download names the student by an anonymous id, which Re-Upload "
                "Submissions cannot match" if uid and uid.startswith("anon_") else
                f"no Canvas user id usable by Re-Upload Submissions ({uid!r})")
    kept = (r.lms or {}).get("attachment_ids")
    per_nb = kept if isinstance(kept, dict) else {}
    if aid is None or not _digits(aid):
        aid = next((v for v in map(ident, per_nb.values()) if v and _digits(v)), None)
    if aid is None:
        return "no Canvas file id of their submission (Re-Upload Submissions matches a file of it)"
    name = canvas_name_part(r.lms.get("name"))
    out = []
    for file, data in r.files():
        own = ident(per_nb.get(file[:-len(".html")] + ".ipynb")) if file != SUMMARY else None
        member = f"{name}_{uid}_{own if own and _digits(own) else aid}_{file}"
        # the name must read back as Canvas's download naming does (lms_layouts), with these ids first
        if not any(x["uid"] == uid and x["aid"] == member.split("_")[2] for x in canvas_splits(member, False)):
            return f"its Canvas name {member!r} would not read back as user {uid}"
        out.append((member, data))
    return out


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
    if pid is None or not _digits(pid):
        return f"no Moodle participant id usable by the feedback zip ({pid!r})"
    prefix = f"{moodle_full_name(r.lms.get('name'))}_{pid}_{MOODLE_PLUGIN}_"
    out = [(prefix + file, data) for file, data in r.files()]
    for member, _ in out:            # read back as Moodle's download naming is read (lms_layouts)
        m = MOODLE_FLAT.match(member)
        if not m or m["pid"] != pid or m["file"] != member[len(prefix):]:
            return f"its Moodle name {member!r} would not read back as participant {pid}"
    return out


def blackboard_entries(r: StudentReturn) -> list[tuple[str, bytes]] | str:
    user = ident(((r.lms or {}).get("ids") or {}).get("username"))
    if user is None or not _safe_id(user) or user.startswith((".", "~")):
        return f"no Blackboard username usable as a file name ({user!r})"
    return [(f"{user}_{file}", data) for file, data in r.files()]


def generic_entries(r: StudentReturn) -> list[tuple[str, bytes]] | str:
    if not _safe_id(r.student):
        return f"its student id {r.student!r} is not usable as a folder name"
    return [(f"{r.student}/{file}", data) for file, data in r.files()]


ENTRIES = {"canvas": canvas_entries, "moodle": moodle_entries, "blackboard": blackboard_entries}
KEYS = {"canvas": "user_id", "moodle": "participant_id", "blackboard": "username"}


def _write_zip(path: Path, entries: list[tuple[str, bytes | Path]]) -> None:
    """Replace ``path`` with a zip of ``entries``: written whole to a temporary file beside it, then
    renamed (a reader never sees half a zip; a failure leaves the old one as it was)."""
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    stamp = time.localtime()[:6]
    try:
        with os.fdopen(fd, "wb") as f, zipfile.ZipFile(f, "w", zipfile.ZIP_DEFLATED) as z:
            for name, source in entries:
                info = zipfile.ZipInfo(name, date_time=stamp)
                info.compress_type = zipfile.ZIP_DEFLATED
                info.external_attr = 0o644 << 16
                z.writestr(info, _content(source))
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _write_folder(path: Path, entries: list[tuple[str, bytes]]) -> None:
    """Replace the folder ``path`` with these files (made beside it, then renamed)."""
    tmp = Path(tempfile.mkdtemp(dir=path.parent, prefix=f".{path.name}."))
    try:
        for name, data in entries:
            (tmp / name).write_bytes(_content(data))
        os.chmod(tmp, 0o755)
        old = None
        if path.exists() or path.is_symlink():
            old = path.with_name(f".{path.name}.old.{os.getpid()}")
            os.replace(path, old)
        os.replace(tmp, path)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True) if old.is_dir() and not old.is_symlink() else old.unlink()
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def _jsonable(report: dict) -> dict:
    keep = ("notes", "completion", "verdicts", "failed", "lms", "undecided", "name", "human", "submitted_at")
    return {s: {k: (rep or {}).get(k) for k in keep if k in (rep or {})} for s, rep in report.items()}


def write_feedback_return(course: Path, report: dict, log=print) -> list[Path]:
    """Write ``<course>/feedback_return/``: each LMS's package for the students that LMS's download
    named, ``feedback_by_student.zip`` for the rest, README.txt and report.json; returns the paths
    written. ``report``: grade_class's per-student report (``report[s]["lms"]``: the LMS identity
    from intake, or None). A package of an LMS no student came from is not written, and one left by
    an earlier run is removed."""
    course = Path(course)
    out_dir = course / RETURN_DIR
    if not report:
        log(f"no student to return feedback to: {out_dir} is left as it was")
        return []
    out_dir.mkdir(exist_ok=True)
    students = gather(course, report)
    packages: dict[str, list] = {}            # system -> [(student, entries)]
    left: dict[str, list[tuple[str, str]]] = {}   # system -> [(student, why)]
    generic: list[tuple[str, list]] = []
    claims: dict[tuple[str, str], list[str]] = {}
    for r in students:
        system = (r.lms or {}).get("system")
        if system in ENTRIES:
            key = ident(((r.lms.get("ids") or {}).get(KEYS[system])))
            claims.setdefault((system, key or ""), []).append(r.student)
    twice = {s for (_, key), ss in claims.items() if key and len(ss) > 1 for s in ss}
    for r in students:
        system = (r.lms or {}).get("system")
        entries = None
        if system in ENTRIES:
            entries = ENTRIES[system](r) if r.student not in twice else \
                f"its {TITLE[system]} id is claimed by another student too (check in {TITLE[system]} whose it is)"
            if isinstance(entries, str):
                left.setdefault(system, []).append((r.student, entries))
                entries = None
            else:
                packages.setdefault(system, []).append((r.student, entries))
        if entries is None:
            g = generic_entries(r)
            if isinstance(g, str):
                left.setdefault("generic", []).append((r.student, g))
            else:
                generic.append((r.student, g))

    written = []
    for system, name in PACKAGES.items():
        path = out_dir / name
        if system in packages:
            entries = [e for _, es in packages[system] for e in es]
            _write_zip(path, entries)
            written.append(path)
            if system == "blackboard":
                _write_folder(out_dir / BLACKBOARD_DIR, entries)
                written.append(out_dir / BLACKBOARD_DIR)
        else:                                   # an earlier run's package for an LMS not in this download
            path.unlink(missing_ok=True)
            if system == "blackboard" and (out_dir / BLACKBOARD_DIR).is_dir():
                shutil.rmtree(out_dir / BLACKBOARD_DIR, ignore_errors=True)
    if generic:
        _write_zip(out_dir / GENERIC_ZIP, [e for _, es in generic for e in es])
        written.append(out_dir / GENERIC_ZIP)
    else:
        (out_dir / GENERIC_ZIP).unlink(missing_ok=True)
    readme = _readme(students, packages, generic, left)
    write_atomic(out_dir / README, readme.encode("utf-8"))
    written.append(out_dir / README)
    write_atomic(out_dir / REPORT_JSON, json.dumps(_jsonable(report), indent=1, sort_keys=True,
                                                    default=str).encode("utf-8"))
    written.append(out_dir / REPORT_JSON)
    for system, items in packages.items():
        log(f"{RETURN_DIR}/{PACKAGES[system]}: feedback for {len(items)} student{'s' * (len(items) != 1)}")
    if generic:
        log(f"{RETURN_DIR}/{GENERIC_ZIP}: feedback for {len(generic)} student{'s' * (len(generic) != 1)}")
    n_left = sum(len(v) for k, v in left.items() if k == "generic")
    if n_left:
        log(f"WARNING: {n_left} student(s) have no feedback package: see {RETURN_DIR}/{README}")
    return written


def _readme(students, packages, generic, left) -> str:
    n = len(students)
    out = [f"Feedback to return, assignment {ASSIGNMENT}: {n} student{'s' * (n != 1)}.",
           "Each student's files: summary.html (total, each notebook's points, hints, hand-graded comments) and "
           "one page per graded notebook. Upload only the zip of the LMS the hand-ins came from.", ""]
    if "canvas" in packages:
        out += [f"== {CANVAS_ZIP}: {len(packages['canvas'])} students ==",
                "  Canvas: the assignment > Re-Upload Submissions (or the Gradebook column's menu) > choose this zip.",
                "  Each file is named <name>_<user id>_<file id>_<page>: Canvas attaches a student's files to ONE comment",
                "  'See attached files' on their submission (hidden while the assignment is muted). Canvas shows each",
                "  file under the name of the student's own upload with that file id (e.g. 02_reward.ipynb); it is",
                "  the HTML page: tell students to open it in a browser. Files Canvas cannot match are ignored: a",
                "  student who submitted again since the download is one (download and grade again first).", ""]
    if "moodle" in packages:
        out += [f"== {MOODLE_ZIP}: {len(packages['moodle'])} students ==",
                "  Moodle: Assignment settings > Feedback types > tick Feedback files; then View all submissions >",
                "  Grading action > Upload multiple feedback files in a zip > choose this zip > Confirm. Show all",
                "  participants (no group selected) first: Moodle imports only the participants shown. Each file",
                "  becomes the student's feedback file and the student is notified; a file unchanged since the last",
                "  upload is skipped.", ""]
    if "blackboard" in packages:
        out += [f"== {BLACKBOARD_DIR}/ ({BLACKBOARD_ZIP}): {len(packages['blackboard'])} students ==",
                "  Blackboard Learn Original has no bulk upload of feedback files: for each student, Grade Center >",
                "  the assignment's column > View Grade Details > Grade Attempt > Feedback to Learner > attach",
                "  <username>_summary.html and their <username>_<notebook>.html pages.", ""]
    if generic:
        out += [f"== {GENERIC_ZIP}: {len(generic)} students ==",
                "  One folder per student id: students whose hand-ins carried no LMS identity this package could use",
                "  (listed below when they came from an LMS). Return each folder by hand.", ""]
    for system, items in sorted(left.items()):
        where = TITLE.get(system, "any package")
        out.append(f"Not in the {where} package ({len(items)}):" if system != "generic" else
                   f"In no package at all ({len(items)}): their summary is not written anywhere:")
        out += [f"  {s}: {why}" for s, why in items]
        out.append("")
    withheld = [(r.student, r.withheld) for r in students if r.withheld]
    if withheld:
        out.append("Notes for the instructor left off the students' pages (they are in report.csv): "
                   + ", ".join(f"{s} ({k})" for s, k in withheld))
    return "\n".join(out).rstrip() + "\n"


# --- the command line -------------------------------------------------------------------------------
def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--course", type=Path, default=COURSE_DIR, help="the graded course folder (default: course/)")
    args = p.parse_args(argv)
    saved = args.course / RETURN_DIR / REPORT_JSON
    if not saved.is_file():
        p.error(f"{saved} does not exist: grade the class first (make grade), which writes it")
    try:
        report = json.loads(saved.read_text(encoding="utf-8"))
    except (OSError, ValueError) as e:
        p.error(f"{saved} cannot be read ({e}): grade the class again")
    if not isinstance(report, dict) or not report:
        p.error(f"{saved} names no student: grade the class first")
    paths = write_feedback_return(args.course, report)
    print("written: " + ", ".join(str(x) for x in paths))
    return 0


if __name__ == "__main__":
    sys.exit(main())
