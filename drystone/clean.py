"""``make clean``: delete what the package wrote in the results folder and its compiled-kernel
cache, nothing else, and say what was left.

    python -m drystone.clean [RESULTS] [--dry-run]

What is the package's (everything else stays, and is listed):

- a run's folder (``simulate.is_run_folder``: spec.json with the spec's format tag), whole:
  a run replaces its folder whole too;
- a sweep's note of a failed run (a folder holding only FAILED.txt), a VTK set the package
  wrote (blocks.pvd with ``vtk.MARK``), and the package's hidden leftovers of an interrupted
  run or write (``.NAME.partial``, ``.NAME.old``, ``.NAME.lock``, ``.NAME.vtk-partial``,
  ``.NAME.vtk-old``, ``atomic`` temporaries);
- every file listed in a folder's ``atomic.MANIFEST`` (the studies' reports, tables, figures,
  plans, sweep files, ``sweep.json``; written through drystone/atomic.py), and the manifest;
- a sweep's ``sweep.json`` written before the manifests existed (recognised by its keys);
- a folder left empty by the above; ``.numba_cache/`` beside the package.

The compiled kernels shared by this user's checkouts (``drystone.kernel_cache_root``) stay:
other checkouts load them; the package keeps the most recently used versions there
(``drystone.prune_kernel_cache``). ``make clean`` says where they are and their size.

A symbolic link is never followed nor deleted. Files the package wrote before it kept
manifests (a study's report of an older version) are left and listed: delete them by hand.
"""
from __future__ import annotations

import json
import re
import shutil
import sys
from pathlib import Path

import drystone
from drystone import atomic, paths

#: the package's hidden leftovers of an interrupted run or VTK write (simulate.py, postprocess/vtk.py)
_LEFTOVER = re.compile(r"\..+\.(partial|old|lock|vtk-partial|vtk-old)")


def _is_sweep_status(p: Path) -> bool:
    try:
        data = json.loads(p.read_text())
    except (OSError, ValueError, RecursionError):
        return False
    return isinstance(data, dict) and {"sweep", "runs"} <= set(data)


def _whole(d: Path) -> bool:
    """A folder that is the package's whole."""
    from drystone.simulate import FAILED_NOTE, is_run_folder

    if _LEFTOVER.fullmatch(d.name) or is_run_folder(d):
        return True
    try:
        names = sorted(p.name for p in d.iterdir())
    except OSError:
        return False
    if names == [FAILED_NOTE]:
        return True
    if "blocks.pvd" not in names:
        return False
    try:
        from drystone.postprocess import vtk
    except ImportError:  # no meshio (make clean before make setup): not recognised, left
        return False
    try:
        vtk.check_out(d)
    except vtk.VtkError:
        return False
    return True


def _own_file(f: Path, manifest: set[str]) -> bool:
    name = f.name
    return (name in manifest or name == atomic.MANIFEST or atomic.is_temporary(name) or bool(_LEFTOVER.fullmatch(name))
            or (name == "sweep.json" and _is_sweep_status(f)))


def _remove(p: Path, dry: bool) -> None:
    if dry:
        return
    if p.is_dir() and not p.is_symlink():
        shutil.rmtree(p)
    else:
        p.unlink()


def _walk(folder: Path, removed: list, left: list, dry: bool) -> bool:
    """Remove the package's entries of ``folder``; True if it is left empty."""
    manifest = atomic.listed(folder)
    kept = False
    for e in sorted(folder.iterdir()):
        if e.is_symlink():
            left.append(e)
            kept = True
        elif e.is_dir():
            if _whole(e):
                _remove(e, dry)
                removed.append(e)
            elif _walk(e, removed, left, dry):
                if not dry:
                    e.rmdir()
            else:
                kept = True
        elif _own_file(e, manifest):
            _remove(e, dry)
            removed.append(e)
        else:
            left.append(e)
            kept = True
    return not kept


def clean(results: Path | None = None, cache: Path | None = None, dry: bool = False) -> tuple[list, list]:
    """Delete the package's outputs under ``results`` (default ``paths.RESULTS``) and the
    kernel cache ``cache`` (default ``.numba_cache`` beside the package); returns (removed,
    left) paths. ``results`` itself goes when nothing is left in it."""
    results = Path(results or paths.RESULTS)
    cache = Path(cache or paths.ROOT / ".numba_cache")
    removed, left = [], []
    if results.is_symlink():
        left.append(results)
    elif results.is_dir() and _walk(results, removed, left, dry) and not dry:
        results.rmdir()
    if cache.is_dir() and not cache.is_symlink():
        _remove(cache, dry)
        removed.append(cache)
    return removed, left


def main(argv=None) -> int:
    import argparse

    ap = argparse.ArgumentParser(prog="python -m drystone.clean", description=__doc__.split("\n")[0])
    ap.add_argument("results", nargs="?", help=f"the results folder ({paths.RESULTS})")
    ap.add_argument("--dry-run", action="store_true", help="say what would be deleted and left; delete nothing")
    a = ap.parse_args(argv)
    try:
        removed, left = clean(a.results, dry=a.dry_run)
    except OSError as exc:
        print(f"error: {exc.filename or a.results or paths.RESULTS}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    verb = "would delete" if a.dry_run else "deleted"
    print(f"clean: {verb} {len(removed)} item(s) the package wrote"
          + "".join(f"\n  {p}" for p in removed[:20]) + (f"\n  ... and {len(removed) - 20} more" if len(removed) > 20 else ""))
    if left:
        print(f"clean: left {len(left)} file(s) the package did not write (or wrote before it listed its files):"
              + "".join(f"\n  {p}" for p in left[:50]) + (f"\n  ... and {len(left) - 50} more" if len(left) > 50 else ""))
    else:
        print("clean: nothing left")
    shared = drystone.kernel_cache_root()
    if shared.is_dir():
        size = sum(f.stat().st_size for f in shared.rglob("*") if f.is_file() and not f.is_symlink())
        print(f"clean: the compiled kernels shared by your checkouts stay in {shared} ({size / 2**20:.0f} MiB; "
              f"the {drystone.KEPT_KERNEL_VERSIONS} versions last used are kept)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
