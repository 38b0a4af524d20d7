"""The stage types (drystone/model/stages.py; issue 13, item 3): one class per type with its keys,
its checks, its resolution and what it imposes at t."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from drystone.model import case as casemod
from drystone.model import stages
from drystone.model.case import CaseError, Key
from drystone.model.loading import LoadProgramme, Stage
from drystone.model.stages import REGISTRY, ResolveContext


def test_registry_has_every_type_in_the_readme_order():
    assert list(REGISTRY) == ["gravity", "settlement", "tilt", "excitation", "rest"]
    for name, t in REGISTRY.items():
        assert t.name == name
        assert list(t.keys)[-1] == "name"  # every stage may carry a name (overrides by name)
        assert all(isinstance(k, Key) for k in t.keys.values())


def test_the_case_reads_the_stage_keys_from_the_registry(tmp_path):
    """One home for the keys: the case fills a stage from its type's keys, and the README
    table (case.describe) lists them."""
    table = casemod.describe()
    for name, t in REGISTRY.items():
        for key in t.keys:
            assert f'| [[stages]] type = "{name}" | `{key}` |' in table
    raw = {"case": {"geometry": {"generator": "four_blocks"}}, "stages": [{"type": "tilt", "rate_deg_s": 1.0,
                                                                          "until_collapse": True}]}
    st = casemod.validate(raw, "t.toml", tmp_path)["stages"][0]
    assert set(st) == set(REGISTRY["tilt"].keys) | {"type"}
    assert st["max_deg"] == REGISTRY["tilt"].keys["max_deg"].default


def _filled(stype: str, **given) -> dict:
    s = {name: (None if k.default is casemod.REQUIRED else k.default) for name, k in REGISTRY[stype].keys.items()}
    s.update(given, type=stype)
    return s


def test_validate_per_type():
    s = _filled("gravity", duration=2.0)
    REGISTRY["gravity"].validate(s, "w", last=True, base_dir=Path("."))
    assert s["ramp"] == 1.0  # half the duration
    with pytest.raises(CaseError, match=r"w: 'ramp' \(3.0 s\) exceeds"):
        REGISTRY["gravity"].validate(_filled("gravity", duration=2.0, ramp=3.0), "w", last=True, base_dir=Path("."))
    with pytest.raises(CaseError, match="either 'to_deg' or 'until_collapse"):
        REGISTRY["tilt"].validate(_filled("tilt", rate_deg_s=1.0), "w", last=True, base_dir=Path("."))
    with pytest.raises(CaseError, match="exceeds 90 deg"):
        REGISTRY["tilt"].validate(_filled("tilt", rate_deg_s=1.0, to_deg=95.0), "w", last=True, base_dir=Path("."))
    quiet = _filled("rest", duration=1.0, until_kinetic_below=1.0)
    REGISTRY["rest"].validate(dict(quiet), "w", last=True, base_dir=Path("."))
    with pytest.raises(CaseError, match="only the last stage"):
        REGISTRY["rest"].validate(quiet, "w", last=False, base_dir=Path("."))
    with pytest.raises(CaseError, match="a sine needs 'frequency_hz'"):
        REGISTRY["excitation"].validate(_filled("excitation", motion="sine", duration=1.0), "w", last=True,
                                        base_dir=Path("."))


def _ctx(tmp_path) -> ResolveContext:
    return ResolveContext(where="w", out=tmp_path, dt=1e-4, ids={0, 1, 2}, free={1, 2})


def test_resolve_per_type(tmp_path):
    ctx = _ctx(tmp_path)
    assert REGISTRY["gravity"].resolve(_filled("gravity", duration=2.0, ramp=1.0), 0, ctx) == (2.0, {"ramp": 1.0})
    tilt = _filled("tilt", rate_deg_s=2.0, to_deg=10.0, towards="-x")
    dur, params = REGISTRY["tilt"].resolve(tilt, 1, ctx)
    assert dur == pytest.approx(5.0) and ctx.tilt_deg == 10.0 and params["towards"] == [-1.0, 0.0, 0.0]
    with pytest.raises(CaseError, match=r"#3: tilt target 10.0 deg is not above the current 10.0 deg"):
        REGISTRY["tilt"].resolve(tilt, 2, ctx)  # the tilt carries over from stage to stage
    with pytest.raises(CaseError, match="settlement block 1 must be a fixed block"):
        REGISTRY["settlement"].resolve(_filled("settlement", duration=1.0, block=1, displacement=0.01), 0, ctx)
    assert REGISTRY["rest"].resolve(_filled("rest", duration=1.0), 0, ctx) == (1.0, {})  # the old fingerprint
    dur, params = REGISTRY["excitation"].resolve(_filled("excitation", motion="sine", frequency_hz=2.0,
                                                         duration=1.0, start="displacement"), 3, ctx)
    assert dur == 1.0 and params["acc_file"] == "excitation_4.npy" and (tmp_path / "excitation_4.npy").is_file()
    assert params["initial_relative_velocity"] == pytest.approx([0.0, -0.5 / (2 * np.pi * 2.0), 0.0])
    assert ctx.excitations[0]["stage"] == 4


def test_types_that_impose_nothing_return_neutral_values():
    st = Stage("rest", 0.0, 1.0, {})
    t = REGISTRY["rest"]
    ts = np.array([0.25, 0.5])  # the body-force hooks take arrays of times
    assert t.gravity_scale(st, ts) is None and t.base_acceleration(st, ts) is None and t.towards(st) is None
    assert np.array_equal(t.tilt_increment(st, ts), [0.0, 0.0]) and t.imposed_velocities(st, 0.5) == {}
    assert np.array_equal(t.velocity_jump(st), np.zeros(3)) and t.settle(st, 1.0) is None
    assert t.moving_blocks(st) == []


def test_a_new_type_needs_only_its_class(monkeypatch):
    """The programme asks the stage types, not their names: a type registered here (a
    constant base acceleration) is applied without touching drystone/model/loading.py."""

    class Push(stages.StageType):
        name = "push"
        keys = {"duration": Key(1.0, "s", "stage length", float, positive=True)}

        def base_acceleration(self, st, t):
            on = (st.start <= t) & (t < st.end)
            return on, np.tile([1.0, 0.0, 0.0], (int(on.sum()), 1))

    monkeypatch.setitem(REGISTRY, "push", Push())
    prog = LoadProgramme([Stage("gravity", 0.0, 1.0, {"ramp": 0.0}), Stage("push", 1.0, 2.0)], 9.81)
    assert prog.body_acceleration(1.5) == pytest.approx([-1.0, 0.0, -9.81])
    assert prog.body_acceleration(0.5) == pytest.approx([0.0, 0.0, -9.81])
    assert list(Push.keys) == ["duration", "name"]


def test_an_unknown_type_is_refused():
    with pytest.raises(ValueError, match="unknown stage type 'spin'"):
        Stage("spin", 0.0, 1.0)
