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


def test_the_class_benchmark_hands_in_every_notebook_per_student_faults_included(executed_notebooks, tmp_path):
    import zipfile
    from collections import Counter

    from autograde.course import NOTEBOOKS
    from benchmarks.bench_class import KINDS, class_zip

    executed, _ = executed_notebooks
    ids = class_zip(executed, len(KINDS) + 2, tmp_path / "class.zip")
    with zipfile.ZipFile(tmp_path / "class.zip") as zf:
        names = zf.namelist()
        per_student = Counter(n.split("_", 1)[0] for n in names)
        assert sorted(per_student) == sorted(ids) and set(per_student.values()) == {len(NOTEBOOKS)}
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


def test_the_planner_summary_is_generated_from_the_csvs_and_names_each_model(tmp_path):
    from benchmarks import plan_table
    from pusht.config import Config
    from benchmarks.bench_plan import MODEL_FIELDS

    chapter = " ".join(f"{k}={getattr(Config(), k)}" for k in MODEL_FIELDS)
    assert plan_table.model_label(chapter) == "chapter"
    recipe = plan_table.read("plan_sensitivity.csv")[0]["model"]
    assert plan_table.model_label(recipe) == "recipe"
    assert plan_table.model_label(recipe.replace("hidden_dim=128", "hidden_dim=64")) == "recipe data, delta 64"
    assert plan_table.settings_label("horizon=16 knots=4 samples=64 iters=4 elites=8 init_std=0.5 min_std=0.05 "
                                     "warm=True window=0 starts=30") == plan_table.FIRST
    eight = "horizon=16 knots=8 samples=64 iters=4 elites=8 init_std=0.5 min_std=0.05 warm=True window=0 starts=30"
    assert plan_table.is_notebook_default({"settings": eight})                 # pusht.plan.NOTEBOOK_PLAN
    assert not plan_table.is_notebook_default({"settings": eight + " objective=tolerance"})
    assert not plan_table.is_notebook_default({"settings": eight.replace("knots=8", "knots=4")})
    assert plan_table.settings_label("horizon=8 knots=4 samples=64 iters=4 elites=8 init_std=0.5 min_std=0.05 "
                                     "warm=True window=0 starts=30") == "horizon 8"
    src = plan_table.BENCH / "plan_sensitivity.csv"
    lines = src.read_text().splitlines()
    rows = [line for line in lines[1:] if "samples=64 iters=4 elites=8" in line]
    assert rows, "plan_sensitivity.csv has 07's default on some seed"
    (tmp_path / "plan_notebook.csv").write_text("\n".join([lines[0]] + rows) + "\n")
    page = plan_table.summary(tmp_path)
    assert "Median success over the seeds" in page and "(no rows yet)" in page    # the other files are absent
    first = next(r for r in plan_table.read("plan_notebook.csv", tmp_path))
    assert f"| {first['seed']} | {first['successes']}/30 " in page
    assert plan_table.sign_test(0, 0) == 1.0 and plan_table.sign_test(5, 0) == 2 / 32 == plan_table.sign_test(0, 5)
