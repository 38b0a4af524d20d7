"""Shared test fixtures: output folders, matplotlib without a display, YADE runs; for
``make test`` (``pytest -n N``): numba's cache compiled once before the workers start, and the
files in decreasing order of their cost."""
from __future__ import annotations

import os
import shutil
from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")


def pytest_addoption(parser):
    parser.addoption("--keep-output", action="store_true",
                     help="keep test output folders under results/tests/ instead of a temporary folder")


@pytest.fixture
def outdir(request, tmp_path) -> Path:
    """A folder for a test's outputs (kept under results/tests/<test> with --keep-output)."""
    if request.config.getoption("--keep-output"):
        from drystone import paths
        p = paths.RESULTS / "tests" / request.node.name
        shutil.rmtree(p, ignore_errors=True)
        p.mkdir(parents=True)
        return p
    return tmp_path


def have_yade() -> bool:
    return shutil.which("yade") is not None or os.path.exists("/usr/bin/yade")


requires_yade = pytest.mark.skipif(not have_yade(), reason="YADE is not installed (run make setup)")

#: the smallest run through the default step engine: one box settling for a few steps, several
#: between two samples (the compiled call of many steps, ``CompiledStep.advance``, as well)
_WARM_CASE = {"case": {"name": "numba_warm", "geometry": {"generator": "boxes_on_platform", "mu": 0.6, "boxes": [
    {"id": 1, "center_xy": [0.0, 0.0], "size": [0.4, 0.4, 0.2]}]}},
    "stages": [{"type": "gravity", "duration": 0.01, "ramp": 0.005}], "output": {"interval": 0.005}}
#: the same case through the other engines' kernels (the numpy law; YADE's contact geometry)
_WARM_OTHERS = (["--engine", "python"], ["--set", "contact.detection=yade"])
#: cost of the test files (s), to order the files for ``-n N``: each file's tests' durations summed
#: (setup, call, teardown) in one run of the whole suite as ``make test`` runs it (``-n 2``, nice)
#: on a shared 2-core machine, so only their ratios matter; files not here (under 1 s) are costed
#: by marks (``_COST_S``, the same units). A stale figure only makes the two workers finish less together.
_FILE_COST_S = {
    "test_yade_contact.py": 44, "test_site_study.py": 58, "test_yade_worker.py": 46, "test_sweep.py": 39,
    "test_shape_study.py": 36, "test_docs_runnable.py": 26, "test_analyses_fragility.py": 26,
    "test_analyses_assess.py": 22, "test_tilt_block.py": 21, "test_reliability_site.py": 19,
    "test_crosscheck.py": 18, "test_multipart_runs.py": 18, "test_yade_compiled.py": 17, "test_fragility.py": 15,
    "test_restitution.py": 13, "test_sacsayhuaman.py": 12, "test_analyses_collapse.py": 12, "test_damping.py": 12,
    "test_reliability_output.py": 12, "test_analyses_tilt.py": 11, "test_energy.py": 10, "test_numba_cache.py": 9,
    "test_reliability_run.py": 9, "test_reliability_geometry.py": 9, "test_motions_catalogue.py": 9,
    "test_fragility_measures.py": 8, "test_report.py": 7, "test_earth_pressure_runs.py": 7, "test_ogawa_study.py": 7,
    "test_analyses_modal.py": 6, "test_regression.py": 6, "test_verification.py": 6, "test_dxf.py": 5,
    "test_polygonal_wall.py": 5, "test_decompose.py": 4, "test_layers.py": 4, "test_excitation.py": 4,
    "test_reliability_vertices.py": 4, "test_identification.py": 4, "test_overlap.py": 3, "test_cases_valid.py": 3,
    "test_bench.py": 3, "test_rocking_pulse.py": 2, "test_left_model_removed.py": 2, "test_packaging.py": 2,
    "test_compiled_step.py": 2, "test_ogawa_3d.py": 2, "test_limit_analysis.py": 2, "test_site.py": 2,
    "test_intensity.py": 2, "test_walls.py": 2, "test_earth_pressure.py": 2, "test_modal.py": 2,
    "test_limit_dem_study.py": 2, "test_meshes.py": 1, "test_limit_settled.py": 1, "test_ogawa_mrb1d.py": 1,
    "test_broad_phase.py": 1}
#: cost of a test (s) by its marks, for the files not in ``_FILE_COST_S``
_COST_S = {"slow": 30.0, "yade": 3.0, "other": 0.3}


