"""One rigid block on the tilting platform (issue 2 tilt protocol; issue 5 sanity checks).

A 0.2 m wide block slides at atan(mu) when mu < b/h, and topples otherwise. With penalty
contact the toppling angle is not atan(b/h) but that of a rigid block on a Winkler joint
(drystone/mechanics/analytic.py: 23.16 deg instead of 26.57 deg for b/h = 0.5 at K_n = 2e8 N/m^3), which
is what the law must reproduce. Tolerance 0.3 deg: the final tilt rate is 0.5 deg/s and the
onset of motion (5 mm per degree of tilt, drystone/mechanics/collapse.py) is dated within about 0.1 deg.
"""
import pytest

import tolerances as tol
from conftest import requires_yade, run_case
from drystone.mechanics import analytic

pytestmark = [requires_yade, pytest.mark.yade, pytest.mark.slow]  # each test > 30 s


def tilt_case(size, mu, start_deg, kn=2e8):
    return {
        "case": {"geometry": {"generator": "boxes_on_platform", "mu": mu, "damping": 0.8, "kn": kn, "kt": kn / 2,
                              "boxes": [{"id": 1, "center_xy": [0.0, 0.0], "size": size}]}},
        "stages": [{"type": "gravity", "duration": 0.5, "ramp": 0.25},
                   {"type": "tilt", "rate_deg_s": 5.0, "to_deg": start_deg},
                   {"type": "tilt", "rate_deg_s": 0.5, "until_collapse": True, "max_deg": start_deg + 6,
                    "after_collapse": 0.2}],
        "output": {"interval": 0.01},
    }


def test_block_slides_at_atan_mu(outdir):
    s, h, _ = run_case(tilt_case([0.2, 0.2, 0.2], 0.4, 20.0), outdir)
    assert s["collapse_angle_deg"] == pytest.approx(analytic.sliding_tilt_deg(0.4), abs=tol.TILT_ANGLE_DEG)
    assert s["collapse"]["onset_block"] == 1


def test_block_topples_at_the_winkler_angle(outdir):
    expected = analytic.toppling_tilt_deg(0.2, 0.4, 0.2, 2300, 2e8)
    s, h, _ = run_case(tilt_case([0.2, 0.2, 0.4], 0.7, expected - 2.0), outdir)
    assert s["collapse_angle_deg"] == pytest.approx(expected, abs=tol.TILT_ANGLE_DEG)
    assert s["blocks"]["1"]["residual_rotation_angle_rad"] > 0.3  # it fell over, not slid
    # the paper's criterion: the vertical reaction drops by 5 % of the weight once the block
    # falls, i.e. after the onset of its run-away and within the time it takes to fall (under
    # 2 s for a 0.4 m block, 1 deg of tilt at 0.5 deg/s); a standing block keeps it at W
    rd = s["reaction_drop_angle_deg"]
    assert rd is not None
    assert s["collapse_angle_deg"] - tol.REACTION_DROP_BEFORE_DEG <= rd <= s["collapse_angle_deg"] + tol.REACTION_DROP_AFTER_DEG
    assert s["collapse"]["reaction_drop"]["fraction"] < 0.95


def test_toppling_block_at_both_quasi_static_rates(outdir):
    """A stiff block has no gradual lean before its limit: it runs away in time, and while
    it does the platform turns further, so the faster the tilt the later its onset (5 mm
    per degree) is dated. The run-away is slowed by the contact damping, which acts on the
    rocking mode since the damping is distributed over the joint (issue 11): with
    xi = 0.8 the 1 deg/s protocol dates the toppling ~0.5 deg late (23.67 against 23.22 at
    0.2 deg/s), with xi = 0.08 it does not. Asserted: the paper's 0.2 deg/s and the
    lightly damped 1 deg/s within the 0.3 deg of the sanity checks; the damped fast run
    later, never earlier, than both. The rate limit of issue 5 (0.2 deg) is checked on the
    wall itself (`make tilt-rate`, drystone/studies/tilt/study.py)."""
    expected = analytic.toppling_tilt_deg(0.2, 0.4, 0.2, 2300, 2e8)
    angles = {}
    for rate, xi in ((0.2, 0.8), (1.0, 0.8), (1.0, 0.08)):
        case = tilt_case([0.2, 0.2, 0.4], 0.7, expected - 1.0)
        case["case"]["geometry"]["damping"] = xi
        case["stages"][2]["rate_deg_s"] = rate
        s, _, _ = run_case(case, outdir, name=f"rate_{rate}_{xi}")
        angles[rate, xi] = s["collapse_angle_deg"]
    assert angles[0.2, 0.8] == pytest.approx(expected, abs=tol.TILT_ANGLE_DEG)
    assert angles[1.0, 0.08] == pytest.approx(expected, abs=tol.TILT_ANGLE_DEG)
    assert angles[1.0, 0.8] >= max(angles[0.2, 0.8], angles[1.0, 0.08])


@pytest.mark.parametrize("mu", [0.8, 1.5, 2.5])
def test_long_block_tilted_along_its_length_stays_in_its_plane(outdir, mu):
    """A 0.4 x 0.2 x 0.2 m box tilted towards +x (along its length: b/h = 2) slides at
    atan(mu) below the Winkler toppling angle (61.7 deg) and topples at it above. The
    stuck shear force acts at the overlap centroid, offset towards the toe, and with the
    load it makes a couple that turns a twisted block further: without the joint's twist
    stiffness (contact.twist_spring) that twist grew from round-off and a mu = 2.5 block
    walked off sideways and was dated collapsed at 58.6 deg. The block is symmetric about
    the tilt plane: until its collapse it neither drifts across it nor spins out of it
    beyond round-off."""
    size = [0.4, 0.2, 0.2]
    expected = min(analytic.sliding_tilt_deg(mu), analytic.toppling_tilt_deg(size[0], size[2], size[1], 2300, 2e8))
    case = tilt_case(size, mu, expected - 1.0)
    case["stages"][2]["rate_deg_s"] = 0.2  # the paper's rate: the wide block's damped run-away dated 0.1 deg late
    for stage in case["stages"][1:]:
        stage["towards"] = "+x"
    s, h, _ = run_case(case, outdir, name=f"mu_{mu}")
    assert s["collapse_angle_deg"] == pytest.approx(expected, abs=tol.TILT_ANGLE_DEG)
    before = h["tilt_deg"] <= s["collapse_angle_deg"]
    assert before.sum() > 100  # the run up to the collapse is sampled (every 0.01 s)
    drift_y = abs(h["pos"][before, 0, 1] - h["pos0"][0, 1]).max()
    spin = abs(h["angvel"][before, 0][:, [0, 2]]).max()  # about x and the vertical: not the tilt axis y
    assert drift_y < tol.SYMMETRIC_DRIFT_M
    assert spin < tol.SYMMETRIC_SPIN_RAD_S
