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
