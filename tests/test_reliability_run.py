"""Issue 12, runs and sweeps: nothing earlier is lost, nothing unstable is reported as a
result, interrupts stop YADE, a results folder has one writer, summary.json comes last.
Each test reproduces the fault of the issue and asserts the named error."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import tolerances as tol
from conftest import requires_yade
from drystone.model import case as casemod
from drystone import paths, runner, sweep
from drystone.mechanics import stability

BOX = {"generator": "boxes_on_platform", "boxes": [{"id": 1, "center_xy": [0.0, 0.0], "size": [0.2, 0.2, 0.2]}],
       "damping": 0.5}


def _case(duration=0.2, **extra) -> dict:
    c = {"case": {"name": "box", "geometry": BOX},
         "stages": [{"type": "gravity", "duration": duration, "ramp": duration / 2}],
         "output": {"interval": 0.01}}
    c.update(extra)
    return c


def _files(out: Path) -> dict:
    return {p.name: p.read_bytes() for p in sorted(out.iterdir()) if p.is_file()}


def descendants(root: int) -> dict[int, str]:
    """Pids of the live processes (not zombies) that descend from process ``root``, with their
    command lines: {pid: command line}."""
    parent, cmd = {}, {}
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                stat = (d / "stat").read_text().rsplit(")", 1)[1].split()
                c = (d / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
            except (OSError, IndexError):
                continue
            if stat[0] != "Z":
                parent[int(d.name)], cmd[int(d.name)] = int(stat[1]), c
    out, todo = {}, [root]
    while todo:
        p = todo.pop()
        for k, pp in parent.items():
            if pp == p and k not in out:
                out[k] = cmd[k]
                todo.append(k)
    return out


def alive(pids) -> list[int]:
    """Those of ``pids`` that still run (not zombies)."""
    out = []
    for pid in pids:
        try:
            if Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z":
                out.append(pid)
        except (OSError, IndexError):
            pass
    return out


def _yade_processes(root: int) -> list[int]:
    """Pids of the YADE processes under process ``root`` (a run's own, or the worker making its
    runs, drystone.simulate)."""
    return [pid for pid, cmd in descendants(root).items() if "yade" in cmd]


# -- plain Python: the stability checks ---------------------------------------------------
def test_energy_watch_passes_free_fall_and_flags_growth_without_work():
    m, g, dt = 2.0, 9.81, 0.01
    w = stability.EnergyWatch(m * g)
    for k in range(200):  # free fall: kinetic energy = the work of gravity, exactly
        t = k * dt
        v = np.array([[0.0, 0.0, -g * t]])
        assert w.update(t, 0.5 * m * (g * t) ** 2, 0.0, stability.load_power([m], v, [0, 0, -g])) is None
    w = stability.EnergyWatch(m * g)
    msg = None
    for k in range(200):  # a block at rest whose energy doubles every step (an unstable integrator)
        msg = msg or w.update(k * dt, 1e-6 * 2.0 ** k, 0.0, 0.0)
    assert msg and "unstable" in msg


def test_energy_watch_counts_injected_velocity_jumps():
    w = stability.EnergyWatch(1.0)
    assert w.update(0.0, 0.0, 0.0, 0.0) is None
    w.inject(5.0)
    assert w.update(0.01, 5.0, 0.0, 0.0) is None  # the jump's energy is not a blow-up
    assert "unstable" in w.update(0.02, 50.0, 0.0, 0.0)


def test_non_finite_and_tunnelling_messages():
    assert stability.non_finite(1.0, a=[1.0, 2.0]) is None
    assert "velocities" in stability.non_finite(1.0, velocities=[np.nan], positions=[0.0])
    assert stability.tunnelling([1e-4], [0.04], [0.2], [0.05], ["1-2"]) is None  # 2.5 mm deep
    msg = stability.tunnelling([1e-3], [0.04], [0.2], [0.04], ["1-2"])  # 25 mm > half of 40 mm
    assert "contact 1-2" in msg and "pass through" in msg


# -- sweeps without YADE ----------------------------------------------------------------------
def _fake_run(out: Path, overrides: list[str]):
    out.mkdir(parents=True)
    (out / "summary.json").write_text(json.dumps({"inputs": {"provenance": {"overrides": overrides}}}))
    (out / "run_info.json").write_text("{}")
    np.savez_compressed(out / "histories.npz", t=np.arange(1000.0), pos=np.zeros((1000, 3)))


def test_sweep_reruns_a_run_with_corrupt_histories_or_a_non_dict_summary(tmp_path):
    job = sweep.Job("r", "case.toml", ["a=1"], str(tmp_path / "r"))
    _fake_run(tmp_path / "r", ["a=1"])
    assert sweep.finished(job)
    p = tmp_path / "r" / "histories.npz"
    good = p.read_bytes()
    p.write_bytes(good[: len(good) // 2])  # truncated (a run killed while writing, a full disk)
    assert not sweep.finished(job)
    b = bytearray(good)
    b[120] ^= 0xFF  # one byte of the first member's data flipped: its CRC fails
    p.write_bytes(bytes(b))
    assert not sweep.finished(job)
    p.write_bytes(good)
    assert sweep.finished(job)
    (tmp_path / "r" / "summary.json").write_text("[]")
    assert not sweep.finished(job)  # no traceback: just not finished


def test_a_finished_run_moved_to_another_folder_keeps_its_fingerprint(tmp_path):
    """spec.json records the absolute folder it was written in; a results folder copied from
    another checkout must still be recognised by what it simulates (its excitation file is
    read beside it, not at the old path)."""
    from drystone import runner

    out = tmp_path / "moved" / "r"
    _fake_run(out, ["a=1"])
    np.save(out / "excitation_0.npy", np.array([0.0, 1.0, -1.0]))
    stage = {"type": "record", "start": 0.0, "end": 1.0, "params": {"acc_file": "excitation_0.npy"}}
    spec = {"format": "drystone-spec", "version": 2, "out_dir": str(tmp_path / "gone" / "r"), "stages": [stage]}
    (out / "spec.json").write_text(json.dumps(spec))
    job = sweep.Job("r", "case.toml", ["a=1"], str(out))
    want = runner.fingerprint(dict(spec, out_dir=str(out)))
    assert sweep.finished(job, want)
    np.save(out / "excitation_0.npy", np.array([0.0, 1.0, -2.0]))  # another record: run again
    assert not sweep.finished(job, want)


# -- with YADE ----------------------------------------------------------------------------
@requires_yade
def test_a_failing_rerun_keeps_the_good_run(outdir):
    out = outdir / "box"
    runner.run_dict(_case(), outdir / "box.toml", out_dir=out, quiet=True)
    before = _files(out)
    assert "summary.json" in before and "histories.npz" in before
    with pytest.raises(casemod.CaseError, match="step"):  # refused before anything is touched
        runner.run(outdir / "box.toml", ["time.step=1.0"], out_dir=out, quiet=True)
    assert _files(out) == before
    # a run that fails inside YADE leaves the good run too: a sudden force whose static
    # depth (F / K_n A = 20 mm) passes the check before the run (25 mm: half the 50 mm
    # platform) overshoots to about twice that without damping, and tunnels
    bad = _case(forces=[{"block": 1, "force": [0.0, 0.0, -0.02 * 2e8 * 0.04], "start": 0.05}])
    bad["case"]["geometry"] = dict(BOX, damping=0.0)
    with pytest.raises(runner.RunError, match="stopped.*penetrates") as e:
        runner.run_dict(bad, outdir / "bad.toml", out_dir=out, quiet=True)
    assert "unchanged" in str(e.value)
    assert _files(out) == before


@requires_yade
@pytest.mark.parametrize("force", [-1e308, -1e9])
def test_huge_forces_are_refused_before_the_run(outdir, force):
    case = _case(forces=[{"block": 1, "force": [0.0, 0.0, force], "start": 0.05}])
    with pytest.raises(casemod.CaseError, match=r"\[\[forces\]\] #1: .* N on block 1 .*pass through"):
        runner.run_dict(case, outdir / "f.toml", out_dir=outdir / "f", quiet=True)
    assert not (outdir / "f" / "summary.json").exists()


@requires_yade
def test_a_second_run_into_a_locked_folder_is_refused(outdir):
    out = outdir / "box"
    with runner.FolderLock(out):
        with pytest.raises(runner.RunError, match="another run"):
            runner.run_dict(_case(), outdir / "box.toml", out_dir=out, quiet=True)
    assert not out.exists()  # the refused run wrote nothing


@requires_yade
def test_summary_is_the_last_file_written(outdir):
    out = outdir / "box"
    runner.run_dict(_case(), outdir / "box.toml", out_dir=out, quiet=True)
    last = max(out.iterdir(), key=lambda p: p.stat().st_mtime_ns)
    assert last.name == "summary.json"


def _terminal_sigint():
    """A child as a terminal starts it: SIGINT at its default (a shell without job control
    starts background commands with SIGINT ignored, and Python then never raises
    KeyboardInterrupt)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _start(args, cwd) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "drystone", *args], cwd=cwd, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, preexec_fn=_terminal_sigint)


