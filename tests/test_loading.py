"""The load programme in the platform frame (drystone/model/loading.py)."""
import math

import numpy as np
import pytest

import tolerances as tol
from drystone.model.loading import LoadProgramme, Stage

G = 9.81


def prog():
    return LoadProgramme([
        Stage("gravity", 0.0, 2.0, {"ramp": 1.0}),
        Stage("tilt", 2.0, 12.0, {"rate_deg_s": 1.0, "towards": [0, 1, 0]}),
        Stage("settlement", 12.0, 17.0, {"block": 3, "displacement": 0.05}),
        Stage("excitation", 17.0, 18.0, {"acc": np.array([0.0, 1.0, 2.0]), "dt": 0.5, "direction": [1, 0, 0]}),
    ], G)


def test_gravity_ramp_then_hold():
    p = prog()
    assert p.body_acceleration(0.5)[2] == pytest.approx(-G / 2)
    assert p.body_acceleration(1.5) == pytest.approx([0, 0, -G])


def test_tilt_rotates_gravity_towards_fall_direction():
    """At 10 deg towards +y: g_eff = g (sin 10, -cos 10) in (y, z); magnitude g."""
    p = prog()
    g = p.body_acceleration(12.0)
    assert p.tilt_deg(12.0) == pytest.approx(10.0)
    assert g == pytest.approx([0, G * math.sin(math.radians(10)), -G * math.cos(math.radians(10))])
    assert p.true_vertical(12.0) @ g == pytest.approx(-G)  # gravity is along the true vertical
    top = p.to_world(12.0, np.array([[0, 0, 1.0]]))[0]
    assert top[1] > 0 and top @ p.to_world(12.0, np.array([[0, 0, 1.0]]))[0] == pytest.approx(1.0)


def test_settlement_velocity():
    p = prog()
    assert p.imposed_velocities(13.0)[3] == pytest.approx([0, 0, -0.01])
    assert p.imposed_velocities(17.5)[3] == pytest.approx([0, 0, 0])


def test_base_acceleration_is_an_inertial_body_force():
    p = prog()
    assert p.base_acceleration(17.25) == pytest.approx([0.5, 0, 0])
    g = p.body_acceleration(17.25)
    assert g[0] == pytest.approx(-0.5)  # the block feels -a_base


# -- Eq. 9 as a displacement (issue 11, item 2) and settling rest stages (item 4) ---------------

def _case(tmp_path, excitation: dict, rest: dict | None = None) -> dict:
    from drystone.model import case as casemod
    from drystone import paths

    raw = {"case": {"geometry": str(paths.CASES / "examples" / "one_block.json")},
           "stages": [{"type": "gravity", "duration": 0.2},
                      dict({"type": "excitation", "motion": "sine", "duration": 1.0, "direction": "y"}, **excitation)]}
    if rest is not None:
        raw["stages"].append(dict({"type": "rest"}, **rest))
    return casemod.validate(raw, "test.toml", tmp_path)


@pytest.mark.parametrize("f, amp, pga_g, direction", [(1.0, 0.5, None, "y"), (0.1, 0.5, None, "x"),
                                                      (0.976, 0.5, 0.3, "y")])
