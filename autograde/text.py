"""Text that leaves the grader for a spreadsheet or a file: the shared helpers of the modules that
write grades, sheets and packages (``lms_export``, ``lms_feedback``, ``to_grade``, ``manual_grade``).

A student's name or answer is untrusted text: it reaches a cell here without control characters
and never read as a formula (``spreadsheet_text``); a file is replaced whole (``write_atomic``);
a CSV is UTF-8 with a byte order mark and CRLF line ends, as Excel, Canvas and Moodle read it.
"""

from __future__ import annotations

import csv
import io
import os
import re
import tempfile
from pathlib import Path

BOM = "\ufeff"
NEWLINE = "\r\n"
CONTROL = re.compile(r"[\x00-\x1f\x7f-\x9f\u2028\u2029]")
FORMULA = ("=", "+", "-", "@")          # a cell starting with one of these is read as a formula


def ident(value) -> str | None:
    """An identifier as text, or None when it is empty or carries control characters."""
    if value is None or isinstance(value, bool):
        return None
    text = str(value).strip()
    if not text or CONTROL.search(text):
        return None
    return text


def digits(text: str) -> bool:
    """ASCII digits only (``str.isdigit`` also takes '²' and other scripts' digits)."""
    return re.fullmatch(r"[0-9]+", text) is not None


def count(n: int) -> str:
    return f"{n} student{'' if n == 1 else 's'}"


def clean_text(text: str) -> str:
    """``text`` on one line: control characters and runs of white space made one space."""
    return " ".join(CONTROL.sub(" ", text).split())


def spreadsheet_text(text: str) -> str:
    """``text`` fit for a spreadsheet cell: no control characters, and never read as a formula."""
    text = clean_text(str(text))
    return "'" + text if text.startswith(FORMULA) else text


def num(x: float | None) -> str:
    """Points as both LMSs read them: '.' decimal point, at most 2 decimals, no exponent."""
    if x is None:
        return ""
    text = f"{round(float(x), 2):.2f}".rstrip("0").rstrip(".")
    return "0" if text in ("", "-0") else text


def write_csv(path: Path, header: list[str], rows: list[list[str]]) -> None:
    """``header`` and ``rows`` as a CSV at ``path`` (BOM, CRLF, minimal quoting), replaced whole."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator=NEWLINE, quoting=csv.QUOTE_MINIMAL)
    w.writerow(header)
    w.writerows(rows)
    write_atomic(path, (BOM + buf.getvalue()).encode("utf-8"))


def write_atomic(path: Path, data: bytes) -> None:
    """Replace ``path`` whole (a reader never sees half a file; a link there is replaced, not followed)."""
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
