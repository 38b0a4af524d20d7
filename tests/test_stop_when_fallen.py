"""output.stop_when_fallen (drystone/mechanics/monitors.py Fallen): the run stops at the first
sample after gravity at which a stone fell (centroid lower than at the end of gravity by more
than half its height) or left the model, never during gravity nor for a stone that only
settled or rocked; the case key changes the run's fingerprint only when set; the collapse
analysis sets it unless --full-runs."""
from types import SimpleNamespace

import numpy as np

from drystone import paths
from drystone.mechanics import monitors
from drystone.model import case as casemod
from drystone.model import resolve


def _run(z):
    return SimpleNamespace(failure=None, dyn=np.array([1, 2]), bid={0: 0, 1: 11, 2: 12}, pos=np.array(z, float),
                           removed=np.zeros(3, bool), stop_at=None, spec_name="t")


def _sample(t):
    return SimpleNamespace(t=t)


def test_fallen_stops_once_a_stone_dropped_half_its_height_after_gravity(capsys):
    heights = np.array([np.inf, 0.4, 0.8])
    m = monitors.Fallen(heights, gravity_end_s=1.0)
    run = _run([[0, 0, -0.05], [0, 0, 0.2], [0, 0, 1.0]])
    run.pos[1, 2] = -5.0  # during gravity a drop counts for nothing (the reference is its end)
    m.on_sample(run, _sample(0.5))
    assert run.stop_at is None and m.z0 is None
    run.pos[1, 2] = 0.2
    m.on_sample(run, _sample(1.0))  # the reference
    run.pos[1, 2] = 0.2 - 0.19      # stone 11 dropped 0.19 < 0.2 = H/2: stands
    run.pos[2, 2] = 1.0 - 0.39      # stone 12 dropped 0.39 < 0.4
    m.on_sample(run, _sample(1.5))
    assert run.stop_at is None and m.info() == {"stopped_when_fallen": None}
    run.pos[2, 2] = 1.0 - 0.41
    m.on_sample(run, _sample(1.7))
    assert run.stop_at == 1.7 and m.info()["stopped_when_fallen"] == {"time_s": 1.7, "fell": [12], "left_model": []}
    assert "stopping" in capsys.readouterr().out


def test_a_stone_taken_out_of_the_scene_stops_the_run():
    m = monitors.Fallen(np.array([np.inf, 0.4, 0.8]), gravity_end_s=0.0)
    run = _run([[0, 0, 0], [0, 0, 0.2], [0, 0, 0.4]])
    m.on_sample(run, _sample(0.0))
    run.removed[1] = True
    m.on_sample(run, _sample(0.3))
    assert run.stop_at == 0.3 and m.info()["stopped_when_fallen"]["left_model"] == [11]


def test_the_key_is_hashed_only_when_set(tmp_path):
    case = paths.ROOT / "cases" / "examples" / "sliding_block_pulse.toml"
    plain = resolve.resolve(casemod.load(case), str(case), tmp_path / "a")
    cut = resolve.resolve(casemod.load(case, ["output.stop_when_fallen=true"]), str(case), tmp_path / "b")
    assert "stop_when_fallen" not in plain.output and cut.output["stop_when_fallen"] is True
    assert resolve.fingerprint(plain) != resolve.fingerprint(cut)
    off = resolve.resolve(casemod.load(case, ["output.stop_when_fallen=false"]), str(case), tmp_path / "c")
    assert resolve.fingerprint(off) == resolve.fingerprint(plain)
