"""The modal analysis of any wall (drystone/analyses/modal.py) on blocks whose modes have closed
forms (no YADE), and once on a settled wall (YADE).

One block b (x) x d (y) x H (z) on a Winkler joint (K_n, K_t per unit area), sunk by its
static penetration delta0 = m g / (K_n A): the closed forms of tests/test_modal.py
(bouncing, two sliding-rocking pairs with gravity's geometric stiffness -W h_c, and the
twist spring's torsion, w^2 = K_t A / m).

A stone of two parts (a YADE clump) is one rigid body: its mass properties the union's, one
contact per pair of parts of different stones, their forces summed on the stone:

* cut across its height (only the lower part touches the platform): the contacts are the
  one-piece stone's, so are the modes, up to round-off (``MULTIPART_MODAL_REL``);
* cut along its height into two halves side by side, each standing on the joint: the
  normal forces K_n V_i at the halves' overlap centroids add up to the one piece's force
  and moment, the tangential springs K_t A_i at two points do too, and in a twist about z
  they resist K_t (A/2) (b/4)^2 x 2 = K_t A b^2 / 16, which with the halves' own twist
  springs 2 K_t (A/2) ((b/2)^2 + d^2) / 12 is the one piece's K_t A (b^2 + d^2) / 12
  (parallel axes): the same six modes.
"""
from __future__ import annotations

import json

import numpy as np
import pytest
from scipy import linalg

import tolerances as tol
from drystone.analyses import modal as am
from drystone.mechanics import modal
from drystone.simulate import RunError

from test_modal import B, D, H, KN, KT, RHO, _box, _rocking_sliding

MU = 0.6


def _block(parts=None, kn=KN, gravity=None, extra=(), blocked=""):
    """The sunk block of tests/test_modal.py (sunk by the vertical part of ``gravity``), as
    one piece or as ``parts`` (a function of its bottom and top z); ``extra``: more
    (vertices, moving, blocked) entries."""
    m = RHO * B * D * H
    delta0 = m * (modal.G if gravity is None else -gravity[2]) / (kn * B * D)
    z0, z1 = -delta0, H - delta0
    block = _box(-B / 2, B / 2, -D / 2, D / 2, z0, z1) if parts is None else parts(z0, z1)
    verts = [_box(-1, 1, -1, 1, -0.2, 0.0), block] + [v for v, _, _ in extra]
    asm = modal.Assembly(verts, moving=[False, True] + [mv for _, mv, _ in extra], density=RHO, kn=kn, kt=KT,
                         blocked=["", blocked] + [b for _, _, b in extra], ids=list(range(len(verts))), mu=MU,
                         **({} if gravity is None else {"gravity": gravity}))
    return asm, m, delta0


def _stacked(z0, z1):
    zc = 0.5 * (z0 + z1)
    return [_box(-B / 2, B / 2, -D / 2, D / 2, z0, zc), _box(-B / 2, B / 2, -D / 2, D / 2, zc, z1)]


def _side_by_side(z0, z1):
    return [_box(-B / 2, 0.0, -D / 2, D / 2, z0, z1), _box(0.0, B / 2, -D / 2, D / 2, z0, z1)]


@pytest.fixture(scope="module")
def one_piece():
    asm, m, delta0 = _block()
    return am.analyse(asm, modes=6), m, delta0


def test_one_block_on_a_winkler_joint(one_piece):
    """The six frequencies are the closed forms, the twist about z the twist spring's;
    no zero mode."""
    r, m, delta0 = one_piece
    bounce = np.sqrt(KN * B * D / m) / (2 * np.pi)
    torsion = np.sqrt(KT * B * D / m) / (2 * np.pi)
    expected = np.sort(np.r_[bounce, torsion, _rocking_sliding(B, D, m, delta0), _rocking_sliding(D, B, m, delta0)])
    np.testing.assert_allclose(r["frequencies_hz"], expected, rtol=tol.MODAL_FREQUENCY_REL)
    assert not r["zero_modes"]
    twist = [mo for mo in r["modes"] if mo["dominant_motion"] == "rotation about z"]
    assert len(twist) == 1 and twist[0]["frequency_hz"] == pytest.approx(torsion, rel=tol.MODAL_FREQUENCY_REL)
    # the lowest mode rocks and slides along x (the narrow side): all the x mass, none along y
    first = r["modes"][0]
    assert first["dominant_direction"] == "x" and first["effective_mass_ratio"]["y"] < tol.EXACT_ABS
    assert sum(mo["effective_mass_ratio"]["x"] for mo in r["modes"]) == pytest.approx(1.0, rel=tol.NUMERICAL_REL)
    assert r["model"]["balance"]["balanced"] and r["model"]["balance"]["friction_use"] < tol.EXACT_ABS


