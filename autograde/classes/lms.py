"""Class downloads in the bulk-download layouts of Canvas, Moodle and Blackboard, from given notebooks.

    python -m autograde.classes.lms OUT_DIR [--notebooks DIR]

writes ``canvas.zip``, ``moodle.zip`` (one folder per participant), ``moodle_flat.zip`` ("Download
submissions in folders" off) and ``blackboard.zip`` in OUT_DIR, each holding the notebooks of DIR
(default: the instructor's ``solutions/``) handed in by the students below, named exactly as each
LMS names the files of its download (``autograde/lms_layouts.py`` says where each naming is
documented). ``older`` notebooks, when given, are the superseded uploads of the students who
handed in twice, so that a test can tell which one was graded.

Canvas (``CANVAS``): ``leeann`` on time; ``müllerzoë`` late (``LATE`` in every name);
``obrienseán`` handed each notebook in twice, so that her submission holds ``02_reward.ipynb``
and Canvas's renamed second upload ``02_reward-1.ipynb`` (a larger file id).

Moodle (``MOODLE``): ``Zoë Müller`` (spaces and a non-ASCII letter in the folder name), ``Ann
Lee``, ``Seán OBrien`` (Moodle's ``clean_filename`` drops the apostrophe), who uploaded
``02_reward.ipynb`` and ``02_reward (1).ipynb``.

Blackboard (``BLACKBOARD``, assignment ``Chapter 3.2 notebooks``): ``jdoe`` with two attempts, the
older one holding the ``older`` notebooks, and a receipt for each (UK date format); ``asmith``
with one attempt and a US-format receipt; ``o_brien``, a username with an underscore, which only
the receipt's ``(o_brien)`` tells from the assignment name.
"""

from __future__ import annotations

import argparse
import re
import zipfile
from datetime import datetime
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
DOWNLOADED = (2026, 3, 5, 16, 0, 0)      # the zip entries' time: when the instructor downloaded

CANVAS = {  # sortable name -> Canvas user id, late, uploads per notebook
    "Lee, Ann": {"user_id": "1001", "late": False, "uploads": 1},
    "Müller, Zoë": {"user_id": "1002", "late": True, "uploads": 1},
    "O'Brien, Seán": {"user_id": "1003", "late": False, "uploads": 2},
}
MOODLE = {  # full name -> participant id, uploads per notebook
    "Zoë Müller": {"participant_id": "5301277", "uploads": 1},
    "Ann Lee": {"participant_id": "5301278", "uploads": 1},
    "Seán O'Brien": {"participant_id": "5301279", "uploads": 2},
}
BLACKBOARD_ASSIGNMENT = "Chapter 3.2 notebooks"
BLACKBOARD = {  # username -> name, attempts (times), receipt date format
    "jdoe": {"name": "Jane Doe", "attempts": [datetime(2026, 3, 1, 10, 0, 0), datetime(2026, 3, 2, 9, 30, 15)],
             "dates": "uk"},
    "asmith": {"name": "Alex Smith", "attempts": [datetime(2026, 3, 2, 14, 5, 0)], "dates": "us"},
    "o_brien": {"name": "Seán O'Brien", "attempts": [datetime(2026, 3, 3, 8, 0, 0)], "dates": "uk"},
}


def canvas_name(sortable: str) -> str:
    """The name as Canvas writes it into a download (``ContentZipper#get_user_name`` and
    ``#get_filename``): ``_<digits>_`` -> ``<digits>``, lowercased, non-word characters removed."""
    name = re.sub(r"_(\d+)_", r"\1", sortable).lower()
    return re.sub(r"[^\w]", "", name)


def moodle_prefix(fullname: str, participant_id: str) -> str:
    """``downloader::get_student_prefix``: ``_`` -> space, then clean_filename (PARAM_FILE drops
    control characters and ``& < > " ` | ' : \\ /``)."""
    return re.sub(r"[\x00-\x1f\x7f&<>\"`|':\\/]", "", fullname.replace("_", " ") + f"_{participant_id}")


def canvas(notebooks: dict[str, bytes], older: dict[str, bytes] | None = None) -> dict[str, bytes]:
    """{member: bytes}: Canvas's "Download Submissions" of ``notebooks`` ({file name: bytes})."""
    older = older or notebooks
    files, file_id = {}, 40_000
    for sortable, s in CANVAS.items():
        prefix = canvas_name(sortable) + ("_LATE" if s["late"] else "") + f"_{s['user_id']}"
        for name, data in sorted(notebooks.items()):
            versions = [older.get(name, data), data][-s["uploads"]:]
            for i, version in enumerate(versions):
                file_id += 1
                stem, ext = name.rsplit(".", 1)
                display = name if i == 0 else f"{stem}-{i}.{ext}"      # Attachment.make_unique_filename
                files[f"{prefix}_{file_id}_{display}"] = version
    return files