def _kill(p: subprocess.Popen, pids) -> None:
    """Kill ``p`` and the processes ``pids`` (its YADE, found while it ran)."""
    if p.poll() is None:
        p.kill()
        p.wait()
    for pid in alive(pids):
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass


def _yade_running(p: subprocess.Popen, log: Path, found: list) -> bool:
    """Whether ``log`` shows a run's first stage and YADE runs under ``p``; their pids into ``found``."""
    if not (log.is_file() and "stage 1/1" in log.read_text()):
        return False
    found.extend(pid for pid in _yade_processes(p.pid) if pid not in found)
    return bool(found)


def _wait_for(pred, timeout=120.0):
    t0 = time.time()
    while time.time() - t0 < timeout:
        if pred():
            return True
        time.sleep(0.2)
    return False


@requires_yade
def test_ctrl_c_on_a_run_kills_yade_and_keeps_the_folder(outdir):
    (outdir / "long.toml").write_text(runner.to_toml(_case(duration=600.0)))
    out = outdir / "long"
    p = _start(["run", str(outdir / "long.toml"), "--out", str(out)], paths.ROOT)
    stage = runner.staging_folder(out)
    yade = []
    try:
        assert _wait_for(lambda: _yade_running(p, stage / "log.txt", yade)), "YADE did not start"
        p.send_signal(signal.SIGINT)
        _, err = p.communicate(timeout=60)
        assert p.returncode == 130, err
        assert _wait_for(lambda: not alive(yade), 10), "YADE was orphaned"
        assert not (out / "summary.json").exists()
    finally:  # a failed test must not leave a 600 s run behind
        _kill(p, yade)


