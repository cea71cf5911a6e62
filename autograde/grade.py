"""Grade a whole class in one command: LMS download -> scores, feedback HTML and a grades CSV.

    python autograde/grade.py SUBMISSIONS [--course autograde] [--timeout 120] [--jobs N]

SUBMISSIONS is a .zip as the LMS hands it over, or a folder: each student's downloaded notebooks
(Jupyter or Colab), named ``<student_id>_<notebook>.ipynb`` or placed in ``<student_id>/``
folders (``intake.py`` says exactly what is accepted and what is refused).

Student code is untrusted. What happens, per student:

1. ``intake.collect`` reads the download in memory (hostile names refused, nothing written
   outside the course), normalises LMS ids and picks the newest of several uploads;
2. ``repair``: each notebook is decoded (any common encoding), cleaned of Colab metadata, its
   graded cells matched back to the instructor's (by id or content) and deleted test cells put
   back; the prediction receipts are checked; the student's own cells are checked for calls to
   the package's implementation of what they were asked to write (``checks.delegations``);
3. the student is graded in a private copy of the course (in a temporary folder), by nbgrader,
   in kernels confined by ``sandbox.py`` (bubblewrap: the student's own working folder and
   nothing else of the course, no network, resource and wall-clock limits, a throw-away uid,
   every process killed when the notebook is done). ``--jobs`` tasks run at once (default: one
   per core); with fewer students than jobs, each student's notebooks are split over several
   tasks, so even one student keeps every core busy. A failure in one notebook costs only that
   notebook;
4. the test cells' verdicts are made here, outside the kernel, from the raw numbers the kernel
   recorded (``checks.judge``), so nothing the student's code does in the kernel can forge them;
5. only this process writes the course's gradebook: every student's scores, completion points
   and manual grades (``manual_grades.csv``), then the feedback pages (hidden tests removed,
   outputs capped), ``grades.csv`` (nbgrader's export of that gradebook) and ``report.csv``.

Grading again gives the same grades: manual grades live in ``manual_grades.csv`` and are
re-applied after every run.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import warnings
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import nbformat
import yaml

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))

import checks  # noqa: E402
import intake  # noqa: E402
import repair  # noqa: E402
import sandbox  # noqa: E402

COURSE = yaml.safe_load((ROOT / "course.yaml").read_text())
ASSIGNMENT = COURSE["assignment"]
COURSE_ID = "zero2robot-ch3.2"      # the same as in nbgrader_config.py
NOTEBOOKS = sorted(p.name for p in (ROOT / "solutions").glob("*.ipynb"))
# The completion task cell of each predict-then-run exercise: "<ex>_order".
EXERCISES = {"ex1": "04_imagination_gap", "ex2": "05_horizon", "ex3": "06_closing_the_gap"}
FEEDBACK_OUTPUT_CHARS = 20_000      # per output in a feedback page; the rest is cut with a note
FEEDBACK_NOTEBOOK_CHARS = 2_000_000  # all outputs of one notebook together
HIDDEN_NOTE = "# (hidden tests: run by the grader; their verdict is printed below)\n"


def tool_env() -> dict:
    """nbgrader shells out to `alembic`: make this interpreter's scripts folder visible."""
    here, path = str(Path(sys.executable).parent), os.environ.get("PATH", "")
    return {**os.environ, "PATH": path if here in path.split(os.pathsep) else f"{here}{os.pathsep}{path}"}


def nbgrader(course: Path, *args: str, timeout: int | None = None) -> subprocess.CompletedProcess:
    cmd = [sys.executable, "-m", "nbgrader", *args, f"--CourseDirectory.root={course}",
           f"--CourseDirectory.db_url=sqlite:///{course / 'gradebook.db'}"]
    if timeout:
        cmd.append(f"--Execute.timeout={timeout}")
    return subprocess.run(cmd, cwd=course, capture_output=True, text=True, env=tool_env())


