"""The Colab lane (`make colab-check`): run every chapter notebook the way a learner runs it in Colab.

    python -m scripts.colab_check [--only 01_world_model ...] [--rebuild] [--keep]

1. .venv-colab: Colab's Python with Colab's packages, as pinned in colab/stack.txt (one line per
   package; its header names the source). Made once and reused while that file is unchanged (the
   stamp .venv-colab/.stack-stamp.json); before each run, whatever an earlier run installed on top
   of the stack (the chapter's package, pymunk) is removed again, so every run starts as a fresh
   Colab runtime does.
2. A stand-in for ``google.colab`` (colab/standin/) is copied into that venv and imported at kernel
   start by an IPython startup file, as Colab does, so the notebooks' Colab install branch runs.
3. The install cell's ``git+https://github.com/<course.yaml repository>@<ref>`` is served from a
   local git repository holding this working tree as it is now (tracked and untracked, not
   ignored files), committed on the branch the cell asks for; a temporary GIT_CONFIG_GLOBAL
   redirects the GitHub address there (url.<local>.insteadOf). The notebooks are not edited.
4. Every solution notebook runs in smoke mode (papermill from this process, with
   scripts/chapter.py's ``execute``) in a kernel of .venv-colab's Python, each notebook copied
   alone into an empty folder that is the kernel's working directory, and the venv reset to the
   stack before each one (a fresh runtime): the package can come only from that notebook's own
   install cell.
5. Checks: every notebook ran top to bottom and showed its figures; its install cell ran (and
   installed this working tree's commit); and the install left every pinned package (torch and numpy above all: Colab has
   them loaded) at the version Colab has. One line per notebook, a summary, exit status 1 on any
   failure.
"""

from __future__ import annotations

import argparse
import fcntl
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
STACK_FILE = ROOT / "colab" / "stack.txt"
STANDIN = ROOT / "colab" / "standin"
VENV = ROOT / ".venv-colab"
STAMP = ".stack-stamp.json"
LOCK = ROOT / ".venv-colab.lock"
PACKAGE = "pusht-dreamer"           # the chapter's package: only ever installed by the install cell
MUST_PIN = ("torch", "numpy")       # Colab has these loaded; the install must never replace them
SHOWN = ("torch", "numpy", "ipython", "ipykernel", "matplotlib")   # named in the summary


# ------------------------------------------------------------------------ the stack file ----

def canonical(name: str) -> str:
    """A distribution name as pip compares them (PEP 503): PyYAML, pyyaml and py_yaml are one."""
    return re.sub(r"[-_.]+", "-", name).lower()


@dataclass(frozen=True)
class Stack:
    python: str                     # "3.13": the interpreter's minor version
    pins: dict                      # canonical name -> version
    digest: str                     # sha256 of the file's text: the venv is rebuilt when it changes


_PIN = re.compile(r"([A-Za-z0-9](?:[A-Za-z0-9._-]*[A-Za-z0-9])?)==([0-9][A-Za-z0-9.+!_-]*)")


def parse_stack(text: str) -> Stack:
    """colab/stack.txt: a pip requirements file of ``name==version`` lines (comments allowed, also
    after a pin) with one ``# python: 3.NN`` comment line. Anything else is an error that names
    its line, so that a typo cannot silently loosen the stack."""
    python, pins = None, {}
    for n, raw in enumerate(text.splitlines(), 1):
        line = raw.strip()
        if not line:
            continue
        if line.startswith("#"):
            m = re.fullmatch(r"#\s*python:\s*(\S+)\s*", line)
            if m:
                if not re.fullmatch(r"3\.\d+", m[1]):
                    raise ValueError(f"colab/stack.txt line {n}: python must be a minor version like "
                                     f"3.13, not {m[1]!r}")
                if python is not None:
                    raise ValueError(f"colab/stack.txt line {n}: a second `# python:` line")
                python = m[1]
            continue
        req = re.split(r"\s+#", line, maxsplit=1)[0].strip()
        m = _PIN.fullmatch(req)
        if not m:
            raise ValueError(f"colab/stack.txt line {n}: {raw.strip()!r} is not an exact pin `name==version`")
        name = canonical(m[1])
        if name in pins:
            raise ValueError(f"colab/stack.txt line {n}: {m[1]} is pinned twice")
        pins[name] = m[2]
    if python is None:
        raise ValueError("colab/stack.txt has no `# python: 3.NN` line (Colab's Python, from os-info.txt)")
    missing = [name for name in MUST_PIN if name not in pins]
    if missing:
        raise ValueError(f"colab/stack.txt must pin {', '.join(missing)}: Colab's own, which the lane checks")
    return Stack(python, pins, hashlib.sha256(text.encode()).hexdigest())


