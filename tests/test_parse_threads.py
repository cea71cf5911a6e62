"""The grader parses cells in several threads at once (one grading task a thread): on CPython 3.11
up to 3.11.8 two threads turning a parse into ``ast`` objects at the same time can raise
"SystemError: AST constructor recursion depth mismatch" (it failed a whole class's grading once,
when two tasks started together). ``cellcode.python_tree`` parses one thread at a time."""

import ast
import gc
import sys
import threading
from pathlib import Path

import pytest

from autograde import cellcode

pytestmark = pytest.mark.slow          # parses the grader's sources in threads, for long

SOURCE = (Path(__file__).resolve().parents[1] / "autograde" / "recreate.py").read_text()


class _Finaliser:
    def __del__(self):          # Python code run by the collector, in the middle of a parse: a switch
        sum(range(50))


def _hammer(parse, threads=4, rounds=60) -> list[str]:
    errors = []

    def work(k):
        for i in range(rounds):
            try:
                parse(f"{SOURCE}\n# {k} {i}\n")
            except SystemError as e:
                errors.append(str(e))
                return
            junk = [_Finaliser() for _ in range(50)]
            for j in junk:
                j.self = j

    old_interval, old_threshold = sys.getswitchinterval(), gc.get_threshold()
    sys.setswitchinterval(1e-6)
    gc.set_threshold(50, 2, 2)
    try:
        ts = [threading.Thread(target=work, args=(k,)) for k in range(threads)]
        for t in ts:
            t.start()
        for t in ts:
            t.join()
    finally:
        sys.setswitchinterval(old_interval)
        gc.set_threshold(*old_threshold)
    return errors


def test_the_graders_parses_are_safe_in_threads():
    assert _hammer(cellcode.python_tree) == []
    assert _hammer(lambda s: cellcode.parse(s)) == []


@pytest.mark.skipif(sys.version_info[:2] != (3, 11), reason="the CPython defect is 3.11's")
def test_the_defect_is_real_here_so_the_test_above_can_fail():
    errors = _hammer(ast.parse)
    if not errors:
        pytest.skip("this CPython does not show the defect (3.11.9 and later are fixed)")
    assert "recursion depth mismatch" in errors[0]
