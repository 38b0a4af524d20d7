"""What ran a result: case, overrides, package, YADE and library versions, git commit."""
from __future__ import annotations

import datetime
import platform
import subprocess
from pathlib import Path

import numpy
import scipy

import drystone
from drystone import paths


def git_commit() -> dict:
    """Commit of the repository and whether the work tree had uncommitted changes."""
    try:
        rev = subprocess.run(["git", "rev-parse", "HEAD"], cwd=paths.ROOT, capture_output=True,
                             text=True, timeout=10).stdout.strip()
        dirty = bool(subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=paths.ROOT,
                                    capture_output=True, text=True, timeout=10).stdout.strip())
        return {"commit": rev or None, "dirty": dirty}
    except (OSError, subprocess.SubprocessError):
        return {"commit": None, "dirty": None}


def yade_version() -> str | None:
    """Debian package version of YADE (without starting it)."""
    try:
        out = subprocess.run(["dpkg-query", "-W", "-f=${Version}", "yade"], capture_output=True,
                             text=True, timeout=10)
        return out.stdout.strip() or None
    except (OSError, subprocess.SubprocessError):
        return None


def collect(case_path, case: dict, overrides: list[str]) -> dict:
    p = Path(case_path)
    return {
        "case_file": str(p.resolve()),
        "case_text": p.read_text() if p.is_file() else None,
        "overrides": list(overrides),
        "drystone_version": drystone.__version__,
        "yade_version": yade_version(),
        "python": platform.python_version(),
        "numpy": numpy.__version__,
        "scipy": scipy.__version__,
        "git": git_commit(),
        "host": platform.node(),
        "date_utc": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
    }
