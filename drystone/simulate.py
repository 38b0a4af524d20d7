"""Simulate: run YADE on a spec.json in a staging folder (drystone/yade_scripts/run_case.py
writes histories.npz and run_info.json beside it), with the results folder locked; a
complete run is swapped in by ``commit``. Nothing here reads histories or summarises.
"""
from __future__ import annotations

import atexit
import json
import os
import shutil
import subprocess
import sys
import threading
from pathlib import Path

from drystone import paths
from drystone.model.spec import spec_dict


class RunError(RuntimeError):
    """A run that could not be prepared or did not complete."""


#: step engines (drystone/yade_scripts/run_case.py): compiled (default) or python
ENGINES = ("compiled", "python")


def _yade_command(spec_path: Path, threads: int, engine: str = "compiled") -> list[str]:
    yade = shutil.which("yade") or "/usr/bin/yade"
    script = paths.PACKAGE / "yade_scripts" / "run_case.py"
    return [sys.executable, yade, "-n", "-x", "-j", str(threads), str(script), str(spec_path), engine]


#: the line a worker (drystone/yade_scripts/worker.py) ends a completed run's output with
RUN_END = "\x1edrystone-run-end"

NOISE = ("Welcome to Yade", "TCP python prompt", "XMLRPC info provider", "Running script", "Using python version")


class FolderLock:
    """Exclusive lock on a results folder for the length of a run (``fcntl.flock`` on a
    hidden file beside it, released by the kernel if the process dies). A second run into
    the same folder is refused with RunError naming the holder's pid. The lock file is
    removed when the lock is released (a lock taken on a file that another holder has
    just removed is taken again on a new one)."""

    def __init__(self, out: Path):
        self.path = out.parent / f".{out.name}.lock"
        self.fd = None

    def __enter__(self):
        import fcntl

        self.path.parent.mkdir(parents=True, exist_ok=True)
        while True:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                holder = os.read(fd, 64).decode(errors="replace").strip() or "?"
                os.close(fd)
                raise RunError(f"{self.path.parent / self.path.name[1:-5]}: another run (pid {holder}) is writing "
                               f"this results folder; wait for it or use another --out") from None
            try:
                same = os.fstat(fd).st_ino == os.stat(self.path).st_ino
            except FileNotFoundError:
                same = False
            if same:
                break
            os.close(fd)  # the previous holder removed the file we locked: lock the new one
        os.ftruncate(fd, 0)
        os.write(fd, str(os.getpid()).encode())
        self.fd = fd
        return self

    def __exit__(self, *exc):
        try:
            self.path.unlink()  # still holding the lock: no other process holds this file
        except FileNotFoundError:
            pass
        os.close(self.fd)


#: the names a run's folder is recognised by: spec.json with the spec's format tag
#: (drystone/model/spec.py; version-1 specs had none: then run_info.json beside it), or a
#: sweep's note of a failed run alone
RUN_MARKER, FAILED_NOTE = "spec.json", "FAILED.txt"


def is_run_folder(folder: Path) -> bool:
    """True when ``folder`` holds a run this package wrote (``RUN_MARKER``)."""
    from drystone.model.spec import SPEC_FORMAT

    folder = Path(folder)
    try:
        spec = json.loads((folder / RUN_MARKER).read_text())
    except (OSError, ValueError, RecursionError):
        return False
    if not isinstance(spec, dict):
        return False
    return spec.get("format") == SPEC_FORMAT or ("format" not in spec and (folder / "run_info.json").is_file())


def check_replaceable(out: Path, where: str = "") -> None:
    """Refuse (RunError naming the folder) to write a run into ``out`` unless the package
    may replace what is there: nothing, an empty folder, a run of its own
    (``is_run_folder``) or only a sweep's ``FAILED.txt``. Anything else, a user's folder,
    a sweep's folder, a file, is never deleted."""
    out = Path(out)
    prefix = f"{where}: " if where else ""
    if not out.exists() and not out.is_symlink():
        return
    if not out.is_dir() or out.is_symlink():
        raise RunError(f"{prefix}{out} exists and is not a folder; choose another --out (or case name)")
    try:
        entries = sorted(p.name for p in out.iterdir())
    except OSError as exc:
        raise RunError(f"{prefix}{out}: cannot read the folder: {exc.strerror or exc}") from None
    if not entries or entries == [FAILED_NOTE] or is_run_folder(out):
        return
    what = ("a sweep's folder (sweep.json)" if "sweep.json" in entries
            else "a folder this package did not write (" + ", ".join(entries[:3]) + (", ..." if len(entries) > 3 else "") + ")")
    raise RunError(f"{prefix}{out} is {what}: a run replaces its results folder whole, so it writes only into a new "
                   f"or empty folder or one of its own runs; choose another --out (or case name)")


def staging_folder(out: Path) -> Path:
    """Where a run is built before it replaces ``out`` (same filesystem: an atomic rename)."""
    return out.parent / f".{out.name}.partial"


