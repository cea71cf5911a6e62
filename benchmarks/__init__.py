"""Speed and memory figures, one script per question (docs/developers.md lists them).

Each is run as a module from the repository root, which puts the root on ``sys.path``::

    python -m benchmarks.bench_class --students 40

so that one benchmark imports another's helpers as ``from benchmarks.bench import host_description``
and the chapter runner as ``from scripts.chapter import execute``. ``make bench`` runs
``python -m benchmarks.bench``.
"""
