"""Issue 25, items 2 and 6: stones of several convex parts in a run.

A multi-part stone is one rigid body (a YADE clump; drystone/yade_scripts/scene.py) whose
parts are the contact shapes of the compiled step and the numpy engine
(drystone/mechanics/contact_step.py: contacts between parts of different stones, forces
summed on the stone). Checked against closed forms:

* an L-shaped stone on a tilting platform topples at the angle its union's centroid sets
  on a Winkler joint (drystone/mechanics/analytic.py stone_toppling_tilt_deg), not at its
  hull's;
* a stone seated on a face inclined beta rides up it under a horizontal push
  W tan(beta + phi); the same stone split into two independent blocks lets its upper part
  slide at mu W_upper;
* a box and the same box cut into two halves give the same run (to round-off);
* the compiled step and the numpy engine agree on a multi-part stone.
"""
import json
import math

import numpy as np
import pytest

import tolerances as tol
from conftest import requires_yade, run_case
from drystone.geometry import polyhedron as ph
from drystone.mechanics import analytic
from drystone.mechanics import contact as law
from drystone.mechanics import rotations
from test_multipart import box, stone_file

pytestmark = [requires_yade, pytest.mark.yade]

RHO, KN = 2000.0, 2e8  # kg/m^3, N/m^3 (stone_file's material)
G = 9.81  # m/s^2, the cases' default gravity


def write(folder, data, name="stone.json"):
    p = folder / name
    p.write_text(json.dumps(data))
    return str(p)


def gravity_then(stages, geometry, **extra):
    case = {"case": {"geometry": geometry}, "stages": [{"type": "gravity", "duration": 0.4, "ramp": 0.2}] + stages,
            "output": {"interval": 0.01}}
    case.update(extra)
    return case


def relative_rotation(h):
    """Rotation matrices of block 0's orientation relative to its first (independent of
    the body frame YADE chose for it)."""
    return rotations.to_matrix(h["quat"][:, 0]) @ rotations.to_matrix(h["quat0"][0]).T


# --- the L topples at its union's angle ------------------------------------------------------

#: an L: a foot [0, 0.3] x [0, 0.2] x [0, 0.1] m with a leg [0, 0.1] x [0, 0.2] x [0.1, 0.6] m
#: at its x = 0 end, toppling over that end (tilt towards -x)
L_FOOT, L_LEG = box((0, 0, 0), (0.3, 0.2, 0.1)), box((0, 0, 0.1), (0.1, 0.2, 0.6))


def test_l_stone_topples_at_the_angle_of_its_union(outdir):
    v_foot, v_leg = 0.3 * 0.1 * 0.2, 0.1 * 0.5 * 0.2
    d = (v_foot * 0.15 + v_leg * 0.05) / (v_foot + v_leg)  # centroid from the toe x = 0, m
    e = (v_foot * 0.05 + v_leg * 0.35) / (v_foot + v_leg)  # and above the base
    expected = analytic.stone_toppling_tilt_deg(d, e, 0.3, 0.2, RHO * G * (v_foot + v_leg), KN)
    # the hull of the L (what a convex stone would be) has its centroid elsewhere: 25.4 deg rigid
    hull = np.array([[0, 0], [0.3, 0], [0.3, 0.1], [0.1, 0.6], [0, 0.6]])
    x, z = hull[:, 0], hull[:, 1]
    cr = x * np.roll(z, -1) - np.roll(x, -1) * z
    hx, hz = ((x + np.roll(x, -1)) * cr).sum() / (3 * cr.sum()), ((z + np.roll(z, -1)) * cr).sum() / (3 * cr.sum())
    assert math.degrees(math.atan2(hx, hz)) - expected > 10 * tol.TILT_ANGLE_DEG
    data = stone_file([L_FOOT, L_LEG])
    data["materials"]["stone"]["mu"] = 0.7  # no sliding before 35 deg
    case = gravity_then([{"type": "tilt", "rate_deg_s": 5.0, "to_deg": expected - 1.0, "towards": "-x"},
                         {"type": "tilt", "rate_deg_s": 0.5, "until_collapse": True, "max_deg": expected + 5.0,
                          "towards": "-x", "after_collapse": 0.2}], write(outdir, data))
    s, h, _ = run_case(case, outdir)
    assert s["collapse_angle_deg"] == pytest.approx(expected, abs=tol.TILT_ANGLE_DEG)
    assert s["blocks"]["7"]["residual_rotation_angle_rad"] > 0.3  # it fell over, not slid
    assert h["pos0"][0, 0] == pytest.approx(d, abs=tol.EXACT_ABS)  # the union's centroid


