"""The stages no student can change, computed once per batch, and the fingerprints that decide a regrade."""

from __future__ import annotations

import hashlib
import json
import shutil
import time
from pathlib import Path

import nbformat

from .course import HERE, ROOT, SOURCE
from .schedule import _split, run_tasks


REFERENCE = "reference-solution"     # the instructor's solutions, graded first when stages are shared


SHARE_FROM = 4                       # share stages from this many students to grade (see grade_class)


SHARED_DIR = "shared_stages"         # in the course: a copy of the stages the reference run left


def shared_stages(bundle: bytes, course: Path, jobs: int, scheduler, timeout: int, confine: bool,
                  limits: dict, log=print) -> dict:
    """The stages no student's code can change, computed once: grade the instructor's solutions as
    one more (confined) submission and keep the stage files its kernels wrote. Returns them as
    {file name: bytes} (each task writes them into its own temporary folder, so no path of the
    course is ever visible in a sandbox) and leaves a copy in ``course/shared_stages`` to look at.

    Which stages qualify is decided by how pusht caches them: a stage is written to the cache only
    when everything it was computed from is named in its file name (the config fields and the
    source of the package modules it runs, hashed); a stage given a learner's function (an actor
    trained with the learner's own lambda-return, say) is never cached, so it is never shared and
    every student's kernel computes it with their own code. A file a student's kernel looks up
    under the same name is therefore the same stage, computed from the same inputs. The shared
    folder is read-only inside every student's sandbox, and nothing a student writes reaches it.
    """
    if SOURCE != ROOT / "solutions":
        raise RuntimeError(f"shared stages are computed by grading the instructor's solutions, and this copy of "
                           f"the course has none ({SOURCE.name}/ only): grade with share=False")
    notebooks = {p.name: p.read_text(encoding="utf-8") for p in sorted(SOURCE.glob("*.ipynb"))}
    stages, failed = {}, []

    def on_done(task, out):
        stages.update(out.get("stages", {}))
        for name, entry in out["results"].items():
            if not entry["ok"]:
                failed.append(f"{name} ({entry['error']})")
            failed.extend(f"{name}: {t}" for t, v in entry["verdicts"].items() if not v["passed"])

    def submit_args(task):
        return (bundle, REFERENCE, {n: notebooks[n] for n in task[1]}, timeout, confine, limits, None, True)

    t = time.perf_counter()
    tasks = _split([REFERENCE], {REFERENCE: notebooks}, jobs if scheduler is None else 2)
    run_tasks(tasks, jobs, scheduler, submit_args, on_done, log)
    folder = course / SHARED_DIR
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir()
    for name, data in stages.items():
        (folder / name).write_bytes(data)
    log(f"shared stages: {len(stages)} files ({sum(map(len, stages.values())) / 1e6:.1f} MB) from grading the "
        f"solutions in {time.perf_counter() - t:.0f} s; every student's kernel reads them")
    if failed:
        log("WARNING: the instructor's solutions fail some of their own tests: " + "; ".join(failed)[:2000])
    return stages


def grader_fingerprint(timeout: int, confine: bool, limits: dict) -> str:
    """Everything besides the submission that decides a student's results: the solutions, the
    grader's code and tests, the package (its code and its words, ``pusht/nb/text/*.md``, which the
    feedback quotes), the settings. A change to any of it regrades everyone."""
    h = hashlib.sha256(json.dumps([timeout, confine, sorted(limits.items())]).encode())
    files = sorted(SOURCE.glob("*.ipynb")) + sorted(HERE.glob("*.py")) + \
        sorted((ROOT / "pusht").rglob("*.py")) + sorted((ROOT / "pusht").rglob("*.md"))
    for p in files:
        h.update(p.relative_to(ROOT).as_posix().encode() + b"\0" + p.read_bytes())
    return h.hexdigest()


def submission_fingerprint(notebooks: dict, grader: str) -> str:
    h = hashlib.sha256(grader.encode())
    for name in sorted(notebooks):
        h.update(name.encode() + b"\0" + nbformat.writes(notebooks[name]).encode() + b"\0")
    return h.hexdigest()
