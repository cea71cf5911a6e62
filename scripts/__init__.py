"""The jobs behind ``make`` (chapter, release, meta, claims, colab-check), one module each.

Each is run as a module from the repository root, which puts the root on ``sys.path``::

    python -m scripts.chapter --smoke --out runs/chapter-smoke

so that a job, a benchmark or a test imports another's functions as ``from scripts.chapter import
execute``. The Makefile's targets run exactly these commands. Nothing here is installed with the
package (pyproject.toml lists the installed packages): these modules are the course's tools, not
the learner's library.
"""
