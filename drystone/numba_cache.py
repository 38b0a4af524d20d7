"""numba's on-disk cache made safe for processes compiling at once.

numba (0.58) keeps, per cached function, an index (signature -> data file) and numbered data
files. A process that saves a new overload reads the index, takes the first free number,
writes the index, then the data file, without a lock: two processes compiling different
overloads of one function at the same time (the test suite's workers, a sweep's runs after
a kernel changed) can both take number 1, and the index then names one overload's file
while the file holds the other's machine code. The next process to load it calls that
code with the wrong arguments: a segmentation fault. (The one crash seen here that was
put down to this race, ``neighbours.update`` called directly after a kernel change,
fits the thread-pool fault below better: it recurs from a warm cache.)

``install`` wraps numba's index-and-data reads and writes in an advisory lock (``fcntl``)
on a file in the cache's root (``NUMBA_CACHE_DIR``, which ``drystone/__init__.py`` sets;
else each function's cache folder): writers one at a time, readers not during a write. Every
module with cached kernels calls it when imported, before any of its kernels can be
loaded or saved; installing twice does nothing. The cost is a lock per cache lookup (a
few microseconds, at a kernel's first call in a process).

``install`` also starts numba's thread pool. A cached kernel that calls a ``parallel``
one (the compiled step calls the neighbour list's ``update`` and ``search``) is loaded
from the cache with its callee's code but without the callee's dispatcher running, and
that dispatcher is what starts the pool on first use (github.com/numba/numba/issues/8578, open for 0.58):
the first ``prange`` then jumps into a pool that does not exist, a segmentation fault,
in a process whose first compiled call is such a kernel from a warm cache (a script
calling ``neighbours.update`` directly; ``CompiledStep`` sets the thread count first and
so started the pool by chance). Starting it costs about a millisecond per process.

``install`` also makes a cached kernel's freshness its source's content, not its place
and time. numba stamps an index with its source file's modification time and size and
files it under a digest of the file's absolute folder: a clone, a copy, a moved checkout
or a ``git checkout`` that rewrote an unchanged file had a cache that no process could
use, while ``drystone.kernels_cached`` said it was there, and every process that ran a
kernel then compiled it (the test suite's study runs, a sweep's workers: each 60-140 s of
a core). The stamp is now the file's size and SHA-256 (``content_stamp``), and in
drystone's own cache (``drystone.OWN_NUMBA_CACHE_DIR``, named by the digest of every
kernel module) a drystone module's kernels are filed under the module's package name
(``drystone.mechanics``), not its folder's path. Elsewhere (an explicit
``NUMBA_CACHE_DIR``, a user's own kernels) numba's folder key stays: there two versions
of drystone could share a folder, and a kernel that inlines another module's code would
load the other version's, which the digest rules out in drystone's own.
"""
from __future__ import annotations

import contextlib
import fcntl
import functools
import hashlib
import os

import numba
import numpy as np
from numba.core import caching, config

#: the lock file in the cache's root
LOCK_NAME = ".drystone-lock"

#: the first row of a kernel's range where its caller does all rows on its own thread
#: (``_damp_range(FIRST, m, ...)``): a literal 0 there is typed as the constant 0
#: (``Literal[int](0)``), not int64, and numba compiles the range kernel a second time for
#: it beside the threads' ``_damp_range(t * m // nt, ...)``; a numpy integer is typed int64.
#: Likewise a kernel called from compiled code and from Python takes no argument with a
#: default: an omitted argument is a type of its own, another compilation of the kernel
#: and of what it calls (with the damping's inlining, a fresh cache's first run compiled for
#: 158 s before and 93 s after: ``make bench``'s compile section)
FIRST = np.int64(0)

#: the ``parallel`` option of the kernels that run on numba's threads: their ``prange`` loops
#: over ranges of rows and nothing else. Numba's other conversions (array expressions,
#: ``np.zeros`` and the like, reductions and in-place operators made parallel loops of their
#: own) are off: each such loop is one more function to compile (the step's first compile
#: 114 s without them against 126 s, one run each, the same tree) and runs on numba's
#: schedule, which ``numba.set_parallel_chunksize`` also sets; the kernels' results are the
#: same bit for bit (their ``prange`` loops are the threads' whole work)
PARALLEL = {"prange": True, "numpy": False, "setitem": False, "reduction": False, "inplace_binop": False,
            "comprehension": False, "stencil": False, "fusion": False}


@contextlib.contextmanager
def locked(folder: str, exclusive: bool):
    """Hold the advisory lock of the cache ``folder`` (made if missing): exclusive for a
    writer, shared for a reader; released when the block ends (the file is closed). Where
    the file system takes no lock (some network mounts), numba's own unlocked way."""
    os.makedirs(folder, exist_ok=True)
    fd = os.open(os.path.join(folder, LOCK_NAME), os.O_RDWR | os.O_CREAT, 0o644)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX if exclusive else fcntl.LOCK_SH)
        except OSError:
            pass
        yield
    finally:
        os.close(fd)


def _under_lock(method, exclusive: bool):
    @functools.wraps(method)
    def wrapper(self, *args, **kwargs):
        with locked(config.CACHE_DIR or self._cache_path, exclusive):
            return method(self, *args, **kwargs)
    wrapper.drystone_locked = True
    return wrapper


_STAMPS: dict = {}


def content_stamp(path: str) -> tuple:
    """The freshness of a kernel's source file: ("sha256", its digest, its size in bytes),
    kept per process by the file's modification time and size."""
    st = os.stat(path)
    key = (path, st.st_mtime_ns, st.st_size)
    if key not in _STAMPS:
        with open(path, "rb") as f:
            _STAMPS[key] = ("sha256", hashlib.sha256(f.read()).hexdigest(), st.st_size)
    return _STAMPS[key]


def _source_stamp(self):
    return content_stamp(self._py_file)


def _cache_subpath(cls, py_file):
    """Where under the cache folder the kernels of ``py_file`` live: in drystone's own cache,
    a drystone module's package name (relocatable); else numba's key of the folder's path."""
    import drystone
    here = os.path.dirname(os.path.abspath(drystone.__file__))
    folder = os.path.dirname(os.path.abspath(py_file))
    if config.CACHE_DIR == drystone.OWN_NUMBA_CACHE_DIR and (folder == here or folder.startswith(here + os.sep)):
        rel = os.path.relpath(folder, here)
        return "drystone" if rel == "." else "drystone." + rel.replace(os.sep, ".")
    return caching._CacheLocator.get_suitable_cache_subpath.__func__(cls, py_file)


def install() -> None:
    """Serialise numba's cache writes (and keep reads out of them) across processes, key a
    kernel by its source's content, and start numba's thread pool (module docstring)."""
    numba.get_num_threads()  # starts the pool (numba.np.ufunc.parallel._launch_threads) if it is not running
    cls = caching.IndexDataCacheFile
    if getattr(cls.save, "drystone_locked", False):
        return
    cls.save = _under_lock(cls.save, exclusive=True)
    cls.load = _under_lock(cls.load, exclusive=False)
    where = caching._UserProvidedCacheLocator  # the locator of a folder set by NUMBA_CACHE_DIR
    where.get_source_stamp = _source_stamp
    where.get_suitable_cache_subpath = classmethod(_cache_subpath)
