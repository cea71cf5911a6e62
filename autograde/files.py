"""Reading a file that a student's kernel could have written: never through a link, a regular file
only, and never more than a cap. One function, so that every reader of grading's outputs (the class
report, the feedback packages) holds to the same rule."""

from __future__ import annotations

import os
import stat
from pathlib import Path


def read_capped(path: Path, cap: int) -> bytes | None:
    """The bytes of ``path``, or None: when it is a link, not a regular file, cannot be opened, or
    holds more than ``cap`` bytes (as it says, and as it reads)."""
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0))
    except OSError:
        return None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode) or st.st_size > cap:
            return None
        with os.fdopen(fd, "rb", closefd=False) as f:
            data = f.read(cap + 1)
    finally:
        os.close(fd)
    return data if len(data) <= cap else None
