"""The benchmark suite: every performance row of the docs, one entry point.

``python benchmarks/run.py`` runs the rows registered by the modules of this package
(:data:`suite.core.ROWS`), writes ``benchmarks/results/<machine>.json`` and, with
``--docs``, rewrites the tables of the pages that show them (docs/performance.md and the
pages it links). Each row states its goal and, where one exists, the peer it is timed
against in the same run; the first calls (imports, numba's compilation or cache load)
are timed apart from the steady state.
"""
