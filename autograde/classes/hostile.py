"""A hostile and an unusual-but-honest class: every attack and unfairness the grader must withstand.

    python -m autograde.classes.hostile OUT.zip --executed DIR [--canary PATH]

``--executed`` is a folder of the solution notebooks already executed (smoke mode is enough).
Each cheat edits one notebook of a correct submission (mostly ``02_reward``) so that, if the
attack worked, it would show: a wrong answer scored, a classmate's grade changed, a file read or
written outside the student's folder, a process left behind. ``STUDENTS`` says what each one
tries and what the grader must give it; ``tests/test_grading_hostile.py`` checks every line.

``--canary PATH``: a file only the grader can see (the tests put one inside the course folder);
the snooping students try to read it and print what they find.
"""

from __future__ import annotations

import argparse
import json
import re
import unicodedata
from datetime import datetime, timedelta
import zipfile
from pathlib import Path

from .synthetic import _cells, _grade_id, _load, _src

WRONG_REWARD = '''def reward_from_obs(norm_obs, mean, std):
    obs = norm_obs * std + mean
    pos_err = torch.linalg.vector_norm(obs[..., 2:4], dim=-1)
    ang_err = torch.acos(obs[..., 5].clamp(-1, 1))          # wrong: loses the sign information
    return -0.5 * (pos_err / POS_SCALE + ang_err / ANG_SCALE), pos_err, ang_err
'''

# student id -> (what it tries, expected points on its 02_reward test cell, or None if it has none)
STUDENTS = {
    "snoop": ("reads the course: other submissions, solutions, hidden tests, gradebook, the canary", 4),
    "gradebook": ("writes the gradebook, manual_grades.csv and grades.csv from its kernel", 4),
    "lingers": ("leaves a setsid process that rewrites grades.csv after grading", 4),
    "patchref": ("wrong reward; replaces pusht.reward.reward_from_obs by it", 0),
    "patchtorch": ("wrong reward; replaces torch.allclose and numpy.allclose by always-True", 0),
    "alwayseq": ("returns always-equal objects", 0),
    "inputhide": ("an IPython input transformer that empties every test cell", 0),
    "asthide": ("an AST transformer that wraps every cell in try/except, with a wrong reward", 0),
    "delegate": ("its reward_from_obs calls the package's own implementation", 0),
    "delegate2": ("reaches the package's implementation through getattr and a string", 0),
    "memory": ("allocates 64 GiB in a later cell; the tests before it keep their points", 4),
    "bigout": ("prints one 25 MB line", 4),
    "forkbomb": ("starts processes until it cannot", 4),
    "network": ("opens a TCP connection to the grader's machine", 4),
    "receiptprint": ("prints forged receipts from a print cell, experiment run first", None),
    "receiptedit": ("locked again after seeing the experiment (store deleted): the lock receipt is newer than "
                    "the lock the experiment quotes", None),
    "alreadylocked": ("prints the words 'already locked' to switch the order check off", None),
    "pipelinefirst": ("runs the experiment's functions directly before locking", None),
    "plannerfirst": ("runs notebook 07's planner directly before locking Exercise 4", None),
    # attacks on the verdict path, the grader's files and its resources
    "forgeresults": ("wrong reward; a post-run hook forges the reference's numbers into every results file and "
                     "rebinds pusht.grading.submit and sys.modules['pusht.grading'] to record the package's answer", 0),
    "stackref": ("wrong reward, unless a probe is on the call stack: then the package's own, reached by a name "
                 "built at run time, through inspect.unwrap and __closure__", 0),
    "probekill": ("a correct reward that, called in the probe process, kills the probe server and forks until it "
                  "cannot: it harms only its own test", 0),
    "answerkey": ("the package's reward_from_obs pasted in, variables renamed: earns its points, flagged", 4),
    "linkfarm": ("correct; then links, fifos, invalid notebooks, a bzip2 results file and random bytes in every "
                 "folder it can write, links where its sockets are, and links named like every file nbgrader writes", 4),
    "diskfill": ("correct; then fills its working folder and /tmp until they are full", 4),
    "xss": ("correct; markdown <script>, onerror, text/html and application/javascript outputs", 4),
    "flood": ("correct; then prints megabytes to stdout and stderr until the cell timeout", 4),
    # honest but unusual
    "stderr": ("a correct reward that prints a warning to stderr", 4),
    "dupcell": ("the solution cell duplicated: a broken draft, then the correct one", 4),
    "retyped": ("the solution cell retyped without its nbgrader metadata", 4),
    "diesafter": ("the kernel dies in a cell after the tests passed", 4),
    "reupload": ("two uploads of 02_reward: an old wrong one, and a newer correct `(1)` copy", 4),
    "bom": ("a correct notebook saved as UTF-8 with a byte-order mark", 4),
    "utf16": ("a correct notebook saved as UTF-16", 4),
    "Ann Lee": ("an LMS id with a space", 4),
    "john_doe": ("an LMS id with an underscore", 4),
    "Zoë": ("an LMS id with an accent", 4),
    "Chloé": ("the same accented id typed two ways (NFC and NFD), one notebook each", 4),
}


