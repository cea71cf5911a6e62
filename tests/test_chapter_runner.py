"""The notebook runner behind `make chapter` and the notebook tests."""

import os

import nbformat
import pytest
from chapter import execute  # scripts/ is put on sys.path by conftest.py


def _notebook(path, source):
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell(source)]
    nb.metadata["kernelspec"] = {"name": "python3", "language": "python", "display_name": "Python 3"}
    nbformat.write(nb, path)
    return path


@pytest.mark.skipif(os.name != "posix", reason="Unix sockets are used on Linux and macOS only")
def test_kernel_runs_over_private_sockets_without_the_tcp_warning(tmp_path, capfd):
    nb = _notebook(tmp_path / "tiny.ipynb", "print(SMOKE, OUT)")
    out = tmp_path / "out"
    out.mkdir()
    execute(nb, out, smoke=True)
    printed = nbformat.read(out / "tiny.ipynb", 4).cells[-1].outputs[0]["text"]
    assert printed.strip() == f"True {out}"          # parameters reached the kernel
    assert "without encryption" not in capfd.readouterr().err
    assert not [p for p in os.listdir(out) if "ipc" in p or p.startswith("k-")]


def test_a_failing_cell_is_reported_by_index(tmp_path):
    import papermill as pm

    nb = _notebook(tmp_path / "bad.ipynb", "raise ValueError('broken on purpose')")
    with pytest.raises(pm.PapermillExecutionError) as info:
        execute(nb, tmp_path, smoke=True)
    assert info.value.ename == "ValueError" and "broken on purpose" in info.value.evalue