#: set by the controller of a parallel run while it compiles numba's cache (``pytest_configure``):
#: the file that exists once the compile is done; the workers wait for it before a kernel is needed
WARMING = "DRYSTONE_TEST_WARMING"
#: words of a test file's source that mark it as one that calls the compiled kernels in its own process
#: (its runs are marked ``yade``): only to order the files while the cache is compiled, the waits
#: below make any order correct
_KERNEL_WORDS = ("contact_step", "overlap", "neighbours", "numba", "CompiledStep")


def pytest_configure(config):
    """In the controller of a parallel run (``-n N``: it runs no test itself) with numba's cache
    cold, compile the contact kernels once, in the background, while the workers start on the
    tests that need no kernel: otherwise each worker, and each YADE run a test starts before the
    cache is written, compiles them on its own (1.5-2.5 min of a core each). The smallest case runs
    through the compiled step in one process and through the other engines' kernels
    (``_WARM_OTHERS``) in another; when both end, the file named by ``$DRYSTONE_TEST_WARMING``
    is written. A worker waits for that file before a test that runs YADE, a run, or a numba
    kernel's first call (``_wait_for_the_kernels``), so that every kernel comes from the cache."""
    import subprocess
    import sys
    import tempfile
    import threading
    import time

    import drystone

    if hasattr(config, "workerinput"):
        config._drystone_warming = bool(os.environ.get(WARMING))  # the same in every worker: one order of files
        if config._drystone_warming:
            _wait_before_kernels()
        return
    parallel = getattr(config.option, "numprocesses", None)
    if not parallel or config.option.collectonly or drystone.kernels_cached() or not have_yade():
        return
    from drystone.tomlio import to_toml

    print("conftest: numba's cache is cold: compiling the contact kernels once, in the background "
          "(one to two minutes; the tests that need them wait)", flush=True)
    d = Path(tempfile.mkdtemp(prefix="drystone-warm-"))
    case, done = d / "warm.toml", d / "done"
    case.write_text(to_toml(_WARM_CASE))
    os.environ[WARMING] = str(done)  # before the workers start: they inherit it

    def run(k, args=()):
        subprocess.run([sys.executable, "-m", "drystone", "run", str(case), "--out", str(d / f"out{k}"), "-q", *args],
                       capture_output=True)

    def others():
        for k, args in enumerate(_WARM_OTHERS):
            run(k + 1, args)

    def warm():
        t0 = time.time()
        try:
            second = threading.Thread(target=others)
            second.start()
            run(0)
            second.join()
        finally:
            done.write_text(f"{time.time() - t0:.1f}\n")  # the compile's wall time, s

    config._drystone_warm = (threading.Thread(target=warm, daemon=True), d)
    config._drystone_warm[0].start()


def pytest_terminal_summary(terminalreporter, config):
    """After a run that compiled numba's cache: how long the compile took and how long each
    worker waited for it (``waits-<worker>`` files beside the ``done`` file)."""
    warm = getattr(config, "_drystone_warm", None)
    if warm is None or not (warm[1] / "done").is_file():
        return
    waits = sorted(warm[1].glob("waits-*"))
    terminalreporter.write_line(
        f"conftest: numba's cache compiled in the background in {(warm[1] / 'done').read_text().strip()} s; "
        + ("; ".join(f"{w.name[6:]} waited {w.read_text().strip()} s for it" for w in waits) or "no worker waited"))


def pytest_unconfigure(config):
    warm = getattr(config, "_drystone_warm", None)
    if warm is not None:
        warm[0].join()
        shutil.rmtree(warm[1], ignore_errors=True)


def _wait_for_the_kernels() -> None:
    """Block until the controller's compile of numba's cache is done (``$DRYSTONE_TEST_WARMING``;
    at most 15 min: a warm-up that hangs leaves the tests to compile on their own)."""
    import time

    done = os.environ.get(WARMING)
    t0 = time.time()
    while done and not os.path.exists(done) and time.time() - t0 < 900:
        time.sleep(0.2)
    if done:  # the time this worker waited (the controller's summary says it)
        Path(done).with_name(f"waits-{os.environ.get('PYTEST_XDIST_WORKER', 'gw')}").write_text(f"{time.time() - t0:.1f}\n")
    os.environ.pop(WARMING, None)


def _wait_before_kernels() -> None:
    """In a worker while the cache is compiled: a numba kernel's first call in this process
    (numba's ``Dispatcher._compile_for_args``: it compiles or loads from the cache) and a run
    (``drystone.simulate._simulate``: YADE loads the kernels) wait for the compile first."""
    from numba.core import dispatcher

    from drystone import simulate as sim

    first_call, simulate = dispatcher.Dispatcher._compile_for_args, sim._simulate

    def waiting_first_call(self, *args, **kws):
        _wait_for_the_kernels()
        return first_call(self, *args, **kws)

    def waiting_simulate(*args, **kws):
        _wait_for_the_kernels()
        return simulate(*args, **kws)

    dispatcher.Dispatcher._compile_for_args = waiting_first_call
    sim._simulate = waiting_simulate


