"""Sweeps: one base case run many times with different overrides, in parallel, resumable.

A sweep file (TOML) names a base case and the runs as tables of overrides (the
``--set key=value`` of ``python -m drystone run``):

    [sweep]
    name = "tilt_seeds"              # results/<name>/<run>/ (default: file stem)
    case = "../tilt_wall.toml"       # base case, relative to this file
    set = ["output.interval=0.05"]   # overrides common to every run (optional)

    [grid]                           # Cartesian product: one run per combination (optional)
    "case.geometry.seed" = [0, 1, 2, 3, 4]

    [[runs]]                         # and/or explicit runs (optional)
    name = "dem"
    set = ["contact.kn=5e7", "contact.kt=2.5e7", "contact.mu=0.7"]
    out = "dem_wall"                 # optional: results/<out>/ instead of results/<name>/<run>/;
                                     # no case.name is added (the run's own set may give one)

Every run is validated (case keys, geometry, time step) before any of them starts. A run
whose folder holds a ``summary.json`` made with the same overrides and the same inputs
(geometry, materials, stages: ``runner.fingerprint``) is finished and skipped, so an
interrupted sweep continues where it stopped (a skipped run's summary is rebuilt with
the current post-processing); a failed run leaves
``FAILED.txt`` (the error and its log's tail) and does not stop the others. The status of
every run is in ``results/<name>/sweep.json``; at the end a results table, one row per run
(its overrides, whether it collapsed and which stones, the largest residual in mm, a tilt's
onset angle: drystone.analyses.common.outcome, the one collapse criterion), is printed and
written to ``results/<name>/runs.csv``. A [grid] value that names a file (a record) names
its runs by the file's stem; runs whose names would repeat get ``-2``, ``-3``.

Backends: ``local`` (default: a process pool on this machine's cores) or ``dask`` (a Dask
distributed scheduler: ``--dask ADDRESS`` for an existing cluster, e.g. started by
dask-jobqueue on SLURM; ``--dask local`` starts a LocalCluster here). Workers of a remote
cluster must see this repository and ``results/`` at the same path (shared filesystem)
and have run ``make setup``.
"""
from __future__ import annotations

import itertools
import json
import os
import re
import threading
import time
import tomllib
import traceback
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path

from drystone import atomic
from drystone.model import case as casemod
from drystone import inputfiles, paths, tomlio
from drystone.simulate import is_run_folder

SWEEP_KEYS = {"name", "case", "set"}
RUN_KEYS = {"name", "set", "out"}


@dataclass
class Job:
    """One run of a sweep: base case file, overrides, output folder."""

    name: str
    case: str
    overrides: list[str]
    out_dir: str
    threads: int = 1
    params: dict = field(default_factory=dict)  # the swept values, for tables


def _is_path(value) -> bool:
    """A swept value that names a file (a record, a geometry): a string with a folder
    separator or ending in a file extension (``.txt``; not a number such as ``0.976``)."""
    return isinstance(value, str) and bool("/" in value or "\\" in value
                                           or re.search(r"\.[A-Za-z][A-Za-z0-9]*$", value))


def _run_name(params: dict) -> str:
    """A [grid] run's name: ``<last key part>_<value>`` joined by ``-``; a value that names
    a file gives its stem (``common.safe_name``), e.g. ``record_farfield_01a-pga_g_0.8``."""
    from drystone.analyses.common import safe_name

    parts = [f"{k.split('.')[-1]}_{safe_name(v) if _is_path(v) else v}" for k, v in params.items()]
    return re.sub(r"[^A-Za-z0-9_.+-]", "", "-".join(parts)) or "run"


def _unique(names: list[str]) -> list[str]:
    """``names`` with the second, third ... of equal ones suffixed ``-2``, ``-3`` (two files
    of one stem in different folders), in order, each name unique among them all."""
    out, seen = [], set(names)
    count: dict[str, int] = {}
    for n in names:
        count[n] = count.get(n, 0) + 1
        if count[n] == 1:
            out.append(n)
            continue
        k = count[n]
        while f"{n}-{k}" in seen:
            k += 1
        seen.add(f"{n}-{k}")
        out.append(f"{n}-{k}")
    return out


