"""One rigid block on the tilting platform (issue 2 tilt protocol; issue 5 sanity checks).

A 0.2 m wide block slides at atan(mu) when mu < b/h, and topples otherwise. With penalty
contact the toppling angle is not atan(b/h) but that of a rigid block on a Winkler joint
(drystone/analytic.py: 23.16 deg instead of 26.57 deg for b/h = 0.5 at K_n = 2e8 N/m^3), which
is what the law must reproduce. Tolerance 0.3 deg: the final tilt rate is 0.5 deg/s and the
onset of motion (5 mm per degree of tilt, drystone/collapse.py) is dated within about 0.1 deg.
"""
import pytest

from conftest import requires_yade, run_case
from drystone import analytic

pytestmark = [requires_yade, pytest.mark.yade]


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
    assert s["collapse_angle_deg"] == pytest.approx(analytic.sliding_tilt_deg(0.4), abs=0.3)
    assert s["collapse"]["onset_block"] == 1


def test_block_topples_at_the_winkler_angle(outdir):
    expected = analytic.toppling_tilt_deg(0.2, 0.4, 0.2, 2300, 2e8)
    s, h, _ = run_case(tilt_case([0.2, 0.2, 0.4], 0.7, expected - 2.0), outdir)
    assert s["collapse_angle_deg"] == pytest.approx(expected, abs=0.3)
    assert s["blocks"]["1"]["residual_rotation_angle_rad"] > 0.3  # it fell over, not slid


def test_toppling_block_at_both_quasi_static_rates(outdir):
    """A stiff block has no gradual lean before its limit: it runs away in time, and at
    1 deg/s the platform turns further while it does, so its onset (5 mm per degree) is
    dated later than at 0.2 deg/s (measured: 23.08 and 23.35 deg, Winkler limit 23.16).
    Both stay within the 0.3 deg of the sanity checks, and the faster rate dates later,
    never earlier. The rate limit of issue 5 (0.2 deg) is checked on the wall itself,
    whose collapse is a gradual lean (`make tilt-rate`, postprocess/tilt.py; and
    tests/test_collapse.py for the onset rule)."""
    expected = analytic.toppling_tilt_deg(0.2, 0.4, 0.2, 2300, 2e8)
    angles = []
    for rate in (0.2, 1.0):
        case = tilt_case([0.2, 0.2, 0.4], 0.7, expected - 1.0)
        case["stages"][2]["rate_deg_s"] = rate
        s, _, _ = run_case(case, outdir, name=f"rate_{rate}")
        angles.append(s["collapse_angle_deg"])
    assert angles == pytest.approx([expected, expected], abs=0.3)
    assert angles[1] >= angles[0]