def prepare_course(course: Path) -> None:
    """Copy solutions/ into the course's source folder and (re)generate the assignment."""
    src = course / "source" / ASSIGNMENT
    src.mkdir(parents=True, exist_ok=True)
    for path in (ROOT / "solutions").glob("*.ipynb"):
        shutil.copy(path, src / path.name)
    if course.resolve() != HERE:
        shutil.copy(HERE / "nbgrader_config.py", course / "nbgrader_config.py")
    res = nbgrader_api(course).generate_assignment(ASSIGNMENT, force=True)
    if not res.get("success"):
        sys.exit(f"nbgrader generate_assignment failed:\n{(res.get('error') or res.get('log') or '')[-3000:]}")


def nbgrader_api(course: Path):
    """nbgrader's own Python API (``NbGraderAPI``) on ``course``, in this process.

    The same steps as the ``nbgrader`` command, without a new interpreter each: one import of
    nbgrader serves the whole batch (an import cost 2.5 s on the recording host; see
    benchmarks/grading_wallclock.txt).
    """
    from nbgrader.apps import NbGraderAPI
    from nbgrader.coursedir import CourseDirectory
    from traitlets.config import PyFileConfigLoader

    os.environ["PATH"] = tool_env()["PATH"]     # a new gradebook runs the venv's `alembic`
    config = PyFileConfigLoader("nbgrader_config.py", path=str(course)).load_config()
    config.CourseDirectory.root = str(course)
    config.CourseDirectory.db_url = f"sqlite:///{course / 'gradebook.db'}"
    return NbGraderAPI(coursedir=CourseDirectory(config=config), config=config)


def export_csv(course: Path, filename: Path) -> None:
    """``nbgrader export`` (its CSV plugin) of the course gradebook into ``filename``, in this process."""
    from nbgrader.api import Gradebook
    from nbgrader.plugins import CsvExportPlugin
    from traitlets.config import Config

    config = Config()
    config.CsvExportPlugin.to = str(filename)      # the plugin's destination trait is `to`
    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb:
        CsvExportPlugin(config=config).export(gb)


# --- per student: repair, then grade in a private course ----------------------------------------
def prepare_student(uploads: dict, release: dict) -> tuple[dict, list[str], dict, dict]:
    """(repaired notebooks by file name, notes, completion verdicts, delegations by test id)."""
    notebooks, notes, completion, delegated = {}, [], {}, {}
    for name, up in sorted(uploads.items()):
        try:
            nb = intake.decode_notebook(up.data)
        except ValueError as e:
            notes.append(f"{name}: {e}; it scores 0")
            continue
        if repair.clean_colab(nb):
            notes.append(f"{name}: saved by Colab; its extra metadata was removed")
        notes += [f"{name}: {n}" for n in repair.match_cells(nb, release[name])]
        for g in repair.restore_locked_cells(nb, release[name]):
            notes.append(f"{name}: the locked test cell '{g}' was missing and was put back; never delete test cells")
        for ex, stem in EXERCISES.items():
            if name.startswith(stem):
                completion[ex] = repair.receipt_verdict(nb, ex)
        release_sources = {repair.source(c) for c in release[name].cells}
        locked = {repair.gid(c) for c in release[name].cells
                  if c.metadata.get("nbgrader", {}).get("locked")}
        for test in checks.TESTS.values():
            if name.startswith(test.notebook):
                found = checks.delegations(test, nb.cells, release_sources, locked)
                if found:
                    delegated[test.test_id] = found
        notebooks[name] = nb
    return notebooks, notes, completion, delegated


def private_course(course: Path, student: str, notebooks: dict, work: Path) -> Path:
    """A copy of the course with only this student in it; the kernel sees none of it but its folder."""
    priv = work / "course"
    priv.mkdir(parents=True)
    shutil.copy(course / "nbgrader_config.py", priv / "nbgrader_config.py")
    shutil.copytree(course / "source", priv / "source")
    shutil.copytree(course / "release", priv / "release")
    shutil.copy(course / "gradebook.template.db", priv / "gradebook.db")
    dest = priv / "submitted" / student / ASSIGNMENT
    dest.mkdir(parents=True)
    for name, nb in notebooks.items():
        nbformat.write(nb, dest / name)
    (dest / "timestamp.txt").write_text("2026-01-01 00:00:00.000000 UTC")   # fixed: regrades match
    return priv


