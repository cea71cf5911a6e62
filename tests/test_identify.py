"""Notebooks known by what they hold, not by their names (autograde/identify.py, intake's ``release=``).

Fast: no kernel. The release is the student notebooks/ of this repository; a student's work is
played by solutions/ (every exercise answered), saved under the names students really give files,
in the generic layouts and in each LMS's own (``autograde/classes/lms.py``). Properties, not only
cases: every renaming a generator makes of every notebook is graded as that notebook; a file that
is no notebook of the assignment is graded as nothing and said to a human; two files that are one
notebook are told.
"""

import random
import zipfile
from pathlib import Path

import nbformat
import pytest

from autograde.classes import lms
from autograde.identify import MIN_SHARE, Identifier
from autograde.intake import NotebookNames, collect

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted(p.name for p in (ROOT / "notebooks").glob("*.ipynb"))
RELEASE = {n: nbformat.read(ROOT / "notebooks" / n, as_version=4) for n in NOTEBOOKS}
WORKED = {n: nbformat.read(ROOT / "solutions" / n, as_version=4) for n in NOTEBOOKS}


def worked(name: str, *, ids: bool = True, tag: str = "") -> bytes:
    nb = nbformat.from_dict(WORKED[name])
    if not ids:                                   # a tool that writes nbformat 4.4 drops cell ids
        for c in nb.cells:
            c.pop("id", None)
        nb.nbformat_minor = 4
    if tag:
        nb.cells.append(nbformat.v4.new_markdown_cell(tag))
    return nbformat.writes(nb).encode("utf-8")


def zipped(tmp_path: Path, members: dict, name="download.zip") -> Path:
    return lms.write_zip(tmp_path / name, members)


def test_each_worked_notebook_is_itself_with_ids_and_without():
    ident = Identifier(RELEASE)
    for n in NOTEBOOKS:
        for ids in (True, False):
            m = ident.identify(nbformat.reads(worked(n, ids=ids).decode(), as_version=4))
            assert m.notebook == n and m.share > 0.8, (n, ids, m)


def test_what_is_no_notebook_of_the_assignment_is_none():
    ident = Identifier(RELEASE)
    blank = nbformat.v4.new_notebook()
    blank.cells = [nbformat.v4.new_code_cell("import numpy as np\nprint('my own experiment, nothing else')")]
    assert ident.identify(blank).notebook is None and "at least" in ident.identify(blank).words()
    # half of 04 pasted into 05: too close to tell, never a guess
    mixed = nbformat.from_dict(WORKED["05_horizon.ipynb"])
    mixed.cells = WORKED["04_imagination_gap.ipynb"].cells[:25] + WORKED["05_horizon.ipynb"].cells[:20]
    m = ident.identify(mixed)
    assert m.notebook is None and "too close to tell" in m.words()


RENAMES = ["{stem}_final", "final {stem}", "{stem} FINAL v3", "my {stem}", "{stem}-submission", "copy of copy of {stem}",
           "{stem} (copy)", "untitled", "Untitled1", "{number}", "notebook_{number}", "{stem}.ipynb_backup"]


@pytest.mark.parametrize("seed", range(4))
def test_any_renaming_is_graded_as_what_it_is(tmp_path, seed):
    """A generator of names students give files: every one is graded as the notebook it holds, in a
    student folder; the note says so, and the instructor's list ('needs a human') names it."""
    rng = random.Random(seed)
    members, expect = {}, {}
    for n in NOTEBOOKS:
        stem = n.removesuffix(".ipynb")
        name = rng.choice(RENAMES).format(stem=stem, number=stem[:2])
        name += f" {len(expect)}.ipynb" if f"s1/{name}.ipynb" in members else ".ipynb"   # one folder, one name
        members[f"s1/{name}"] = worked(n, ids=rng.random() < 0.5)
        expect[n] = name
    got = collect(zipped(tmp_path, members), NOTEBOOKS, release=RELEASE)
    assert set(got.students["s1"]) == set(NOTEBOOKS), (got.rejected, got.notes)
    for n, name in expect.items():
        assert got.students["s1"][n].member.endswith(name)
    renamed = {h["file"] for h in got.human if h["graded"]}
    named = NotebookNames(NOTEBOOKS)
    for n, name in expect.items():
        if named.parse(name) is None:           # its name says no notebook: its content did
            assert name in renamed and any(line.startswith(f"{name}: graded as {n}") for line in got.notes["s1"])