def _same_version(a: str | None, b: str | None) -> bool:
    if a is None or b is None:
        return a == b
    try:
        from packaging.version import Version
        return Version(a) == Version(b)
    except Exception:                           # noqa: BLE001 - not a PEP 440 version: compare text
        return a == b


def version_changes(before: dict, after: dict) -> list[str]:
    """``name old -> new`` for every package of ``before`` whose version differs in ``after``
    (``-> removed`` when it is gone). Both map canonical names to versions."""
    return [f"{name} {old} -> {after.get(name, 'removed')}" for name, old in sorted(before.items())
            if not _same_version(old, after.get(name))]


def stack_mismatches(pins: dict, installed: dict) -> list[str]:
    """The pinned packages that are missing or at another version in ``installed``."""
    return version_changes(pins, installed)


# ------------------------------------------------------------------------- the Python 3.13 ----

def pyenv_roots() -> list[Path]:
    roots = []
    try:
        out = subprocess.run(["pyenv", "root"], capture_output=True, text=True, timeout=30)
        if out.returncode == 0 and out.stdout.strip():
            roots.append(Path(out.stdout.strip()))
    except (OSError, subprocess.SubprocessError):
        pass
    if os.environ.get("PYENV_ROOT"):
        roots.append(Path(os.environ["PYENV_ROOT"]))
    roots.append(Path.home() / ".pyenv")
    seen, unique = set(), []
    for r in roots:
        if r not in seen:
            seen.add(r)
            unique.append(r)
    return unique


def find_python(minor: str, roots: list[Path] | None = None, path: str | None = None) -> Path:
    """Python ``minor`` (e.g. "3.13"): the newest pyenv version ``minor.*`` under ``roots`` (default:
    `pyenv root`, $PYENV_ROOT, ~/.pyenv), else ``python<minor>`` on ``path`` (default $PATH).
    Raises FileNotFoundError naming where it looked."""
    roots = pyenv_roots() if roots is None else roots
    looked = []
    for root in roots:
        found = []
        for d in (Path(root) / "versions").glob(f"{minor}*"):
            m = re.fullmatch(re.escape(minor) + r"(?:\.(\d+))?", d.name)   # not 3.13t, 3.130, 3.13-dev
            exe = d / "bin" / f"python{minor}"
            if m and exe.is_file() and os.access(exe, os.X_OK):
                found.append((int(m[1] or -1), exe))
        if found:
            return max(found)[1]
        looked.append(f"{root}/versions/{minor}.*")
    exe = shutil.which(f"python{minor}", path=path)
    if exe:
        return Path(exe)
    looked.append(f"python{minor} on PATH")
    raise FileNotFoundError(
        f"the Colab lane needs Python {minor} (Colab's, per colab/stack.txt) and found none; looked in: "
        f"{'; '.join(looked)}. Install it (e.g. `pyenv install {minor}`, or your system's python{minor} "
        f"package with its venv module), then run make colab-check again")


# ------------------------------------------------------------------------------ the venv ----

def venv_python(venv: Path = VENV) -> Path:
    return venv / "bin" / "python"


# Run with -I (isolated): from the repository root, the current directory on sys.path would add the
# main venv's pusht_dreamer.egg-info (its editable install) to what looks installed.
_PROBE = ("import importlib.metadata as m, json\n"
          "print(json.dumps({d.metadata['Name']: d.version for d in m.distributions() if d.metadata['Name']}))")


def installed(python: Path) -> dict:
    """Every distribution installed for ``python``: canonical name -> version (importlib.metadata)."""
    out = subprocess.run([str(python), "-I", "-c", _PROBE], capture_output=True, text=True, check=True)
    return {canonical(name): v for name, v in json.loads(out.stdout).items()}