def worker(priv: Path, student: str, timeout: int, confine: bool, uid: int | None, limits: dict) -> dict:
    """Autograde every notebook of one student in the private course ``priv`` (runs in its own
    process). Returns {notebook: {"ok", "error", "scores": {grade_id: auto score}, "verdicts"}}."""
    from nbgrader.api import Gradebook
    from nbgrader.apps import NbGraderAPI
    from nbgrader.coursedir import CourseDirectory
    from traitlets.config import PyFileConfigLoader

    run = priv.parent / "run"
    grading, sockets, runtime = run / "grading", run / "sockets", run / "runtime"
    for p in (grading / "cases", sockets, runtime):
        p.mkdir(parents=True, exist_ok=True)
    for test in checks.TESTS.values():
        (grading / "cases" / f"{test.test_id}.json").write_text(json.dumps([c.spec for c in test.cases]))
    os.environ["JUPYTER_RUNTIME_DIR"] = str(runtime)
    os.environ["NBGRADER_EXECUTION"] = "autograde"
    config = PyFileConfigLoader("nbgrader_config.py", path=str(priv)).load_config()
    config.CourseDirectory.root = str(priv)
    config.CourseDirectory.db_url = f"sqlite:///{priv / 'gradebook.db'}"
    config.Execute.timeout = timeout
    config.KernelManager.transport = "ipc"
    config.KernelManager.ip = str(sockets / "k")
    if confine:
        sandbox.write_kernelspec(run / "jupyter", {"socket_dir": str(sockets), "grading_dir": str(grading),
                                                   "uid": uid, "limits": limits})
        os.environ["JUPYTER_PATH"] = str(run / "jupyter")
        config.Execute.kernel_name = sandbox.KERNEL_NAME
    else:
        os.environ["PUSHT_GRADING_DIR"] = str(grading)
    out = {}
    for name in [p.name for p in sorted((priv / "submitted" / student / ASSIGNMENT).glob("*.ipynb"))]:
        nb_id = name[:-len(".ipynb")]
        shutil.rmtree(grading / "results", ignore_errors=True)
        (grading / "results").mkdir()
        coursedir = CourseDirectory(config=config)
        coursedir.notebook_id = nb_id
        api = NbGraderAPI(coursedir=coursedir, config=config)
        started = time.perf_counter()
        res = api.autograde(ASSIGNMENT, student, force=True, create=True)
        entry = {"ok": bool(res.get("success")), "error": "" if res.get("success") else
                 _last_error(res.get("error", "") or res.get("log", "")), "scores": {}, "verdicts": {},
                 "seconds": round(time.perf_counter() - started, 2)}   # nbgrader's autograde, kernel included
        if entry["ok"]:
            with Gradebook(config.CourseDirectory.db_url, course_id=COURSE_ID) as gb:
                sub = gb.find_submission_notebook(nb_id, ASSIGNMENT, student)
                entry["scores"] = {g.name: g.auto_score for g in sub.grades}
        # judged here, in the worker, which the kernel cannot reach (the results files are its)
        for test in checks.TESTS.values():
            if name.startswith(test.notebook):
                results = grading / "results" / f"{test.test_id}.npz"
                entry["verdicts"][test.test_id] = vars(checks.judge(test, results))
        out[name] = entry
    return out


def _last_error(text: str) -> str:
    lines = [l for l in text.strip().splitlines() if l.strip() and "NbGraderException" not in l]
    for l in reversed(lines):
        if "Error" in l or "error" in l:
            return l.strip()[:300]
    return (lines[-1] if lines else "nbgrader failed")[:300]