def test_a_stone_cut_across_its_height_has_the_modes_of_one_piece(one_piece):
    r1, _, _ = one_piece
    asm, _, _ = _block(_stacked)
    r2 = am.analyse(asm, modes=6)
    assert r2["model"]["multi_part_stones"] == [1] and r2["model"]["contacts"] == 1
    np.testing.assert_allclose(r2["frequencies_hz"], r1["frequencies_hz"], rtol=tol.MULTIPART_MODAL_REL)
    assert not r2["zero_modes"]


def test_a_stone_cut_into_two_halves_side_by_side(one_piece):
    """Two contacts (one per part on the joint): the same six frequencies, the twist about
    z's stiffness shared between the two tangential springs and the halves' twist springs
    (module docstring)."""
    r1, m, _ = one_piece
    asm, _, _ = _block(_side_by_side)
    r2 = am.analyse(asm, modes=6)
    assert r2["model"]["contacts"] == 2 and not r2["zero_modes"]
    np.testing.assert_allclose(r2["frequencies_hz"], r1["frequencies_hz"], rtol=tol.MODAL_FREQUENCY_REL)


def test_an_unstable_equilibrium_is_refused_naming_the_stone():
    """A joint 10 times softer: K_n I_y = 400 N m < W h_c = 600 N m: rocking along x has
    negative stiffness; no frequency is printed, the stone is named."""
    asm, m, delta0 = _block(kn=KN / 10)
    assert KN / 10 * D * B ** 3 / 12 < m * modal.G * (H / 2 - delta0 / 2)
    with pytest.raises(RunError, match=r"negative eigenvalue.*stone 1 .*not a stable equilibrium"):
        am.analyse(asm)


def test_a_stone_out_of_balance_is_refused_naming_it():
    """A second stone hangs in the air: no shear of any joint balances it."""
    far = (_box(2.0, 2.2, 0.0, 0.2, 1.0, 1.2), True, "")
    asm, _, _ = _block(extra=[far])
    with pytest.raises(RunError, match=r"stone 2 is out of balance.*settle it"):
        am.analyse(asm)


def test_a_contact_past_friction_is_named():
    """Gravity tilted by 35 deg along x, the block held against rotation (its moment would
    need an uneven sink, not shear) and sunk by the normal part of its weight: the joint
    would need tan 35 / mu = 0.70 / 0.6 = 1.17 times its friction: within friction it is
    left out of balance by (sin 35 - mu cos 35) W = 8.2 % of W. The modes are then those of
    the nearest equilibrium of the joints, whose spring carries the whole W sin 35: the
    contact is named with its friction use, 1.17. At 30 deg (0.58 < 0.6) the shear within
    friction balances it, using 0.962 of it, and the recorded state is kept."""
    for deg in (30.0, 35.0):
        a = np.radians(deg)
        asm, _, _ = _block(gravity=modal.G * np.array([np.sin(a), 0.0, -np.cos(a)]), blocked="XYZ")
        r = am.analyse(asm)["model"]
        use = np.tan(a) / MU
        if deg == 30.0:
            # balanced to 1e-3 BALANCE_TOL of the weight (modal.balance): the friction use is
            # low by up to that over mu cos(a), beside the programme's own tolerance
            slack = 1e-3 * modal.BALANCE_TOL / (MU * np.cos(a))
            assert r["balance"]["friction_use"] == pytest.approx(use, rel=tol.LP_REL + slack)
            assert r["nearby_equilibrium"] is None
        else:
            assert r["balance"]["residual"] == pytest.approx(np.sin(a) - MU * np.cos(a), rel=tol.LP_REL)
            near = r["nearby_equilibrium"]
            assert "stone 1 is out of balance by 8.2 %" in near["reason"]
            assert near["friction_contact"] == [0, 1]
            assert near["friction_use"] == pytest.approx(use, rel=tol.EQUILIBRIUM_REL)


def test_a_stone_touching_nothing_is_explained():
    """A stone held in translation (blocked x y z) that touches nothing: its three rotations
    have no stiffness, each explained as such, none a frequency."""
    free = (_box(2.0, 2.2, 0.0, 0.2, 1.0, 1.2), True, "xyz")
    asm, _, _ = _block(extra=[free])
    r = am.analyse(asm)
    lonely = [z for z in r["zero_modes"] if z["dominant_stone"] == 2]
    assert len(lonely) == 3 and all("touches nothing" in z["explanation"] for z in lonely)
    assert len(r["zero_modes"]) == 3 and len(r["frequencies_hz"]) == 6


