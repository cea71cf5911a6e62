"""Intake of Canvas, Moodle and Blackboard bulk downloads (autograde/lms_layouts.py, autograde/intake.py):
each student is found by the LMS's own id, keeps that identity in ``Intake.lms``, and their latest
upload of each notebook is graded; late markers, attempts and receipts are recorded in words.

Fast: tiny notebooks and zips built in tmp_path (``autograde/classes/lms.py`` names the files as
each LMS does), no kernel. Grading a download of each LMS with real nbgrader, from intake to the
feedback returned, is tests/test_instructor_week.py.
"""

import stat
import time
import unicodedata
import zipfile
from datetime import datetime
from pathlib import Path

import nbformat
import pytest

from autograde import lms_layouts
from autograde.classes import lms
from autograde.intake import collect

NOTEBOOKS = ["01_world_model.ipynb", "02_reward.ipynb", "03_imagination_actor.ipynb"]
RECORD_KEYS = {"system", "name", "ids", "late", "submitted_at", "attempt", "attachment_ids"}


def notebook_bytes(tag: str) -> bytes:
    nb = nbformat.v4.new_notebook()
    nb.cells.append(nbformat.v4.new_code_cell(f"print({tag!r})"))
    return nbformat.writes(nb).encode("utf-8")


NEW = {n: notebook_bytes(f"new {n}") for n in NOTEBOOKS[:2]}
OLD = {n: notebook_bytes(f"old {n}") for n in NOTEBOOKS[:2]}


def make_zip(path: Path, members: dict, symlinks: dict | None = None) -> Path:
    with zipfile.ZipFile(path, "w") as zf:
        for name, data in members.items():
            info = zipfile.ZipInfo(name, date_time=lms.DOWNLOADED)
            info.external_attr = (stat.S_IFREG | 0o644) << 16
            zf.writestr(info, data)
        for name, target in (symlinks or {}).items():
            info = zipfile.ZipInfo(name, date_time=lms.DOWNLOADED)
            info.create_system = 3
            info.external_attr = (stat.S_IFLNK | 0o777) << 16
            zf.writestr(info, target)
    return path


def intake_of(tmp_path, members, **kw):
    return collect(make_zip(tmp_path / "download.zip", members, kw.pop("symlinks", None)), NOTEBOOKS, **kw)


def graded(intake, sid, notebook="02_reward.ipynb"):
    return intake.students[sid][notebook]


def rejected_for(intake, text):
    return [line for line in intake.rejected if text in line]


# --- each LMS's layout ---------------------------------------------------------------------------
def test_canvas_download_is_read_by_user_id_with_late_marker_and_resubmission(tmp_path):
    intake = intake_of(tmp_path, lms.canvas(NEW, OLD))
    assert list(intake.students) == ["canvas_1001", "canvas_1002", "canvas_1003"]
    assert intake.rejected == [] and intake.warnings == []
    assert all(set(uploads) == set(NEW) for uploads in intake.students.values())
    assert intake.lms["canvas_1001"] == {"system": "canvas", "name": "leeann",
                                         "ids": {"user_id": "1001", "attachment_id": "40002"},
                                         "late": False, "submitted_at": None, "attempt": None,
                                         "attachment_ids": {"01_world_model.ipynb": "40001",
                                                            "02_reward.ipynb": "40002"}}
    zoe = intake.lms["canvas_1002"]
    assert zoe["name"] == "müllerzoë" and zoe["late"] is True and zoe["ids"]["user_id"] == "1002"
    assert graded(intake, "canvas_1002").member.startswith("müllerzoë_LATE_1002_")
    assert any("marked this submission late" in n and "'LATE'" in n for n in intake.notes["canvas_1002"])
    # the resubmission: Canvas renamed the second upload 02_reward-1.ipynb and gave it a larger file id
    up = graded(intake, "canvas_1003")
    assert up.data == NEW["02_reward.ipynb"] and up.member == "obrienseán_1003_40008_02_reward-1.ipynb"
    [note] = [n for n in intake.notes["canvas_1003"] if n.startswith("02_reward.ipynb")]
    assert "2 uploads; graded 'obrienseán_1003_40008_02_reward-1.ipynb' (Canvas file id 40008)" in note
    assert "ignored the older 'obrienseán_1003_40007_02_reward.ipynb' (Canvas file id 40007)" in note
    assert intake.lms["canvas_1003"]["ids"] == {"user_id": "1003", "attachment_id": "40008"}
    assert intake.display_names["canvas_1003"] == "canvas_1003"
    for record in intake.lms.values():
        assert set(record) == RECORD_KEYS and all(isinstance(v, str) for v in record["ids"].values())


