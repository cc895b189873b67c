"""Parts of ``tools/bench.py``: plan, sessions, measured runs, paper numbers, report and plot."""
