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


NESTED = textwrap.dedent('''
    from drystone.mechanics import overlap  # a kernel module: starts numba's thread pool
    import numpy as np
    from numba import njit, prange

    @njit(cache=True, parallel=True)
    def doubled(x):
        out = np.zeros(len(x))
        for t in prange(len(x)):
            out[t] = 2.0 * x[t]
        return out

    @njit(cache=True)
    def total(x):
        return doubled(x).sum()

    print(total(np.ones(4)), flush=True)
''')


def test_a_cached_kernel_calling_a_parallel_one_loads(tmp_path):
    """A cached kernel whose first call in a process runs a parallel one from the cache
    (the compiled step's ``neighbours.update``): without the thread pool that a kernel
    module starts, the second process (loading from the cache) crashed (github.com/numba/numba/issues/8578)."""
    (tmp_path / "nested.py").write_text(NESTED)
    env = {"NUMBA_CACHE_DIR": str(tmp_path / "cache"), "PYTHONPATH": str(tmp_path), "PATH": "/usr/bin:/bin"}
    for run in ("compiles", "loads"):
        proc = subprocess.run([sys.executable, "-c", "import nested"], env=env, cwd=tmp_path, capture_output=True,
                              text=True, timeout=300)
        assert proc.returncode == 0, (run, proc.returncode, proc.stderr[-2000:])
        assert proc.stdout.split() == ["8.0"]
    assert list((tmp_path / "cache").rglob("*total*.nbi"))


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


CLIP = textwrap.dedent('''
    import numpy as np
    from drystone.mechanics import overlap
    P = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    m = overlap._clip(P, 3, np.array([-1.0, 1.0, -1.0]), np.empty((8, 3)))
    print(m, sum(overlap._clip.stats.cache_hits.values()), flush=True)
''')


def test_a_copied_checkout_loads_the_kernels_its_original_compiled(tmp_path):
    """A copy of a checkout (another folder, every file with a new modification time: a
    clone, ``cp -r``, a ``git checkout`` that rewrote the files) loads the kernels the
    original compiled into the user's shared cache instead of compiling them again (numba's
    own keys, the folder's path and the file's time, made them unusable to the copy)."""
    import shutil
    from pathlib import Path
    import drystone
    package = Path(drystone.__file__).parent
    original = tmp_path / "original"
    shutil.copytree(package, original / "drystone", ignore=shutil.ignore_patterns("__pycache__"))
    env = {"PYTHONPATH": "", "PATH": "/usr/bin:/bin", "HOME": str(tmp_path)}
    hits = []
    for where in ("original", "copy"):
        if where == "copy":  # shutil.copy: new modification times
            shutil.copytree(original, tmp_path / "copy", copy_function=shutil.copy)
            shutil.rmtree(original)
        env["PYTHONPATH"] = str(tmp_path / where)
        proc = subprocess.run([sys.executable, "-c", CLIP], env=env, cwd=tmp_path / where, capture_output=True,
                              text=True, timeout=300)
        assert proc.returncode == 0, (where, proc.stderr[-2000:])
        m, hit = proc.stdout.split()
        assert m == "4"  # the triangle cut by a plane through two of its edges: a quadrilateral
        hits.append(int(hit))
    assert hits == [0, 1], hits


WHERE = "import drystone; print(drystone.OWN_NUMBA_CACHE_DIR)"


def _cache_folder(env, cwd):
    proc = subprocess.run([sys.executable, "-c", WHERE], env=env, cwd=cwd, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return proc.stdout.strip()


def test_the_kernel_cache_is_the_users_named_by_the_kernels_and_numba(tmp_path):
    """The compiled kernels go to the cache this user's checkouts share, in a folder named by
    the kernels' digest and numba's version ($XDG_CACHE_HOME, else ~/.cache); where that
    cannot be written, to ``.numba_cache/`` beside the package; an explicit NUMBA_CACHE_DIR
    is numba's."""
    import hashlib
    from importlib.metadata import version
    from pathlib import Path
    import drystone
    root = Path(drystone.__file__).parent.parent
    h = hashlib.sha256()
    for name in drystone._KERNEL_SOURCES:
        h.update((root / "drystone" / name).read_bytes())
    digest = h.hexdigest()[:16]
    env = {"PYTHONPATH": str(root), "PATH": "/usr/bin:/bin", "HOME": str(tmp_path / "home")}
    name = f"{digest}-numba{version('numba')}"
    assert _cache_folder(env, tmp_path) == str(tmp_path / "home" / ".cache" / "drystone" / "numba" / name)
    assert (tmp_path / "home" / ".cache" / "drystone" / "numba" / name).is_dir()
    assert _cache_folder(dict(env, XDG_CACHE_HOME=str(tmp_path / "xdg")), tmp_path) == str(
        tmp_path / "xdg" / "drystone" / "numba" / name)
    (tmp_path / "file").write_text("not a folder")
    assert _cache_folder(dict(env, XDG_CACHE_HOME=str(tmp_path / "file")), tmp_path) == str(root / ".numba_cache" / digest)
    assert _cache_folder(dict(env, NUMBA_CACHE_DIR=str(tmp_path / "own")), tmp_path) == ""


def test_the_shared_cache_keeps_the_versions_last_used(tmp_path):
    """Pruning deletes the kernel versions' folders used longest ago beyond the number kept,
    never the one in use, and nothing it did not name."""
    import os
    import drystone
    folders = [tmp_path / f"{i:016x}-numba0.58.1" for i in range(5)]
    for i, f in enumerate(folders):
        (f / "drystone.mechanics").mkdir(parents=True)
        os.utime(f, (1000.0 + i, 1000.0 + i))  # folder 4 used last, 0 first
    other = tmp_path / "mine"
    other.mkdir()
    (tmp_path / "notes.txt").write_text("kept")
    gone = drystone.prune_kernel_cache(tmp_path, keep=folders[0], versions=3)
    assert sorted(gone) == sorted(folders[1:3])
    assert [f.is_dir() for f in folders] == [True, False, False, True, True]
    assert other.is_dir() and (tmp_path / "notes.txt").is_file()