def test_canvas_names_of_the_older_format_anonymous_grading_text_entries_and_uuid_suffixes(tmp_path):
    older = intake_of(tmp_path, {"lee--ann-late_1001_7_02_reward.ipynb": NEW["02_reward.ipynb"],
                                 "o_brien--sean_1003_8_02_reward.ipynb": NEW["02_reward.ipynb"],
                                 "o_brien--sean_1003_text.html": b"<html>my answer</html>"})
    assert older.lms["canvas_1001"]["late"] is True and older.lms["canvas_1001"]["name"] == "lee--ann"
    assert any("'-late' in its file names" in n for n in older.notes["canvas_1001"])
    assert older.lms["canvas_1003"]["late"] is False and set(older.students["canvas_1003"]) == {"02_reward.ipynb"}
    assert "made it for a text entry" in rejected_for(older, "text.html")[0]
    assert any("a text entry" in n and "not a .ipynb" in n for n in older.notes["canvas_1003"])
    uuid = "-3f2b8c1e-aaaa-4bbb-8ccc-0123456789ab"
    (tmp_path / "anon").mkdir()
    anon = intake_of(tmp_path / "anon", {"anon_x1Y2z_70_02_reward.ipynb": NEW["02_reward.ipynb"],
                                         f"LATE_anon_Ab3dE_71_02_reward{uuid}.ipynb": NEW["02_reward.ipynb"]})
    assert list(anon.students) == ["canvas_anon_Ab3dE", "canvas_anon_x1Y2z"] and anon.rejected == []
    assert anon.lms["canvas_anon_Ab3dE"] == {"system": "canvas", "name": None,
                                             "ids": {"user_id": "anon_Ab3dE", "attachment_id": "71"},
                                             "late": True, "submitted_at": None, "attempt": None,
                                             "attachment_ids": {"02_reward.ipynb": "71"}}


@pytest.mark.parametrize("folders", [True, False])
def test_moodle_download_is_read_by_participant_id(tmp_path, folders):
    intake = intake_of(tmp_path, lms.moodle(NEW, OLD, folders=folders))
    assert list(intake.students) == ["moodle_5301277", "moodle_5301278", "moodle_5301279"]
    assert intake.rejected == [] and intake.warnings == []
    zoe = intake.lms["moodle_5301277"]
    assert zoe == {"system": "moodle", "name": "Zoë Müller", "ids": {"participant_id": "5301277"},
                   "late": None, "submitted_at": None, "attempt": None, "attachment_ids": None}
    assert graded(intake, "moodle_5301277").member.startswith("Zoë Müller_5301277_assignsubmission_file")
    assert intake.lms["moodle_5301279"]["name"] == "Seán OBrien"
    up = graded(intake, "moodle_5301279")
    assert up.data == NEW["02_reward.ipynb"] and up.member.endswith("02_reward (1).ipynb")
    assert any(n.startswith("02_reward.ipynb: 2 uploads") for n in intake.notes["moodle_5301279"])