def direct_url(python: Path, dist: str) -> dict | None:
    """The PEP 610 direct_url.json of ``dist`` as installed for ``python`` (None if absent)."""
    code = ("import importlib.metadata as m, sys\n"
            "try:\n    print(m.distribution(sys.argv[1]).read_text('direct_url.json') or '')\n"
            "except m.PackageNotFoundError:\n    print('')")
    out = subprocess.run([str(python), "-I", "-c", code, dist], capture_output=True, text=True, check=True)
    return json.loads(out.stdout) if out.stdout.strip() else None


def _pip(python: Path, *args: str, log: Path) -> None:
    with open(log, "a") as f:
        f.write(f"\n$ {python} -m pip {' '.join(args)}\n")
        f.flush()
        proc = subprocess.run([str(python), "-m", "pip", *args], stdout=f, stderr=subprocess.STDOUT)
    if proc.returncode != 0:
        tail = "\n".join(log.read_text().splitlines()[-25:])
        cap = ""
        if "constraint" in tail.lower():
            cap = ("\n(If pip refused a version because of a constraint, that is this machine's pip "
                   "configuration, e.g. /etc/xdg/pip/constraints.txt, not Colab's: report it.)")
        raise RuntimeError(f"pip {' '.join(args[:3])} ... failed in .venv-colab (log: {log}):\n{tail}{cap}")


def site_packages(python: Path) -> Path:
    out = subprocess.run([str(python), "-I", "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"],
                         capture_output=True, text=True, check=True)
    return Path(out.stdout.strip())


def install_standin(python: Path) -> Path:
    """Copy colab/standin/google/colab into the venv's site-packages (``google`` stays a namespace
    package, so a real google-* distribution could still sit beside it)."""
    target = site_packages(python) / "google" / "colab"
    if target.exists():
        shutil.rmtree(target)
    shutil.copytree(STANDIN / "google" / "colab", target, ignore=shutil.ignore_patterns("__pycache__"))
    return target


def ensure_venv(stack: Stack, venv: Path = VENV, rebuild: bool = False, say=print) -> tuple[Path, str, dict]:
    """.venv-colab with the stack installed; returns (python, "created" | "reused", installed versions).

    Reused while its stamp records this stack file's digest. Distributions that are not in the
    stamp's baseline (what the stack installed) are uninstalled first; a pinned package found at
    another version (an earlier run's install replaced it) is put back from the stack file."""
    python, stamp = venv_python(venv), venv / STAMP
    log = venv.parent / f"{venv.name}-install.log"
    state = None
    if not rebuild and stamp.exists() and python.exists():
        try:
            state = json.loads(stamp.read_text())
        except ValueError:
            state = None
    if state and state.get("stack_sha256") == stack.digest:
        current = installed(python)
        extra = sorted(set(current) - (set(state["baseline"]) - {PACKAGE}))
        if extra:
            say(f"  removing what an earlier run installed on top of the stack: {', '.join(extra)}")
            _pip(python, "uninstall", "--yes", *extra, log=log)
            current = installed(python)
        wrong = stack_mismatches(stack.pins, current)
        if wrong:
            say(f"  putting back pinned packages an earlier run changed: {', '.join(wrong)}")
            _pip(python, "install", "--quiet", "-r", str(STACK_FILE), log=log)
            current = installed(python)
            wrong = stack_mismatches(stack.pins, current)
            if wrong:
                raise RuntimeError(f".venv-colab does not match colab/stack.txt: {', '.join(wrong)}")
        install_standin(python)
        return python, "reused", current
    base = find_python(stack.python)
    say(f"  making {venv.name} from {base} and installing colab/stack.txt (log: {log.name}); "
        "the first time this downloads torch's CUDA build, several GB")
    if venv.exists():
        shutil.rmtree(venv)
    log.write_text("")
    subprocess.run([str(base), "-m", "venv", str(venv)], check=True)
    if "pip" in stack.pins:               # the install cell's pip is Colab's pip
        _pip(python, "install", "--quiet", f"pip=={stack.pins['pip']}", log=log)
    _pip(python, "install", "--quiet", "-r", str(STACK_FILE), log=log)
    current = installed(python)
    wrong = stack_mismatches(stack.pins, current)
    if wrong:
        raise RuntimeError(f"pip did not install colab/stack.txt as pinned: {', '.join(wrong)} (log: {log})")
    install_standin(python)
    stamp.write_text(json.dumps({"stack_sha256": stack.digest, "python": str(base),
                                 "baseline": current}, indent=1, sort_keys=True) + "\n")
    return python, "created", current