@requires_yade
def test_ctrl_c_on_a_sweep_stops_the_pool_and_records_what_finished(outdir):
    (outdir / "base.toml").write_text(runner.to_toml(_case()))
    (outdir / "s.toml").write_text('[sweep]\nname = "s"\ncase = "base.toml"\n\n'
                                   '[[runs]]\nname = "short"\nset = []\n\n'
                                   '[[runs]]\nname = "long"\nset = ["stages.0.duration=600.0"]\n\n'
                                   '[[runs]]\nname = "queued"\nset = ["stages.0.duration=0.3"]\n')
    env_results = outdir / "results"
    code = ("import sys; from pathlib import Path; from drystone import sweep, cli; cli.interrupt_on_sigterm();\n"
            "try:\n r = sweep.run(sys.argv[1], workers=1, results=Path(sys.argv[2]), heartbeat_s=3600)\n"
            "except KeyboardInterrupt:\n sys.exit(99)\n"
            "sys.exit(130 if r['interrupted'] else 0)")
    p = subprocess.Popen([sys.executable, "-c", code, str(outdir / "s.toml"), str(env_results)], cwd=paths.ROOT,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, preexec_fn=_terminal_sigint)
    long_stage = runner.staging_folder(env_results / "s" / "long")
    yade = []
    try:
        assert _wait_for(lambda: _yade_running(p, long_stage / "log.txt", yade), 240), "the long run did not start"
        p.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=120)
        assert p.returncode == 130, out + err
        assert _wait_for(lambda: not alive(yade), 10), "YADE was orphaned"
    finally:
        _kill(p, yade)
    runs = {r["name"]: r["status"] for r in json.loads((env_results / "s" / "sweep.json").read_text())["runs"]}
    assert runs == {"short": "done", "long": "interrupted", "queued": "pending"}
    assert not (env_results / "s" / "queued").exists()
    assert "Traceback" not in err


def test_keys_piped_into_head_has_no_traceback():
    r = subprocess.run(f"{sys.executable} -m drystone keys | head -1", shell=True, cwd=paths.ROOT,
                       capture_output=True, text=True)
    assert r.stdout.strip() and "Traceback" not in r.stderr and "BrokenPipe" not in r.stderr


def test_energy_bound_ratio_of_a_free_fall_is_one_half():
    """Replayed on recorded samples: free fall turns the work of gravity W into kinetic
    energy, E - E_0 = W against a bound 2 W + E_tol: the ratio tends to 1/2."""
    g, m = 9.81, np.array([3.0])
    t = np.linspace(0.0, 2.0, 201)
    vel = np.zeros((len(t), 1, 3))
    vel[:, 0, 2] = -g * t
    ke = 0.5 * m[0] * (g * t) ** 2
    r = stability.energy_bound_ratio(t, m, vel, np.tile([0.0, 0.0, -g], (len(t), 1)), ke, np.zeros_like(t), g)
    assert tol.FREE_FALL_RATIO_MIN < r < 0.5


def test_a_geometry_without_platform_is_refused(tmp_path):
    from drystone.geometry import blockfile as bf

    data = {"format": bf.FORMAT, "version": bf.VERSION, "materials": {"stone": {"density": 2300.0, "kn": 2e8,
                                                                               "kt": 1e8, "mu": 0.6, "damping": 0.1}},
            "blocks": [{"id": 1, "role": "free", "material": "stone",
                        "vertices": bf.box_vertices((0, 0, 0.1), (0.2, 0.2, 0.2))}]}
    with pytest.raises(bf.GeometryError, match="no block has role 'platform' or 'fixed'"):
        bf.parse(data, "walls.json")