# --- a stone seated on an inclined face: riding up it, or its upper part sliding off --------

BETA, MU = math.radians(15.0), 0.5
_TB, _T = math.tan(BETA), 0.2


def _prism(xz):
    """The prism of an (x, z) polygon (m) through y in [0, 0.2]."""
    return [[x, y, z] for x, z in xz for y in (0.0, _T)]


#: a fixed step whose top rises at BETA; the stone: a tooth whose base lies on it and a slab
#: on the tooth overhanging it on both sides (a T: not convex)
_H1 = 0.1 + 0.4 * _TB + 0.05
RAMP = _prism([(0, 0), (0.6, 0), (0.6, 0.1 + 0.6 * _TB), (0, 0.1)])
TOOTH = _prism([(0.1, 0.1 + 0.1 * _TB), (0.4, 0.1 + 0.4 * _TB), (0.4, _H1), (0.1, _H1)])
SLAB = box((0.0, 0.0, _H1), (0.5, _T, _H1 + 0.15))


def _seated(split: bool) -> dict:
    stone = ([{"id": 2, "role": "free", "material": "stone", "vertices": TOOTH},
              {"id": 3, "role": "free", "material": "stone", "vertices": SLAB}] if split
             else [{"id": 2, "role": "free", "material": "stone", "parts": [TOOTH, SLAB]}])
    data = stone_file(vertices=box((0, 0, 0), (0.1, 0.1, 0.1)))
    data["materials"]["stone"]["mu"] = MU
    data["blocks"] = [data["blocks"][0], {"id": 1, "role": "fixed", "material": "stone", "vertices": RAMP}] + stone
    data["control_points"] = []
    return data


def _push(outdir, split, block, force, name):
    """Displacement (m, x y z) of the free blocks 0.6 s after a horizontal push ``force`` (N, +x) on ``block``."""
    case = gravity_then([{"type": "rest", "duration": 0.6}], write(outdir, _seated(split), f"{name}.json"),
                        forces=[{"block": block, "force": [force, 0.0, 0.0], "start": 0.4}])
    _, h, _ = run_case(case, outdir, name=name)
    i = int(np.searchsorted(h["t"], 0.4))
    return dict(zip(h["block_ids"].tolist(), h["pos"][-1] - h["pos"][i]))


def test_seated_stone_rides_up_at_w_tan_beta_plus_phi(outdir):
    w = RHO * G * (ph.volume_centroid(TOOTH)[0] + ph.volume_centroid(SLAB)[0])
    p = w * math.tan(BETA + math.atan(MU))  # N
    below, above = _push(outdir, False, 2, 0.95 * p, "below")[2], _push(outdir, False, 2, 1.05 * p, "above")[2]
    assert np.linalg.norm(below) < tol.PUSH_STAYED_M
    assert above[0] > tol.PUSH_MOVED_M
    assert above[2] == pytest.approx(above[0] * _TB, rel=0.05)  # up the incline, as one body


def test_split_stone_lets_its_upper_part_slide_at_mu_w(outdir):
    w_slab = RHO * G * ph.volume_centroid(SLAB)[0]
    below = _push(outdir, True, 3, 0.95 * MU * w_slab, "below")
    above = _push(outdir, True, 3, 1.05 * MU * w_slab, "above")
    assert np.linalg.norm(below[3]) < tol.PUSH_STAYED_M
    assert above[3][0] > tol.PUSH_MOVED_M
    assert np.linalg.norm(above[2]) < tol.PUSH_STAYED_M  # the tooth stays on its step


# --- one block, or the same block cut in two -------------------------------------------------