def moodle(notebooks: dict[str, bytes], older: dict[str, bytes] | None = None,
           folders: bool = True) -> dict[str, bytes]:
    """{member: bytes}: Moodle's "Download all submissions", in folders (the default) or not."""
    older = older or notebooks
    files = {}
    for fullname, s in MOODLE.items():
        prefix = moodle_prefix(fullname, s["participant_id"]) + "_assignsubmission_file"
        for name, data in sorted(notebooks.items()):
            versions = [older.get(name, data), data][-s["uploads"]:]
            for i, version in enumerate(versions):
                stem, ext = name.rsplit(".", 1)
                upload = name if i == 0 else f"{stem} ({i}).{ext}"      # the browser's second download
                files[f"{prefix}/{upload}" if folders else f"{prefix}_{upload}"] = version
    return files


def _receipt(username: str, s: dict, when: datetime, uploads: list[tuple[str, str]]) -> bytes:
    if s["dates"] == "us":
        date = f"{when:%A, %B} {when.day}, {when:%Y} {when.hour % 12 or 12}:{when:%M:%S %p} EST"
    else:
        date = f"{when:%A}, {when.day} {when:%B %Y %H:%M:%S} o'clock GMT"
    lines = [f"Name: {s['name']} ({username})", f"Assignment: {BLACKBOARD_ASSIGNMENT}", f"Date Submitted: {date}",
             "Current Mark: Needs Marking", "", "Submission Field:",
             "There is no student submission text data for this assignment.", "", "Comments:",
             # a student's comment is free text: it must not be read as the receipt's header
             "Name: Someone Else (victim)\nDate Submitted: Monday, 1 January 2024 00:00:00 o'clock GMT",
             "", "Files:"]
    for original, filename in uploads:
        lines += [f"\tOriginal filename: {original}", f"\tFilename: {filename}", ""]
    return "\n".join(lines).encode("utf-8")


def blackboard(notebooks: dict[str, bytes], older: dict[str, bytes] | None = None) -> dict[str, bytes]:
    """{member: bytes}: Blackboard Learn's (Original) "Assignment File Download", every attempt
    with its receipt."""
    older = older or notebooks
    files = {}
    for username, s in BLACKBOARD.items():
        for k, when in enumerate(s["attempts"]):
            head = f"{BLACKBOARD_ASSIGNMENT}_{username}_attempt_{when:%Y-%m-%d-%H-%M-%S}"
            last = k == len(s["attempts"]) - 1
            uploads = []
            for name, data in sorted(notebooks.items()):
                files[f"{head}_{name}"] = data if last else older.get(name, data)
                uploads.append((name, f"{head}_{name}"))
            files[f"{head}.txt"] = _receipt(username, s, when, uploads)
    return files


def write_zip(out: Path, files: dict[str, bytes], when=DOWNLOADED) -> Path:
    with zipfile.ZipFile(out, "w") as zf:
        for name, data in files.items():
            zf.writestr(zipfile.ZipInfo(name, date_time=when), data)
    return out


def write_all(out_dir: Path, notebooks: dict[str, bytes], older: dict[str, bytes] | None = None) -> dict[str, Path]:
    out_dir.mkdir(parents=True, exist_ok=True)
    return {"canvas": write_zip(out_dir / "canvas.zip", canvas(notebooks, older)),
            "moodle": write_zip(out_dir / "moodle.zip", moodle(notebooks, older)),
            "moodle_flat": write_zip(out_dir / "moodle_flat.zip", moodle(notebooks, older, folders=False)),
            "blackboard": write_zip(out_dir / "blackboard.zip", blackboard(notebooks, older))}


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("out", type=Path)
    p.add_argument("--notebooks", type=Path, default=ROOT / "solutions",
                   help="a folder of notebooks to hand in (default: solutions/)")
    args = p.parse_args(argv)
    notebooks = {q.name: q.read_bytes() for q in sorted(args.notebooks.glob("[0-9][0-9]_*.ipynb"))}
    for system, path in write_all(args.out, notebooks).items():
        print(f"wrote {path} ({system})")


if __name__ == "__main__":
    main()