def test_a_file_named_for_one_notebook_that_holds_another_is_graded_as_what_it_holds(tmp_path):
    got = collect(zipped(tmp_path, {"s1_04_imagination_gap.ipynb": worked("05_horizon.ipynb")}), NOTEBOOKS,
                  release=RELEASE)
    assert list(got.students["s1"]) == ["05_horizon.ipynb"]
    [h] = got.human
    assert h == {"student": "s1", "file": "s1_04_imagination_gap.ipynb", "graded": "05_horizon.ipynb",
                 "why": h["why"]} and "its name says 04_imagination_gap.ipynb" in h["why"]


def test_no_notebook_and_two_of_one_go_to_a_human_and_to_the_student(tmp_path):
    blank = nbformat.v4.new_notebook()
    blank.cells = [nbformat.v4.new_markdown_cell("My scratch work for the course, not an assignment notebook.")]
    members = {"s1/scratch.ipynb": nbformat.writes(blank).encode(),
               "s1/05_horizon.ipynb": worked("05_horizon.ipynb", tag="first"),
               "s1/05_horizon_final.ipynb": worked("05_horizon.ipynb", tag="second")}
    path = tmp_path / "download.zip"
    with zipfile.ZipFile(path, "w") as zf:          # the renamed one saved later: it is the newest
        for i, (name, data) in enumerate(members.items()):
            zf.writestr(zipfile.ZipInfo(name, date_time=(2026, 3, 5, 16, i, 0)), data)
    got = collect(path, NOTEBOOKS, release=RELEASE)
    assert set(got.students["s1"]) == {"05_horizon.ipynb"}
    assert got.students["s1"]["05_horizon.ipynb"].member == "s1/05_horizon_final.ipynb"
    refused = [h for h in got.human if h["graded"] is None]
    assert [h["file"] for h in refused] == ["scratch.ipynb"] and f"{MIN_SHARE:.0%}" in refused[0]["why"]
    [two] = [h for h in got.human if "files are" in h["why"]]
    assert "05_horizon.ipynb" in two["file"] and "05_horizon_final.ipynb" in two["file"]
    notes = "\n".join(got.notes["s1"])
    assert "scratch.ipynb: not graded" in notes and "05_horizon_final.ipynb: graded as 05_horizon.ipynb" in notes
    assert any("scratch.ipynb" in r for r in got.rejected)


def test_the_same_name_twice_is_a_reupload_not_a_question(tmp_path):
    members = {"s1/05_horizon.ipynb": worked("05_horizon.ipynb", tag="old"),
               "s1/05_horizon (1).ipynb": worked("05_horizon.ipynb", tag="new")}
    got = collect(zipped(tmp_path, members), NOTEBOOKS, release=RELEASE)
    assert got.human == [] and got.students["s1"]["05_horizon.ipynb"].member == "s1/05_horizon (1).ipynb"


@pytest.mark.parametrize("system", ["canvas", "moodle", "blackboard"])
def test_renamed_in_each_lms_download(tmp_path, system):
    """Each LMS's own layout: the renamed notebooks are graded for every student, by the LMS's id."""
    files = {"05_horizon_final.ipynb": worked("05_horizon.ipynb"), "Copy of 04_imagination_gap (2).ipynb":
             worked("04_imagination_gap.ipynb"), "untitled.ipynb": worked("06_closing_the_gap.ipynb")}
    got = collect(zipped(tmp_path, getattr(lms, system)(files)), NOTEBOOKS, release=RELEASE)
    assert got.students and all(s.startswith(system + "_") for s in got.students)
    for sid, uploads in got.students.items():
        assert set(uploads) == {"04_imagination_gap.ipynb", "05_horizon.ipynb", "06_closing_the_gap.ipynb"}, \
            (sid, got.notes[sid], got.rejected)
    assert not [r for r in got.rejected if "refused" in r and ".ipynb" in r and "receipt" not in r]


def test_without_the_release_names_alone_decide_as_before(tmp_path):
    got = collect(zipped(tmp_path, {"s1_05_horizon_final.ipynb": worked("05_horizon.ipynb")}), NOTEBOOKS)
    assert not got.students.get("s1") and got.human == [] and "no notebook" in got.rejected[0]


# --- found by a red team (issue 39): each case failed before its fix ---------------------------------
def released(name: str) -> bytes:
    return nbformat.writes(nbformat.from_dict(RELEASE[name])).encode("utf-8")


