"""Research code: ablations, experiments, A/B timings and profiling runs.

Not part of the installed package (``pyproject.toml`` packages ``engine``, ``widgets`` and
``app`` only) and never imported by them (``tests/test_boundaries.py``). Each script and
what it answered: ``research/README.md``. Run them from the repository root.
"""
