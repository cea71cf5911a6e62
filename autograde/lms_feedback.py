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

Each LMS's package, with the source or help pages read to decide its names, is in the docstring
of its plug-in: ``autograde/lms/canvas.py`` (*Re-Upload Submissions*), ``autograde/lms/moodle.py``
(*Upload multiple feedback files in a zip*) and ``autograde/lms/blackboard.py`` (no bulk return:
files to attach by hand). This module holds what is the same for all of them: the summary page,
the pages gathered, the zips and folders written, README.txt and report.json.
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
import zipfile
from pathlib import Path

from .class_report import CSP, display_name, gradebook_rows, hint_of, page_text
from .course import ASSIGNMENT, COURSE_DIR, NOTEBOOKS
from .files import read_capped
from .gradebook import read_manual
from .lms import PLUGINS, TITLE
from .lms.base import SUMMARY, StudentReturn, lms_record, safe_id  # noqa: F401  (SUMMARY: a public name, moved)
from .lms.blackboard import FEEDBACK_DIR as BLACKBOARD_DIR  # noqa: F401  (a public name, moved)
from .lms.blackboard import FEEDBACK_ZIP as BLACKBOARD_ZIP  # noqa: F401  (a public name, moved)
from .lms.canvas import FEEDBACK_ZIP as CANVAS_ZIP  # noqa: F401  (a public name, moved)
from .lms.moodle import FEEDBACK_ZIP as MOODLE_ZIP  # noqa: F401  (a public name, moved)
from .lms_export import lms_settings, read_standings
from .text import ident, num, write_atomic

RETURN_DIR = "feedback_return"
GENERIC_ZIP = "feedback_by_student.zip"
README = "README.txt"
REPORT_JSON = "report.json"
PACKAGES = {lms.name: lms.feedback_zip for lms in PLUGINS}
MAX_PAGE_BYTES = 32 << 20            # a feedback page read from disk, at most (pages are capped far below)
INSTRUCTOR_ONLY = "for the instructor"


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
        pairs = [(k, ids.get(k)) for k in KEYS.values() if ids.get(k)]
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
def _read_page(path: Path) -> bytes | None:
    """A feedback page as bytes: no link followed, a regular file, at most MAX_PAGE_BYTES."""
    return read_capped(path, MAX_PAGE_BYTES)


def _pages(course: Path, student: str) -> dict[str, Path]:
    """The student's feedback pages that can be sent: regular files (no link), not too large."""
    if not safe_id(student):
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
def generic_entries(r: StudentReturn) -> list[tuple[str, bytes]] | str:
    if not safe_id(r.student):
        return f"its student id {r.student!r} is not usable as a folder name"
    return [(f"{r.student}/{file}", data) for file, data in r.files()]


ENTRIES = {lms.name: lms.feedback_entries for lms in PLUGINS}
KEYS = {lms.name: lms.id_key for lms in PLUGINS}



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
    for lms in PLUGINS:
        path = out_dir / lms.feedback_zip
        folder = out_dir / lms.feedback_folder if lms.feedback_folder else None
        if lms.name in packages:
            entries = [e for _, es in packages[lms.name] for e in es]
            _write_zip(path, entries)
            written.append(path)
            if folder:                          # an LMS whose files are attached by hand: a folder too
                _write_folder(folder, entries)
                written.append(folder)
        else:                                   # an earlier run's package for an LMS not in this download
            path.unlink(missing_ok=True)
            if folder and folder.is_dir():
                shutil.rmtree(folder, ignore_errors=True)
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
    for lms in PLUGINS:
        if lms.name in packages:
            out += lms.feedback_readme(len(packages[lms.name]))
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