# ------------------------------------------------------- the local stand-in for GitHub ----

def _git(*args: str, cwd: Path, env: dict | None = None) -> str:
    proc = subprocess.run(["git", *args], cwd=cwd, env=env, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"git {' '.join(args)} failed in {cwd}:\n{proc.stdout}{proc.stderr}")
    return proc.stdout


def snapshot_repo(root: Path, dest: Path, branch: str) -> tuple[Path, str, int]:
    """A bare repository ``dest/repo.git`` whose ``branch`` holds one commit of ``root``'s working
    tree as it is now: the files git tracks or would track (`git ls-files -co --exclude-standard`),
    with their current contents. ``root``'s own git state is only read. Returns (bare, commit, files)."""
    names = sorted({n for n in _git("ls-files", "-co", "--exclude-standard", "-z", cwd=root).split("\0") if n})
    work = dest / "work"
    count = 0
    for name in names:
        src = root / name
        if src.is_symlink() or src.is_file():  # a deleted tracked file is listed but absent
            (work / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, work / name, follow_symlinks=False)
            count += 1
    env = {**os.environ, "GIT_CONFIG_GLOBAL": os.devnull, "GIT_CONFIG_NOSYSTEM": "1",
           "GIT_AUTHOR_NAME": "colab-check", "GIT_AUTHOR_EMAIL": "colab-check@localhost",
           "GIT_COMMITTER_NAME": "colab-check", "GIT_COMMITTER_EMAIL": "colab-check@localhost"}
    _git("init", "--quiet", "--initial-branch", branch, str(work), cwd=dest, env=env)
    _git("add", "--all", cwd=work, env=env)
    _git("commit", "--quiet", "--no-verify", "-m", "the working tree, for make colab-check", cwd=work, env=env)
    commit = _git("rev-parse", "HEAD", cwd=work, env=env).strip()
    bare = dest / "repo.git"
    _git("clone", "--quiet", "--bare", str(work), str(bare), cwd=dest, env=env)
    shutil.rmtree(work)
    return bare, commit, count


def github_redirect(config: Path, repository: str, bare: Path) -> Path:
    """A git config file (for GIT_CONFIG_GLOBAL) that sends https://github.com/<repository> to ``bare``."""
    config.write_text(f'[url "{bare.as_uri()}"]\n'
                      f"\tinsteadOf = https://github.com/{repository}\n"
                      '[protocol "file"]\n\tallow = always\n')
    return config


# ---------------------------------------------------------------------------- the kernel ----

STARTUP = ("# Colab imports google.colab before the first cell runs (colab/standin/ stands in for it)\n"
           "__import__('google.colab')\n")


def ipython_dir(dest: Path) -> Path:
    """An IPYTHONDIR whose default profile's startup file imports ``google.colab``."""
    startup = dest / "profile_default" / "startup"
    startup.mkdir(parents=True, exist_ok=True)
    (startup / "00-google-colab.py").write_text(STARTUP)
    return dest


def write_kernelspec(jupyter_dir: Path, python: Path, env: dict) -> Path:
    """A kernelspec ``python3`` (the name scripts/chapter.py's execute() asks for) under
    ``jupyter_dir/kernels``; put ``jupyter_dir`` first on JUPYTER_PATH and it wins over the
    main venv's own python3."""
    spec = jupyter_dir / "kernels" / "python3"
    spec.mkdir(parents=True, exist_ok=True)
    (spec / "kernel.json").write_text(json.dumps({
        "argv": [str(python), "-m", "ipykernel_launcher", "-f", "{connection_file}"],
        "display_name": "Python 3 (Colab's stack, .venv-colab)", "language": "python", "env": env,
    }, indent=1))
    return jupyter_dir