def test_moodle_names_written_in_other_unicode_forms_and_trailing_underscore_folders(tmp_path):
    nfd = unicodedata.normalize("NFD", "Zoë Müller")
    intake = intake_of(tmp_path, {f"{nfd}_5301277_assignsubmission_file_/02_reward.ipynb": NEW["02_reward.ipynb"],
                                  "Zoë Müller_5301277_assignsubmission_file/sub/01_world_model.ipynb": b"{}",
                                  "Ann Lee_5301278_assignsubmission_onlinetext/onlinetext.html": b"<p>hi</p>"})
    assert set(intake.students["moodle_5301277"]) == {"02_reward.ipynb", "01_world_model.ipynb"}
    assert intake.lms["moodle_5301277"]["name"] == "Zoë Müller"                  # NFC, as written
    assert intake.students["moodle_5301278"] == {}
    assert any("onlinetext.html" in n and "not a .ipynb" in n for n in intake.notes["moodle_5301278"])


def test_blackboard_download_latest_attempt_wins_and_receipts_are_read(tmp_path):
    intake = intake_of(tmp_path, lms.blackboard(NEW, OLD))
    assert list(intake.students) == ["blackboard_asmith", "blackboard_jdoe", "blackboard_o_brien"]
    assert intake.rejected == [] and intake.warnings == []         # receipts are not "unrecognised"
    jdoe = intake.lms["blackboard_jdoe"]
    assert jdoe == {"system": "blackboard", "name": "Jane Doe", "ids": {"username": "jdoe"}, "late": None,
                    "submitted_at": "2026-03-02T09:30:15", "attempt": 2, "attachment_ids": None}
    assert all(graded(intake, "blackboard_jdoe", n).data == NEW[n] for n in NEW)
    summary = intake.notes["blackboard_jdoe"][0]
    assert "2 attempts in this download (2026-03-01 10:00:00, 2026-03-02 09:30:15)" in summary
    assert "graded from the attempt of 2026-03-02 09:30:15" in summary
    assert "its receipt says submitted \"Monday, 2 March 2026 09:30:15 o'clock GMT\"" in summary
    assert "set aside: the attempt of 2026-03-01 10:00:00" in summary
    assert any(n.startswith("02_reward.ipynb: 2 uploads") and "ignored the older" in n and "2026-03-01 10:00:00" in n
               for n in intake.notes["blackboard_jdoe"])
    # the receipt's own comment section holds "Name: Someone Else (victim)": free text, not read
    assert "blackboard_victim" not in intake.students
    assert intake.lms["blackboard_asmith"]["submitted_at"] == "2026-03-02T14:05:00"       # "2:05:00 PM EST"
    # a username with an underscore: only the receipt's "(o_brien)" tells it from the assignment name
    assert intake.lms["blackboard_o_brien"]["ids"] == {"username": "o_brien"}
    assert intake.lms["blackboard_o_brien"]["name"] == "Seán O'Brien"


def test_blackboard_each_notebook_from_the_latest_attempt_holding_it(tmp_path):
    head = "HW3_jdoe_attempt_"
    intake = intake_of(tmp_path, {f"{head}2026-03-01-10-00-00_01_world_model.ipynb": OLD["01_world_model.ipynb"],
                                  f"{head}2026-03-01-10-00-00_02_reward.ipynb": OLD["02_reward.ipynb"],
                                  f"{head}2026-03-02-09-00-00_02_reward.ipynb": NEW["02_reward.ipynb"],
                                  "HW3_asmith_attempt_2026-03-02-11-00-00_02_reward.ipynb": NEW["02_reward.ipynb"]})
    assert graded(intake, "blackboard_jdoe").data == NEW["02_reward.ipynb"]
    assert graded(intake, "blackboard_jdoe", "01_world_model.ipynb").data == OLD["01_world_model.ipynb"]
    record = intake.lms["blackboard_jdoe"]
    assert record["attempt"] == 2 and record["submitted_at"] == "2026-03-02T09:00:00" and record["name"] == "jdoe"
    summary = intake.notes["blackboard_jdoe"][0]
    assert "notebooks also come from the attempt of 2026-03-01 10:00:00" in summary and "set aside" not in summary
    assert intake.rejected == [] and intake.warnings == []        # no receipt: the shared "HW3" is the assignment


