"""drystone: seismic analysis of dry-stone masonry with rigid polyhedral blocks in YADE.

Units are SI throughout (m, kg, s, N, Pa, rad) unless a name says otherwise (``_deg``, ``_mm``, ``_g``).
Axes: x along the wall (in plane), y through the thickness (out of plane), z vertical, up.
"""
import hashlib as _hashlib
import os as _os
import re as _re
from pathlib import Path as _Path

__version__ = "0.1.0"

#: drystone's own numba cache folder (``_numba_cache_dir``); numba's cache is there unless
#: NUMBA_CACHE_DIR was set before drystone was first imported
OWN_NUMBA_CACHE_DIR = ""

#: the modules with numba kernels (``@njit(cache=True)``), and numba_cache (its ``FIRST`` is compiled in)
_KERNEL_SOURCES = ("mechanics/overlap.py", "mechanics/contact.py", "mechanics/contact_step.py",
                   "mechanics/contact_rows.py", "mechanics/neighbours.py", "mechanics/energy.py",
                   "mechanics/integration.py", "numba_cache.py")

#: versions of the kernels kept in the shared cache (``kernel_cache_root``): the most recently used
KEPT_KERNEL_VERSIONS = 8

#: a version's folder in the shared cache: the kernels' digest and numba's version
_VERSION_FOLDER = _re.compile(r"^[0-9a-f]{16}-numba[0-9A-Za-z.+_-]+$")


def kernel_cache_root() -> _Path:
    """The folder of the compiled kernels shared by every checkout of this user (clones,
    worktrees, copies, installs): ``$XDG_CACHE_HOME/drystone/numba``, else
    ``~/.cache/drystone/numba``."""
    base = _os.environ.get("XDG_CACHE_HOME") or _os.path.join(_os.path.expanduser("~"), ".cache")
    return _Path(base) / "drystone" / "numba"


def _numba_version() -> str:
    try:
        from importlib.metadata import version
        return version("numba")
    except Exception:  # not installed (yet): no kernel can be compiled anyway
        return "none"


def _numba_cache_dir() -> None:
    """Point numba's on-disk cache at a folder named by a digest of every kernel module and
    numba's version, in the cache shared by this user's checkouts (``kernel_cache_root``:
    a clone or a worktree of the same kernels loads what another compiled; the first
    compile costs 1.5-2.5 min of a core), else, where that cannot be written, in
    ``.numba_cache/`` beside the package. Numba re-validates a cached function against its
    own file only: a kernel that inlines one from another module (the compiled step calls
    the overlap clip) would otherwise keep running the old code after that module changes;
    numba's version in the name keeps two numbas from rewriting each other's index. A new
    version's folder prunes the shared cache to the KEPT_KERNEL_VERSIONS most recently
    used (``prune_kernel_cache``). Set before numba is imported; an explicit
    NUMBA_CACHE_DIR is respected."""
    global OWN_NUMBA_CACHE_DIR
    here = _Path(__file__).resolve().parent
    h = _hashlib.sha256()
    for name in _KERNEL_SOURCES:
        h.update((here / name).read_bytes())
    digest = h.hexdigest()[:16]
    folder = kernel_cache_root() / f"{digest}-numba{_numba_version()}"
    local = here.parent / ".numba_cache" / digest
    given = _os.environ.get("NUMBA_CACHE_DIR")
    if given:  # a drystone process's child (its runs, workers) gets the folder it chose
        if given in (str(folder), str(local)):
            OWN_NUMBA_CACHE_DIR = given
        return
    try:
        new = not folder.is_dir()
        folder.mkdir(parents=True, exist_ok=True)
        _os.utime(folder)  # its last use: what pruning keeps
        if new:
            prune_kernel_cache(folder.parent, keep=folder)
    except OSError:  # no writable home: the checkout's own folder
        folder = local
    OWN_NUMBA_CACHE_DIR = str(folder)
    _os.environ["NUMBA_CACHE_DIR"] = OWN_NUMBA_CACHE_DIR


def prune_kernel_cache(root: _Path, keep: _Path | None = None, versions: int = KEPT_KERNEL_VERSIONS) -> list:
    """Delete all but the ``versions`` most recently used kernel versions' folders in the
    shared cache ``root`` (folders named as ``_numba_cache_dir`` names them; anything else
    there stays), never ``keep``; returns the deleted folders. A process that still runs
    a deleted version's kernels has them loaded; it compiles again only what it had not."""
    import shutil
    try:
        found = [p for p in root.iterdir() if _VERSION_FOLDER.match(p.name) and p.is_dir() and not p.is_symlink()]
    except OSError:
        return []
    found.sort(key=lambda p: p.stat().st_mtime, reverse=True)
    gone = [p for p in found if p != keep][max(0, versions - 1):]
    for p in gone:
        shutil.rmtree(p, ignore_errors=True)
    return gone


_numba_cache_dir()


def kernels_cached() -> bool:
    """Whether numba's cache holds the compiled step for the current kernel sources (else the
    first run compiles them: 1.5-2.5 min of a core)."""
    cache = _Path(_os.environ.get("NUMBA_CACHE_DIR", ""))
    return bool(_os.environ.get("NUMBA_CACHE_DIR")) and cache.is_dir() and any(cache.rglob("contact_step.*.nbi"))
