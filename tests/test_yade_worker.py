"""The YADE worker (drystone/yade_scripts/worker.py, drystone/simulate.py ``_worker``): one YADE
process runs many cases in turn. A case run as a later run of a worker, after other cases
(a multi-part stone's clump, a shorter run), gives the histories of the same case run in a
YADE process of its own, bit for bit (one thread is bitwise reproducible: the same
arithmetic from the same state, so exact equality is exact by construction), and the same
run_info apart from its timings. A run that fails in the worker is reported as a run alone
is (RunError) and ends that worker; the next run gets a new one."""
from __future__ import annotations

import json

import numpy as np
import pytest

from conftest import requires_yade
from drystone import paths, runner, simulate

pytestmark = [requires_yade, pytest.mark.yade]

SHORT = ["stages.0.duration=0.2", "stages.0.ramp=0.1"]
#: small runs that differ in what YADE and the step hold: four boxes (the compiled step, then
#: YADE's contact geometry, then YADE's stock law), and an L-shaped stone of two parts (a
#: clump) toppling on a tilting platform
CASES = {"four_blocks": (paths.CASES / "gravity4.toml", SHORT),
         "four_blocks_yade_geometry": (paths.CASES / "gravity4.toml", SHORT + ["contact.detection=yade"]),
         "four_blocks_stock_law": (paths.CASES / "gravity4.toml", SHORT + ["contact.law=stock_volumetric"]),
         "l_stone": (paths.CASES / "examples" / "l_stone_tilt.toml",
                     SHORT + ["stages.1.to_deg=16.5", "stages.1.rate_deg_s=20"])}
#: runs that are not bitwise reproducible even between two YADE processes of their own
NOT_BITWISE = {"four_blocks_stock_law"}
#: run_info.json's figures of the process and its clock, which differ between any two runs
TIMINGS = {"wall_time_s", "us_per_step", "python_us_per_step", "kernel_us_per_step", "max_rss_mib"}


def _run(tmp_path, tag: str, name: str) -> tuple[dict, dict]:
    case, over = CASES[name]
    out = tmp_path / f"{tag}_{name}"
    runner.run(case, over, out_dir=out, quiet=True)
    with np.load(out / "histories.npz") as h:
        hist = {k: h[k] for k in h.files}
    info = json.loads((out / "run_info.json").read_text())
    return hist, {k: v for k, v in info.items() if k not in TIMINGS}


def _same(a: dict, b: dict) -> list[str]:
    """The names of the arrays that are not the same bytes (and dtype, shape) in both."""
    return sorted(k for k in set(a) | set(b) if k not in a or k not in b or a[k].dtype != b[k].dtype
                  or a[k].shape != b[k].shape or a[k].tobytes() != b[k].tobytes())


def test_later_runs_of_a_worker_are_bit_for_bit_a_fresh_process(tmp_path, monkeypatch):
    """YADE's stock law runs among them, but its own run is not compared: its histories are not
    bitwise reproducible even between two processes of their own (round-off, 1e-16 m)."""
    monkeypatch.setenv("DRYSTONE_YADE_WORKER", "0")
    fresh = {n: _run(tmp_path, "fresh", n) for n in CASES if n not in NOT_BITWISE}
    monkeypatch.setenv("DRYSTONE_YADE_WORKER", "1")
    pids = []
    order = ["l_stone", "four_blocks_yade_geometry", "four_blocks_stock_law", "four_blocks", "l_stone"]
    for k, name in enumerate(order):
        h, info = _run(tmp_path, f"worker{k}", name)
        pids.append(simulate.own_worker(1).proc.pid)
        if name not in NOT_BITWISE:
            assert _same(h, fresh[name][0]) == [], f"run {k + 1} of the worker ({name})"
            assert info == fresh[name][1], f"run {k + 1} of the worker ({name})"
    assert len(set(pids)) == 1, "the runs were not made by one worker"


