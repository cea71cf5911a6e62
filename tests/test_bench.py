"""The benchmark keeps a history: each run appends, older rows are never lost or rewritten."""

import csv
from pathlib import Path

from benchmarks import bench


def _read(path):
    with open(path, newline="") as f:
        return list(csv.reader(f))


def test_rows_are_appended_and_an_old_file_gains_an_empty_commit_column(tmp_path):
    path = tmp_path / "wallclock.csv"
    old_row = ["2026-11-22T05:28:59+00:00", "cpu", "old host", "startup", "1.523", "s", "median of 5"]
    with open(path, "w", newline="") as f:
        csv.writer(f).writerows([bench.HEADER[:-1], old_row])

    new_row = ["2026-12-01T00:00:00+00:00", "cpu", "new host", "startup", "0.830", "s", "median of 5",
               "abc1234"]
    bench.append_rows(path, [new_row])
    bench.append_rows(path, [new_row])

    rows = _read(path)
    assert rows[0] == bench.HEADER
    assert rows[1] == old_row + [""]
    assert rows[2:] == [new_row, new_row]


def test_a_csv_with_foreign_columns_is_refused_not_overwritten(tmp_path):
    path = tmp_path / "wallclock.csv"
    path.write_text("a,b\n1,2\n")
    try:
        bench.append_rows(path, [["x"] * len(bench.HEADER)])
    except SystemExit as e:
        assert "unexpected columns" in str(e)
    else:
        raise AssertionError("append_rows overwrote a CSV it does not understand")
    assert path.read_text() == "a,b\n1,2\n"


def test_host_description_names_the_cpu_family_where_linux_tells_it():
    desc = bench.host_description()
    assert "torch" in desc
    cpuinfo = Path("/proc/cpuinfo")
    if cpuinfo.exists() and "cpu family" in cpuinfo.read_text():
        assert "family" in desc


def test_the_class_benchmark_hands_in_six_notebooks_per_student_faults_included(executed_notebooks, tmp_path):
    import zipfile
    from collections import Counter

    from benchmarks.bench_class import KINDS, class_zip

    executed, _ = executed_notebooks
    ids = class_zip(executed, len(KINDS) + 2, tmp_path / "class.zip")
    with zipfile.ZipFile(tmp_path / "class.zip") as zf:
        names = zf.namelist()
        per_student = Counter(n.split("_", 1)[0] for n in names)
        assert sorted(per_student) == sorted(ids) and set(per_student.values()) == {6}
        assert zf.read("wrong002_02_reward.ipynb") != zf.read("perfect000_02_reward.ipynb")   # the fault is in
        assert zf.read("wrong002_01_world_model.ipynb") == zf.read("perfect000_01_world_model.ipynb")
    assert [i[:-3] for i in ids[:len(KINDS)]] == list(KINDS)


def test_the_handwritten_bound_compares_like_with_like(capsys):
    # bench_handwritten.py bounds what rewriting the update by hand could gain (issue 12); its figures
    # mean something only while the hand-written dream and lambda-return give autograd's gradients.
    import torch

    from benchmarks.bench_handwritten import lambda_return_matrix, main
    from pusht.imagination import lambda_return

    rewards, values = torch.randn(7, 5), torch.randn(8, 5)
    assert torch.allclose(lambda_return_matrix(rewards, values, 0.9, 0.7), lambda_return(rewards, values, 0.9, 0.7),
                          atol=1e-5)
    assert main(["--repeats", "3"]) == 0      # it checks the dream's gradients against autograd's first
    assert "saved" in capsys.readouterr().out
