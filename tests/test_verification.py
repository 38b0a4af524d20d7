"""The paper's four-block verification cases end to end (issue 2, §6-7; paper §3.1)."""
import math

import pytest

import tolerances as tol
from conftest import assert_figure, requires_yade
from drystone import paths, runner
from drystone.postprocess import compare

pytestmark = [requires_yade, pytest.mark.yade]
W = 2200 * 0.220 * 0.105 * 0.050 * 9.81  # 24.93 N, paper §3.1


def test_gravity4_penetration(outdir):
    """Penetration 1-2 = W / (K_n A) = 0.55e-4 m (paper Eq. 5 and Fig. 7) within 2 %:
    the volumetric law is exact for a flat joint; 2 % leaves room for the residual
    vibration at 2 s (damping 0.08)."""
    s = runner.run(paths.CASES / "gravity4.toml", out_dir=outdir / "g", quiet=True)
    assert s["penetration_1_2_m"] == pytest.approx(W / (1.96e7 * 0.220 * 0.105), rel=tol.PENETRATION_REL)
    assert s["penetration_1_2_m"] == pytest.approx(0.55e-4, rel=tol.PENETRATION_REL)
    assert_figure(outdir / "g" / "penetration_1-2.png", (7, 4), dpi=120)  # postprocess.plots


def test_settlement4_slip(outdir):
    """Block 2 slips when F_t/F_n reaches tan 38 deg (within 3 %), with F_t = W sin 38 deg
    (3 %) and block 1 tilted by 38 deg (within 1.5 deg: block 1 tilts at about 7 deg/s when
    block 2 lets go, and the support edges sink a few mm into block 1 at these soft
    stiffnesses)."""
    s = runner.run(paths.CASES / "settlement4.toml", out_dir=outdir / "s", quiet=True)
    phi = math.radians(38)
    assert s["slip_force_ratio"] == pytest.approx(math.tan(phi), rel=tol.SLIP_FORCE_REL)
    assert s["slip_force_N"] == pytest.approx(W * math.sin(phi), rel=tol.SLIP_FORCE_REL)
    assert s["slip_normal_force_N"] == pytest.approx(W * math.cos(phi), rel=tol.SLIP_FORCE_REL)
    assert s["slip_tilt_deg"] == pytest.approx(38.0, abs=tol.SLIP_TILT_DEG)
    assert s["blocks"]["2"]["collapsed"]  # it slid off block 1 and left the model
    assert_figure(outdir / "s" / "contact_1-2.png", (7, 4), dpi=120)
    table = compare.report([str(outdir / "s")])
    assert "F_t/F_n at slip" in table