def test_sine_started_as_displacement_gives_every_free_block_minus_the_base_velocity(tmp_path, f, amp, pga_g,
                                                                                    direction):
    """d(t) = A/w^2 sin(wt) has d'(0) = A/w (0.080 m/s at 1 Hz, 0.80 m/s at 0.1 Hz) and
    d''(t) = -A sin(wt), the sampled acceleration: the resolved stage carries -A/w along the
    excitation direction, the load programme gives it at the stage's start only, and the
    samples are the same as with start = 'rest'."""
    from drystone import runner

    exc = {"frequency_hz": f, "amplitude": amp, "direction": direction, "start": "displacement"}
    if pga_g is not None:
        exc["pga_g"] = pga_g
    spec = runner.resolve(_case(tmp_path / "d", exc), "test.toml", tmp_path)
    st = spec["stages"][1]
    a = amp if pga_g is None else pga_g * 9.80665
    e = np.array(runner.AXES[direction])
    v_b = a / (2 * math.pi * f)
    assert st["params"]["start"] == "displacement"
    assert st["params"]["initial_relative_velocity"] == pytest.approx(-v_b * e, rel=tol.EXACT_REL)
    assert spec["excitations"][0]["initial_relative_velocity_m_s"] == st["params"]["initial_relative_velocity"]
    acc = np.load(tmp_path / st["params"]["acc_file"])
    dt = st["params"]["dt"]
    # the base velocity of the samples from v_b: trapezoidal integral of a(t) = -A sin(wt) returns
    # to v_b after each whole period (the jump is consistent with the samples' sign)
    n = int(round(1.0 / (f * dt)))
    if n < len(acc):
        v = v_b + np.concatenate([[0.0], np.cumsum(0.5 * (acc[1:] + acc[:-1]) * dt)])
        assert v[n] == pytest.approx(v_b, rel=tol.TRAPEZOID_REL)
        assert v[n // 4] == pytest.approx(0.0, abs=tol.TRAPEZOID_REL * v_b)  # d' = A/w cos(wt) = 0 at a quarter period
    stages = [Stage(**s) for s in spec["stages"]]
    p = LoadProgramme(stages, G)
    assert p.velocity_jump(0) == pytest.approx([0, 0, 0])
    assert p.velocity_jump(1) == pytest.approx(-v_b * e)
    rest = runner.resolve(_case(tmp_path / "r", dict(exc, start="rest")), "test.toml", tmp_path / "r")
    assert rest["stages"][1]["params"]["initial_relative_velocity"] == [0.0, 0.0, 0.0]
    assert np.array_equal(np.load(tmp_path / "r" / rest["stages"][1]["params"]["acc_file"]), acc)
    assert runner.fingerprint(rest) != runner.fingerprint(spec)


def test_start_and_settle_keys_are_checked(tmp_path):
    from drystone.model.case import CaseError

    with pytest.raises(CaseError, match=r"#2.*'start' = 'displacement' is defined for motion 'sine' only"):
        _case(tmp_path, {"motion": "white_noise", "start": "displacement"})
    with pytest.raises(CaseError, match=r"'start' must be one of"):
        _case(tmp_path, {"frequency_hz": 1.0, "start": "velocity"})
    with pytest.raises(CaseError, match="not both"):
        _case(tmp_path, {"frequency_hz": 1.0}, {"duration": 1.0, "until_kinetic_below": 1.0,
                                                "until_kinetic_below_per_weight": 1e-7})
    with pytest.raises(CaseError, match="settle_window"):
        _case(tmp_path, {"frequency_hz": 1.0}, {"duration": 1.0, "until_kinetic_below": 1.0, "settle_window": 2.0})
    # only the last stage may end the run early
    from drystone.model import case as casemod
    from drystone import paths
    raw = {"case": {"geometry": str(paths.CASES / "examples" / "one_block.json")},
           "stages": [{"type": "rest", "duration": 1.0, "until_kinetic_below": 1.0}, {"type": "rest", "duration": 1.0}]}
    with pytest.raises(CaseError, match=r"test.toml \[\[stages\]\] #1: .*only the last stage"):
        casemod.validate(raw, "test.toml", tmp_path)


def test_settle_threshold_absolute_or_per_weight(tmp_path):
    """The threshold is the given energy (J) or W x the given length (m)."""
    from drystone import runner

    for rest, weight, thr in (({"until_kinetic_below": 0.05}, 500.0, 0.05),
                              ({"until_kinetic_below_per_weight": 1e-7}, 5e5, 0.05)):
        spec = runner.resolve(_case(tmp_path, {"frequency_hz": 1.0}, dict(rest, duration=3.0, settle_window=1.0)),
                              "test.toml", tmp_path)
        p = LoadProgramme([Stage(**s) for s in spec["stages"]], G)
        assert p.settle(2, weight) == {"threshold_J": pytest.approx(thr), "window_s": 1.0}
        assert p.settle(1, weight) is None
    plain = runner.resolve(_case(tmp_path, {"frequency_hz": 1.0}, {"duration": 3.0}), "test.toml", tmp_path)
    assert plain["stages"][2]["params"] == {}  # a plain rest keeps its old fingerprint


def test_the_programme_of_a_version_1_spec_is_the_same():
    """spec.json of finished runs says "kind" (version 1): ``from_spec`` reads it as "type"."""
    stages = [{"kind": s.type, "start": s.start, "end": s.end, "params": s.params} for s in prog().stages]
    p, q = prog(), LoadProgramme.from_spec({"stages": stages, "gravity": G})
    assert [s.type for s in q.stages] == [s.type for s in p.stages]
    for t in (0.5, 5.0, 13.0, 17.25, 30.0):
        assert np.array_equal(q.body_acceleration(t), p.body_acceleration(t))
        assert q.imposed_velocities(t).keys() == p.imposed_velocities(t).keys() == {3}
    assert q.moving_blocks() == [3]


def _one_time(p: LoadProgramme, t: float) -> np.ndarray:
    """The body force at one time by the formulas written out in plain Python floats (the
    programme's per-step path before it took arrays): the reference for bit-for-bit checks."""
    st = {s.type: s for s in p.stages}
    g, tilt, exc = st["gravity"], st["tilt"], st["excitation"]
    scale = min(max((t - g.start) / g.params["ramp"], 0.0), 1.0)
    theta = 0.0 if t <= tilt.start else tilt.params["rate_deg_s"] * (min(t, tilt.end) - tilt.start)
    th = math.radians(theta)
    body = p.gravity * scale * (math.sin(th) * np.array(tilt.params["towards"], float) - math.cos(th) * np.array([0, 0, 1.0]))
    a = 0.0
    if exc.start <= t < exc.end:
        acc = exc.params["acc"]
        x = (t - exc.start) / exc.params["dt"]
        i = int(x)
        a = (acc[-1] if i < len(acc) else 0.0) if i + 1 >= len(acc) else acc[i] + (x - i) * (acc[i + 1] - acc[i])
    return body - float(a) * np.array(exc.params["direction"], float)


def test_many_times_at_once_are_each_time_alone_bit_for_bit():
    """``body_acceleration_at`` (a recorded sample's steps in one call, what the compiled
    loop is given) equals the per-time formula bit for bit, signs of zeros included, across
    the ramp, a tilt, a record held at its last sample and zero past it, and every stage
    boundary; the scalar methods agree with it."""
    p = LoadProgramme([
        Stage("gravity", 0.0, 2.0, {"ramp": 1.0}),
        Stage("tilt", 2.0, 12.0, {"rate_deg_s": 1.3, "towards": [0, -1, 0]}),
        Stage("excitation", 12.0, 14.0, {"acc": np.array([0.0, -1.0, 2.5]), "dt": 0.5, "direction": [1, 0, 0]}),
        Stage("rest", 14.0, 15.0, {}),
    ], G)
    rng = np.random.default_rng(1)
    ts = np.concatenate([rng.uniform(-0.5, 16.0, 2000), [0.0, 1.0, 2.0, 12.0, 12.5, 13.0, 13.5, 14.0, 15.0]])
    many = p.body_acceleration_at(ts)
    one = np.array([_one_time(p, t) for t in ts])
    assert np.array_equal(many, one) and np.array_equal(np.signbit(many), np.signbit(one))
    held = (ts >= 13.0) & (ts < 13.5)  # i = 2: the last sample held
    assert held.any() and np.all(p.base_acceleration_at(ts[held])[:, 0] == 2.5)
    past = (ts >= 13.5) & (ts < 14.0)
    assert past.any() and np.all(p.base_acceleration_at(ts[past]) == 0.0)
    for t in ts[:50]:
        assert np.array_equal(p.body_acceleration(t), p.body_acceleration_at(np.array([t]))[0])
        assert p.tilt_deg(t) == p.tilt_deg_at(np.array([t]))[0]


def test_the_field_ahead_is_each_steps_field_bit_for_bit():
    """``FieldAhead`` (the engines whose every step goes through the driver: the field a block
    of steps ahead) gives each step's ``body_acceleration`` bit for bit, across a stage's end, a
    block's end and a record's samples, and again after a step at a time it did not foresee;
    one computation per block."""
    from drystone.yade_scripts.quiet_steps import FieldAhead

    p = LoadProgramme([
        Stage("gravity", 0.0, 2.0, {"ramp": 1.0}),
        Stage("tilt", 2.0, 12.0, {"rate_deg_s": 1.3, "towards": [0, -1, 0]}),
        Stage("excitation", 12.0, 14.0, {"acc": np.array([0.0, -1.0, 2.5]), "dt": 0.5, "direction": [1, 0, 0]}),
    ], G)
    dt = 0.0123
    runs = [np.add.accumulate(np.concatenate([[t0], np.full(n - 1, dt)])) for t0, n in ((1.9, 300), (11.9, 200))]
    calls = []
    at = p.body_acceleration_at
    p.body_acceleration_at = lambda ts: calls.append(len(ts)) or at(ts)
    f = FieldAhead(p)
    got = np.array([f.at(t, dt) for t in np.concatenate(runs)])
    p.body_acceleration_at = at
    want = np.array([p.body_acceleration(t) for t in np.concatenate(runs)])
    assert np.array_equal(got, want) and np.array_equal(np.signbit(got), np.signbit(want))
    assert calls == [FieldAhead.BLOCK] * (-(-300 // FieldAhead.BLOCK) + -(-200 // FieldAhead.BLOCK))