@pytest.mark.yade
def test_modal_of_a_settled_wall(tmp_path):
    """The example DXF wall settled under gravity: every eigenvalue positive, none zero, the
    joints' shear balancing every stone within friction; modal.json, the figure and the
    report written; a rerun reuses the settling run."""
    from conftest import have_yade

    if not have_yade():
        pytest.skip("YADE is not installed")
    from drystone import paths

    case = paths.ROOT / "cases" / "examples" / "dxf_wall.toml"
    r = am.modal(case, out=tmp_path / "modal", modes=4, workers=1)
    assert all(f > 0 for f in r["model"]["all_frequencies_hz"]) and not r["zero_modes"]
    assert r["model"]["ndof"] == 6 * r["model"]["free_stones"]
    assert r["model"]["balance"]["balanced"]
    saved = json.loads((tmp_path / "modal" / "modal.json").read_text())
    assert saved["frequencies_hz"] == r["frequencies_hz"] and len(saved["frequencies_hz"]) == 4
    assert (tmp_path / "modal" / "modes.png").is_file() and (tmp_path / "modal" / "report.html").is_file()


@pytest.mark.yade
def test_modal_of_one_block_settled_by_the_analysis(tmp_path):
    """The full command on a case without a gravity stage (one block on the platform, a rest
    stage only): the analysis settles it under the gravity stage it adds (said so), and the
    frequencies of the settled block are the Winkler closed forms: bouncing and the two
    sliding-rocking pairs, the twist spring's torsion. The settled sink is the closed
    form's delta0 up to the residual motion of the run, and the frequencies depend on it
    only through h_c = H/2 - delta0/2 (delta0 / H = 1e-4 here)."""
    from conftest import have_yade
    from drystone.runner import to_toml

    if not have_yade():
        pytest.skip("YADE is not installed")
    kn, kt = 2e8, 1e8
    case = {"case": {"name": "one_block_modal", "geometry": {
        "generator": "boxes_on_platform", "mu": 0.7, "damping": 0.3, "density": RHO, "kn": kn, "kt": kt,
        "boxes": [{"id": 1, "center_xy": [0.0, 0.0], "size": [B, D, H]}]}},
        "stages": [{"type": "rest", "duration": 0.1}], "output": {"interval": 0.01}}
    path = tmp_path / "one_block.toml"
    path.write_text(to_toml(case))
    r = am.modal(path, out=tmp_path / "modal", modes=6, workers=1)
    assert r["settle"]["gravity_stage"].startswith("added")
    m = RHO * B * D * H
    delta0 = m * modal.G / (kn * B * D)
    a = B * D
    hc = H / 2 - delta0 / 2

    def pair(b, d):
        rock = kn * d * b ** 3 / 12 + kt * a * hc ** 2 - m * modal.G * hc
        K = np.array([[kt * a, -kt * a * hc], [-kt * a * hc, rock]])
        return np.sqrt(linalg.eigh(K, np.diag([m, m * (b * b + H * H) / 12]), eigvals_only=True)) / (2 * np.pi)

    expected = np.sort(np.r_[np.sqrt(kn * a / m) / (2 * np.pi), np.sqrt(kt * a / m) / (2 * np.pi), pair(B, D),
                             pair(D, B)])
    np.testing.assert_allclose(r["frequencies_hz"], expected, rtol=tol.SETTLED_MODAL_REL)
    assert not r["zero_modes"]


@pytest.mark.yade
def test_a_wall_still_moving_is_refused(tmp_path):
    """A block dropped from 5 cm with gravity switched on at once for 0.1 s is still falling
    at the end of the gravity stage: refused, naming it, before any mode is computed."""
    from conftest import have_yade
    from drystone.runner import to_toml

    if not have_yade():
        pytest.skip("YADE is not installed")
    case = {"case": {"name": "falling_block", "geometry": {
        "generator": "boxes_on_platform", "mu": 0.7, "density": RHO, "kn": 2e8, "kt": 1e8,
        "boxes": [{"id": 1, "center_xy": [0.0, 0.0], "size": [B, D, H], "z0": 0.05}]}},
        "stages": [{"type": "gravity", "duration": 0.1, "ramp": 0.0}], "output": {"interval": 0.01}}
    path = tmp_path / "falling.toml"
    path.write_text(to_toml(case))
    with pytest.raises(RunError, match=r"stone 1 still moves at .* the wall has not settled"):
        am.modal(path, out=tmp_path / "modal", workers=1)
    assert not (tmp_path / "modal" / "modal.json").exists()
