"""Simulate: run YADE on a spec.json in a staging folder (drystone/yade_scripts/run_case.py
writes histories.npz and run_info.json beside it), with the results folder locked; a
complete run is swapped in by ``commit``. Nothing here reads histories or summarises.
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

from drystone import paths
from drystone.spec import spec_dict


class RunError(RuntimeError):
    """A run that could not be prepared or did not complete."""


#: step engines (drystone/yade_scripts/run_case.py): compiled (default) or python
ENGINES = ("compiled", "python")


def _yade_command(spec_path: Path, threads: int, engine: str = "compiled") -> list[str]:
    yade = shutil.which("yade") or "/usr/bin/yade"
    script = paths.PACKAGE / "yade_scripts" / "run_case.py"
    return [sys.executable, yade, "-n", "-x", "-j", str(threads), str(script), str(spec_path), engine]


NOISE = ("Welcome to Yade", "TCP python prompt", "XMLRPC info provider", "Running script", "Using python version")


class FolderLock:
    """Exclusive lock on a results folder for the length of a run (``fcntl.flock`` on a
    hidden file beside it, released by the kernel if the process dies). A second run into
    the same folder is refused with RunError naming the holder's pid."""

    def __init__(self, out: Path):
        self.path = out.parent / f".{out.name}.lock"
        self.fd = None

    def __enter__(self):
        import fcntl

        self.path.parent.mkdir(parents=True, exist_ok=True)
        fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.read(fd, 64).decode(errors="replace").strip() or "?"
            os.close(fd)
            raise RunError(f"{self.path.parent / self.path.name[1:-5]}: another run (pid {holder}) is writing "
                           f"this results folder; wait for it or use another --out") from None
        os.ftruncate(fd, 0)
        os.write(fd, str(os.getpid()).encode())
        self.fd = fd
        return self

    def __exit__(self, *exc):
        os.close(self.fd)  # releases the lock; the (empty) lock file stays, harmlessly


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


def _simulate(spec_path: Path, threads: int, quiet: bool, engine: str = "compiled") -> int:
    """Run YADE on ``spec_path`` (its log to log.txt beside it); returns YADE's exit code.
    YADE runs in its own session, so a Ctrl-C reaches only this process, which then
    kills YADE (no orphan) and re-raises."""
    env = dict(os.environ, PYTHONUNBUFFERED="1")  # YADE runs this interpreter: drystone is installed
    with open(spec_path.parent / "log.txt", "w") as log:
        proc = subprocess.Popen(_yade_command(spec_path, threads, engine), stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT, text=True, env=env, cwd=paths.ROOT,
                                start_new_session=True)
        try:
            for line in proc.stdout:
                log.write(line)
                log.flush()  # sweeps read the progress of running jobs from log.txt
                if not quiet and not line.startswith(NOISE) and "verletDist is set to 0" not in line:
                    print(line, end="", flush=True)
            return proc.wait()
        except BaseException:  # Ctrl-C, SIGTERM (sweep workers), errors: never leave YADE running
            proc.kill()
            proc.wait()
            raise


def simulate(spec, stage: Path, threads: int = 1, quiet: bool = False, where: str = "",
             engine: str = "compiled") -> None:
    """Write ``spec`` (a drystone.spec.Spec or a spec dict) to ``stage``/spec.json and run
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
    if (stage / "failure.txt").is_file():  # stopped by a stability check (drystone/stability.py)
        raise RunError(f"{where}: the simulation was stopped: {(stage / 'failure.txt').read_text().strip()}; "
                       f"{out} is unchanged; log {stage / 'log.txt'}")
    if rc != 0 or not (stage / "histories.npz").is_file():
        tail = (stage / "log.txt").read_text(errors="replace").splitlines()[-20:]
        raise RunError(f"{where}: YADE failed (exit {rc}); {out} is unchanged; log {stage / 'log.txt'}:\n"
                       + "\n".join(tail))