def commit(stage: Path, out: Path) -> None:
    """Replace ``out`` by the complete run in ``stage``; the old run is removed only after
    the new one is in place."""
    old = out.parent / f".{out.name}.old"
    shutil.rmtree(old, ignore_errors=True)
    if out.exists():
        os.replace(out, old)
    os.replace(stage, out)
    shutil.rmtree(old, ignore_errors=True)


def _prctl():
    """libc's prctl, or None where there is none (looked up before any fork: a child of a
    threaded process must not load libraries)."""
    import ctypes

    try:
        return ctypes.CDLL(None, use_errno=True).prctl
    except (OSError, AttributeError):
        return None


_PRCTL = _prctl()


def die_with_parent(sig: int = 9) -> None:
    """Ask the kernel (Linux ``prctl(PR_SET_PDEATHSIG)``) to send ``sig`` to this process
    when its parent dies, even by kill -9, so that no YADE process or sweep worker outlives
    the process that started it. A no-op where the call is not available."""
    if _PRCTL is not None:
        _PRCTL(1, int(sig), 0, 0, 0)  # PR_SET_PDEATHSIG = 1


#: a YADE process per thread (and thread count of its runs) that runs cases in turn
#: (drystone/yade_scripts/worker.py), keyed by (threads, the thread's ident): YADE's start,
#: drystone's imports and numba's cache load paid once, not per run; ``DRYSTONE_YADE_WORKER=0``
#: runs each case in a YADE process of its own
_WORKERS: dict = {}
#: a worker's YADE process grows by its runs (~1.6 MB per short run of a two-part stone, what
#: ``O.reset()`` keeps): it is replaced by a new one after this many runs or this growth (MiB)
#: over its size after its first run
RUNS_PER_WORKER, GROWTH_PER_WORKER_MIB = 100, 1024.0
#: environment variables that change while a process runs cases and that no run reads
#: (pytest's note of the running test): a worker is kept when only they changed
_ENV_IGNORED = ("PYTEST_CURRENT_TEST",)


def _env_key(env: dict) -> dict:
    return {k: v for k, v in env.items() if k not in _ENV_IGNORED}


class _Worker:
    """One YADE process serving runs (drystone/yade_scripts/worker.py), started by one thread of
    this process with this environment (another thread, a changed environment or a forked child
    gets another)."""

    def __init__(self, threads: int, env: dict):
        yade = shutil.which("yade") or "/usr/bin/yade"
        script = paths.PACKAGE / "yade_scripts" / "worker.py"
        self.env, self.root = _env_key(env), paths.ROOT
        # the thread that starts it: the kernel kills the process when that thread ends (die_with_parent)
        self.thread = threading.current_thread()
        self.key = (threads, self.thread.ident)
        self.runs, self.first_mib = 0, None  # runs made; resident size after the first (MiB)
        self.proc = subprocess.Popen([sys.executable, yade, "-n", "-x", "-j", str(threads), str(script)],
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                     env=env, cwd=paths.ROOT, start_new_session=True, preexec_fn=die_with_parent)

    def usable(self, env: dict) -> bool:
        return (self.env == _env_key(env) and self.root == paths.ROOT and self.proc.poll() is None
                and self.runs < RUNS_PER_WORKER and self.growth_mib() < GROWTH_PER_WORKER_MIB)

    def resident_mib(self) -> float | None:
        """The YADE process's resident size (MiB; Linux's ``VmRSS``, else None)."""
        try:
            with open(f"/proc/{self.proc.pid}/status") as f:
                return next(float(x.split()[1]) for x in f if x.startswith("VmRSS:")) / 1024.0
        except (OSError, StopIteration, ValueError, IndexError):
            return None

    def completed(self) -> None:
        """A run was completed by this worker."""
        self.runs += 1
        if self.runs == 1:
            self.first_mib = self.resident_mib()

    def growth_mib(self) -> float:
        now = self.resident_mib()
        return 0.0 if now is None or self.first_mib is None else now - self.first_mib

    def end(self) -> None:
        """Kill the process (a run that failed or was interrupted, a worker no longer usable)."""
        self.proc.kill()
        self.proc.wait()
        self.proc.stdin.close()
        self.proc.stdout.close()


def end_workers() -> None:
    """End this process's workers (at exit, or where a process is done with runs for a while)."""
    while _WORKERS:
        _WORKERS.popitem()[1].end()


def _forget_workers() -> None:
    """In a forked child: the parent's workers are the parent's (the child starts its own);
    close the child's copies of their pipes."""
    for w in _WORKERS.values():
        w.proc.returncode = 0  # not this process's child: never waited for here
        w.proc.stdin.close()  # nothing buffered: the parent writes a request whole
        w.proc.stdout.close()
    _WORKERS.clear()


atexit.register(end_workers)
os.register_at_fork(after_in_child=_forget_workers)