def _overrides(value, where: str) -> list[str]:
    """A ``set`` list: strings of the form key=value."""
    if not isinstance(value, list) or not all(isinstance(x, str) for x in value):
        raise casemod.CaseError(f"{where}: 'set' must be a list of \"key=value\" strings, got {value!r}")
    bad = [x for x in value if "=" not in x]
    if bad:
        raise casemod.CaseError(f"{where}: override {bad[0]!r} in 'set' is not of the form key=value")
    return list(value)


def _check_outputs(where: str, root: Path, jobs: list[Job]) -> None:
    """Every run writes its own folder: no two runs share one, and no run's folder holds,
    or lies inside, another run's folder or the sweep's own (``results/<sweep>``, where
    sweep.json lives); otherwise each resume would overwrite or delete the other."""
    folders = [(f"run {j.name!r}", Path(j.out_dir)) for j in jobs]
    for k, (who, d) in enumerate(folders):
        if d == root or d in root.parents:
            raise casemod.CaseError(f"{where}: {who} would write into {d}, which is or holds the sweep's own "
                                    f"folder {root} (sweep.json): give it another 'out'")
        for other, e in folders[k + 1:]:
            if d == e:
                raise casemod.CaseError(f"{where}: {who} and {other} would both write into {d}: give each its "
                                        "own 'out'")
            if d in e.parents or e in d.parents:
                (inner, a), (outer, b) = ((other, e), (who, d)) if d in e.parents else ((who, d), (other, e))
                raise casemod.CaseError(f"{where}: the folder of {inner} ({a}) lies inside that of {outer} ({b}): "
                                        "a run replaces its folder whole; give them separate 'out' folders")


def load(path, results: Path | None = None, threads: int = 1) -> tuple[str, list[Job]]:
    """Read a sweep file; returns (sweep name, jobs). Raises CaseError naming the file and
    key for unknown keys, a missing base case, bad names, duplicate run names, runs whose
    folders collide or an empty sweep."""
    p = Path(path)
    where = str(p)
    raw = inputfiles.load_toml(p, casemod.CaseError, "sweep file")
    unknown = sorted(set(raw) - {"sweep", "grid", "runs"})
    if unknown:
        raise casemod.CaseError(f"{where}: unknown table(s) {unknown}; allowed: sweep, grid, runs")
    sw, grid, given = raw.get("sweep", {}), raw.get("grid", {}), raw.get("runs", [])
    for key, value, kind in (("[sweep]", sw, dict), ("[grid]", grid, dict), ("[[runs]]", given, list)):
        if not isinstance(value, kind):
            raise casemod.CaseError(f"{where}: {key} must be a {'table' if kind is dict else 'list of tables'}, "
                                    f"got {value!r}")
    bad = sorted(set(sw) - SWEEP_KEYS)
    if bad:
        raise casemod.CaseError(f"{where}: [sweep]: unknown key(s) {bad}; allowed: {sorted(SWEEP_KEYS)}")
    if not isinstance(sw.get("case"), str):
        raise casemod.CaseError(f"{where}: [sweep]: 'case' (the base case file, relative to this file) is required "
                                f"and must be a string, got {sw.get('case')!r}")
    base = (p.parent / sw["case"]).resolve()
    if not base.is_file():
        raise casemod.CaseError(f"{where}: [sweep] 'case': base case {base} not found")
    name = sw.get("name", p.stem)
    casemod.check_name(f"{where}: [sweep] 'name'", name)
    common = _overrides(sw.get("set", []), f"{where}: [sweep]")
    root = (results or paths.RESULTS).resolve() / name
    runs: list[tuple[str, list[str], dict]] = []
    for key, values in grid.items():
        if not isinstance(values, list) or not values:
            raise casemod.CaseError(f"{where}: [grid] '{key}' must be a non-empty list of values")
    if grid:
        keys = list(grid)
        combos = [dict(zip(keys, combo)) for combo in itertools.product(*(grid[k] for k in keys))]
        for n, params in zip(_unique([_run_name(c) for c in combos]), combos):
            runs.append((n, [f"{k}={tomlio.value(v)}" for k, v in params.items()], params, None))
    for k, r in enumerate(given):
        bad = sorted(set(r) - RUN_KEYS) if isinstance(r, dict) else None
        if bad is None or bad or "name" not in r:
            raise casemod.CaseError(f"{where}: [[runs]] #{k + 1}: keys must be 'name' and optional 'set', 'out' "
                                    f"(got {sorted(r) if isinstance(r, dict) else r!r})")
        casemod.check_name(f"{where}: [[runs]] #{k + 1} 'name'", r["name"])
        out = r.get("out")
        if out is not None and not (isinstance(out, str) and out.strip() and not Path(out).is_absolute()
                                    and ".." not in Path(out).parts):
            raise casemod.CaseError(f"{where}: [[runs]] #{k + 1}: 'out' must be a folder relative to the results "
                                    f"folder (no '..'), got {out!r}")
        sets = _overrides(r.get("set", []), f"{where}: [[runs]] #{k + 1}")
        params = dict(item.split("=", 1) for item in sets)
        runs.append((r["name"], sets, params, out))
    if not runs:
        raise casemod.CaseError(f"{where}: the sweep has no runs (add [grid] or [[runs]])")
    for n, *_ in runs:  # generated from [grid]: the same rule
        casemod.check_name(f"{where}: run name", n)
    names = [r[0] for r in runs]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise casemod.CaseError(f"{where}: duplicate run name(s) {dup}")
    jobs = [Job(n, str(base), common + over + ([] if out else [f"case.name={name}/{n}"]),
                str(root.parent / out if out else root / n), threads, params)
            for n, over, params, out in runs]
    _check_outputs(where, root, jobs)
    return name, jobs