@pytest.hookimpl(tryfirst=True)
def pytest_runtest_setup(item):
    """A test that runs YADE waits for the controller's compile of numba's cache (its YADE
    process loads the kernels from it)."""
    if os.environ.get(WARMING) and _cost(item) > _COST_S["other"]:
        _wait_for_the_kernels()


def _cost(item) -> float:
    if item.get_closest_marker("slow"):
        return _COST_S["slow"]
    yade = item.get_closest_marker("yade") or requires_yade.mark in item.iter_markers("skipif")
    return _COST_S["yade" if yade else "other"]


def pytest_collection_modifyitems(config, items):
    """The files in decreasing order of their cost (``_FILE_COST_S``, else by marks), each
    file's tests in their order: ``make test`` (``-n N --dist loadfile --no-loadscope-reorder``)
    hands the next file to the first idle worker, so the longest start first and the workers
    finish together, and one worker runs a whole file (a module fixture's runs are made once).
    While the controller compiles numba's cache, the files that need no kernel come first."""
    files: dict = {}
    for item in items:
        files.setdefault(item.nodeid.split("::", 1)[0], []).append(item)

    def cost(path: str) -> float:
        return _FILE_COST_S.get(Path(path).name) or sum(_cost(i) for i in files[path])

    def later(path: str) -> bool:
        """While numba's cache is compiled: a file that may need the kernels (its tests would wait)."""
        if not getattr(config, "_drystone_warming", False):
            return False
        text = files[path][0].path.read_text()
        return any(_cost(i) > _COST_S["other"] for i in files[path]) or any(w in text for w in _KERNEL_WORDS)

    items[:] = [i for path in sorted(files, key=lambda p: (later(p), -cost(p))) for i in files[path]]  # stable


def run_case(case: dict, outdir: Path, name: str = "case", **kw) -> tuple[dict, dict, dict]:
    """Write ``case`` as TOML, run it, return (summary, histories, spec)."""
    import json

    from drystone import runner
    from drystone.postprocess import summary as summ

    out = outdir / name
    s = runner.run_dict(case, outdir / f"{name}.toml", out_dir=out, quiet=True)
    spec = json.loads((out / "spec.json").read_text())
    return s, summ.load_histories(out), spec


def assert_figure(path, size_in: tuple[float, float], dpi: float) -> None:
    """``path`` is a PNG of ``size_in`` inches (width, height) at ``dpi`` with drawn content:
    the middle half of the image has ink (pixels darker than 0.9) and many colours, which an
    empty axes or a blank figure has not (thresholds: tests/tolerances.py)."""
    import matplotlib.image
    import numpy as np

    from tolerances import FIGURE_MIN_COLOURS, FIGURE_MIN_INK

    img = matplotlib.image.imread(path)[..., :3]
    h, w = img.shape[:2]
    assert (w, h) == (round(size_in[0] * dpi), round(size_in[1] * dpi)), f"{path}: {w} x {h} pixels"
    middle = img[h // 4: 3 * h // 4, w // 4: 3 * w // 4]
    ink = (middle.min(axis=2) < 0.9).mean()
    colours = len(np.unique((middle.reshape(-1, 3) * 255).round().astype(int), axis=0))
    assert ink >= FIGURE_MIN_INK and colours >= FIGURE_MIN_COLOURS, \
        f"{path}: {ink:.2%} of the middle inked, {colours} colours: nothing drawn?"


def refused_run(folder: Path, blocks: dict) -> str:
    """Write ``blocks`` (a block-file dict) and a gravity case using it into ``folder``, run
    ``python -m drystone run`` there; assert the refusal (exit 2, one line, no traceback,
    nothing written) and return its message."""
    import json
    import subprocess
    import sys

    (folder / "blocks.json").write_text(json.dumps(blocks))
    (folder / "c.toml").write_text('[case]\ngeometry = "blocks.json"\n[[stages]]\ntype = "gravity"\nduration = 0.1\n')
    r = subprocess.run([sys.executable, "-m", "drystone", "run", "c.toml", "--out", "out"], cwd=folder,
                       capture_output=True, text=True)
    assert r.returncode == 2, r.stderr
    assert r.stderr.strip().count("\n") == 0 and "Traceback" not in r.stderr
    assert sorted(p.name for p in folder.iterdir()) == ["blocks.json", "c.toml"]
    return r.stderr
