"""The feedback returned to each LMS (autograde/lms_feedback.py), read back as the LMS reads it.

A real nbgrader gradebook in this course's shape (tests/test_lms_export.py's template: a test
cell, a one-sentence answer graded by hand, a completion task cell), scores recorded by
``gradebook.record`` as grading does, and fake feedback pages on disk; nothing runs a notebook.
Each package is then read by a small parser written from the LMS's own importer, not with the
writer's helpers:

* Canvas, ``app/models/assignment.rb`` ``infer_comment_context_from_filename``: the basename split
  on ``_``, the first two all-digit parts are the user id and the attachment id; a last part
  starting with ``link`` or a name starting with ``._`` carries no attachment;
* Moodle, ``mod/assign/feedback/file/importziplib.php`` ``is_valid_filename_for_import``: each
  path part ``explode('_', $part, 5)``: at least 4 pieces, the second a participant id, the third
  and fourth a plugin of the assignment, the rest the file name; names starting ``.``/``~`` skipped;
* Blackboard: no importer; the files are named ``<username>_<page>``.
"""

from __future__ import annotations

import io
import re
import zipfile
from html.parser import HTMLParser

import pytest

from autograde import checks, lms_feedback
from autograde.class_report import CSP
from autograde.course import ASSIGNMENT
from autograde.lms_feedback import (BLACKBOARD_DIR, BLACKBOARD_ZIP, CANVAS_ZIP, GENERIC_ZIP, MOODLE_ZIP, README,
                                    RETURN_DIR, write_feedback_return)
from browser_support import chromium
from test_lms_export import canvas_id, course, grade, moodle_id, template  # noqa: F401 (fixtures)

HOSTILE = '<script>alert("x")</script><img src=x onerror=alert(1)>'
NAMES = {"ann": "Ann Lee", "bob": "O'Brien, Bob \"Bobby\"", "zoe": "Zoë_Ångström", "eve": "=HYPERLINK(\"x\")"}
PLUGINS = {("assignsubmission", "file"), ("assignfeedback", "file")}   # the plugins of the assignment




def pages_for(course, students, notebooks=("02_reward", "04_imagination_gap")) -> dict:
    """Fake feedback pages as grading leaves them: {student: {page name: bytes}}."""
    out = {}
    for s in students:
        folder = course / "feedback" / s / ASSIGNMENT
        folder.mkdir(parents=True)
        for nb in notebooks:
            data = f"<!DOCTYPE html><title>{nb}</title><p>page of {s}: {nb}</p>".encode()
            (folder / f"{nb}.html").write_bytes(data)
            out.setdefault(s, {})[f"{nb}.html"] = data
    return out


def members(path) -> dict[str, bytes]:
    with zipfile.ZipFile(path) as z:
        return {i.filename: z.read(i) for i in z.infolist() if not i.is_dir()}


# --- the LMSs' importers, re-read from their source ---------------------------------------------
def canvas_infer(filename: str) -> tuple[str | None, str | None]:
    """(user id, attachment id) as Canvas's infer_comment_context_from_filename reads a zip member."""
    base = filename.rsplit("/", 1)[-1]
    split = base.split("_")
    digits = [p for p in split if re.fullmatch(r"\d+", p)][:2]
    user_id = digits[0] if digits else None
    attachment_id = digits[1] if len(digits) > 1 else None
    if split[-1].startswith("link") or base.startswith("._"):
        attachment_id = None
    return user_id, attachment_id


def moodle_import(path: str, participants: set[str]) -> tuple[str, str] | None:
    """(participant id, file name) as Moodle's is_valid_filename_for_import reads a zip member, or None."""
    base = path.rsplit("/", 1)[-1]
    if base.startswith((".", "~")):
        return None
    parts = ("/import/" + path).split("/")
    while parts:
        info = parts.pop(0).split("_", 4)            # PHP explode('_', $part, 5)
        if len(info) < 4 or not info[1].isdigit() or info[1] not in participants:
            continue
        if (info[2], info[3]) not in PLUGINS:
            continue
        parts.insert(0, info[4] if len(info) == 5 else "")
        return info[1], "/".join(parts)
    return None