def _code_cell(src):
    return {"cell_type": "code", "execution_count": None, "metadata": {}, "outputs": [], "source": src}


def _insert_after(nb, pred, cell):
    i = next(i for i, c in enumerate(nb["cells"]) if pred(c))
    nb["cells"].insert(i + 1, cell)


def _set_solution(nb, grade_id, src):
    for cell in _cells(nb, lambda c: _grade_id(c) == grade_id):
        cell["source"] = src


def _reward(executed):
    return _load(executed, "02_reward")


def _after_tests(executed, src):
    """A correct 02_reward with one more code cell, ``src``, right after its test cell."""
    nb = _reward(executed)
    _insert_after(nb, lambda c: _grade_id(c) == "reward_impl_tests", _code_cell(src))
    return nb



def build(executed: Path, canary: str = "/nonexistent") -> dict[str, bytes]:
    files: dict[str, bytes] = {}

    def put(student, nb, name="02_reward"):
        files[f"{student}_{name}.ipynb"] = json.dumps(nb).encode()

    is_impl = lambda c: _grade_id(c) == "reward_impl"                     # noqa: E731

    nb = _reward(executed)
    _insert_after(nb, is_impl, _code_cell(
        "import os, sys\n"
        f"canary = '{canary}'\n"
        "for p in (canary, os.path.dirname(canary), os.path.join(os.path.dirname(canary), 'gradebook.db')):\n"
        "    try:\n"
        "        print('FOUND', p, open(p, errors='replace').read(200) if os.path.isfile(p) else os.listdir(p))\n"
        "    except Exception as e:\n"
        "        print('DENIED', p, type(e).__name__)\n"
        "# everything this kernel can see, outside the system, Python and its own folder\n"
        "skip = {'/usr', '/proc', '/dev', '/sys', sys.base_prefix, sys.prefix}\n"
        "seen = []\n"
        "for root, dirs, files in os.walk('/'):\n"
        "    dirs[:] = [d for d in dirs if os.path.join(root, d) not in skip]\n"
        "    seen += [os.path.join(root, f) for f in files]\n"
        "    if len(seen) > 20000:\n"
        "        break\n"
        "words = ('gradebook', 'solutions', 'submitted', 'source', 'instructor_only', 'manual_grades', 'autograde/')\n"
        "print('SEEN', len(seen), 'files;', [p for p in seen if any(w in p for w in words)][:20])\n"
        "here = os.path.abspath('.')\n"
        "for up in range(1, 6):\n"
        "    d = os.path.normpath(os.path.join(here, *['..'] * up))\n"
        "    try:\n"
        "        print('LIST', d, sorted(os.listdir(d))[:50])\n"
        "    except Exception as e:\n"
        "        print('NOLIST', d, e)\n"))
    put("snoop", nb)

    nb = _reward(executed)
    _insert_after(nb, is_impl, _code_cell(
        "import glob, os, sqlite3\n"
        "here = os.path.abspath('.')\n"
        "for up in range(1, 6):\n"
        "    d = os.path.normpath(os.path.join(here, *['..'] * up))\n"
        "    for db in glob.glob(os.path.join(d, '**', 'gradebook*.db'), recursive=True):\n"
        "        try:\n"
        "            con = sqlite3.connect(db); con.execute('update grade set manual_score = 99'); con.commit()\n"
        "            print('WROTE', db)\n"
        "        except Exception as e:\n"
        "            print('NOWRITE', db, e)\n"
        "    for name in ('manual_grades.csv', 'grades.csv'):\n"
        "        try:\n"
        "            open(os.path.join(d, name), 'a').write('perfect,02_reward,reward_impl_tests,0,\\n')\n"
        "            print('WROTE', d, name)\n"
        "        except Exception as e:\n"
        "            pass\n"))
    put("gradebook", nb)

    nb = _reward(executed)
    _insert_after(nb, is_impl, _code_cell(
        "import os, subprocess\n"
        "here = os.path.abspath('.')\n"
        "targets = ' '.join(os.path.normpath(os.path.join(here, *['..'] * up, 'grades.csv')) for up in range(1, 6))\n"
        "subprocess.Popen(['setsid', 'sh', '-c', f'sleep 20; for t in {targets}; do echo hacked >> $t; done; "
        "touch /tmp/lingered'], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)\n"
        "print('left a process behind')\n"))
    put("lingers", nb)

    nb = _reward(executed)
    _set_solution(nb, "reward_impl", WRONG_REWARD + "import pusht.reward\npusht.reward.reward_from_obs = reward_from_obs\n")
    put("patchref", nb)

    nb = _reward(executed)
    _set_solution(nb, "reward_impl", WRONG_REWARD + "import numpy\ntorch.allclose = lambda *a, **k: True\n"
                  "numpy.allclose = lambda *a, **k: True\ntorch.equal = lambda *a, **k: True\n")
    put("patchtorch", nb)

    nb = _reward(executed)
    _set_solution(nb, "reward_impl", (
        "class _Yes(float):\n"
        "    shape = ()\n"
        "    requires_grad = True\n"
        "    def __eq__(self, o): return True\n"
        "    def __ne__(self, o): return False\n"
        "    def __lt__(self, o): return True\n"
        "    def __gt__(self, o): return False\n"
        "    def __abs__(self): return self\n"
        "    def __sub__(self, o): return self\n"
        "    __rsub__ = __add__ = __radd__ = __sub__\n"
        "    def item(self): return 0.0\n"
        "    def sum(self): return self\n"
        "    def backward(self): pass\n"
        "    def numpy(self): return self\n"
        "    def detach(self): return self\n"
        "def reward_from_obs(norm_obs, mean, std):\n"
        "    return _Yes(0.0), _Yes(0.0), _Yes(0.0)\n"))
    put("alwayseq", nb)

    nb = _reward(executed)
    _set_solution(nb, "reward_impl", WRONG_REWARD + (
        "def _drop_tests(lines):\n"
        "    return [] if any('assert' in l or 'submit' in l for l in lines) else lines\n"
        "get_ipython().input_transformers_post.append(_drop_tests)\n"))
    put("inputhide", nb)

    nb = _reward(executed)
    _set_solution(nb, "reward_impl", WRONG_REWARD + (
        "import ast\n"
        "class _Swallow(ast.NodeTransformer):\n"
        "    def visit_Module(self, node):\n"
        "        handler = ast.ExceptHandler(type=ast.Name('BaseException', ast.Load()), name=None, body=[ast.Pass()])\n"
        "        node.body = [ast.Try(body=node.body or [ast.Pass()], handlers=[handler], orelse=[], finalbody=[])]\n"
        "        return ast.fix_missing_locations(node)\n"
        "get_ipython().ast_transformers.append(_Swallow())\n"))
    put("asthide", nb)

    nb = _reward(executed)
    _set_solution(nb, "reward_impl", "from pusht.reward import reward_from_obs as _theirs\n\n\n"
                  "def reward_from_obs(norm_obs, mean, std):\n    return _theirs(norm_obs, mean, std)\n")
    put("delegate", nb)

    nb = _reward(executed)
    _set_solution(nb, "reward_impl", "import importlib\n_m = importlib.import_module('pusht.' + 'reward')\n"
                  "_f = getattr(_m, 'reward_' + 'from_obs')\n\n\n"
                  "def reward_from_obs(norm_obs, mean, std):\n    return _f(norm_obs, mean, std)\n")
    put("delegate2", nb)

    nb = _reward(executed)
    nb["cells"].append(_code_cell("big = bytearray(64 * 2**30)\nprint(len(big))\n"))
    put("memory", nb)

    nb = _reward(executed)
    _insert_after(nb, lambda c: _grade_id(c) == "reward_impl_tests", _code_cell("print('x' * 25_000_000)\n"))
    put("bigout", nb)

    nb = _after_tests(executed, (
        "import subprocess\nprocs = []\n"
        "try:\n    for _ in range(5000):\n        procs.append(subprocess.Popen(['sleep', '60']))\n"
        "except Exception as e:\n    print('stopped after', len(procs), type(e).__name__)\n"))
    put("forkbomb", nb)

    nb = _reward(executed)
    _insert_after(nb, is_impl, _code_cell(
        "import os, socket\nport = int(os.environ.get('HOSTILE_PORT', '1'))\n"
        "try:\n    socket.create_connection(('127.0.0.1', 1), timeout=3)\n    print('NET OPEN')\n"
        "except Exception as e:\n    print('no network:', e)\n"
        "for host in ('127.0.0.1', 'localhost'):\n"
        "    try:\n        socket.create_connection((host, 22), timeout=2); print('NET OPEN', host)\n"
        "    except Exception as e:\n        print('no network:', host, e)\n"))
    put("network", nb)

    # --- receipts: the experiment ran first, then the outputs were doctored -----------------------
    gap = _load(executed, "04_imagination_gap")
    nb = json.loads(json.dumps(gap))
    # ran the experiment first (no real lock receipt), then printed receipts from a new cell
    lc = next(c for c in nb["cells"] if _grade_id(c) == "ex1_prediction")
    lc["outputs"] = []
    forged = ("[prediction locked] ex1: (b) at 2020-01-01T00:00:00.000+00:00\n"
              "[experiment started] ex1 at 2030-01-01T00:00:00.000+00:00 (prediction locked at 2020-01-01T00:00:00.000+00:00)\n")
    cell = _code_cell(f"print({forged!r})")
    cell["execution_count"] = 99
    cell["outputs"] = [{"output_type": "stream", "name": "stdout", "text": forged}]
    nb["cells"].append(cell)
    files["receiptprint_04_imagination_gap.ipynb"] = json.dumps(nb).encode()

    nb = json.loads(json.dumps(gap))
    lc = next(c for c in nb["cells"] if _grade_id(c) == "ex1_prediction")
    rc = next(c for c in nb["cells"] if "run_exercise(\"ex1\"" in _src(c))
    # saw the result, deleted .pusht_predictions.json, locked another choice and ran the lock cell
    # again: its fresh receipt is later than the experiment, which still quotes the first lock.
    # (Swapping only the execution counts, as this student once did, is what an honest restart
    # between the lock and the experiment leaves: receipts.py's module doc.)
    started = re.search(r"\[experiment started\] ex1 at (\S+)", "".join(
        "".join(o.get("text", [])) for o in rc["outputs"])).group(1)
    later = (datetime.fromisoformat(started) + timedelta(minutes=3)).isoformat(timespec="milliseconds")
    for o in lc["outputs"]:
        if "text" in o:
            o["text"] = re.sub(r"\(\w\) at \S+", f"(c) at {later}", "".join(o["text"]), count=1)
    lc["execution_count"] = max(c.get("execution_count") or 0 for c in nb["cells"]) + 1
    files["receiptedit_04_imagination_gap.ipynb"] = json.dumps(nb).encode()

    nb = json.loads(json.dumps(gap))
    lc = next(c for c in nb["cells"] if _grade_id(c) == "ex1_prediction")
    lc["outputs"] = [{"output_type": "stream", "name": "stdout", "text": "already locked\n"}]
    files["alreadylocked_04_imagination_gap.ipynb"] = json.dumps(nb).encode()

    nb = json.loads(json.dumps(gap))
    lc = next(c for c in nb["cells"] if _grade_id(c) == "ex1_prediction")
    early = _code_cell("peek = run_seed(cfg.seed)\n")
    early["execution_count"] = lc["execution_count"]        # run just before the lock, in one session
    for c in nb["cells"]:
        if isinstance(c.get("execution_count"), int) and c["execution_count"] >= early["execution_count"]:
            c["execution_count"] += 1
    lc_index = nb["cells"].index(lc)
    nb["cells"].insert(lc_index, early)
    files["pipelinefirst_04_imagination_gap.ipynb"] = json.dumps(nb).encode()

    nb = _load(executed, "07_planning")             # the planner run on the starts, then the lock
    lc = next(c for c in nb["cells"] if _grade_id(c) == "ex4_prediction")
    early = _code_cell("peek = nb07.plan_in(rungs['recipe'].stage, STARTS, cfg.eval_horizon, S)\n")
    early["execution_count"] = lc["execution_count"]
    for c in nb["cells"]:
        if isinstance(c.get("execution_count"), int) and c["execution_count"] >= early["execution_count"]:
            c["execution_count"] += 1
    nb["cells"].insert(nb["cells"].index(lc), early)
    files["plannerfirst_07_planning.ipynb"] = json.dumps(nb).encode()

    # --- attacks on the verdict path, the grader's files and its resources ---------------------------
    nb = _reward(executed)
    _set_solution(nb, "reward_impl", WRONG_REWARD + (
        "import os, sys, types, numpy as np, pusht.grading, pusht.reward\n"
        "def _forge(*_):\n"
        "    good = pusht.reward.reward_from_obs(torch.zeros(2, 6), torch.zeros(6), torch.ones(6))\n"
        "    fake = {'fresh': np.array(1.0), 'c0.out0': good[0].numpy()}\n"
        "    for root, dirs, _f in os.walk('/'):\n"
        "        if root.startswith(('/proc', '/sys', '/dev', '/usr', sys.prefix, sys.base_prefix)):\n"
        "            dirs[:] = []\n"
        "            continue\n"
        "        if os.access(root, os.W_OK):\n"
        "            for name in ('reward_impl_tests.npz', 'results.npz'):\n"
        "                try:\n"
        "                    np.savez(os.path.join(root, name), **fake)\n"
        "                except OSError:\n"
        "                    pass\n"
        "get_ipython().events.register('post_run_cell', _forge)\n"
        "_real = pusht.grading.submit\n"
        "pusht.grading.submit = lambda test_id, fn: _real(test_id, pusht.reward.reward_from_obs)\n"
        "fake_mod = types.ModuleType('pusht.grading')\n"
        "fake_mod.submit = pusht.grading.submit\n"
        "sys.modules['pusht.grading'] = fake_mod\n"))
    put("forgeresults", nb)

    nb = _reward(executed)
    _set_solution(nb, "reward_impl", WRONG_REWARD.replace("def reward_from_obs(", "def _mine(") + (
        "import importlib, inspect\n"
        "def reward_from_obs(norm_obs, mean, std):\n"
        "    names = {f.function for f in inspect.stack()}\n"
        "    if names & {'probe', 'run_probes', 'submit', '_child'}:\n"
        "        mod = importlib.import_module(bytes([112, 117, 115, 104, 116, 46, 114, 101, 119, 97, 114, 100]).decode())\n"
        "        fn = getattr(mod, bytes([114, 101, 119, 97, 114, 100, 95, 102, 114, 111, 109, 95, 111, 98, 115]).decode())\n"
        "        fn = inspect.unwrap(fn)\n"
        "        for cell in (fn.__closure__ or ()):\n"
        "            if callable(cell.cell_contents):\n"
        "                fn = cell.cell_contents\n"
        "        return fn(norm_obs, mean, std)\n"
        "    return _mine(norm_obs, mean, std)\n"))
    put("stackref", nb)

    nb = _reward(executed)
    impl = next(c for c in nb["cells"] if _grade_id(c) == "reward_impl")
    impl["source"] = _src(impl).replace("    ### BEGIN SOLUTION\n", (
        "    ### BEGIN SOLUTION\n"
        "    import builtins, os, signal, time\n"
        "    if not hasattr(builtins, 'get_ipython'):     # not in a kernel: the grader's probe process\n"
        "        os.kill(os.getppid(), signal.SIGKILL)\n"
        "        for _ in range(400):\n"
        "            try:\n"
        "                if os.fork() == 0:\n"
        "                    time.sleep(30)\n"
        "                    os._exit(0)\n"
        "            except OSError:\n"
        "                break\n"), 1)
    put("probekill", nb)

    import inspect as _inspect, pusht.reward as _reward_module    # noqa: E401  the key a learner can read
    key = _inspect.getsource(_reward_module.reward_from_obs).split("\n", 1)[1]    # without the decorator
    key = key.replace("obs", "o").replace("pos_err", "d").replace("ang_err", "a").replace("reward", "r", 2)
    _set_solution(nb := _reward(executed), "reward_impl", key.replace("def r_from_o(", "def reward_from_obs(")
                  .replace("norm_o", "norm_obs"))
    put("answerkey", nb)

    nb = _after_tests(executed, (
        "import io, os, random, sys, zipfile\n"
        f"canary = {canary!r}\n"
        "rng = random.Random(os.urandom(8))\n"
        "targets = [canary, '/etc/passwd', '/etc/shadow', os.path.expanduser('~'), '../../../gradebook.db',\n"
        "           '../../../source/ps/02_reward.ipynb', '../../../../grades.csv', '/proc/1/root']\n"
        "names = ['02_reward.ipynb', '03_imagination_actor.ipynb', 'timestamp.txt', 'gradebook.db', 'feedback',\n"
        "         'results', 'reward_impl_tests.npz', '.ipynb_checkpoints', 'x.ipynb', 'graded.json']\n"
        "bomb = io.BytesIO()\n"
        "with zipfile.ZipFile(bomb, 'w', zipfile.ZIP_BZIP2) as z:\n"
        "    z.writestr('fresh.npy', b'\\0' * (64 << 20))\n"
        "made = 0\n"
        "for root, dirs, files in os.walk('/'):\n"
        "    if root.startswith(('/proc', '/sys', '/dev', '/usr', sys.prefix, sys.base_prefix)):\n"
        "        dirs[:] = []\n"
        "        continue\n"
        "    if not os.access(root, os.W_OK):\n"
        "        continue\n"
        "    for name in names:\n"
        "        p = os.path.join(root, name)\n"
        "        for attempt in ('unlink', 'link', 'fifo', 'junk'):\n"
        "            try:\n"
        "                if attempt == 'unlink':\n"
        "                    os.unlink(p)\n"
        "                elif attempt == 'link':\n"
        "                    os.symlink(rng.choice(targets), p); made += 1\n"
        "                elif attempt == 'fifo':\n"
        "                    os.mkfifo(p + '.fifo'); made += 1\n"
        "                else:\n"
        "                    with open(p + '.junk', 'wb') as f:\n"
        "                        f.write(bomb.getvalue() if rng.random() < 0.5 else rng.randbytes(rng.randrange(1 << 16)))\n"
        "                    made += 1\n"
        "            except OSError:\n"
        "                pass\n"
        "    for _ in range(5):\n"
        "        enc = rng.choice(['utf-8', 'utf-16', 'latin-1', 'utf-32'])\n"
        "        name = ''.join(rng.choice('abc\u00e9\u0456\u202e.ipynb') for _ in range(12))\n"
        "        try:\n"
        "            with open(os.path.join(root, name), 'wb') as f:\n"
        "                f.write(('{\"cells\": [' + 'x' * rng.randrange(100)).encode(enc)); made += 1\n"
        "        except (OSError, ValueError):\n"
        "            pass\n"
        "print('LINKFARM made', made)\n"
        "# the folder of this kernel's own sockets, where the grader's ZeroMQ would reconnect\n"
        "import json\n"
        "from ipykernel.kernelapp import IPKernelApp\n"
        "sockets = os.path.dirname(json.load(open(IPKernelApp.instance().connection_file))['ip'])\n"
        "try:\n"
        "    os.symlink('/etc/passwd', os.path.join(sockets, 'k-1-link'))\n"
        "    print('SOCKETS WRITABLE', sockets)\n"
        "except OSError as e:\n"
        "    print('SOCKETS LOCKED', type(e).__name__)\n"))
    put("linkfarm", nb)

    nb = _after_tests(executed, (
        "import os\n"
        "block = b'x' * (16 << 20)\n"
        "for where in ('.', '/tmp'):\n"
        "    total = 0\n"
        "    for k in range(400):\n"
        "        try:\n"
        "            with open(os.path.join(where, f'fill{k}'), 'wb') as f:\n"
        "                for _ in range(8):\n"
        "                    f.write(block); f.flush(); total += len(block)\n"
        "        except OSError as e:\n"
        "            print('FULL', where, total >> 20, 'MB', type(e).__name__)\n"
        "            break\n"
        "    else:\n"
        "        print('NOT FULL', where, total >> 20, 'MB')\n"))
    put("diskfill", nb)

    nb = _after_tests(executed, (
        "import os, sys\n"
        "line = 'x' * (1 << 20) + '\\n'\n"
        "while True:\n"
        "    sys.stdout.write(line)\n"
        "    os.write(2, line.encode())\n"))
    put("flood", nb)

    nb = _reward(executed)
    nb["cells"].insert(1, {"cell_type": "markdown", "metadata": {}, "source":
                           "<script>document.title='XSS-MD'</script><img src=x onerror=\"document.title='XSS-IMG'\">\n"
                           "<a href=\"javascript:document.title='XSS-A'\">click</a>"})
    _insert_after(nb, lambda c: _grade_id(c) == "reward_impl_tests", _code_cell(
        "from IPython.display import HTML, Javascript, SVG, display\n"
        "display(HTML(\"<script>document.title='XSS-HTML'</script><img src=x onerror=\\\"document.title='XSS-ON'\\\">\"))\n"
        "display(Javascript(\"document.title='XSS-JS'\"))\n"
        "display(SVG('<svg xmlns=\"http://www.w3.org/2000/svg\" onload=\"document.title=1\"><script>document.title=2</script></svg>'))\n"))
    put("xss", nb)

    # --- honest but unusual ----------------------------------------------------------------------
    ref_src = _src(next(c for c in _reward(executed)["cells"] if _grade_id(c) == "reward_impl"))

    nb = _reward(executed)
    _set_solution(nb, "reward_impl", ref_src.replace("    ### BEGIN SOLUTION\n",
                  "    ### BEGIN SOLUTION\n    import sys, warnings\n    warnings.warn('my own warning')\n"
                  "    print('debug', file=sys.stderr)\n", 1))
    put("stderr", nb)

    nb = _reward(executed)
    impl = next(c for c in nb["cells"] if _grade_id(c) == "reward_impl")
    draft = json.loads(json.dumps(impl))
    draft["source"] = "def reward_from_obs(norm_obs, mean, std):\n    raise NotImplementedError()\n"
    nb["cells"].insert(nb["cells"].index(impl), draft)
    put("dupcell", nb)

    nb = _reward(executed)
    impl = next(c for c in nb["cells"] if _grade_id(c) == "reward_impl")
    impl["metadata"] = {}
    impl.pop("id", None)
    put("retyped", nb)

    nb = _reward(executed)
    _insert_after(nb, lambda c: _grade_id(c) == "reward_impl_tests",
                  _code_cell("import os, signal\nos.kill(os.getpid(), signal.SIGKILL)\n"))
    put("diesafter", nb)

    nb = _reward(executed)
    _set_solution(nb, "reward_impl", WRONG_REWARD)
    files["reupload_02_reward.ipynb"] = json.dumps(nb).encode()
    files["reupload_02_reward (1).ipynb"] = json.dumps(_reward(executed)).encode()

    files["bom_02_reward.ipynb"] = b"\xef\xbb\xbf" + json.dumps(_reward(executed)).encode()
    files["utf16_02_reward.ipynb"] = json.dumps(_reward(executed), ensure_ascii=False).encode("utf-16")
    for sid in ("Ann Lee", "john_doe", "Zoë"):
        put(sid, _reward(executed))
    put(unicodedata.normalize("NFC", "Chloé"), _reward(executed))
    files[f"{unicodedata.normalize('NFD', 'Chloé')}_03_imagination_actor.ipynb"] = \
        json.dumps(_load(executed, "03_imagination_actor")).encode()

    # --- hostile member names: nothing may be written outside the course -------------------------
    ok = json.dumps(_reward(executed)).encode()
    files["../escape_02_reward.ipynb"] = ok
    files["/abs/rooted_02_reward.ipynb"] = ok
    files["../../02_reward.ipynb"] = ok
    files["mallory/perfect_02_reward.ipynb"] = json.dumps(_reward(executed) | {}).encode()
    return files


def write_zip(out: Path, executed: Path, canary: str = "/nonexistent", extra: dict | None = None) -> Path:
    with zipfile.ZipFile(out, "w") as zf:
        for name, data in sorted({**build(executed, canary), **(extra or {})}.items()):
            info = zipfile.ZipInfo(name, date_time=(2026, 1, 2, 3, 4, 5) if "(1)" in name else (2026, 1, 1, 0, 0, 0))
            zf.writestr(info, data)
    return out


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("out", type=Path)
    p.add_argument("--executed", type=Path, required=True)
    p.add_argument("--canary", default="/nonexistent")
    args = p.parse_args(argv)
    print(f"wrote {write_zip(args.out, args.executed, args.canary)}")


if __name__ == "__main__":
    main()
