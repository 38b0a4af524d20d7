"""numba's on-disk cache serialised across processes (drystone/numba_cache.py): a process
that compiles a cached kernel while another holds the cache folder's lock waits for it, so
two processes never number their overloads' data files at once (numba's own index and
data writes take no lock: an index naming one overload's file while it holds another's
code, a segmentation fault at the next load)."""
import subprocess
import sys
import textwrap
import time

import tolerances as tol
from drystone import numba_cache
from drystone.mechanics import overlap  # noqa: F401 (a kernel module: installs the lock)

KERNEL = textwrap.dedent('''
    from drystone.mechanics import overlap  # installs the lock
    from numba import njit

    @njit(cache=True)
    def twice(x):
        return 2 * x

    print(twice(21), twice(1.5), flush=True)
''')


def test_kernel_modules_install_the_lock():
    from numba.core import caching
    assert getattr(caching.IndexDataCacheFile.save, "drystone_locked", False)
    assert getattr(caching.IndexDataCacheFile.load, "drystone_locked", False)
    numba_cache.install()  # twice: nothing more
    assert not getattr(caching.IndexDataCacheFile.save.__wrapped__, "drystone_locked", False)


def test_a_compiling_process_waits_for_the_lock(tmp_path):
    """While this process holds the cache folder's lock, another compiling a cached kernel
    writes no index; released, it writes it and runs."""
    cache = tmp_path / "cache"
    (tmp_path / "kernel.py").write_text(KERNEL)
    env = {"NUMBA_CACHE_DIR": str(cache), "PYTHONPATH": str(tmp_path), "PATH": "/usr/bin:/bin"}
    with numba_cache.locked(str(cache), exclusive=True):
        proc = subprocess.Popen([sys.executable, "-c", "import kernel"], env=env, cwd=tmp_path,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        time.sleep(tol.LOCK_WAIT_S)
        assert proc.poll() is None and not list(cache.rglob("*.nbi"))
    out, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err
    assert out.split() == ["42", "3.0"]
    assert list(cache.rglob("*twice*.nbi"))