class Page(HTMLParser):
    """What a browser would make of a summary page: its elements, attributes and text."""

    def __init__(self, data: bytes):
        super().__init__(convert_charrefs=True)
        self.tags, self.text, self.attrs, self.head_first = [], [], [], None
        self.feed(data.decode("utf-8"))

    def handle_starttag(self, tag, attrs):
        self.tags.append(tag)
        self.attrs += attrs
        if self.head_first is None and self.tags[:-1] == ["html", "head"]:
            self.head_first = (tag, dict(attrs))

    def handle_data(self, data):
        self.text.append(data)

    @property
    def words(self) -> str:
        return "".join(self.text)


def assert_safe_page(data: bytes):
    page = Page(data)
    assert page.head_first == ("meta", {"http-equiv": "Content-Security-Policy", "content": CSP})
    assert "script-src 'none'" in CSP and "default-src 'none'" in CSP
    assert "script" not in page.tags and "iframe" not in page.tags and "img" not in page.tags
    assert not any(k.startswith("on") for k, _ in page.attrs)
    assert ("name", "viewport") in page.attrs
    text = data.decode()
    assert "prefers-color-scheme: dark" in text and "color-scheme: light dark" in text
    assert not re.search(r"(?<!max-)width:\s*\d+px", text)          # no fixed width: fits a phone
    return page


# --- Canvas ---------------------------------------------------------------------------------------
def test_canvas_reupload_zip_reaches_each_user_and_attachment(course):
    ids = {s: canvas_id(100 + i, NAMES[s]) for i, s in enumerate(NAMES)}
    report = grade(course, {s: (ids[s], "answered") for s in NAMES}, manual={"ann": 1, "bob": 0.5, "zoe": 0})
    report["ann"]["notes"] += [f"02_reward.ipynb: {HOSTILE}", "02_reward.ipynb: answer key, for the instructor: x"]
    hint = checks.TESTS["reward_impl_tests"].cases[0].hint
    report["bob"]["verdicts"]["reward_impl_tests"] = (0.0, 4.0, f"2 of 9 checks passed; first failure: check 1: "
                                                                 f"{hint} (got 3)")
    pages = pages_for(course, ["ann", "bob", "zoe"])                  # eve: no page was made
    lines = []
    paths = write_feedback_return(course, report, log=lines.append)

    out = course / RETURN_DIR
    assert sorted(p.name for p in out.iterdir()) == sorted([CANVAS_ZIP, README, "report.json"])
    assert out / CANVAS_ZIP in paths and not (out / MOODLE_ZIP).exists() and not (out / GENERIC_ZIP).exists()
    got: dict[tuple, dict] = {}
    for name, data in members(out / CANVAS_ZIP).items():
        uid, aid = canvas_infer(name)
        assert uid and aid, name
        got.setdefault((uid, aid), {})[name.split(f"_{uid}_{aid}_", 1)[1]] = data
    assert set(got) == {(ids[s]["ids"]["user_id"].__str__(), ids[s]["ids"]["attachment_id"]) for s in NAMES}
    for s in NAMES:
        files = got[(str(ids[s]["ids"]["user_id"]), ids[s]["ids"]["attachment_id"])]
        assert sorted(files) == sorted(["summary.html", *pages.get(s, {})])
        for page, data in pages.get(s, {}).items():
            assert files[page] == data                             # the notebook pages, unchanged
        summary = assert_safe_page(files["summary.html"])
        shown = NAMES[s]
        assert shown in summary.words                              # quotes, Unicode and '=' shown as text
        assert f"student id {s}" in summary.words
        assert f"Canvas user id {100 + list(NAMES).index(s)}" in summary.words

    ann = Page(got[("100", "9100")]["summary.html"])
    assert HOSTILE in ann.words                                    # the hostile note is text, not markup
    assert "answer key" not in ann.words                            # the instructor's note stays with them
    assert "Total: 9 of 9 points" in ann.words and "Clear." in ann.words       # manual grade and its comment
    bob = Page(got[("101", "9101")]["summary.html"])
    assert "Total: 8.5 of 9 points" in bob.words
    assert f"reward_impl_tests: check 1: {hint}" in bob.words and "(got 3)" not in bob.words
    eve = Page(got[("103", "9103")]["summary.html"])
    assert "not graded yet and not counted above (never as 0): 04_imagination_gap ex1_sentence" in eve.words
    assert "Total: 8 of 9 points" in eve.words and "There are none: no feedback page was made" in eve.words
    readme = (out / README).read_text()
    assert "Re-Upload Submissions" in readme and "ann (1)" in readme
    assert "canvas_feedback_upload.zip: feedback for 4 students" in " ".join(lines)