def validate(jobs: list[Job]) -> dict[str, str]:
    """Check every run before anything runs: case keys and values, overrides, geometry
    (generated or read), stages, records and time step (``runner.resolve`` into a scratch
    folder). Raises CaseError or GeometryError naming the run. Returns each run's
    fingerprint (``runner.fingerprint``: what it would simulate)."""
    import tempfile

    from drystone import runner
    from drystone.geometry.blockfile import GeometryError

    prints = {}
    checked = set()  # geometries whose pairwise overlap test has run (once per geometry)
    with tempfile.TemporaryDirectory() as tmp:
        for j in jobs:
            try:
                case = casemod.load(j.case, j.overrides, sweep_run=True)
                geo = json.dumps(case["case"]["geometry"], sort_keys=True)
                spec = runner.resolve(case, j.case, Path(tmp), check_overlaps=geo not in checked)
                checked.add(geo)
                runner.check_replaceable(Path(j.out_dir))
            except (casemod.CaseError, GeometryError, runner.RunError) as exc:
                raise casemod.CaseError(f"run {j.name!r}: {exc}") from None
            prints[j.name] = runner.fingerprint(spec)
    return prints


def finished(job: Job, fingerprint: str | None = None) -> bool:
    """True when the job's folder holds a complete run made with the same overrides and,
    when ``fingerprint`` is given, simulating the same thing (so a run made before a change
    of the geometry generator, a record or a default is run again, not reused)."""
    from drystone import runner

    out = Path(job.out_dir)
    s = out / "summary.json"
    if not s.is_file():
        return False
    try:
        done = json.loads(s.read_text())["inputs"]["provenance"]["overrides"]
        if done != job.overrides or not _histories_intact(out):
            return False
        if fingerprint is None:
            return True
        spec = json.loads((out / "spec.json").read_text())
        spec["out_dir"] = str(out)  # the folder may have moved since (a worktree, a copied results/)
        return runner.fingerprint(spec) == fingerprint
    except (KeyError, TypeError, ValueError, OSError):  # unreadable, or not the dict a run writes
        return False


def _histories_intact(out: Path) -> bool:
    """histories.npz and run_info.json are there and readable (every member's CRC checked)."""
    import zipfile
    import zlib

    try:
        json.loads((out / "run_info.json").read_text())
        with zipfile.ZipFile(out / "histories.npz") as z:
            return z.testzip() is None and "t.npy" in z.namelist()
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, zlib.error):
        return False


def _resummarise(job: Job, status: dict) -> None:
    """A skipped run's summary is rebuilt with the current post-processing (seconds), so
    that its numbers follow the code, not the code of the day it ran."""
    from drystone import runner

    try:
        s = runner.resummarise(job.out_dir)
        status["collapse_angle_deg"] = s.get("collapse_angle_deg")
    except Exception as exc:  # noqa: BLE001 - the run itself is complete; say so and go on
        status["resummarise_error"] = f"{type(exc).__name__}: {exc}"