def grade_student(course: Path, student: str, notebooks: dict, timeout: int, confine: bool,
                  index: int, limits: dict) -> dict:
    """Run the worker for one student in a subprocess; copy its autograded notebooks back."""
    work = Path(tempfile.mkdtemp(prefix="pusht-grade-"))
    os.chmod(work, 0o755)
    try:
        priv = private_course(course, student, notebooks, work)
        args = {"priv": str(priv), "student": student, "timeout": timeout, "confine": confine,
                "uid": sandbox.student_uid(index) if confine else None, "limits": limits}
        proc = subprocess.Popen([sys.executable, str(Path(__file__).resolve()), "--worker", json.dumps(args)],
                                cwd=priv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                env=tool_env(), start_new_session=True)
        budget = limits["wall_seconds"] * max(1, len(notebooks)) + 120
        try:
            stdout, stderr = proc.communicate(timeout=budget)
        except subprocess.TimeoutExpired:
            stdout, stderr = "", "the grading of this student ran out of time"
        finally:
            try:
                os.killpg(proc.pid, signal.SIGKILL)   # nothing this student started outlives grading
            except ProcessLookupError:
                pass
            proc.wait()
        line = next((l for l in reversed(stdout.splitlines()) if l.startswith("{")), None)
        result = json.loads(line) if line else {}
        if not result:
            result = {name: {"ok": False, "error": _last_error(stderr), "scores": {}, "verdicts": {}}
                      for name in notebooks}
        src = priv / "autograded" / student / ASSIGNMENT
        dest = course / "autograded" / student / ASSIGNMENT     # emptied once per student by grade_class
        dest.mkdir(parents=True, exist_ok=True)
        for name in notebooks:
            if (src / name).exists():
                shutil.copy(src / name, dest / name)
        return result
    finally:
        shutil.rmtree(work, ignore_errors=True)