def test_box_and_the_box_cut_in_two_give_the_same_run(outdir):
    """Cut along the direction it slides (tilt towards +x past atan(mu)), no contact damping
    (each contact's own damping is not additive, drystone/mechanics/contact.py)."""
    whole = stone_file(vertices=box((0, 0, 0), (0.4, 0.2, 0.2)))
    halves = stone_file([box((0, 0, 0), (0.4, 0.1, 0.2)), box((0, 0.1, 0), (0.4, 0.2, 0.2))])
    runs = []
    for name, data in (("whole", whole), ("halves", halves)):
        case = gravity_then([{"type": "tilt", "rate_deg_s": 20.0, "to_deg": 30.0, "towards": "+x"}],
                            write(outdir, data, f"{name}.json"), time={"step": 2e-5}, contact={"damping": 0.0})
        runs.append(run_case(case, outdir, name=name)[1])
    a, b = runs
    assert a["pos"][-1, 0, 0] - a["pos"][0, 0, 0] > 0.03  # it slid (mu 0.4 < tan 30 deg)
    assert np.abs(a["pos"] - b["pos"]).max() < tol.CUT_BLOCK_SAME_RUN_M
    assert np.abs(a["cp"] - b["cp"]).max() < tol.CUT_BLOCK_SAME_RUN_M
    assert np.abs(relative_rotation(a) - relative_rotation(b)).max() < tol.CUT_BLOCK_SAME_RUN_M / 0.2
    assert a["mass"][0] == pytest.approx(b["mass"][0], rel=tol.EXACT_REL)


def test_engines_agree_on_a_multi_part_stone(outdir):
    """The compiled step and the numpy engine on the L stone tilted at 40 deg/s to 34 deg: it
    slides 3.5 cm (measured), both engines within ENGINES_MULTIPART_M."""
    data = stone_file([L_FOOT, L_LEG])
    case = gravity_then([{"type": "tilt", "rate_deg_s": 40.0, "to_deg": 34.0, "towards": "+x"}], write(outdir, data))
    from drystone import runner
    hs = []
    for engine in ("compiled", "python"):
        runner.run_dict(case, outdir / f"{engine}.toml", out_dir=outdir / engine, quiet=True, engine=engine)
        hs.append(np.load(outdir / engine / "histories.npz"))
    assert hs[0]["pos"][-1, 0, 0] - hs[0]["pos"][0, 0, 0] > 0.01  # it moved
    assert np.abs(hs[0]["pos"] - hs[1]["pos"]).max() < tol.ENGINES_MULTIPART_M


def test_stock_law_refuses_a_multi_part_stone(tmp_path):
    import subprocess
    import sys

    (tmp_path / "blocks.json").write_text(json.dumps(stone_file([L_FOOT, L_LEG])))
    (tmp_path / "c.toml").write_text('[case]\ngeometry = "blocks.json"\n[contact]\nlaw = "stock_volumetric"\n'
                                     '[[stages]]\ntype = "gravity"\nduration = 0.1\n')
    r = subprocess.run([sys.executable, "-m", "drystone", "run", "c.toml", "--out", "out"], cwd=tmp_path,
                       capture_output=True, text=True)
    assert r.returncode == 2 and r.stderr.strip().count("\n") == 0
    assert "block 7 has 2 parts" in r.stderr and "stock_volumetric" in r.stderr
    assert not (tmp_path / "out").exists()


# --- the damping ratio shared by the contacts of one joint ------------------------------------

def test_joint_share_keeps_one_contact_and_splits_equal_halves():
    ia, ib = np.array([0, 3, 0, 1]), np.array([1, 1, 2, 0])  # pairs (0, 1) twice, (1, 3), (0, 2)
    area = np.array([0.02, 0.05, 0.04, 0.02])
    f = law.joint_share(ia, ib, 4, area)
    assert f[1] == 1.0 and f[2] == 1.0  # one contact for its pair: unchanged, exactly
    assert f[0] == pytest.approx(1 / math.sqrt(2), rel=tol.FEW_ULP_REL) and f[3] == f[0]
    # the joint's translation: sum of 2 xi f sqrt(K_n A_i m) equals 2 xi sqrt(K_n sum(A) m)
    assert (f[0] * np.sqrt(area[[0, 3]])).sum() == pytest.approx(np.sqrt(area[[0, 3]].sum()), rel=tol.FEW_ULP_REL)


# --- figures and VTK draw every part ----------------------------------------------------------