def run_job(job: Job) -> dict:
    """Run one job (in a pool worker, or in the sweep's process for one worker); never raises but
    on an interrupt: returns a status dict."""
    global _IN_RUN
    from drystone import runner

    if _PARENT_PID is not None and os.getppid() != _PARENT_PID:  # the sweep is gone: start nothing
        os._exit(143)
    out = Path(job.out_dir)
    t0 = time.time()
    _IN_RUN = True
    try:
        # the geometry's overlap test ran once for the whole sweep (validate)
        s = runner.run(job.case, job.overrides, out_dir=out, threads=job.threads, quiet=True, check_overlaps=False,
                       sweep_run=True)
        (out / "FAILED.txt").unlink(missing_ok=True)  # an earlier failure of this run
        return {"name": job.name, "status": "done", "wall_s": time.time() - t0,
                "collapse_angle_deg": s.get("collapse_angle_deg")}
    except Exception as exc:  # noqa: BLE001 - one failed run must not stop the sweep
        msg = f"{type(exc).__name__}: {exc}\n\n{traceback.format_exc()}"
        out.mkdir(parents=True, exist_ok=True)
        atomic.write_text(out / "FAILED.txt", msg)
        return {"name": job.name, "status": "failed", "wall_s": time.time() - t0, "error": str(exc)[-2000:],
                "log": str(runner.staging_folder(out) / "log.txt")}
    except BaseException:  # SIGTERM from the sweep (_worker_init): the run has killed its YADE
        if threading.current_thread() is threading.main_thread() and _IN_RUN and os.getpid() != _MAIN_PID:
            os._exit(143)  # a pool worker: end here, do not take the next queued run
        raise
    finally:
        _IN_RUN = False


def _progress_line(job: Job) -> str:
    """The last progress line of a running job's YADE log (simulated time and percent)."""
    from drystone import runner

    log = runner.staging_folder(Path(job.out_dir)) / "log.txt"  # a run is built there
    try:
        lines = [ln for ln in log.read_text(errors="replace").splitlines() if "%)" in ln]
    except OSError:
        return f"{job.name}: starting"
    if not lines:
        return f"{job.name}: starting"
    m = re.search(r"t =\s*([\d.]+) /\s*([\d.]+) s \(\s*([\d.]+) %\).*?tilt\s+([-\d.]+) deg", lines[-1])
    return f"{job.name}: {m.group(3)} % (t {m.group(1)} s, tilt {m.group(4)} deg)" if m else f"{job.name}: running"


class _Heartbeat(threading.Thread):
    """Prints the progress of the running jobs every ``every`` s."""

    def __init__(self, name, jobs, every=60.0):
        super().__init__(daemon=True)
        self.sweep, self.jobs, self.every = name, jobs, every
        self.running: set[str] = set()
        self.stop = threading.Event()

    def run(self):
        while not self.stop.wait(self.every):
            live = [j for j in self.jobs if j.name in self.running]
            if live:
                print(f"[{self.sweep}] running: " + "; ".join(_progress_line(j) for j in live), flush=True)


#: the runs (folders) that failed in this process's sweeps: a study that ran them exits non-zero
#: (drystone.studies.exit_status), whatever its report could still say
FAILED_RUNS: list[str] = []


