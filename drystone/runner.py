"""Run a case: validate, simulate, summarise (the layer above core and postprocess).

``run(case_path, overrides, out_dir=None, threads=1)`` is what ``python -m drystone run``,
``make run CASE=...`` and sweeps call: ``drystone.model.resolve`` checks everything and writes the
run specification, ``drystone.simulate`` runs YADE in a staging folder, and
``drystone.postprocess`` writes the summary and figures; the run is then swapped in.
"""
from __future__ import annotations

import json
import os
import shutil
import sys
import time
from pathlib import Path

import drystone
from drystone import atomic
from drystone.model import case as casemod
from drystone import paths, provenance
from drystone.model.resolve import AXES, TOWARDS, fingerprint, initial_relative_velocity, resolve  # noqa: F401
from drystone.simulate import FolderLock, RunError, check_replaceable, commit, simulate, staging_folder  # noqa: F401
from drystone.postprocess import plots
from drystone.postprocess import summary as summ
from drystone.tomlio import to_toml


def run(case_path, overrides=None, out_dir=None, threads=1, quiet=False, check_overlaps=True,
        engine="compiled", sweep_run=False) -> dict:
    """Validate, simulate and summarise one case; returns the summary dict.

    Nothing in the results folder changes until the new run is complete: the case, its
    geometry, records and time step are checked and the run is built in a staging folder
    beside it (``staging_folder``), then swapped in; a failed or interrupted run leaves the
    previous results as they were (and its log in the staging folder). summary.json is
    the last file written. The folder is locked for the run (``FolderLock``).
    ``check_overlaps=False`` skips the geometry's pairwise overlap test (sweeps have run
    it once for all their runs). ``engine``: ``compiled`` (default) or ``python``, the
    step engine of the project's law (``drystone.simulate.ENGINES``). ``out_dir`` (default
    results/<case name>) is refused unless it is new, empty or a run of this package
    (``simulate.check_replaceable``): a run never deletes what the package did not write.
    ``sweep_run``: the case name may be ``<sweep>/<run>`` (drystone/sweep.py)."""
    case_path = Path(case_path).expanduser().resolve()  # YADE runs in the repository root
    case = casemod.load(case_path, overrides or [], sweep_run=sweep_run)
    where = str(case_path)
    out = Path(out_dir).expanduser().resolve() if out_dir else paths.RESULTS / case["case"]["name"]
    check_replaceable(out, where)  # before anything is written
    with FolderLock(out):
        check_replaceable(out, where)  # what another run may have done meanwhile
        stage = staging_folder(out)
        shutil.rmtree(stage, ignore_errors=True)
        stage.mkdir(parents=True)
        t0 = time.time()
        try:
            spec = resolve(case, where, stage, check_overlaps=check_overlaps)
        except BaseException:  # a refusal leaves nothing behind
            shutil.rmtree(stage, ignore_errors=True)
            raise
        # a Spec is frozen: a new one with where the run will live (YADE writes beside its
        # spec.json) and how it was made
        spec = spec.replace(out_dir=str(out), provenance=provenance.collect(case_path, case, overrides or []))
        for e in spec["excitations"]:  # a site response that did not converge (recorded in the excitation too)
            if (e.get("site") or {}).get("warning"):
                print(f"{e['site']['warning']} ([[stages]] #{e.get('stage')})", file=sys.stderr, flush=True)
        if not quiet:
            print(f"[{spec['name']}] dt = {spec['dt']:.3g} s (critical {spec['dt_critical']:.3g} s), "
                  f"{len(spec['blocks'])} blocks, {spec['stages'][-1]['end']:.2f} s simulated, law {spec['law']}, "
                  f"{spec['stages'][-1]['end'] / spec['dt']:.0f} steps", flush=True)
            if not drystone.kernels_cached():
                print(f"[{spec['name']}] first run of the contact kernels since they changed: numba compiles them "
                      f"(1.5-2.5 min of a core, once; cached in {os.environ.get('NUMBA_CACHE_DIR', '.numba_cache/')})", flush=True)
        try:
            simulate(spec, stage, threads, quiet, where, engine)
            summary = summ.build(spec, stage)
            summary["wall_time_total_s"] = time.time() - t0
            figures = plots.standard(stage, summary)
            try:
                summ.write(summary, stage)  # last: the marker of a complete run
            except ValueError as exc:
                raise RunError(f"{where}: {exc}; {out} is unchanged") from None
            commit(stage, out)
        except OSError as exc:  # disk full, a read-only results folder
            raise RunError(f"{where}: could not write the run ({exc.strerror or exc}: {exc.filename or stage}); "
                           f"{out} is unchanged") from None
    if not quiet:
        print(f"[{spec['name']}] results in {out}: summary.json, histories.npz, "
              + ", ".join(f.name for f in figures), flush=True)
    return summary


def resummarise(out) -> dict:
    """Rebuild a finished run's summary.json from its spec, histories and run info with
    the current post-processing (e.g. the collapse onset rule); the figures are kept."""
    out = Path(out)
    old = json.loads((out / "summary.json").read_text())
    summary = summ.build(json.loads((out / "spec.json").read_text()), out)
    if "wall_time_total_s" in old:
        summary["wall_time_total_s"] = old["wall_time_total_s"]
    summ.write(summary, out)
    return summary


def run_dict(case_dict: dict, case_path: Path, overrides=None, **kw) -> dict:
    """Write a case dict as a TOML file and run it (used by tests, sweeps and bench)."""
    case_path = Path(case_path)
    atomic.write_text(case_path, to_toml(case_dict))
    return run(case_path, overrides, **kw)