def kernel_environ(python: Path) -> dict:
    """This process's environment as the kernel should inherit it: the main venv's traces
    (VIRTUAL_ENV, its bin/ on PATH, PYTHONPATH) replaced by .venv-colab's."""
    env = {k: v for k, v in os.environ.items() if k not in ("VIRTUAL_ENV", "PYTHONPATH", "PYTHONHOME")}
    main_bin = str(Path(sys.prefix) / "bin")
    path = [p for p in env.get("PATH", "").split(os.pathsep) if p and Path(p) != Path(main_bin)]
    env["PATH"] = os.pathsep.join([str(python.parent)] + path)
    return env


# -------------------------------------------------------------------------------- running ----

def read_executed(saved: Path) -> tuple[str, int]:
    """What the executed notebook's Colab install cell printed to stdout (empty if nothing), and how
    many figures (image/png outputs) the notebook showed."""
    import nbformat

    if not saved.exists():
        return "", 0
    nb = nbformat.read(str(saved), as_version=4)
    said = next(("".join(o.get("text", "") for o in cell.get("outputs", [])
                         if o.get("output_type") == "stream" and o.get("name") == "stdout")
                 for cell in nb.cells if cell.cell_type == "code" and "google.colab" in cell.source), "")
    figures = sum("image/png" in o.get("data", {}) for c in nb.cells for o in c.get("outputs", []))
    return said, figures