def run(path, workers: int | None = None, backend: str = "local", dask_address: str | None = None,
        threads: int = 1, only: list[str] | None = None, results: Path | None = None,
        heartbeat_s: float = 60.0) -> dict:
    """Run (or continue) the sweep in ``path``; returns the status dict written to
    ``results/<name>/sweep.json``."""
    name, jobs = load(path, results, threads)
    if only:
        missing = sorted(set(only) - {j.name for j in jobs})
        if missing:
            raise casemod.CaseError(f"{path}: no run(s) named {missing}; runs: {[j.name for j in jobs]}")
        jobs = [j for j in jobs if j.name in only]
    root = (results or paths.RESULTS).resolve() / name
    if is_run_folder(root):
        raise casemod.CaseError(f"{path}: {root} is the folder of a run (a case named {name!r}), not of a sweep: "
                                "give the sweep another [sweep] 'name' (a case and a sweep must not share a name)")
    prints = validate(jobs)
    root.mkdir(parents=True, exist_ok=True)
    status = {j.name: {"name": j.name, "status": "pending", "params": j.params, "out_dir": j.out_dir} for j in jobs}
    todo = []
    for j in jobs:
        if finished(j, prints[j.name]):
            status[j.name]["status"] = "skipped (finished earlier)"
            _resummarise(j, status[j.name])
        else:
            todo.append(j)
    _write_status(root, name, path, status)  # the folder is a sweep's from now on (a case may not replace it)
    workers = max(1, min(workers or os.cpu_count() or 1, len(todo) or 1))
    print(f"[{name}] {len(jobs)} runs: {len(jobs) - len(todo)} finished earlier, {len(todo)} to run on "
          f"{workers} {'Dask' if backend == 'dask' else 'local'} worker(s); results in {root}", flush=True)
    beat = _Heartbeat(name, todo, heartbeat_s)
    beat.running = {j.name for j in todo[:workers]}
    beat.start()
    t0 = time.time()
    done = 0
    interrupted = False
    results = _execute(todo, workers, backend, dask_address)
    try:
        for res in results:
            done += 1
            status[res["name"]].update(res)
            beat.running.discard(res["name"])
            waiting = [j.name for j in todo if status[j.name]["status"] == "pending" and j.name not in beat.running]
            if waiting:
                beat.running.add(waiting[0])
            el = time.time() - t0
            eta = el / done * (len(todo) - done)
            extra = f"  log {res['log']}: {res['error'].splitlines()[0][:200]}" if res["status"] == "failed" else ""
            print(f"[{name}] {done}/{len(todo)} {res['name']}: {res['status']} in {res['wall_s']:.0f} s "
                  f"(elapsed {el:.0f} s, ETA {eta:.0f} s){extra}", flush=True)
            _write_status(root, name, path, status)
    except KeyboardInterrupt:
        interrupted = True
        print(f"\n[{name}] interrupted: stopping the running runs (their results folders are unchanged)", flush=True)
    finally:
        results.close()  # stops the workers and their YADE processes (_execute)
        beat.stop.set()
        for n in beat.running:
            if status[n]["status"] == "pending":
                status[n]["status"] = "interrupted"
        _write_status(root, name, path, status)
    failed = [n for n, s in status.items() if s["status"] == "failed"]
    FAILED_RUNS.extend(str(root / n) for n in failed if str(root / n) not in FAILED_RUNS)
    if failed:
        print(f"[{name}] {len(failed)} run(s) failed: {failed}; see FAILED.txt and log.txt in their folders",
              flush=True)
    results_table(root, name, jobs, status)
    if interrupted:
        n_done = sum(s["status"] == "done" for s in status.values())
        print(f"[{name}] {n_done} run(s) finished before the interrupt; status in {root / 'sweep.json'}", flush=True)
    return {"name": name, "root": str(root), "runs": status, "failed": failed, "interrupted": interrupted}


#: the columns of a sweep's results table (results/<sweep>/runs.csv)
#: the widest cell of the printed results table (characters)
PRINT_CELL = 60
TABLE_COLUMNS = ("run", "overrides", "status", "collapsed", "collapsed_stones", "largest_residual_mm",
                 "onset_deg")


def table_rows(jobs: list[Job], status: dict) -> list[dict]:
    """One row per run (``TABLE_COLUMNS``), read from its folder through the one collapse
    criterion and reduction (drystone.analyses.common.outcome): whether it collapsed and
    which stones (ids joined by spaces), the largest residual displacement of the stones
    still in the model (mm) and, for a run with a tilt stage, the onset angle (deg); a run
    not finished has its status and empty values."""
    from drystone.analyses.common import outcome

    rows = []
    for j in jobs:
        st = (status.get(j.name) or {}).get("status", "pending")
        row = {"run": j.name, "overrides": "; ".join(f"{k}={v}" for k, v in j.params.items()), "status": st,
               "collapsed": "", "collapsed_stones": "", "largest_residual_mm": "", "onset_deg": ""}
        if st == "done" or st.startswith("skipped"):
            o = outcome(j.out_dir)
            if o["status"] != "done":
                row["status"] = f"failed: {o.get('error', '')}"[:120]
            else:
                res, onset = o.get("largest_residual_m"), o.get("onset_deg")
                row.update(collapsed="yes" if o["collapsed"] else "no",
                           collapsed_stones=" ".join(str(b) for b in o["collapsed_stones"]),
                           largest_residual_mm="" if res is None else f"{1e3 * res:.4g}",
                           onset_deg="" if onset is None else f"{onset:.4g}")
        rows.append(row)
    return rows