def test_a_failed_run_ends_the_worker_and_the_next_gets_a_new_one(tmp_path, monkeypatch):
    """A spec the driver cannot read fails in the worker (its traceback in log.txt, exit 1):
    RunError as for a run alone, that worker gone; the next run is made by a new worker."""
    monkeypatch.setenv("DRYSTONE_YADE_WORKER", "1")
    _run(tmp_path, "before", "four_blocks")
    first = simulate.own_worker(1).proc
    stage = tmp_path / "bad"
    stage.mkdir()
    spec = json.loads((tmp_path / "before_four_blocks" / "spec.json").read_text())
    del spec["blocks"]
    with pytest.raises(simulate.RunError, match=r"YADE failed \(exit 1\)(?s:.*)missing \[.blocks.\]"):
        simulate.simulate(spec, stage, quiet=True, where="bad")
    assert first.poll() == 1 and simulate.own_worker(1) is None
    h, _ = _run(tmp_path, "after", "four_blocks")
    assert simulate.own_worker(1).proc is not first
    assert _same(h, _run(tmp_path, "again", "four_blocks")[0]) == []


def _fork_run(tmp_path, tag: str) -> tuple[dict, int]:
    """In a forked child: a run, and the pid of the worker that made it."""
    h, _ = _run(tmp_path, tag, "four_blocks")
    return h, simulate.own_worker(1).proc.pid


def test_a_forked_child_gets_its_own_worker(tmp_path, monkeypatch):
    """A process forked from one that holds a worker (a sweep's pool, a study's forked
    analyses) starts its own, never writes to its parent's; both give the same histories."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    monkeypatch.setenv("DRYSTONE_YADE_WORKER", "1")
    mine, _ = _run(tmp_path, "parent", "four_blocks")
    pid = simulate.own_worker(1).proc.pid
    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("fork")) as pool:
        theirs, child_pid = pool.submit(_fork_run, tmp_path, "child").result()
    assert child_pid != pid and simulate.own_worker(1).proc.pid == pid
    assert _same(theirs, mine) == [] and _same(_run(tmp_path, "parent_again", "four_blocks")[0], mine) == []
    assert simulate.own_worker(1).proc.pid == pid


def test_a_thread_keeps_a_worker_of_its_own_which_ends_with_it(tmp_path, monkeypatch):
    """A thread that makes runs (a Dask worker's task thread) makes them all in one worker of
    its own, not the main thread's; when the thread ends, the kernel kills that YADE process
    (``die_with_parent``) and the next call forgets it."""
    import threading

    monkeypatch.setenv("DRYSTONE_YADE_WORKER", "1")
    made = []

    def runs():
        for k in range(2):
            made.append((_run(tmp_path, f"thread{k}", "four_blocks")[0], simulate.own_worker(1)))

    t = threading.Thread(target=runs)
    t.start()
    t.join()
    (h0, w0), (h1, w1) = made
    assert w0 is w1 and w0.runs == 2 and w0.key == (1, t.ident) and w0.key[1] != threading.get_ident()
    assert _same(h0, h1) == []
    assert w0.proc.wait(timeout=30) == -9  # SIGKILL from the kernel: its thread ended
    simulate._drop_ended()
    assert w0.key not in simulate._WORKERS


def test_a_worker_is_replaced_after_its_share_of_runs(tmp_path, monkeypatch):
    """A worker's process grows by its runs: after ``RUNS_PER_WORKER`` runs the next run gets a
    new one (the same histories)."""
    monkeypatch.setenv("DRYSTONE_YADE_WORKER", "1")
    monkeypatch.setattr(simulate, "RUNS_PER_WORKER", 2)
    simulate.end_workers()
    first = [_run(tmp_path, f"r{k}", "four_blocks")[0] for k in range(2)]
    pid = simulate.own_worker(1).proc.pid
    assert simulate.own_worker(1).runs == 2 and simulate.own_worker(1).growth_mib() >= 0.0
    h, _ = _run(tmp_path, "r2", "four_blocks")
    assert simulate.own_worker(1).proc.pid != pid and simulate.own_worker(1).runs == 1
    assert _same(first[0], first[1]) == [] and _same(h, first[0]) == []