def test_canvas_name_part_never_reads_as_an_id(course):
    odd = {"d": canvas_id(7, "2024"), "u": canvas_id(8, "lee_12_ann"), "l": canvas_id(9, "link")}
    report = grade(course, {s: (lms, "blank") for s, lms in odd.items()})
    write_feedback_return(course, report, log=lambda _: None)
    names = members(course / RETURN_DIR / CANVAS_ZIP)
    assert {canvas_infer(n) for n in names} == {("7", "97"), ("8", "98"), ("9", "99")}
    assert "student_7_97_summary.html" in names and "lee12ann_8_98_summary.html" in names


def test_canvas_only_report_writes_no_other_package_and_removes_a_stale_one(course):
    out = course / RETURN_DIR
    out.mkdir()
    (out / MOODLE_ZIP).write_bytes(b"old")
    (out / BLACKBOARD_DIR).mkdir()
    report = grade(course, {"ann": (canvas_id(1, "Ann"), "blank")})
    write_feedback_return(course, report, log=lambda _: None)
    assert sorted(p.name for p in out.iterdir()) == sorted([CANVAS_ZIP, README, "report.json"])


def test_anonymous_and_doubly_claimed_canvas_ids_go_to_the_per_student_zip(course):
    report = grade(course, {"anon": ({**canvas_id("anon_Xy12", None), "name": None}, "blank"),
                            "a1": (canvas_id(5, "Ann"), "blank"), "a2": (canvas_id(5, "Ann"), "blank"),
                            "ok": (canvas_id(6, "Ok"), "blank")})
    write_feedback_return(course, report, log=lambda _: None)
    out = course / RETURN_DIR
    assert {canvas_infer(n)[0] for n in members(out / CANVAS_ZIP)} == {"6"}
    assert sorted(members(out / GENERIC_ZIP)) == sorted(f"{s}/summary.html" for s in ("anon", "a1", "a2"))
    readme = (out / README).read_text()
    assert "anon: anonymous grading" in readme and "a1: its Canvas id is claimed by another student" in readme


# --- Moodle ---------------------------------------------------------------------------------------
def test_moodle_feedback_zip_reaches_each_participant(course):
    ids = {s: moodle_id(str(48210 + i), NAMES[s]) for i, s in enumerate(NAMES)}
    report = grade(course, {s: (ids[s], "blank") for s in NAMES})
    report["zoe"]["notes"].append(HOSTILE)
    pages = pages_for(course, list(NAMES))
    write_feedback_return(course, report, log=lambda _: None)
    out = course / RETURN_DIR
    assert not (out / CANVAS_ZIP).exists() and (out / MOODLE_ZIP).is_file()
    participants = {m["ids"]["participant_id"] for m in ids.values()}
    got: dict[str, dict] = {}
    for name, data in members(out / MOODLE_ZIP).items():
        found = moodle_import(name, participants)
        assert found, name
        pid, file = found
        assert "/" not in file
        got.setdefault(pid, {})[file] = data
        assert not re.search(r"[\x00-\x1f]", name)
    for s in NAMES:
        files = got[ids[s]["ids"]["participant_id"]]
        assert sorted(files) == sorted(["summary.html", *pages[s]])
        assert all(files[p] == pages[s][p] for p in pages[s])
        summary = assert_safe_page(files["summary.html"])
        assert NAMES[s] in summary.words and "Total: 8 of 9 points" in summary.words
    assert HOSTILE in Page(got["48212"]["summary.html"]).words
    # Moodle splits the full name on '_': Zoë's is written with a space, as Moodle's own download does
    assert "Zoë Ångström_48212_assignsubmission_file_summary.html" in members(out / MOODLE_ZIP)
    with zipfile.ZipFile(out / MOODLE_ZIP) as z:                       # names marked UTF-8 (general purpose bit 11)
        assert all(i.flag_bits & 0x800 for i in z.infolist() if not i.filename.isascii())
    assert "OBrien, Bob Bobby_48211_assignsubmission_file_summary.html" in members(out / MOODLE_ZIP)
    assert "Upload multiple feedback files in a zip" in (out / README).read_text()