def describe_error(e: Exception) -> str:
    ename, evalue = getattr(e, "ename", None), getattr(e, "evalue", None)
    if ename:
        cell = getattr(e, "exec_count", None) or getattr(e, "cell_index", "?")
        return f"cell {cell}: {ename}: {str(evalue).splitlines()[0] if evalue else ''}"
    return f"{type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''}"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--only", nargs="+", metavar="NAME", help="run only these notebooks (name or number prefix)")
    p.add_argument("--rebuild", action="store_true", help="make .venv-colab again even if the stack is unchanged")
    p.add_argument("--keep", action="store_true", help="keep the temporary folder (executed notebooks) and say where")
    args = p.parse_args(argv)
    t_start = time.perf_counter()

    from autograde.course import COURSE as course
    stack = parse_stack(STACK_FILE.read_text())
    notebooks = sorted((ROOT / "solutions").glob("*.ipynb"))
    if args.only:
        notebooks = [nb for nb in notebooks if any(nb.stem.startswith(o.removesuffix(".ipynb")) for o in args.only)]
        if not notebooks:
            print(f"colab-check: no solution notebook matches {args.only}")
            return 2

    lock = open(LOCK, "w")
    try:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        print("colab-check: another colab-check is running on this checkout (.venv-colab.lock)")
        return 2

    print(f"colab-check: Colab's stack from colab/stack.txt (Python {stack.python}, "
          + ", ".join(f"{n} {stack.pins[n]}" for n in SHOWN if n in stack.pins) + ")")
    t = time.perf_counter()
    try:
        python, how, before = ensure_venv(stack, rebuild=args.rebuild)
    except (FileNotFoundError, RuntimeError, subprocess.CalledProcessError) as e:
        print(f"colab-check FAILED: {e}")
        return 1
    t_venv = time.perf_counter() - t
    pyver = subprocess.run([str(python), "-c", "import platform; print(platform.python_version())"],
                           capture_output=True, text=True, check=True).stdout.strip()
    print(f"  .venv-colab {how} in {t_venv:.0f} s (Python {pyver})")

    tmp = Path(tempfile.mkdtemp(prefix="colab-check-"))
    problems: list[str] = []
    try:
        t = time.perf_counter()
        bare, commit, nfiles = snapshot_repo(ROOT, tmp, str(course["ref"]))
        gitconfig = github_redirect(tmp / "gitconfig", course["repository"], bare)
        print(f"  https://github.com/{course['repository']}@{course['ref']} -> a local snapshot of this "
              f"working tree ({nfiles} files, commit {commit[:10]}), {time.perf_counter() - t:.0f} s")

        env = kernel_environ(python)
        os.environ.clear()
        os.environ.update(env)
        kernel_env = {"IPYTHONDIR": str(ipython_dir(tmp / "ipython")), "GIT_CONFIG_GLOBAL": str(gitconfig),
                      "PATH": env["PATH"],
                      # debugpy 1.8 on Python 3.13 warns at every kernel start about frozen modules
                      "PYDEVD_DISABLE_FILE_VALIDATION": "1"}
        jupyter = write_kernelspec(tmp / "jupyter", python, kernel_env)
        os.environ["JUPYTER_PATH"] = os.pathsep.join([str(jupyter)] + [
            x for x in os.environ.get("JUPYTER_PATH", "").split(os.pathsep) if x])

        from scripts.chapter import execute

        pinned_before = {n: before[n] for n in stack.pins}
        baseline = set(before) - {PACKAGE}
        current = before
        log = VENV.parent / f"{VENV.name}-install.log"
        (tmp / "executed").mkdir()
        width = max(len(nb.stem) for nb in notebooks)
        t_nbs = time.perf_counter()
        for nb in notebooks:
            folder = tmp / "content" / nb.stem          # the kernel's cwd: this notebook and nothing else
            folder.mkdir(parents=True)
            shutil.copy(nb, folder / nb.name)
            saved = tmp / "executed" / nb.name
            extra = sorted(set(current) - baseline)     # a fresh runtime: the last notebook's install goes
            if extra:
                _pip(python, "uninstall", "--quiet", "--yes", *extra, log=log)
            t = time.perf_counter()
            error = None
            try:
                # OUT as the notebook's own default (what a learner in Colab gets), relative to the cwd
                execute(folder / nb.name, folder, smoke=True, parameters={"OUT": "runs/notebooks"}, saved=saved)
            except Exception as e:                  # noqa: BLE001 - reported below
                error = describe_error(e)
            seconds = time.perf_counter() - t
            current = installed(python)
            changed = version_changes(pinned_before, current)
            got = ((direct_url(python, PACKAGE) or {}).get("vcs_info") or {}).get("commit_id")
            said, figures = read_executed(saved)
            line = next((ln for ln in said.splitlines() if ln.startswith("Installed:")), "")
            status = "ok"
            if error:
                status = "FAILED"
                problems.append(f"{nb.stem}: {error}")
            elif not figures:
                status = "FAILED"
                problems.append(f"{nb.stem}: ran, but showed no figure (matplotlib's inline backend?)")
            if not said.startswith("Installing "):
                status = "FAILED"
                problems.append(f"{nb.stem}: the Colab install cell did not run its install branch "
                                f"(it printed {said.strip()[:80]!r}): is google.colab imported at kernel start?")
            elif got != commit:
                status = "FAILED"
                problems.append(f"{nb.stem}: {PACKAGE} was not installed from the snapshot {commit[:10]} of "
                                f"this working tree (installed commit: {got}): did the GitHub redirect work?")
            if changed:
                status = "FAILED"
                problems.append(f"{nb.stem}: the install changed Colab's pinned packages: {', '.join(changed)}")
            print(f"  {nb.stem:<{width}}  {status:<6} {seconds:6.1f} s  {figures:2d} figures   {line}", flush=True)
        t_nbs = time.perf_counter() - t_nbs

        after = current
        unchanged = len(stack.pins) - len(version_changes(pinned_before, after))
    finally:
        if args.keep:
            print(f"  kept {tmp} (executed notebooks in executed/, each notebook's folder in content/)")
        else:
            shutil.rmtree(tmp, ignore_errors=True)

    total = time.perf_counter() - t_start
    if problems:
        print(f"colab-check FAILED ({total:.0f} s):")
        for problem in problems:
            print(f"  - {problem}")
        return 1
    which = f"all {len(notebooks)} notebooks" if not args.only else f"the {len(notebooks)} notebook(s) asked for"
    print(f"colab-check: {which} ran top to bottom in smoke mode on Colab's stack, each "
          f"alone in an empty folder with the package from its own install cell (commit {commit[:10]} of this "
          f"working tree); the install left all {unchanged} pinned packages (torch {after['torch']}, numpy "
          f"{after['numpy']}) as Colab has them. {total:.0f} s in all (venv {how} {t_venv:.0f} s, notebooks "
          f"{t_nbs:.0f} s).")
    return 0


if __name__ == "__main__":
    sys.exit(main())
