"""The machine a figure was measured on, in one place: every timing, table and note that names its host
reads the CPU here (``/proc/cpuinfo`` on Linux, ``platform`` elsewhere)."""

from __future__ import annotations

import os
import platform
from pathlib import Path


def cpu_info() -> dict:
    """The first processor's entries of ``/proc/cpuinfo`` ({} where there is none)."""
    info: dict = {}
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            key, _, value = line.partition(":")
            if not key.strip():
                break                                   # the first processor is enough
            info.setdefault(key.strip(), value.strip())
    except OSError:
        pass
    return info


def cpu_model(family: bool = False) -> str:
    """The CPU's model name ("Intel(R) Xeon(R) Processor"); with ``family``, its family and model numbers too,
    which tell apart processors that share a marketing name."""
    info = cpu_info()
    model = info.get("model name") or platform.processor() or platform.machine() or "unknown CPU"
    if family and "cpu family" in info:
        model += f" (family {info['cpu family']} model {info.get('model', '?')})"
    return model


def cores() -> int:
    """The cores this process may use (its affinity where the OS says, else the machine's count)."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
