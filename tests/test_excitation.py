"""Base excitation through the whole path (case -> platform-frame body force -> contact law),
against an independent fine-step integration of the rigid-plastic sliding block."""
import numpy as np
import pytest

import tolerances as tol
from conftest import requires_yade, run_case
from reference import sliding_block

pytestmark = [requires_yade, pytest.mark.yade]
G = 9.81


@pytest.mark.parametrize("mu, amp", [(0.05, 1.0), (0.3, 1.0)])
def test_sine_base_motion_sliding_block(outdir, mu, amp):
    """A 0.4 x 0.4 x 0.04 m slab under a 2 Hz base acceleration of amplitude 1 m/s^2 (the
    paper's Eq. 9 shape): relative displacement history equal to the rigid-plastic block's
    within 3 % of its peak (elastic joint deflection ~1e-6 m, the 2 % sampling of the sine
    and the joint's elastic stick phase); with mu g > amplitude it does not slide (< 1e-5 m)."""
    f = 2.0
    case = {"case": {"geometry": {"generator": "boxes_on_platform", "mu": mu, "damping": 0.8,
                                  "boxes": [{"id": 1, "center_xy": [0.0, 0.0], "size": [0.4, 0.4, 0.04]}]}},
            "stages": [{"type": "gravity", "duration": 0.4, "ramp": 0.2},
                       {"type": "excitation", "motion": "sine", "frequency_hz": f, "amplitude": amp,
                        "direction": "x", "duration": 1.5}],
            "output": {"interval": 0.005}}
    s, h, spec = run_case(case, outdir)
    t = h["t"]
    on = t >= 0.4
    u = h["pos"][on, 0, 0] - h["pos"][on, 0, 0][0]
    te = t[on] - 0.4
    ref = sliding_block(lambda x: -amp * np.sin(2 * np.pi * f * x), te, mu)
    if mu * G > amp:
        assert np.abs(u).max() < tol.NO_SLIDE_M
    else:
        peak = np.abs(ref).max()
        assert peak > 5e-3  # it really slides
        assert np.abs(u - ref).max() < tol.SLIDING_REL * peak
    assert spec["excitations"][0]["pga_m_s2"] == pytest.approx(amp, rel=tol.NUMERICAL_REL)


def test_sine_started_as_displacement_gives_a_sticking_block_the_velocity_jump(outdir):
    """Eq. 9 as a displacement (issue 11, item 2): the one-block example (0.2 m cube, 18.4 kg,
    mu 0.4) sticks on the platform after gravity; a 1 Hz, 0.5 m/s^2 sine started as a
    displacement gives it the relative velocity -A/w = -0.0796 m/s along y, i.e. the kinetic
    energy m (A/w)^2 / 2 = 0.058 J, which friction then dissipates over a slide of about
    0.8 mm (A < mu g: started from rest it would not slide at all). Then the last rest stage
    ends as soon as the kinetic energy has settled (item 4).

    Tolerances: over the time t1 from the jump to the first sample, friction (at most
    mu m g, the Coulomb cap) and the base acceleration (at most A) can change the velocity by
    (mu g + A) t1, which bounds the velocity and kinetic energy there. The rigid-plastic
    reference slide (tests/reference.py, same jump) differs from the penalty joint by the
    joint's elastic deflection under the friction force, shear mu m g / (K_t a) plus the
    centroid's shift from the rocking under the moment mu m g h/2, (mu m g h/2)/(K_n I) h/2
    (4.5e-5 m here): once while the friction builds up and, at the end, once more when it is
    released; plus one step of timing, (A/w) dt."""
    from drystone import paths

    f, amp, mu, g, b = 1.0, 0.5, 0.4, G, 0.2
    ts = 0.3  # stage start (s)

    def case(start):
        return {"case": {"geometry": str(paths.CASES / "examples" / "one_block.json")},
                "stages": [{"type": "gravity", "duration": ts, "ramp": 0.15},
                           {"type": "excitation", "motion": "sine", "frequency_hz": f, "amplitude": amp,
                            "direction": "y", "duration": 0.4, "start": start},
                           {"type": "rest", "duration": 2.0, "until_kinetic_below": 1e-7, "settle_window": 0.1}],
                "output": {"interval": 0.001}}

    s, h, spec = run_case(case("displacement"), outdir, "displacement")
    m = float(h["mass"][0])
    v_b = amp / (2 * np.pi * f)
    t = h["t"]
    i1 = int(np.flatnonzero(t >= ts)[0])
    assert np.abs(h["vel"][i1 - 1, 0]).max() < tol.STICK_VELOCITY  # sticking before the stage
    t1 = t[i1] - ts
    bound = (mu * g + amp) * t1
    vy = h["vel"][i1, 0, 1]
    assert -v_b - tol.SLACK <= vy <= -v_b + bound
    assert 0.5 * m * (v_b - bound) ** 2 <= h["kinetic"][i1] <= 0.5 * m * v_b ** 2 * (1 + tol.KINETIC_JUMP_REL)
    assert s["run"]["velocity_jumps"][0]["relative_velocity_m_s"] == pytest.approx([0, -v_b, 0])
    # the slide: peak against the rigid-plastic reference with the same jump, then the residual
    u = h["pos"][:, 0, 1] - h["pos"][i1 - 1, 0, 1]
    on = t >= ts
    ref = sliding_block(lambda x: -amp * np.sin(2 * np.pi * f * x), t[on] - ts, mu, v0=-v_b)
    d_el = mu * m * g * (1 / (1e8 * b * b) + (b / 2) ** 2 / (2e8 * b ** 4 / 12))
    step = v_b * spec["dt"]
    assert ref.min() < -5e-4  # it really slides
    assert abs(u[on].min() - ref.min()) <= d_el + step
    assert abs(u[-1] - ref[-1]) <= 2 * d_el + step
    # settled early: the kinetic energy stayed below 1e-7 J for 0.1 s, well before the 2 s limit
    st = s["run"]["settle"]
    assert st["reached"] and st["time_s"] < spec["stages"][-1]["end"] - 1.0
    assert st["time_s"] - st["below_since_s"] >= 0.1 - tol.SLACK and h["kinetic"][-1] < 1e-7
    assert s["run"]["simulated_time_s"] == pytest.approx(st["time_s"], abs=tol.SETTLE_STEPS * spec["dt"])

    s, h, spec = run_case(case("rest"), outdir, "rest")  # the same sine from rest: no slide
    assert s["run"]["velocity_jumps"] == []
    assert np.abs(h["pos"][:, 0, 1] - h["pos"][0, 0, 1]).max() < tol.NO_SLIDE_M
