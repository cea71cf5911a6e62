"""The LMSs a class download can come from, one plug-in module each (``base.Lms`` is the protocol).

Adding an LMS is one module here and one line in ``PLUGINS``: ``lms_layouts`` reads its download,
``intake`` names its students, ``lms_export`` writes its import file and ``lms_feedback`` its
feedback package, each by looping over ``PLUGINS`` in this order (which also breaks a tie when a
download's files follow two LMSs' namings equally).
"""

from __future__ import annotations

from .base import Lms
from .blackboard import BLACKBOARD
from .canvas import CANVAS
from .moodle import MOODLE

PLUGINS: tuple[Lms, ...] = (CANVAS, MOODLE, BLACKBOARD)
SYSTEMS = tuple(p.name for p in PLUGINS)
TITLE = {p.name: p.title for p in PLUGINS}
_BY_NAME = {p.name: p for p in PLUGINS}


def plugin(system: str) -> Lms:
    """The plug-in of the LMS tagged ``system`` ("canvas", "moodle", "blackboard")."""
    return _BY_NAME[system]
