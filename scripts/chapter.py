"""The chapter's main job: execute every instructor notebook (01-06) at the default config, in order.

    python -m scripts.chapter [--out runs/chapter] [--smoke]

Each notebook runs headless with papermill into ``--out`` (executed notebooks, figures under
figures/, per-seed metrics under metrics/, and the model cache shared between notebooks). Frozen
progress bars are removed from the saved notebooks (every other output is kept). The peak resident
memory of each notebook's kernel is measured while it runs and written to ``<out>/memory.json``.
At the end it prints the headline table from the metrics the notebooks wrote and the memory table.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
COLUMNS = [("imagined_return_per_step", "imagined r/step", "+.3f"),
           ("real_return_per_step", "real r/step", "+.3f"),
           ("imagination_gap", "gap", "+.3f"),
           ("imagined_final_tee_dist", "dream tee-dist m", ".3f"),
           ("real_final_tee_dist", "real tee-dist m", ".3f"),
           ("spawn_tee_dist", "spawn tee-dist m", ".3f"),
           ("real_success_rate", "real success", ".2f")]
# Binder gives a session 2 GB; each notebook's kernel must stay under this (issue 10).
MEMORY_LIMIT_MB = 1500.0                        # MB = 10**6 bytes throughout
MEMORY_METHOD = ("VmHWM (the kernel's resident-memory high-water mark, kept by Linux) from "
                 "/proc/<kernel pid>/status, read after every cell and every 0.25 s until the "
                 "kernel exits; 'with children' is the largest sampled sum of VmRSS over the "
                 "kernel and its child processes")


def headline_table(metrics_dir: Path) -> str:
    rows = []
    for path in sorted(metrics_dir.glob("seed*.json")):
        m = json.loads(path.read_text())
        rows.append([path.stem] + [format(m[key], fmt) for key, _, fmt in COLUMNS])
    header = ["run"] + [title for _, title, _ in COLUMNS]
    widths = [max(len(r[i]) for r in rows + [header]) for i in range(len(header))]
    lines = ["  ".join(h.rjust(w) for h, w in zip(header, widths))]
    lines += ["  ".join(c.rjust(w) for c, w in zip(r, widths)) for r in rows]
    return "\n".join(lines)


# ---------------------------------------------------------------- peak memory of the kernel ----

def memory_measurable() -> tuple[bool, str]:
    """Whether peak kernel memory can be measured here, and if not, why."""
    if not Path(f"/proc/{os.getpid()}/status").exists():
        return False, f"not measured: this platform ({sys.platform}) has no /proc to read VmHWM from"
    if _status_kb(os.getpid(), "VmHWM") is None:
        return False, "not measured: /proc/<pid>/status has no VmHWM on this platform"
    return True, ""


def _status_kb(pid: int, field: str) -> int | None:
    """A ``kB`` field (VmHWM, VmRSS) of /proc/<pid>/status; None once the process is gone."""
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith(field + ":"):
                    return int(line.split()[1])
    except (OSError, ValueError, IndexError):
        return None
    return None


def _children(pid: int) -> set[int]:
    """Direct children of ``pid`` (from /proc/<pid>/task/*/children, else a scan of /proc)."""
    kids: set[int] = set()
    try:
        tasks = os.listdir(f"/proc/{pid}/task")
    except OSError:
        return kids
    try:
        for tid in tasks:
            with open(f"/proc/{pid}/task/{tid}/children") as f:
                kids.update(int(k) for k in f.read().split())
        return kids
    except FileNotFoundError:                   # kernel without CONFIG_PROC_CHILDREN
        pass
    except OSError:
        return kids
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat") as f:
                    stat = f.read()
                if int(stat[stat.rindex(")") + 2:].split()[1]) == pid:
                    kids.add(int(entry))
            except (OSError, ValueError, IndexError):
                continue
    return kids


def _descendants(pid: int) -> set[int]:
    found, todo = set(), [pid]
    while todo:
        for kid in _children(todo.pop()) - found:
            found.add(kid)
            todo.append(kid)
    return found


def _cmdline(pid: int) -> list[str]:
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as f:
            return [a.decode(errors="replace") for a in f.read().split(b"\0") if a]
    except OSError:
        return []


def is_kernel(cmdline: list[str]) -> bool:
    """An ipykernel process (``python -m ipykernel_launcher -f ...``), not papermill itself."""
    return any("ipykernel" in arg for arg in cmdline)


class PeakMemory:
    """Peak resident memory of the processes this process starts that ``match`` their command line
    (by default: Jupyter kernels), read from /proc while they run.

    Use as a context manager around the code that starts them; pass ``poll`` as a hook to read
    right at moments that matter (after each cell). The high-water mark VmHWM is kept by Linux, so
    the kernel's own peak is exact whenever it is read before the process exits, however briefly
    the peak lasted; the sum over the process and its children is sampled, so it is a lower bound.
    Processes that were already running when the block was entered are ignored.
    """

    def __init__(self, match=is_kernel, interval: float = 0.25):
        self.match, self.interval = match, interval
        self.available, self.reason = memory_measurable()
        self.hwm_kb: dict[int, int] = {}        # matched pid -> largest VmHWM read
        self.tree_peak_kb = 0                   # largest sampled VmRSS sum, matched + descendants
        self.children_seen: set[int] = set()    # descendants of matched processes
        self._baseline: set[int] = set()
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def __enter__(self):
        if self.available:
            self._baseline = _descendants(os.getpid())
            self._thread = threading.Thread(target=self._run, name="kernel-memory", daemon=True)
            self._thread.start()
        return self

    def __exit__(self, *exc):
        if self._thread is not None:
            self._stop.set()
            self._thread.join()
            self.poll()
        return False

    def _run(self):
        while not self._stop.is_set():
            self.poll()
            self._stop.wait(self.interval)

    def poll(self, **_hook_kwargs) -> None:
        """Read every matching process now (also usable as nbclient's ``on_cell_executed`` hook)."""
        if not self.available:
            return
        with self._lock:
            mine = _descendants(os.getpid())
            for pid in mine - self._baseline - set(self.hwm_kb):
                if self.match(_cmdline(pid)):   # not cached when False: a fresh fork may not have exec'd yet
                    self.hwm_kb[pid] = 0
            tree_kb = 0
            for pid in list(self.hwm_kb):
                if pid not in mine:             # exited (or reaped): its last reading stands
                    continue
                hwm, rss = _status_kb(pid, "VmHWM"), _status_kb(pid, "VmRSS")
                if hwm is not None:
                    self.hwm_kb[pid] = max(self.hwm_kb[pid], hwm)
                tree_kb += rss or 0
                kids = _descendants(pid)
                self.children_seen |= kids
                tree_kb += sum(_status_kb(k, "VmRSS") or 0 for k in kids)
            self.tree_peak_kb = max(self.tree_peak_kb, tree_kb)

    def result(self) -> dict:
        """The readings, in MB (10**6 bytes); ``measured`` False (with ``reason``) if impossible."""
        if not self.available:
            return {"measured": False, "reason": self.reason}
        if not any(self.hwm_kb.values()):
            return {"measured": False, "reason": "no matching process was seen while it ran"}
        mb = lambda kb: round(kb * 1024 / 1e6, 1)  # noqa: E731
        peak = max(self.hwm_kb.values())
        return {"measured": True, "peak_rss_mb": mb(peak), "processes": len(self.hwm_kb),
                "with_children_peak_rss_mb": mb(max(self.tree_peak_kb, peak)),
                "child_processes": len(self.children_seen)}


# ------------------------------------------------------------------- frozen progress bars ----

# tqdm's text bar, with a total ("desc:  42%|####  | 42/100 [00:01<00:02, 30.1it/s, loss=1]") or
# without one ("desc: 42it [00:01, 30.1it/s]"): its timing-and-rate bracket ends the line.
_TIME = r"(?:\d+d, )?\d+:\d\d(?::\d\d)?"
_NUM = r"[\d.]+\s?[kMGTPEZY]?"
_RATE = rf"(?:\?|{_NUM})\s?(?:[^\s,\]]+/s|s/[^\s,\]]+)"
_BAR = re.compile(rf"^(?:.*?: ?)?\s*(?:\d{{1,3}}%\|[^|]*\|\s*{_NUM}/(?:{_NUM}|\?)|{_NUM}[^\s\[]*)"
                  rf"\s\[{_TIME}(?:<(?:\?|{_TIME}))?,\s*{_RATE}(?:,[^\]\r\n]*)?\]\s*$")
_WIDGET = "application/vnd.jupyter.widget-view+json"


def is_progress_bar_text(text: str) -> bool:
    """Whether one line (between \\r and \\n) of an output is a tqdm progress bar."""
    return bool(_BAR.match(text.strip("\r\n")))


def _widget_refs(state: dict, model_id: str) -> set[str]:
    """``model_id`` and every widget model it refers to (children, layout, style), recursively."""
    found, todo = set(), [model_id]
    while todo:
        mid = todo.pop()
        if mid in found or mid not in state:
            continue
        found.add(mid)
        todo += re.findall(r"IPY_MODEL_([\w-]+)", json.dumps(state[mid].get("state", {})))
    return found


def _is_bar_widget(output: dict, state: dict) -> bool:
    view = output.get("data", {}).get(_WIDGET)
    if not isinstance(view, dict):
        return False
    if is_progress_bar_text("".join(output["data"].get("text/plain", ""))):
        return True
    # tqdm.notebook's bar: an HBox of [HTML, FloatProgress/IntProgress, HTML]
    model = state.get(view.get("model_id"), {})
    kids = re.findall(r"IPY_MODEL_([\w-]+)", json.dumps(model.get("state", {}).get("children", [])))
    return model.get("model_name") == "HBoxModel" and any(
        state.get(k, {}).get("model_name") in ("FloatProgressModel", "IntProgressModel") for k in kids)


def _clean_stream_text(text: str) -> str:
    """Drop the progress-bar segments of a stream's text. A line made only of bar updates goes,
    with its newline (tqdm's own on close); every other line is kept as it was."""
    kept = []
    for line in re.findall(r"[^\n]*\n|[^\n]+$", text):   # not splitlines: it splits at \r
        body = line.rstrip("\n")
        segments = body.split("\r")
        left = [s for s in segments if not is_progress_bar_text(s)]
        if len(left) == len(segments):
            kept.append(line)                   # no bar on this line: untouched
        elif any(s.strip() for s in left):
            kept.append("\r".join(s for s in left if s.strip()) + line[len(body):])
    return "".join(kept)


def strip_progress_bars(nb) -> int:
    """Remove frozen tqdm progress bars from an executed notebook (nbformat node, in place):
    widget views of a bar (and their saved widget state), and bar updates written to stderr or
    stdout. Every other output is kept. Returns how many outputs were removed or changed."""
    from nbformat import from_dict

    widgets = nb.metadata.get("widgets", {}).get("application/vnd.jupyter.widget-state+json", {})
    state = widgets.get("state", {}) if isinstance(widgets, dict) else {}
    dropped_models, kept_models, changed = set(), set(), 0
    for cell in nb.cells:
        if cell.get("cell_type") != "code":
            continue
        outputs, i = [], 0
        while i < len(cell.outputs):
            out = cell.outputs[i]
            if out.get("output_type") == "display_data" and _WIDGET in out.get("data", {}):
                mid = out["data"][_WIDGET].get("model_id")
                if _is_bar_widget(out, state):
                    dropped_models |= _widget_refs(state, mid)
                    changed += 1
                else:
                    kept_models |= _widget_refs(state, mid)
                    outputs.append(out)
                i += 1
            elif out.get("output_type") == "stream":
                # a run of outputs of one stream reads as one text; clean it only if it has a bar
                j = i
                while (j < len(cell.outputs) and cell.outputs[j].get("output_type") == "stream"
                       and cell.outputs[j].get("name") == out.get("name")):
                    j += 1
                run = cell.outputs[i:j]
                text = "".join("".join(o["text"]) if isinstance(o["text"], list) else o["text"]
                               for o in run)
                if any(is_progress_bar_text(s) for line in text.split("\n") for s in line.split("\r")):
                    cleaned = _clean_stream_text(text)
                    changed += len(run)
                    if cleaned:
                        out = from_dict(dict(run[0]))
                        out["text"] = cleaned
                        outputs.append(out)
                else:
                    outputs.extend(run)
                i = j
            else:
                outputs.append(out)
                i += 1
        cell.outputs = outputs
    for mid in dropped_models - kept_models:
        state.pop(mid, None)
    if widgets and not state:
        del nb.metadata["widgets"]
    return changed


def clean_saved_notebook(path: Path) -> int:
    """Strip progress bars from the executed notebook at ``path``, rewriting it if anything went."""
    import nbformat

    nb = nbformat.read(str(path), as_version=4)
    changed = strip_progress_bars(nb)
    if changed:
        nbformat.write(nb, str(path))
    return changed


# ------------------------------------------------------------------------------ running ----

def execute(nb: Path, out: Path, smoke: bool, on_cell_executed=None, parameters: dict | None = None,
            saved: Path | None = None) -> None:
    """Run one instructor notebook headless into ``out`` with papermill, parameters SMOKE and OUT
    (and any other ``parameters``, e.g. SEED), saving the executed copy as ``saved`` (default
    ``out / nb.name``).

    Raises ``papermill.PapermillExecutionError`` naming the failing cell. On Linux and macOS the
    kernel talks to papermill over Unix sockets in a private temporary folder instead of TCP ports
    on localhost: nothing here needs the network, and ipykernel would otherwise print a warning
    about unencrypted TCP at every kernel start. ``on_cell_executed`` is nbclient's hook, called
    after each cell.
    """
    import papermill as pm
    from traitlets.config import Config

    with tempfile.TemporaryDirectory(prefix="pusht-kernel-") as sockets:
        config = Config()
        if os.name == "posix":
            config.KernelManager.transport = "ipc"
            config.KernelManager.ip = os.path.join(sockets, "k")
        hooks = {"on_cell_executed": on_cell_executed} if on_cell_executed else {}
        pm.execute_notebook(str(nb), str(saved or out / nb.name), kernel_name="python3", cwd=str(out),
                            parameters={"SMOKE": smoke, "OUT": str(out), **(parameters or {})},
                            progress_bar=False,
                            config=config, **hooks)


def run_notebook(nb: Path, out: Path, smoke: bool) -> dict:
    """Execute one notebook (``execute``), measuring its kernel's peak memory, then strip the
    progress bars from the saved copy. Returns the record written to memory.json; on failure
    the record is attached to the raised error as ``.memory``."""
    t = time.perf_counter()
    error = None
    with PeakMemory() as mem:
        try:
            execute(nb, out, smoke, on_cell_executed=mem.poll)
        except Exception as e:                  # noqa: BLE001 - re-raised below
            error = e
    record = {"seconds": round(time.perf_counter() - t, 1), **mem.result(),
              "status": "ok" if error is None else f"failed: {type(error).__name__}"}
    if (out / nb.name).exists():
        record["progress_bar_outputs_removed"] = clean_saved_notebook(out / nb.name)
    if error is not None:
        error.memory = record
        raise error
    return record


def memory_table(records: dict) -> str:
    lines = [f"{'notebook':<28} {'time s':>7} {'kernel peak MB':>15} {'with children MB':>17}"]
    for name, r in records.items():
        if r.get("measured"):
            flag = "  OVER the limit" if r["peak_rss_mb"] > MEMORY_LIMIT_MB else ""
            lines.append(f"{name:<28} {r['seconds']:>7.0f} {r['peak_rss_mb']:>15.0f} "
                         f"{r['with_children_peak_rss_mb']:>17.0f}{flag}")
        else:
            lines.append(f"{name:<28} {r['seconds']:>7.0f}  {r.get('reason', 'not measured')}")
        if not r["status"].startswith("ok"):
            lines[-1] += f"  ({r['status']})"
    return "\n".join(lines)


def write_memory(out: Path, records: dict, smoke: bool) -> Path:
    path = out / "memory.json"
    path.write_text(json.dumps({"config": "smoke" if smoke else "default", "unit": "MB = 10**6 bytes",
                                "limit_mb": MEMORY_LIMIT_MB, "method": MEMORY_METHOD,
                                "notebooks": records}, indent=1) + "\n")
    return path


def record_times(out: Path) -> Path:
    """pusht/nb/times.json from the executed notebooks in ``out`` (see pusht/nb/timing.py)."""
    import subprocess
    from datetime import datetime, timezone

    import nbformat

    from pusht.nb import timing

    from pusht.host import cpu_model

    cpu = cpu_model()
    try:
        rev = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True,
                             check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        rev = "unknown"
    data = {"written_by": "scripts/chapter.py --record-times (make times)",
            "host": f"{cpu}, {os.cpu_count()} cores", "measured_at":
            datetime.now(timezone.utc).isoformat(timespec="seconds"), "commit": rev, "config": "default",
            "notebooks": {nb.stem: timing.measure(nbformat.read(nb, as_version=4))
                          for nb in sorted(out.glob("0*.ipynb"))}}
    timing.TIMES.write_text(json.dumps(data, indent=1) + "\n")
    return timing.TIMES


def main(argv=None) -> int:
    import papermill as pm

    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", type=Path, default=ROOT / "runs" / "chapter")
    p.add_argument("--smoke", action="store_true", help="the tiny config (seconds per notebook)")
    p.add_argument("--record-times", action="store_true",
                   help="write each notebook's measured time to pusht/nb/times.json (the default config only)")
    args = p.parse_args(argv)
    if args.record_times and args.smoke:
        p.error("--record-times records the default config's times; drop --smoke")
    out = args.out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    records: dict = {}
    for nb in sorted((ROOT / "solutions").glob("*.ipynb")):
        print(f"running {nb.name} ...", flush=True)
        try:
            records[nb.name] = run_notebook(nb, out, args.smoke)
        except pm.PapermillExecutionError as e:
            records[nb.name] = e.memory
            write_memory(out, records, args.smoke)
            print(f"FAILED: {nb.name}, cell {e.cell_index}: {e.ename}: {e.evalue}\n"
                  f"the executed notebook with the error is {out / nb.name}", file=sys.stderr)
            print(f"\nkernel memory so far ({out / 'memory.json'}):\n{memory_table(records)}")
            return 1
        except Exception as e:                  # a dead kernel, a timeout: record, then re-raise
            if getattr(e, "memory", None):
                records[nb.name] = e.memory
                write_memory(out, records, args.smoke)
            raise
        write_memory(out, records, args.smoke)
        r = records[nb.name]
        peak = f", kernel peak {r['peak_rss_mb']:.0f} MB" if r.get("measured") else ""
        print(f"  done in {r['seconds']:.0f} s{peak} -> {out / nb.name}", flush=True)
    print(f"\nall notebooks ran in {time.perf_counter() - t0:.0f} s; figures in {out / 'figures'}\n")
    from chapter_site.scrubber import export     # the site's iteration scrubber (make site)
    export(out, args.smoke)
    if args.record_times:
        print(f"notebook times recorded in {record_times(out)}")
    if list((out / "metrics").glob("seed*.json")):
        from pusht.config import make_config
        print(f"The same policy, two worlds ({make_config(smoke=args.smoke).eval_episodes} held-out starts per seed):")
        print(headline_table(out / "metrics"))
    print(f"\nPeak kernel memory per notebook (limit {MEMORY_LIMIT_MB:.0f} MB for Binder's 2 GB; "
          f"{out / 'memory.json'}):")
    print(memory_table(records))
    return 0


if __name__ == "__main__":
    sys.exit(main())