def test_blackboard_without_receipts_for_one_student_says_how_the_username_was_read(tmp_path):
    intake = intake_of(tmp_path, {"Lab 2_s1234567_attempt_2026-03-02-09-00-00_02_reward.ipynb": NEW["02_reward.ipynb"]})
    assert list(intake.students) == ["blackboard_s1234567"]
    [warning] = intake.warnings
    assert "without a receipt" in warning and "last '_' part" in warning


def test_receipt_dates_and_an_unreadable_one(tmp_path):
    date = lms_layouts.parse_receipt_date
    assert date("Tuesday, 21 April 2020 06:34:13 o'clock BST") == datetime(2020, 4, 21, 6, 34, 13)
    assert date("Monday, February 3, 2020 10:15:45 PM EST") == datetime(2020, 2, 3, 22, 15, 45)
    assert date("Monday, February 3, 2020 12:15:45 AM EST") == datetime(2020, 2, 3, 0, 15, 45)
    assert date("maandag 3 februari 2020 10:15:45") is None
    head = "HW3_jdoe_attempt_2026-03-02-09-00-00"
    intake = intake_of(tmp_path, {f"{head}_02_reward.ipynb": NEW["02_reward.ipynb"],
                                  f"{head}.txt": "Naam: Jane Doe (jdoe)\nOpdracht: HW3\nIngediend op: maandag 2 maart "
                                                 "2026 09:00:00\n\nFiles:\n".encode()})
    record = intake.lms["blackboard_jdoe"]
    assert record["name"] == "Jane Doe" and record["submitted_at"] == "2026-03-02T09:00:00"
    assert intake.rejected == []


def test_unreadable_receipts_other_files_and_a_student_with_only_a_receipt(tmp_path):
    head = "HW3_jdoe_attempt_2026-03-02-09-00-00"
    intake = intake_of(tmp_path, {f"{head}_02_reward.ipynb": NEW["02_reward.ipynb"], f"{head}_essay.pdf": b"%PDF",
                                  f"{head}.txt": b"Name: Jane Doe (jdoe)\n" + b" " * (70 * 1024),
                                  "HW3_asmith_attempt_2026-03-02-10-00-00.txt": b"Name: Alex Smith (asmith)\n"})
    assert "receipt that could not be read" in rejected_for(intake, f"{head}.txt")[0]
    assert any("essay.pdf: not a .ipynb notebook" in n for n in intake.notes["blackboard_jdoe"])
    assert intake.lms["blackboard_jdoe"]["name"] == "jdoe"                  # the receipt could not say
    assert any("could not be read" in n for n in intake.notes["blackboard_jdoe"])
    assert intake.students["blackboard_asmith"] == {}
    assert intake.lms["blackboard_asmith"]["name"] == "Alex Smith"
    assert "no notebook of this assignment was graded" in intake.notes["blackboard_asmith"][0]


def test_receipt_that_names_another_user_is_not_believed(tmp_path):
    head = "HW3_jdoe_attempt_2026-03-02-09-00-00"
    intake = intake_of(tmp_path, {f"{head}_02_reward.ipynb": NEW["02_reward.ipynb"],
                                  "HW3_asmith_attempt_2026-03-02-10-00-00_02_reward.ipynb": NEW["02_reward.ipynb"],
                                  f"{head}.txt": b"Name: Alex Smith (asmith)\nDate Submitted: Monday, 2 March 2026 "
                                                 b"23:59:59 o'clock GMT\n"})
    assert set(intake.students) == {"blackboard_jdoe", "blackboard_asmith"}
    record = intake.lms["blackboard_jdoe"]
    assert record["name"] == "jdoe" and record["submitted_at"] == "2026-03-02T09:00:00"
    assert any("names 'asmith', not 'jdoe'" in n for n in intake.notes["blackboard_jdoe"])


