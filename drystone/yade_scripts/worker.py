"""A YADE process that runs many resolved cases in turn:
``yade -n -x -j N drystone/yade_scripts/worker.py``, one request per line on stdin
(``{"spec": "/path/spec.json", "engine": "compiled"}``), each run exactly as
run_case.py runs it alone (its ``Driver``; the scene is rebuilt from ``O.reset()``), its
output on stdout followed by the line ``RUN_END``. drystone/simulate.py keeps one per process
that runs cases, so that YADE's start, drystone's imports and numba's cache load (~2.5 s of
a core) are paid once, not per run.

A run that fails ends the process as a run alone ends its own: a failed stability check
(failure.txt, exit 3) or an error (its traceback, exit 1); the parent then reports that run
exactly as it reports a run alone, and starts a new worker for the next. End of stdin: exit 0.
"""
from __future__ import annotations

import json
import os
import sys
import traceback
from pathlib import Path

from drystone.model.spec import load_spec
from drystone.simulate import RUN_END
from drystone.yade_scripts import run_case


def _reset_peak_memory() -> None:
    """Start the process's peak resident memory (``VmHWM``, run_info.json ``max_rss_mib``) again
    from its current size, so that each run reports its own peak (Linux; elsewhere a no-op)."""
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
    except OSError:
        pass


def serve(requests) -> None:
    for line in requests:
        if not line.strip():
            continue
        try:
            req = json.loads(line)
            spec = Path(req["spec"])
            _reset_peak_memory()
            run_case.Driver(load_spec(spec), spec.resolve().parent, req.get("engine", "compiled")).run()
        except BaseException as exc:  # noqa: BLE001 (SystemExit too): the run failed, this worker ends
            if isinstance(exc, SystemExit) and isinstance(exc.code, str):
                print(exc.code, flush=True)
            else:
                traceback.print_exc()
            sys.stdout.flush()
            sys.stderr.flush()
            os._exit(exc.code if isinstance(exc, SystemExit) and isinstance(exc.code, int) and exc.code else 1)
        sys.stderr.flush()
        print(RUN_END, flush=True)


if __name__ == "__main__":  # yade -x runs this file as __main__
    serve(sys.stdin)
