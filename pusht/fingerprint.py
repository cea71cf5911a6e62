"""The platform fingerprint: what the floats of a run depend on, recorded beside its numbers.

Where every ``FLOAT_KEYS`` entry matches the one ``meta.yaml`` recorded, a run must reproduce it bit
for bit (``tests/test_reproduce.py``); where one differs, only within the recorded tolerance bands.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import torch


# MKL's conditional-numerical-reproducibility branches (mkl_cbwr_get's return codes).
_MKL_BRANCHES = {1: "AUTO", 2: "AUTO", 3: "COMPATIBLE", 4: "SSE2", 6: "SSSE3", 7: "SSE4_1",
                 8: "SSE4_2", 9: "AVX", 10: "AVX2", 11: "AVX512_MIC", 12: "AVX512",
                 13: "AVX512_MIC_E1", 14: "AVX512_E1"}

# The fingerprint keys that decide the floats of a run: where all of them match meta.yaml's, a run
# must reproduce it bit for bit; where one differs, only within the recorded tolerance bands.
FLOAT_KEYS = ("machine", "cpu_vendor", "cpu_model", "torch", "cpu_capability", "mkl", "mkl_path",
              "numpy", "pymunk")


def _mkl() -> tuple[str, str]:
    """(MKL version, the code path MKL takes here), read from the MKL linked into torch.

    The path is MKL's CNR branch: the one MKL_CBWR forces, else the one MKL picks for this CPU
    itself (on Intel CPUs an ISA such as AVX512; elsewhere "AUTO", plus "+zen" where MKL uses its
    AMD Zen kernels). Two hosts with the same torch and cpu_capability can differ here (issue 9).
    """
    import ctypes

    if not torch.backends.mkl.is_available():
        return "none", "none"
    try:
        lib = ctypes.CDLL(str(Path(torch.__file__).parent / "lib" / "libtorch_cpu.so"))
        buf = ctypes.create_string_buffer(256)
        lib.MKL_Get_Version_String(buf, len(buf))
        version = buf.value.decode().split(" for ")[0].replace("Intel(R) oneAPI Math Kernel Library ", "MKL ")
        branch = lib.mkl_serv_cbwr_get(1)                        # MKL_CBWR_BRANCH
        if branch in (1, 2):                                     # not forced: what MKL picks itself
            branch = lib.mkl_serv_cbwr_get_auto_branch()
        path = _MKL_BRANCHES.get(branch & 0xFFFF, str(branch))
        if branch & 0x10000:
            path += ",STRICT"
        if lib.mkl_serv_cpuiszen():
            path += "+zen"
        return version, path
    except (OSError, AttributeError):                          # no such library or symbol here
        return "unknown", "unknown"


def platform_fingerprint() -> dict:
    """What the floats of a run depend on, recorded beside its numbers (see FLOAT_KEYS).

    Cheap: reads /proc/cpuinfo and asks the MKL already loaded with torch, no computation.
    """
    import platform

    from .host import cpu_info, cpu_model

    info = cpu_info()
    model = cpu_model(family=True)
    mkl, mkl_path = _mkl()
    try:
        from importlib.metadata import version
        pymunk_version = version("pymunk")
    except Exception:  # noqa: BLE001  not installed as a distribution
        pymunk_version = "unknown"
    return {"torch": str(torch.__version__), "cpu_capability": torch.backends.cpu.get_cpu_capability(),
            "machine": platform.machine(), "python": platform.python_version(),
            "numpy": str(np.__version__), "pymunk": pymunk_version,
            "cpu_vendor": info.get("vendor_id", "unknown"), "cpu_model": model,
            "mkl": mkl, "mkl_path": mkl_path, "mkl_cbwr": os.environ.get("MKL_CBWR"),
            "aten_cpu_capability": os.environ.get("ATEN_CPU_CAPABILITY")}