# --- which layout, and what does not fit it ------------------------------------------------------
def test_a_download_mixing_two_lms_layouts_is_refused(tmp_path):
    members = {**lms.canvas(NEW), **lms.moodle(NEW)}
    with pytest.raises(ValueError, match="mixes the layouts of Canvas and Moodle") as e:
        intake_of(tmp_path, members)
    assert "one at a time" in str(e.value)
    (tmp_path / "b").mkdir()
    with pytest.raises(ValueError, match="Moodle and Blackboard"):
        intake_of(tmp_path / "b", {**lms.moodle(NEW), **lms.blackboard(NEW)})


def test_generic_names_are_not_taken_for_an_lms_layout(tmp_path):
    intake = intake_of(tmp_path, {"victim_2_02_reward.ipynb": NEW["02_reward.ipynb"],
                                  "victim2_02_reward.ipynb": NEW["02_reward.ipynb"],
                                  "s042/02_reward.ipynb": NEW["02_reward.ipynb"]})
    assert set(intake.students) == {"victim_2", "victim2", "s042"} and intake.lms == {}


def test_a_file_that_does_not_follow_the_lms_naming_is_graded_for_nobody(tmp_path):
    intake = intake_of(tmp_path, {**lms.canvas(NEW), "s042_02_reward.ipynb": NEW["02_reward.ipynb"],
                                  "export/readme.txt": b"hello"})
    assert list(intake.students) == ["canvas_1001", "canvas_1002", "canvas_1003"]
    line = rejected_for(intake, "'s042_02_reward.ipynb'")[0]
    assert "not named as Canvas names" in line and "no Canvas user" in line
    assert rejected_for(intake, "readme.txt") and "in a folder" in rejected_for(intake, "readme.txt")[0]


def test_a_wrapper_folder_and_a_plain_folder_read_the_same(tmp_path):
    wrapped = intake_of(tmp_path, {f"Assignment 3/{k}": v for k, v in lms.canvas(NEW).items()})
    assert list(wrapped.students) == ["canvas_1001", "canvas_1002", "canvas_1003"] and wrapped.rejected == []
    root = tmp_path / "moodle"
    for member, data in lms.moodle(NEW).items():
        (root / member).parent.mkdir(parents=True, exist_ok=True)
        (root / member).write_bytes(data)
    folder = collect(root, NOTEBOOKS)
    assert list(folder.lms) == ["moodle_5301277", "moodle_5301278", "moodle_5301279"]
    assert folder.lms["moodle_5301277"]["name"] == "Zoë Müller"


def test_ids_are_stable_across_downloads_when_names_and_late_markers_change(tmp_path):
    first = intake_of(tmp_path, {"leeann_1001_10_02_reward.ipynb": NEW["02_reward.ipynb"]})
    (tmp_path / "2").mkdir()
    second = intake_of(tmp_path / "2", {"leeannmarie_LATE_1001_11_02_reward.ipynb": NEW["02_reward.ipynb"]})
    assert list(first.students) == list(second.students) == ["canvas_1001"]
    assert second.lms["canvas_1001"]["name"] == "leeannmarie" and second.lms["canvas_1001"]["late"] is True


def test_usernames_that_would_be_one_folder_are_two_students(tmp_path):
    intake = intake_of(tmp_path, {"HW3_Ann_attempt_2026-03-02-09-00-00_02_reward.ipynb": NEW["02_reward.ipynb"],
                                  "HW3_ann_attempt_2026-03-02-09-00-00_02_reward.ipynb": OLD["02_reward.ipynb"]})
    assert len(intake.students) == 2
    assert {r["ids"]["username"] for r in intake.lms.values()} == {"Ann", "ann"}
    assert all(any("same folder" in n for n in notes) for notes in intake.notes.values())


