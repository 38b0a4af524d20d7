"""Studies that reproduce the papers: tilt-table validation, Ogawa et al., the Sacsayhuaman wall."""
from __future__ import annotations

import sys


def exit_status(rc: int) -> int:
    """A study's exit status: ``rc`` (its ``main``'s), or 1 where it would be 0 but a run of
    one of its sweeps failed (drystone.sweep.FAILED_RUNS; the report marks those results
    missing), with one line on standard error naming them."""
    from drystone import sweep

    if rc == 0 and sweep.FAILED_RUNS:
        n = len(sweep.FAILED_RUNS)
        print(f"error: {n} run(s) failed, their results are missing from the report: "
              + ", ".join(sweep.FAILED_RUNS[:5]) + (", ..." if n > 5 else "")
              + " (FAILED.txt and log.txt in each folder; run the study again to retry them)", file=sys.stderr)
        return 1
    return rc


def in_parallel(fn, items: list, n: int) -> list:
    """``fn(*item)`` for every item, ``n`` at a time, their results in order. Each call is one
    or more analyses (drystone/analyses/), whose runs are processes or Dask tasks of their
    own; with n > 1 the calls run in forked processes (an analysis draws its figures with
    matplotlib, which is not thread-safe), so ``fn`` is a module-level function and the items
    and results are picklable. n <= 1: one after the other, in this process."""
    if n <= 1 or len(items) <= 1:
        return [fn(*item) for item in items]
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    with ProcessPoolExecutor(min(n, len(items)), mp_context=multiprocessing.get_context("fork")) as pool:
        return list(pool.map(fn, *zip(*items)))
