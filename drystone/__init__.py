"""drystone: seismic analysis of dry-stone masonry with rigid polyhedral blocks in YADE.

Units are SI throughout (m, kg, s, N, Pa, rad) unless a name says otherwise (``_deg``, ``_mm``, ``_g``).
Axes: x along the wall (in plane), y through the thickness (out of plane), z vertical, up.
"""
import hashlib as _hashlib
import os as _os
from pathlib import Path as _Path

__version__ = "0.1.0"

#: drystone's own numba cache folder (``_numba_cache_dir``); numba's cache is there unless
#: NUMBA_CACHE_DIR was set before drystone was first imported
OWN_NUMBA_CACHE_DIR = ""

#: the modules with numba kernels (``@njit(cache=True)``), and numba_cache (its ``FIRST`` is compiled in)
_KERNEL_SOURCES = ("mechanics/overlap.py", "mechanics/contact.py", "mechanics/contact_step.py",
                   "mechanics/contact_rows.py", "mechanics/neighbours.py", "mechanics/energy.py",
                   "mechanics/integration.py", "numba_cache.py")


def _numba_cache_dir() -> None:
    """Point numba's on-disk cache at a folder named by a digest of every kernel module.
    Numba re-validates a cached function against its own file only: a kernel that inlines
    one from another module (the compiled step calls the overlap clip) would otherwise keep
    running the old code after that module changes. Set before numba is imported; an
    explicit NUMBA_CACHE_DIR is respected."""
    global OWN_NUMBA_CACHE_DIR
    here = _Path(__file__).resolve().parent
    h = _hashlib.sha256()
    for name in _KERNEL_SOURCES:
        h.update((here / name).read_bytes())
    OWN_NUMBA_CACHE_DIR = str(here.parent / ".numba_cache" / h.hexdigest()[:16])
    _os.environ.setdefault("NUMBA_CACHE_DIR", OWN_NUMBA_CACHE_DIR)


_numba_cache_dir()


def kernels_cached() -> bool:
    """Whether numba's cache holds the compiled step for the current kernel sources (else the
    first run compiles them: 1.5-2.5 min of a core)."""
    cache = _Path(_os.environ.get("NUMBA_CACHE_DIR", ""))
    return bool(_os.environ.get("NUMBA_CACHE_DIR")) and cache.is_dir() and any(cache.rglob("contact_step.*.nbi"))