def test_lookalike_usernames_are_two_students_and_both_are_told(tmp_path):
    pytest.importorskip("icu", reason="PyICU is not installed: look-alike ids are not checked (make icu)")
    cyrillic = "v\u0456ctim2"
    when = "attempt_2026-03-02-09-00-00_02_reward.ipynb"
    intake = intake_of(tmp_path, {f"HW3_victim2_{when}": NEW["02_reward.ipynb"],
                                  f"HW3_{cyrillic}_{when}": OLD["02_reward.ipynb"]})
    assert set(intake.students) == {"blackboard_victim2", f"blackboard_{cyrillic}"}
    assert intake.lms[f"blackboard_{cyrillic}"]["ids"] == {"username": cyrillic}
    for sid in intake.students:
        assert any("looks like" in n and "U+0456" in n for n in intake.notes[sid])


# --- hostile names in an LMS layout ----------------------------------------------------------------
@pytest.mark.parametrize("name", ["../leeann_1001_5_02_reward.ipynb", "/abs/leeann_1001_5_02_reward.ipynb",
                                  "x/../../leeann_1001_5_02_reward.ipynb", "leeann_1001_5_02\u202e_reward.ipynb"])
def test_hostile_member_names_in_an_lms_layout_are_refused(tmp_path, name, monkeypatch):
    monkeypatch.chdir(tmp_path)
    before = sorted(tmp_path.rglob("*"))
    intake = intake_of(tmp_path, {**lms.canvas(NEW), name: OLD["02_reward.ipynb"]},
                       symlinks={"müllerzoë_1002_99999_01_world_model.ipynb": "/etc/passwd"})
    assert sorted(p for p in tmp_path.rglob("*") if p.name != "download.zip") == before
    assert all(u.data in NEW.values() for ups in intake.students.values() for u in ups.values())
    assert rejected_for(intake, repr(name)) and "refused" in rejected_for(intake, repr(name))[0]
    assert "symbolic link" in rejected_for(intake, "99999")[0]


def test_canvas_file_named_as_another_users_file_is_graded_for_nobody(tmp_path):
    intake = intake_of(tmp_path, {**lms.canvas(NEW),
                                  "evil_1004_50_leeann_1001_40002_02_reward.ipynb": OLD["02_reward.ipynb"],
                                  # their own file, downloaded from Canvas and handed in again, is theirs
                                  "evil_1004_51_evil_1004_49_01_world_model.ipynb": OLD["01_world_model.ipynb"]})
    assert graded(intake, "canvas_1001").data == NEW["02_reward.ipynb"]
    assert set(intake.students["canvas_1004"]) == {"01_world_model.ipynb"}
    line = rejected_for(intake, "evil_1004_50")[0]
    assert "Canvas user 1004's upload" in line and "user 1001" in line and "nobody" in line
    assert any("belongs to Canvas user 1001, not to you" in n for n in intake.notes["canvas_1004"])


def test_canvas_name_ending_in_another_users_id_does_not_make_the_file_theirs(tmp_path):
    # A student whose Canvas name ends in "_1001" (another student's id): Canvas writes
    # "evil_1001_<own id 1004>_<file id>_<file>". Read by its notebook name, it is user 1004's.
    members = {"leeann_1001_40_02_reward.ipynb": NEW["02_reward.ipynb"],
               "evil_1001_1004_60_02_reward.ipynb": OLD["02_reward.ipynb"],
               "evil_1001_1004_61_9_01_world_model.ipynb": OLD["01_world_model.ipynb"]}
    intake = intake_of(tmp_path, members)
    assert graded(intake, "canvas_1001").data == NEW["02_reward.ipynb"]
    assert set(intake.students["canvas_1001"]) == {"02_reward.ipynb"}
    assert graded(intake, "canvas_1004").data == OLD["02_reward.ipynb"]
    assert intake.lms["canvas_1004"]["name"] == "evil_1001"
    # its other file reads two ways, as 1001's "61_9_01_world_model.ipynb" or as 1004's
    # "9_01_world_model.ipynb": the way its other file agrees on wins, and it is 1004's
    assert set(intake.students["canvas_1004"]) == {"02_reward.ipynb", "01_world_model.ipynb"}