def own_worker(threads: int = 1) -> _Worker | None:
    """The calling thread's worker for ``threads``, if it has one."""
    return _WORKERS.get((threads, threading.get_ident()))


def _drop_ended() -> None:
    """Forget the workers of threads that have ended (the kernel has killed their processes)."""
    for w in [w for w in list(_WORKERS.values()) if not w.thread.is_alive()]:
        if _WORKERS.pop(w.key, None) is not None:
            w.end()


def _worker(threads: int, env: dict) -> _Worker | None:
    """The calling thread's worker for ``threads`` (started if needed), or None where runs get a
    process each (switched off). Each thread has its own: a worker dies with the thread that
    started it (``die_with_parent``), and a thread runs one case at a time (a Dask worker's
    task threads, which live as long as their worker, each keep one across their tasks).
    The workers of threads that have ended are dropped first (``_drop_ended``)."""
    if os.environ.get("DRYSTONE_YADE_WORKER", "1") == "0":
        return None
    _drop_ended()
    w = own_worker(threads)
    if w is not None and not w.usable(env):
        _WORKERS.pop(w.key, None)
        w.end()
        w = None
    if w is None:
        w = _Worker(threads, env)
        _WORKERS[w.key] = w
    return w


def _simulate(spec_path: Path, threads: int, quiet: bool, engine: str = "compiled") -> int:
    """Run YADE on ``spec_path`` (its log to log.txt beside it); returns YADE's exit code.
    YADE runs in its own session, so a Ctrl-C reaches only this process, which then
    kills YADE (no orphan) and re-raises; if this process is killed outright (kill -9),
    the kernel kills YADE (``die_with_parent``). The run goes to this process's worker
    (``_worker``): a run that fails ends it, with the exit code a run alone would have had."""
    env = dict(os.environ, PYTHONUNBUFFERED="1")  # YADE runs this interpreter: drystone is installed
    w = _worker(threads, env)
    with open(spec_path.parent / "log.txt", "w") as log:
        if w is None:
            proc = subprocess.Popen(_yade_command(spec_path, threads, engine), stdout=subprocess.PIPE,
                                    stderr=subprocess.STDOUT, text=True, env=env, cwd=paths.ROOT,
                                    start_new_session=True, preexec_fn=die_with_parent)
        else:
            proc = w.proc
        try:
            if w is not None:
                try:
                    proc.stdin.write(json.dumps({"spec": str(Path(spec_path).resolve()), "engine": engine}) + "\n")
                    proc.stdin.flush()
                except BrokenPipeError:  # it died since ``usable``: its exit code is this run's
                    pass
            for line in proc.stdout:
                if w is not None and line.endswith(RUN_END + "\n"):  # after a line the run left open, if any
                    log.write(line[:-len(RUN_END) - 1])
                    w.completed()
                    return 0
                log.write(line)
                log.flush()  # sweeps read the progress of running jobs from log.txt
                if not quiet and not line.startswith(NOISE) and "verletDist is set to 0" not in line:
                    print(line, end="", flush=True)
            if w is not None:  # the worker ended (a failed run): its exit code is the run's
                _WORKERS.pop(w.key, None)
                w.end()
            proc.stdout.close()
            return proc.wait()
        except BaseException:  # Ctrl-C, SIGTERM (sweep workers), errors: never leave YADE running
            if w is not None:
                _WORKERS.pop(w.key, None)
                w.end()
            else:
                proc.kill()
                proc.wait()
            raise


def simulate(spec, stage: Path, threads: int = 1, quiet: bool = False, where: str = "",
             engine: str = "compiled") -> None:
    """Write ``spec`` (a drystone.model.spec.Spec or a spec dict) to ``stage``/spec.json and run
    YADE on it; raises RunError (naming ``where``, the stability check that stopped it or
    the log's tail) unless histories.npz and run_info.json were written. ``spec['out_dir']`` is where the run will live.
    ``engine``: the step engine of the project's law (``ENGINES``; not physics: both give
    the same run, the compiled one faster)."""
    if engine not in ENGINES:
        raise RunError(f"{where}: unknown engine {engine!r}; allowed: {', '.join(ENGINES)}")
    stage = Path(stage)
    spec_path = stage / "spec.json"
    spec_path.write_text(json.dumps(spec_dict(spec), indent=1))
    out = spec["out_dir"]
    rc = _simulate(spec_path, threads, quiet, engine)
    if (stage / "failure.txt").is_file():  # stopped by a stability check (drystone/mechanics/stability.py)
        raise RunError(f"{where}: the simulation was stopped: {(stage / 'failure.txt').read_text().strip()}; "
                       f"{out} is unchanged; log {stage / 'log.txt'}")
    if rc != 0 or not (stage / "histories.npz").is_file():
        tail = (stage / "log.txt").read_text(errors="replace").splitlines()[-20:]
        raise RunError(f"{where}: YADE failed (exit {rc}); {out} is unchanged; log {stage / 'log.txt'}:\n"
                       + "\n".join(tail))