def test_moodle_names_that_would_hide_or_split_are_cleaned(course):
    report = grade(course, {"a": (moodle_id("11", ".hidden"), "blank"), "b": (moodle_id("12", "a/b\x07c"), "blank"),
                            "c": (moodle_id("13", ""), "blank")})
    write_feedback_return(course, report, log=lambda _: None)
    names = members(course / RETURN_DIR / MOODLE_ZIP)
    assert {moodle_import(n, {"11", "12", "13"})[0] for n in names} == {"11", "12", "13"}
    assert "hidden_11_assignsubmission_file_summary.html" in names
    assert "ab c_12_assignsubmission_file_summary.html" in names      # '/' removed as clean_param does
    assert "Participant_13_assignsubmission_file_summary.html" in names


# --- Blackboard -----------------------------------------------------------------------------------
def test_blackboard_files_are_named_by_username(course):
    bb = {s: {"system": "blackboard", "name": NAMES[s], "ids": {"username": u}, "late": None,
              "submitted_at": None, "attempt": 1} for s, u in zip(NAMES, ("alee", "s_0042", "zoe.a", "eve9"))}
    report = grade(course, {s: (bb[s], "blank") for s in NAMES})
    pages = pages_for(course, list(NAMES))
    write_feedback_return(course, report, log=lambda _: None)
    out = course / RETURN_DIR
    folder = {p.name: p.read_bytes() for p in (out / BLACKBOARD_DIR).iterdir()}
    assert folder == members(out / BLACKBOARD_ZIP)
    expected_pages = ["summary.html", "02_reward.html", "04_imagination_gap.html"]
    for s in NAMES:
        user = bb[s]["ids"]["username"]
        mine = {n[len(user) + 1:]: d for n, d in folder.items() if n.startswith(f"{user}_")
                and n[len(user) + 1:] in expected_pages}
        assert sorted(mine) == sorted(expected_pages)
        assert all(mine[p] == pages[s][p] for p in pages[s])
        assert NAMES[s] in assert_safe_page(mine["summary.html"]).words
    assert len(folder) == 3 * len(NAMES)
    assert "Blackboard Learn Original has no bulk upload" in (out / README).read_text()
    assert not (out / CANVAS_ZIP).exists() and not (out / MOODLE_ZIP).exists()


# --- generic layouts, no pages, the command line, atomic writes -------------------------------------
def test_generic_students_get_a_folder_each_and_a_summary_without_pages(course):
    report = grade(course, {"s042": (None, "blank"), "s043": (None, "missing")})
    report["nobody"] = {"notes": ["skipped: 'x.ipynb' is not a notebook of this assignment"], "completion": {},
                        "verdicts": {}, "failed": {}, "lms": None}
    pages_for(course, ["s042"])
    write_feedback_return(course, report, log=lambda _: None)
    names = members(course / RETURN_DIR / GENERIC_ZIP)
    assert sorted(names) == ["nobody/summary.html", "s042/02_reward.html", "s042/04_imagination_gap.html",
                             "s042/summary.html", "s043/summary.html"]
    nobody = assert_safe_page(names["nobody/summary.html"]).words
    assert "no notebook of yours could be graded" in nobody and "is not a notebook of this assignment" in nobody
    s043 = Page(names["s043/summary.html"]).words
    assert "not graded (not handed in, or not readable" in s043 and "Total: 4 of 9 points" in s043


def test_command_line_rewrites_from_the_saved_report(course, monkeypatch):
    report = grade(course, {"ann": (canvas_id(1, "Ann"), "answered")})
    write_feedback_return(course, report, log=lambda _: None)
    before = members(course / RETURN_DIR / CANVAS_ZIP)
    assert "not graded yet" in Page(before["ann_1_91_summary.html"]).words
    grade(course, {"ann": (canvas_id(1, "Ann"), "answered")}, manual={"ann": 1})      # hand grading, then
    assert lms_feedback.main(["--course", str(course)]) == 0
    after = Page(members(course / RETURN_DIR / CANVAS_ZIP)["ann_1_91_summary.html"]).words
    assert "Total: 9 of 9 points" in after and "not graded yet" not in after
    with pytest.raises(SystemExit):
        lms_feedback.main(["--course", str(course / "nowhere")])