def test_canvas_name_that_cannot_be_told_whose_it_is_is_graded_for_nobody(tmp_path):
    intake = intake_of(tmp_path, {"leeann_1001_40_02_reward.ipynb": NEW["02_reward.ipynb"],
                                  "evil_1001_1004_60_9_02_reward.ipynb": OLD["02_reward.ipynb"]})
    assert list(intake.students) == ["canvas_1001"]
    assert graded(intake, "canvas_1001").data == NEW["02_reward.ipynb"]
    line = rejected_for(intake, "evil_1001")[0]
    assert "user 1001 or 1004" in line and "graded for nobody" in line


def test_moodle_file_named_as_another_participants_is_graded_for_nobody(tmp_path):
    own = "Ann Lee_5301278_assignsubmission_file_01_world_model.ipynb"       # her own file, downloaded again
    intake = intake_of(tmp_path, {**lms.moodle(NEW),
                                  "Ann Lee_5301278_assignsubmission_file/Zoë Müller_5301277_assignsubmission_file_"
                                  "02_reward.ipynb": OLD["02_reward.ipynb"],
                                  f"Ann Lee_5301278_assignsubmission_file/x/{own}": NEW["01_world_model.ipynb"],
                                  "Ann Lee_5301278_assignsubmission_file/Zoë Müller_5301277_assignsubmission_file/"
                                  "01_world_model.ipynb": OLD["01_world_model.ipynb"]})
    assert graded(intake, "moodle_5301277").data == NEW["02_reward.ipynb"]
    assert graded(intake, "moodle_5301278").data == NEW["02_reward.ipynb"]
    assert graded(intake, "moodle_5301278", "01_world_model.ipynb").data == NEW["01_world_model.ipynb"]
    assert len(rejected_for(intake, "participant 5301277")) == 0
    lines = [line for line in intake.rejected if "Moodle user 5301277" in line]
    assert len(lines) == 2 and all("nobody" in line for line in lines)
    assert sum("belongs to Moodle user 5301277" in n for n in intake.notes["moodle_5301278"]) == 2


def test_blackboard_file_named_as_another_users_attempt_is_graded_for_nobody(tmp_path):
    forged = "Chapter 3.2 notebooks_jdoe_attempt_2026-03-09-00-00-00_02_reward.ipynb"
    own = "Chapter 3.2 notebooks_asmith_attempt_2026-03-08-00-00-00"
    intake = intake_of(tmp_path, {**lms.blackboard(NEW, OLD), f"{own}_{forged}": OLD["02_reward.ipynb"]})
    assert graded(intake, "blackboard_jdoe").data == NEW["02_reward.ipynb"]
    assert graded(intake, "blackboard_asmith").data == NEW["02_reward.ipynb"]
    assert "Blackboard user jdoe" in rejected_for(intake, "2026-03-08")[0]
    assert any("belongs to Blackboard user jdoe" in n for n in intake.notes["blackboard_asmith"])


def test_size_caps_hold_in_an_lms_layout(tmp_path):
    members = lms.canvas(NEW)
    members["leeann_1001_50000_02_reward-1.ipynb"] = b" " * 5000          # the newest, too big
    intake = intake_of(tmp_path, members, max_member_bytes=4000)
    assert graded(intake, "canvas_1001").member == "leeann_1001_40002_02_reward.ipynb"
    assert "limit for one file" in rejected_for(intake, "50000")[0]
    assert any("too big" in n for n in intake.notes["canvas_1001"])
    big = intake_of(tmp_path, members, max_total_bytes=3 * len(NEW["02_reward.ipynb"]))
    assert rejected_for(big, "limit for all files together")


def test_an_lms_download_of_a_large_class_is_read_quickly(tmp_path):
    members = {}
    for i in range(300):
        for n in NOTEBOOKS:
            members[f"student{i}_{2000 + i}_{90000 + 10 * i + NOTEBOOKS.index(n)}_{n}"] = b"{}"
    t = time.perf_counter()
    intake = intake_of(tmp_path, members)
    assert len(intake.lms) == 300 and intake.rejected == []
    assert time.perf_counter() - t < 10
