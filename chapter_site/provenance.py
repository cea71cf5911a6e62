"""Where and from what a site build's numbers came: the commit and the host, one way."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def commit() -> str:
    """``git describe --always --dirty`` of the checkout ("unknown" outside one)."""
    try:
        return subprocess.run(["git", "describe", "--always", "--dirty"], cwd=ROOT, capture_output=True,
                              text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def host() -> str:
    """The CPU's model name, the number of cores and torch's version."""
    import torch

    from pusht.host import cpu_model

    return f"{cpu_model()}, {os.cpu_count()} cores, torch {torch.__version__}"