def test_a_failed_write_leaves_the_old_zip_whole(course, monkeypatch):
    report = grade(course, {"ann": (canvas_id(1, "Ann"), "blank")})
    write_feedback_return(course, report, log=lambda _: None)
    old = (course / RETURN_DIR / CANVAS_ZIP).read_bytes()

    def broken(source):
        raise OSError("disk full")
    monkeypatch.setattr(lms_feedback, "_content", broken)          # fails halfway through the zip
    with pytest.raises(OSError):
        write_feedback_return(course, report, log=lambda _: None)
    assert (course / RETURN_DIR / CANVAS_ZIP).read_bytes() == old
    assert zipfile.ZipFile(io.BytesIO(old)).testzip() is None
    assert not [p for p in (course / RETURN_DIR).iterdir() if p.name.startswith(".")]


def test_a_notebook_page_carries_its_own_canvas_file_id_where_intake_kept_it(course):
    lms = canvas_id(7, "Ann")
    lms["attachment_ids"] = {"02_reward.ipynb": "5551", "04_imagination_gap.ipynb": "5552"}
    report = grade(course, {"ann": (lms, "blank")})
    pages_for(course, ["ann"])
    write_feedback_return(course, report, log=lambda _: None)
    got = {name.split("_", 3)[3]: canvas_infer(name) for name in members(course / RETURN_DIR / CANVAS_ZIP)}
    assert got == {"summary.html": ("7", "97"), "02_reward.html": ("7", "5551"),
                   "04_imagination_gap.html": ("7", "5552")}


def test_a_linked_or_huge_page_is_not_sent(course, tmp_path, monkeypatch):
    report = grade(course, {"s1": (None, "blank")})
    folder = course / "feedback" / "s1" / ASSIGNMENT
    folder.mkdir(parents=True)
    secret = tmp_path / "secret.html"
    secret.write_text("instructor's file")
    (folder / "02_reward.html").symlink_to(secret)                      # a link is never followed
    (folder / "04_imagination_gap.html").write_bytes(b"x" * 100)
    monkeypatch.setattr(lms_feedback, "MAX_PAGE_BYTES", 50)             # nor a page over the cap
    write_feedback_return(course, report, log=lambda _: None)
    names = members(course / RETURN_DIR / GENERIC_ZIP)
    assert list(names) == ["s1/summary.html"]
    assert "instructor's file" not in names["s1/summary.html"].decode()


