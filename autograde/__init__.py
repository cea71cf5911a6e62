"""The course's grader, one idea per module. What it writes goes to the course folder
(``course.COURSE_DIR``, ``course/`` at the repository's root), never into this package.

The front is ``grade`` (``python -m autograde.grade``, ``grade_class``); ``grade``'s docstring says
which module does which step. ``classes`` holds the test classes (synthetic, hostile and honest
hand-ins) that the test suite and the benchmarks grade; nothing in the grader imports them.
"""