# --- the whole batch ---------------------------------------------------------------------------
def grade_class(submissions: Path, course: Path = HERE, timeout: int = 120, jobs: int | None = None,
                log=print, confine: bool | None = None, limits: dict | None = None,
                progress: bool = True) -> dict:
    """Grade every submission in ``submissions``; returns the per-student report."""
    from nbgrader.api import Gradebook

    course = course.resolve()
    limits = {**sandbox.DEFAULT_LIMITS, **(limits or {})}
    ok, why = sandbox.available()
    if confine is None:
        confine = ok
    if confine and not ok:
        raise RuntimeError(f"confined grading was asked for, but {why}")
    if not confine:
        msg = (f"WARNING: submissions are NOT confined ({why or 'confinement switched off'}): "
               f"student code runs as you, with your files in reach. Install bubblewrap to confine it.")
        log(msg)
        warnings.warn(msg)
    prepare_course(course)
    shutil.copy(course / "gradebook.db", course / "gradebook.template.db")
    got = intake.collect(submissions, NOTEBOOKS)
    for line in got.rejected:
        log(f"skipped {line}")
    release = {name: nbformat.read(course / "release" / ASSIGNMENT / name, as_version=4) for name in NOTEBOOKS}
    report = {s: {"notes": list(got.notes.get(s, [])), "completion": {}, "verdicts": {}, "failed": {}}
              for s in got.students}
    prepared = {}
    for s, uploads in got.students.items():
        nbs, notes, completion, delegated = prepare_student(uploads, release)
        report[s]["notes"] += notes
        report[s]["completion"] = completion
        report[s]["delegated"] = delegated
        prepared[s] = nbs
    jobs = jobs or max(1, (os.cpu_count() or 2))
    order = sorted(prepared)
    from concurrent.futures import as_completed

    from tqdm.auto import tqdm

    # Each task grades some of one student's notebooks in its own private course and throw-away uid.
    # With at least as many students as cores, one task per student (the notebooks of a task run
    # one after another and share its stage cache); with fewer, each student's notebooks are split
    # into that many tasks, so the cores stay busy even for one student. Only this process writes
    # the course gradebook (``record``).
    students = [s for s in order if prepared[s]]
    groups = max(1, jobs // max(1, len(students)))
    tasks = []
    for s in students:
        names = sorted(prepared[s])
        for g in range(min(groups, len(names))):
            tasks.append((s, names[g::groups]))          # 01, 03, 05 | 02, 04, 06 for two groups
        shutil.rmtree(course / "autograded" / s / ASSIGNMENT, ignore_errors=True)
    results, left = {}, {s: sum(1 for t in tasks if t[0] == s) for s in students}
    with ThreadPoolExecutor(jobs) as pool:
        futures = {pool.submit(grade_student, course, s, {n: prepared[s][n] for n in names}, timeout, confine,
                               i, limits): (s, names) for i, (s, names) in enumerate(tasks)}
        with tqdm(total=len(left), desc=f"grading ({jobs} at a time)", unit="student",
                  disable=not progress) as bar:
            for f in as_completed(futures):
                s, _ = futures[f]
                results.setdefault(s, {}).update(f.result())
                left[s] -= 1
                if not left[s]:                  # the bar counts students: all their tasks done
                    bar.set_postfix_str(s[:20])
                    bar.update()
    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb:
        for s in report:
            gb.update_or_create_student(s)
            try:
                gb.remove_submission(ASSIGNMENT, s)
            except Exception:
                pass
        gb.db.commit()
    record(course, report, results)
    sanitize_feedback_sources(course, report)
    res = nbgrader_api(course).generate_feedback(ASSIGNMENT, force=True)
    if not res.get("success"):
        log(f"nbgrader generate_feedback failed: {_last_error(res.get('error') or res.get('log') or '')}")
    export(course, report, got.rejected)
    return report


def record(course: Path, report: dict, results: dict) -> None:
    """Write every student's scores into the course gradebook (this process is its only writer)."""
    from nbgrader.api import Gradebook, MissingEntry

    scheme = yaml.safe_load((HERE / "mark_scheme.yaml").read_text()) if (HERE / "mark_scheme.yaml").exists() else {}
    manual = read_manual(course)
    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb:
        for student, rep in report.items():
            res = results.get(student, {})
            if not res:
                continue
            gb.add_submission(ASSIGNMENT, student, timestamp="2026-01-01 00:00:00.000000 UTC")
            for name, entry in res.items():
                nb_id = name[:-len(".ipynb")]
                if not entry["ok"]:
                    rep["failed"][name] = entry["error"]
                    rep["notes"].append(f"{name}: nbgrader could not finish this notebook ({entry['error']}); "
                                        f"points from the tests that had already run are kept")
                sub = gb.find_submission_notebook(nb_id, ASSIGNMENT, student)
                for grade in sub.grades:
                    g = grade.name
                    comment = None
                    if g in entry["scores"] and entry["scores"][g] is not None:
                        grade.auto_score = entry["scores"][g]
                    if g in entry["verdicts"]:
                        v = entry["verdicts"][g]
                        found = rep["delegated"].get(g)
                        if found:
                            v = vars(checks.judge(checks.TESTS[g], "", delegation=found))
                        grade.manual_score = grade.max_score if v["passed"] else 0.0
                        grade.needs_manual_grade = False
                        rep["verdicts"][g] = (grade.manual_score, grade.max_score, v["message"])
                    ex = g[:-len("_order")] if g.endswith("_order") else None
                    if ex in rep["completion"]:
                        ok, why = rep["completion"][ex]
                        grade.manual_score = grade.max_score if ok else 0.0
                        grade.needs_manual_grade = False
                        comment = why
                    elif g in scheme:
                        comment = f"Mark scheme: {scheme[g]}"
                    row = manual.get((student, nb_id, g))
                    if row:
                        try:
                            score = float(row["score"])
                        except ValueError:
                            score = float("nan")
                        if 0 <= score <= grade.max_score:
                            grade.manual_score = score
                            grade.needs_manual_grade = False
                            comment = (row.get("comment") or "") + (f"\n\n{comment}" if comment else "")
                        else:
                            rep["notes"].append(f"manual grade {row['score']!r} for {nb_id} {g} refused: "
                                                f"outside 0..{grade.max_score}")
                    if comment is not None:
                        try:
                            gb.find_comment(g, nb_id, ASSIGNMENT, student).manual_comment = comment
                        except MissingEntry:
                            pass
            gb.db.commit()


def read_manual(course: Path) -> dict:
    manual = {}
    if (course / "manual_grades.csv").exists():
        with open(course / "manual_grades.csv", newline="") as f:
            for row in csv.DictReader(f):
                manual[(row["student_id"], row["notebook"], row["grade_id"])] = row
    return manual


def sanitize_feedback_sources(course: Path, report: dict) -> None:
    """Before feedback: hidden tests out, each test's verdict in, long outputs cut."""
    for student, rep in report.items():
        folder = course / "autograded" / student / ASSIGNMENT
        for path in folder.glob("*.ipynb"):
            nb = nbformat.read(path, as_version=4)
            budget = FEEDBACK_NOTEBOOK_CHARS
            for cell in nb.cells:
                g = repair.gid(cell)
                if cell.cell_type == "code" and "### BEGIN HIDDEN TESTS" in cell.source:
                    cell.source = _strip_hidden(cell.source)
                if g in rep["verdicts"]:
                    score, max_score, msg = rep["verdicts"][g]
                    cell.outputs = [o for o in cell.get("outputs", []) if not
                                    (o.get("output_type") == "stream" and "[graded outside this kernel]" in o.get("text", ""))]
                    cell.outputs.append(nbformat.v4.new_output("stream", name="stdout",
                                        text=f"[grader] {g}: {score:g} of {max_score:g} points: {msg}\n"))
                if cell.cell_type == "code":
                    budget = _cap_outputs(cell, budget)
            nbformat.write(nb, path)


def _strip_hidden(src: str) -> str:
    out, hidden = [], False
    for line in src.splitlines(keepends=True):
        if line.strip() == "### BEGIN HIDDEN TESTS":
            hidden = True
            out.append(HIDDEN_NOTE)
        elif line.strip() == "### END HIDDEN TESTS":
            hidden = False
        elif not hidden:
            out.append(line)
    return "".join(out)


def _cap_outputs(cell, budget: int) -> int:
    kept = []
    for o in cell.get("outputs", []):
        for key in ("text",):
            if isinstance(o.get(key), str) and len(o[key]) > FEEDBACK_OUTPUT_CHARS:
                o[key] = o[key][:FEEDBACK_OUTPUT_CHARS] + f"\n[... output cut at {FEEDBACK_OUTPUT_CHARS} characters]\n"
        if o.get("output_type") == "error":
            o["traceback"] = [t[:FEEDBACK_OUTPUT_CHARS] for t in o.get("traceback", [])[:50]]
        size = len(json.dumps(o))
        if size > budget:
            kept.append(nbformat.v4.new_output("stream", name="stdout",
                                               text="[... further output removed: the page is capped in size]\n"))
            break
        budget -= size
        kept.append(o)
    cell.outputs = kept
    return budget


def export(course: Path, report: dict, rejected: list[str] = ()) -> None:
    """grades.csv (nbgrader's export of the gradebook) and report.csv (what happened to each file)."""
    export_csv(course, course / "grades.csv")
    from nbgrader.api import Gradebook, MissingEntry

    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb, \
            open(course / "report.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["student_id", "score", "max_score", "notes"])
        for student in sorted(report):
            try:
                sub = gb.find_submission(ASSIGNMENT, student)
                score, max_score = sub.score, sub.max_score
            except MissingEntry:
                score, max_score = 0.0, gb.find_assignment(ASSIGNMENT).max_score
            rep = report[student]
            notes = rep["notes"] + [why for _, why in rep["completion"].values()]
            notes += [f"{g}: {s:g}/{m:g}: {msg}" for g, (s, m, msg) in sorted(rep["verdicts"].items())]
            w.writerow([student, round(score, 3), round(max_score, 3), " | ".join(notes)])
        for line in rejected:          # files that could not be placed to any student
            w.writerow(["(not graded)", "", "", line])


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["--worker"]:
        a = json.loads(argv[1])
        out = worker(Path(a["priv"]), a["student"], a["timeout"], a["confine"], a["uid"], a["limits"])
        print(json.dumps(out))
        return 0
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("submissions", type=Path, help="a .zip from the LMS, or a folder of notebooks")
    p.add_argument("--course", type=Path, default=HERE, help="nbgrader course folder (default: autograde/)")
    p.add_argument("--timeout", type=int, default=120, help="seconds per cell before it is interrupted")
    p.add_argument("--jobs", type=int, default=None, help="grading tasks at once (default: one per core); fewer students than that split their notebooks")
    p.add_argument("--no-confine", action="store_true",
                   help="run student code unconfined (only for trusted notebooks; prints a warning)")
    args = p.parse_args(argv)
    if not args.submissions.exists():
        p.error(f"{args.submissions} does not exist")
    report = grade_class(args.submissions, args.course, args.timeout, args.jobs,
                         confine=False if args.no_confine else None)
    print(f"graded {len(report)} students: scores in {args.course / 'grades.csv'}, per-file notes in "
          f"{args.course / 'report.csv'}, feedback in {args.course / 'feedback'}/")
    return 0


if __name__ == "__main__":
    sys.exit(main())