@pytest.fixture(scope="module")
def settled_l(tmp_path_factory):
    """The L stone settled on the platform under gravity: the run folder (one run for the
    figures, the VTK files and the modal model below)."""
    d = tmp_path_factory.mktemp("settled_l")
    run_case(gravity_then([], write(d, stone_file([L_FOOT, L_LEG]))), d)
    return d / "case"


def test_figures_and_vtk_draw_each_part(outdir, settled_l):
    import meshio
    from conftest import assert_figure
    from drystone.postprocess import snapshots, vtk

    data = stone_file([L_FOOT, L_LEG])
    pts, faces = snapshots.stone_geometry(data["blocks"])[7]
    assert len(pts) == 16 and len(faces) == 12  # two boxes' corners and faces, not their hull's 8 and 6
    assert_figure(snapshots.elevation(write(outdir, data), outdir / "elevation.png"), (10, 5), dpi=110)
    pvd = vtk.write(settled_l, every=10, out=outdir / "vtk")
    last = meshio.read(sorted(pvd.parent.glob("blocks_*.vtu"))[-1])
    ids = np.concatenate(last.cell_data["block_id"])
    assert len(ids) == 18 and (ids == 7).sum() == 12  # the platform's 6 faces and the L's 12
    assert len(last.points) == 8 + 16  # the platform's corners and both parts'
    assert_figure(snapshots.render(settled_l, [0.0, 1e9], outdir / "final.png"), (8.4, 4.2), dpi=110)


def test_modal_model_of_a_settled_multi_part_stone(settled_l):
    """The L settled on the platform enters the modal model as one rigid body: the union's
    mass and inertia (drystone/geometry/massprops.py) at the recorded position, its foot the
    only part in contact (one contact); the analysis gives six frequencies, the twist about z
    on that single joint held by its twist spring, and no motion without stiffness."""
    from drystone.analyses import modal as am
    from drystone.geometry import massprops
    from drystone.postprocess import identification

    asm = identification.wall_assembly(settled_l)
    b = asm.ids.index(7)
    mp = massprops.mass_properties([L_FOOT, L_LEG], RHO)
    assert len(asm.parts[b]) == 2 and asm.mass[b] == pytest.approx(mp.mass, rel=tol.EXACT_REL)
    np.testing.assert_allclose(np.linalg.eigvalsh(asm.inertia[b]), mp.principal_moments, rtol=tol.NUMERICAL_REL)
    r = am.analyse(asm)
    assert r["model"]["contacts"] == 1 and r["model"]["multi_part_stones"] == [7]
    assert len(r["frequencies_hz"]) == 6 and min(r["frequencies_hz"]) > 0
    assert not r["zero_modes"]


def test_named_contact_of_a_multi_part_stone_is_the_sum_of_its_parts(outdir):
    """A recorded joint between a platform and a stone of two parts standing on it is two
    contacts; the joint's history is their sum: the same normal force, area and volume as
    the uncut box's one contact (to round-off: K_n V and the areas are additive)."""
    whole = stone_file(vertices=box((0, 0, 0), (0.4, 0.2, 0.2)))
    halves = stone_file([box((0, 0, 0), (0.2, 0.2, 0.2)), box((0.2, 0, 0), (0.4, 0.2, 0.2))])
    out = {"interval": 0.01, "contacts": [{"name": "base", "blocks": [0, 7]}]}
    hs = [run_case(gravity_then([], write(outdir, d, f"{n}.json"), output=out, contact={"damping": 0.0},
                                time={"step": 2e-5}), outdir, name=n)[1]
          for n, d in (("whole", whole), ("halves", halves))]
    a, b = hs
    w = RHO * G * 0.4 * 0.2 * 0.2
    assert a["contacts"]["base"]["fn"][-1] == pytest.approx(w, rel=0.05)  # the weight, give or take the undamped bounce after the ramp
    for k in ("fn", "area", "volume"):
        assert np.allclose(a["contacts"]["base"][k], b["contacts"]["base"][k], rtol=tol.CUT_BLOCK_CONTACT_REL, atol=0)
    assert np.allclose(a["contacts"]["base"]["normal"], b["contacts"]["base"]["normal"], atol=tol.CUT_BLOCK_CONTACT_REL)