def test_one_students_many_files_cannot_spend_the_class_limit(tmp_path):
    """Read ahead, every file counts against the class's byte limit: one hand-in of 40 copies may
    not leave a later student unread. A student's files are read newest first, at most
    MAX_FILES_PER_NOTEBOOK uploads of each notebook; the rest are said, not silently dropped."""
    from autograde.intake import MAX_FILES_PER_NOTEBOOK

    copy = worked("05_horizon.ipynb")
    members = {f"aaa/05_horizon ({i}).ipynb": copy for i in range(1, 41)}
    members.update({"zzz/02_reward.ipynb": worked("02_reward.ipynb"), "zzz/05_horizon.ipynb": copy})
    limit = (MAX_FILES_PER_NOTEBOOK * len(NOTEBOOKS) + 3) * len(copy)
    got = collect(zipped(tmp_path, members), NOTEBOOKS, release=RELEASE, max_total_bytes=limit)
    assert set(got.students["zzz"]) == {"02_reward.ipynb", "05_horizon.ipynb"}, got.notes["zzz"]
    assert got.students["aaa"]["05_horizon.ipynb"].member == "aaa/05_horizon (40).ipynb"
    assert any("ignored the older" in n and "05_horizon (1).ipynb" in n for n in got.notes["aaa"])   # said, not dropped


def test_a_canvas_download_whose_files_are_all_renamed_is_still_canvas(tmp_path):
    files = {"05_horizon_final.ipynb": worked("05_horizon.ipynb"), "my 04.ipynb": worked("04_imagination_gap.ipynb")}
    got = collect(zipped(tmp_path, lms.canvas(files)), NOTEBOOKS, release=RELEASE)
    assert sorted(got.students) == ["canvas_1001", "canvas_1002", "canvas_1003"] and len(got.lms) == 3
    assert all(set(u) == {"04_imagination_gap.ipynb", "05_horizon.ipynb"} for u in got.students.values())
    assert not [r for r in got.rejected if "refused" in r]


def test_the_work_is_graded_before_a_newer_copy_of_the_hand_out(tmp_path):
    path = tmp_path / "download.zip"
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr(zipfile.ZipInfo("bob/05_horizon.ipynb", date_time=(2026, 3, 5, 16, 0, 0)), worked("05_horizon.ipynb"))
        zf.writestr(zipfile.ZipInfo("bob/05_horizon_original.ipynb", date_time=(2026, 3, 6, 9, 0, 0)),
                    released("05_horizon.ipynb"))
    got = collect(path, NOTEBOOKS, release=RELEASE)
    assert got.students["bob"]["05_horizon.ipynb"].member == "bob/05_horizon.ipynb"
    assert any("holds the notebook as handed out" in n for n in got.notes["bob"])
    assert [h["graded"] for h in got.human] == ["05_horizon.ipynb"]


def test_flat_names_whose_student_part_is_unreadable_find_their_student(tmp_path):
    members = {"s042_Copy of Copy of 05_horizon.ipynb": worked("05_horizon.ipynb"),
               "s042_04_imagination_gap.ipynb": worked("04_imagination_gap.ipynb"),
               "ann_horizon.ipynb": worked("05_horizon.ipynb"), "ann_04_imagination_gap.ipynb": worked("04_imagination_gap.ipynb"),
               "nobody here.ipynb": worked("02_reward.ipynb")}
    got = collect(zipped(tmp_path, members), NOTEBOOKS, release=RELEASE)
    assert set(got.students["s042"]) == set(got.students["ann"]) == {"04_imagination_gap.ipynb", "05_horizon.ipynb"}
    assert any(n.startswith("ann_horizon.ipynb: graded as 05_horizon.ipynb") for n in got.notes["ann"])
    assert any("nobody here.ipynb" in r and "no student" in r for r in got.rejected)


def test_a_name_whose_content_is_too_close_to_tell_is_said(tmp_path):
    mixed = nbformat.from_dict(WORKED["05_horizon.ipynb"])
    mixed.cells = WORKED["04_imagination_gap.ipynb"].cells[:25] + WORKED["05_horizon.ipynb"].cells[:20]
    got = collect(zipped(tmp_path, {"eve/04_imagination_gap.ipynb": nbformat.writes(mixed).encode()}), NOTEBOOKS,
                  release=RELEASE)
    assert list(got.students["eve"]) == ["04_imagination_gap.ipynb"]          # by its name, and said
    [h] = got.human
    assert h["graded"] == "04_imagination_gap.ipynb" and "too close to tell" in h["why"]
    assert any("by its name only" in n for n in got.notes["eve"])