def results_table(root: Path, name: str, jobs: list[Job], status: dict) -> Path:
    """Write ``root``/runs.csv (``table_rows``) and print it as a table; returns its path."""
    import csv
    import io

    rows = table_rows(jobs, status)
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=TABLE_COLUMNS, lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    path = atomic.write_text(Path(root) / "runs.csv", buf.getvalue())
    head = {"run": "run", "overrides": "overrides", "status": "status", "collapsed": "collapsed",
            "collapsed_stones": "stones", "largest_residual_mm": "residual mm", "onset_deg": "onset deg"}
    # printed cells are clipped to PRINT_CELL characters (an analysis's override can be a whole
    # stage list); runs.csv keeps them whole
    shown = [{c: r[c] if len(r[c]) <= PRINT_CELL else r[c][:PRINT_CELL - 3] + "..." for c in TABLE_COLUMNS}
             for r in [head] + rows]
    width = {c: max(len(r[c]) for r in shown) for c in TABLE_COLUMNS}
    print(f"[{name}] results ({path}):", flush=True)
    for r in shown:
        print("  " + "  ".join(r[c].ljust(width[c]) for c in TABLE_COLUMNS).rstrip(), flush=True)
    return path


def _write_status(root: Path, name: str, path, status: dict) -> None:
    atomic.write_text(root / "sweep.json", json.dumps({"sweep": name, "file": str(Path(path).resolve()),
                                                       "runs": list(status.values())}, indent=1, default=str))


def _execute(jobs: list[Job], workers: int, backend: str, address: str | None):
    """Yield each job's status dict as it completes."""
    if not jobs:
        return
    if backend == "local" and workers == 1:
        # one at a time: in this process, whose YADE worker (drystone.simulate) makes every run in turn
        for j in jobs:
            yield run_job(j)
    elif backend == "local":
        ex = ProcessPoolExecutor(max_workers=workers, initializer=_worker_init, initargs=(os.getpid(),))
        futures = [ex.submit(run_job, j) for j in jobs]
        complete = False
        try:
            for f in as_completed(futures):
                yield f.result()
            complete = True
        finally:  # Ctrl-C or an error: nothing queued starts, running workers stop
            if not complete:
                for f in futures:
                    f.cancel()
                for proc in list((ex._processes or {}).values()):
                    if proc.is_alive():
                        proc.terminate()  # SIGTERM: the worker kills its YADE (runner._simulate)
            ex.shutdown(wait=True, cancel_futures=True)
    elif backend == "dask":
        yield from _execute_dask(jobs, workers, address)
    else:
        raise ValueError(f"unknown sweep backend {backend!r}: local or dask")


_IN_RUN = False  # a pool worker is inside run_job
_PARENT_PID = None  # a pool worker: the sweep's process (_worker_init)
_MAIN_PID = os.getpid()  # the process that imported this module first (pool workers fork or spawn later)


def _worker_init(parent: int | None = None):
    """Pool workers leave Ctrl-C to the sweep's main process. SIGTERM ends a worker: inside
    a run it raises SystemExit, so the run kills its YADE process on the way out (and
    run_job then ends the worker); between runs it exits at once. A worker gets SIGTERM
    when the sweep's process dies, even by kill -9 (``simulate.die_with_parent``), and
    takes no further run once its parent is gone (``run_job``)."""
    import signal

    from drystone.simulate import die_with_parent

    global _PARENT_PID

    def _exit(signum, frame):
        if _IN_RUN:
            raise SystemExit(128 + signum)
        os._exit(128 + signum)

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, _exit)
    _PARENT_PID = parent
    die_with_parent(signal.SIGTERM)
    if parent is not None and os.getppid() != parent:  # the sweep died before the line above
        os._exit(128 + signal.SIGTERM)


def _execute_dask(jobs: list[Job], workers: int, address: str | None):
    try:
        from dask.distributed import Client, LocalCluster, as_completed as dask_completed
    except ImportError as exc:  # pragma: no cover - installed by make setup
        raise RuntimeError("the dask backend needs dask.distributed (make setup installs it)") from exc
    cluster = None
    if address in (None, "local"):
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0")
        client = Client(cluster)
    else:
        client = Client(address)
    try:
        # one task per worker slot; each task thread makes its runs in a YADE process of its own, kept between tasks
        futures = [client.submit(run_job, j, pure=False, key=f"drystone-{Path(j.out_dir).parent.name}-{j.name}")
                   for j in jobs]
        for f in dask_completed(futures):
            yield f.result()
    finally:
        client.cancel(futures)  # Ctrl-C: nothing more is started
        client.close()
        if cluster is not None:
            cluster.close()