@pytest.mark.lane
@pytest.mark.slow                  # opens Chromium
def test_the_summary_opens_on_a_phone_in_light_and_dark_mode(course, tmp_path):
    """Headless Chromium at a phone's width: nothing runs, nothing is fetched, nothing overflows
    sideways, the hostile note and name are text, and dark mode is dark."""
    long_name = "Zoë " + "Ångström-" * 30 + HOSTILE
    report = grade(course, {"zoe": (moodle_id("48212", long_name), "answered")})
    report["zoe"]["notes"].append(HOSTILE + " " + "x" * 400)
    report["zoe"]["human"] = [       # as intake finds them: a renamed notebook, graded; a stray file, not
        {"student": "zoe", "file": "05_horizon_final.ipynb", "graded": "05_horizon.ipynb",
         "why": "its name names no notebook of this assignment, but it holds 97% of 05_horizon.ipynb's cells"},
        {"student": "zoe", "file": "scratch.ipynb", "graded": None,
         "why": "it holds at most 3% of any notebook's cells (at least 30% are needed)"}]
    pages_for(course, ["zoe"])
    write_feedback_return(course, report, log=lambda _: None)
    data = next(d for n, d in members(course / RETURN_DIR / MOODLE_ZIP).items() if n.endswith("_summary.html"))
    page_file = tmp_path / "summary.html"
    page_file.write_bytes(data)
    results = {}
    with chromium() as browser:
        for scheme in ("light", "dark"):
            page = browser.new_page(viewport={"width": 360, "height": 640}, color_scheme=scheme)
            seen = {"console": [], "errors": [], "requests": [], "dialogs": []}
            page.on("console", lambda m, seen=seen: seen["console"].append(f"{m.type}: {m.text}"))
            page.on("pageerror", lambda e, seen=seen: seen["errors"].append(str(e)))
            page.on("request", lambda r, seen=seen: seen["requests"].append(r.url))
            page.on("dialog", lambda d, seen=seen: (seen["dialogs"].append(d.message), d.dismiss()))
            page.goto(page_file.as_uri())
            page.wait_for_load_state("load")
            results[scheme] = {
                **seen,
                "overflow": page.evaluate("document.documentElement.scrollWidth - window.innerWidth"),
                "scripts": page.evaluate("document.scripts.length + document.images.length"),
                "text": page.evaluate("document.body.innerText"),
                "colors": page.evaluate("[getComputedStyle(document.body).color, "
                                        "getComputedStyle(document.body).backgroundColor]"),
            }
            page.close()
    for scheme, r in results.items():
        assert not r["errors"] and not r["dialogs"] and not [m for m in r["console"] if m.startswith("error")], r
        assert r["requests"] == [page_file.as_uri()], r["requests"]
        assert r["overflow"] <= 0, (scheme, r["overflow"])             # no sideways scrolling on a phone
        assert r["scripts"] == 0 and HOSTILE in r["text"] and "Zoë Ångström-" in r["text"]
        # the renamed and the refused file, said as the student reads it, beside their name and ids
        assert "05_horizon_final.ipynb: graded as 05_horizon.ipynb" in r["text"], r["text"]
        assert "scratch.ipynb: not graded" in r["text"] and "zoe" in r["text"] and "48212" in r["text"]

    def luminance(css):
        return sum(int(v) for v in re.findall(r"\d+", css)[:3]) / 3

    light_fg, light_bg = map(luminance, results["light"]["colors"])
    dark_fg, dark_bg = map(luminance, results["dark"]["colors"])
    assert light_bg > 200 and light_fg < 60 and dark_bg < 60 and dark_fg > 200


def test_no_student_changes_nothing_and_a_refused_manual_grade_is_not_shown(course, monkeypatch):
    out = course / RETURN_DIR
    out.mkdir()
    (out / CANVAS_ZIP).write_bytes(b"earlier")
    assert write_feedback_return(course, {}, log=lambda _: None) == []
    assert [p.name for p in out.iterdir()] == [CANVAS_ZIP] and (out / CANVAS_ZIP).read_bytes() == b"earlier"

    report = grade(course, {"ann": (canvas_id(1, "Ann"), "answered")}, manual={"ann": 7})   # outside 0..1
    monkeypatch.setattr(lms_feedback, "lms_settings", lambda: ({"points_possible": 90.0}, []))
    write_feedback_return(course, report, log=lambda _: None)
    words = Page(members(out / CANVAS_ZIP)["ann_1_91_summary.html"]).words
    assert "ex1_sentence: not graded yet" in words and "7 of" not in words and "Clear." in words
    assert "Total: 8 of 9 points" in words and "out of 90: 80 of 90" in words


def test_a_very_long_name_makes_member_names_a_file_system_can_hold(course):
    """A name of thousands of characters (a red team's) still gives each zip member a name of at most
    255 bytes, as most file systems hold, and the ids still reach the student."""
    long = "Zoë " * 1500
    report = grade(course, {"ann": (canvas_id(7, long), "blank"), "zoe": (moodle_id("48212", long), "blank")})
    pages_for(course, ["ann", "zoe"])
    write_feedback_return(course, report, log=lambda _: None)
    for zip_name in (CANVAS_ZIP, MOODLE_ZIP):
        names = members(course / RETURN_DIR / zip_name)
        assert names and all(len(n.rsplit("/", 1)[-1].encode()) <= 255 for n in names), zip_name
    assert {canvas_infer(n)[0] for n in members(course / RETURN_DIR / CANVAS_ZIP)} == {"7"}
    assert {moodle_import(n, {"48212"})[0] for n in members(course / RETURN_DIR / MOODLE_ZIP)} == {"48212"}
