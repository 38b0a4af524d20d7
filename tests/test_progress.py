"""The progress line's ETA: measured from the simulation's pace, not from the pause while
numba compiles the kernels on their first use (which once printed "ETA 1235202 s")."""
from __future__ import annotations

from types import SimpleNamespace

import pytest

from drystone.mechanics import monitors


class Clock:
    def __init__(self):
        self.now = 1000.0

    def __call__(self):
        return self.now


def test_eta_ignores_a_compilation_pause(monkeypatch, capsys):
    clock = Clock()
    monkeypatch.setattr(monitors.time, "time", clock)
    run = SimpleNamespace(prog=SimpleNamespace(end=10.0, stages=[SimpleNamespace(type="rest")],
                                               tilt_deg=lambda t: 0.0),
                          spec_name="x", engine=SimpleNamespace(contacts=lambda: SimpleNamespace(fn=[])))
    p = monitors.Progress(every_s=5.0)
    p.on_step(run, 0.0, 0)            # the first step: the clock starts
    clock.now += 60.0                 # numba compiles the next kernel: no simulated time passes
    p.on_step(run, 0.001, 0)          # a pause > STALL_S: the clock restarts here
    for k in range(1, 11):            # then 1 s of wall time per 0.1 s simulated
        clock.now += 1.0
        p.on_step(run, 0.001 + 0.1 * k, 0)
    t, frac = 0.001 + 1.0, (0.001 + 1.0) / 10.0
    # 1 s simulated in 10 s of wall time since the pause: 10 - 1.001 s left to simulate -> 89.99 s
    assert p.eta(clock.now, frac) == pytest.approx(10.0 * (10.0 - 1.001))
    line = capsys.readouterr().out.strip().splitlines()[-1]
    assert "ETA" in line and float(line.split("ETA")[1].split()[0]) < 100


def test_no_eta_before_any_pace():
    p = monitors.Progress()
    assert p.eta(0.0, 0.5) is None


def test_kernels_cached_reads_numba_cache(monkeypatch, tmp_path):
    """The runner announces the compilation when numba's cache has no compiled step for the
    current kernel sources (``drystone.kernels_cached``)."""
    import drystone

    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    assert not drystone.kernels_cached()
    (tmp_path / "drystone_x").mkdir()
    (tmp_path / "drystone_x" / "contact_step.advance-400.py311.nbi").write_bytes(b"")
    assert drystone.kernels_cached()
