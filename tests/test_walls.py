"""Irregular wall generator (drystone/geometry/irregular_wall.py)."""
import numpy as np
import pytest

import tolerances as tol
from conftest import assert_figure
from drystone.geometry import blockfile as bf
from drystone.geometry import irregular_wall as iw


def stones(d):
    return [b for b in d["blocks"] if b["role"] != "platform"]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_tilt_wall_valid_tiles_and_weighs_1371(seed):
    """Convex, no overlaps (blockfile.parse), the stones tile L x H x T exactly (1e-9) and
    the wall weighs 1371 N at 2300 kg/m^3 (paper §3.2)."""
    d = iw.tilt_wall(seed=seed)
    bs = bf.parse(d)
    vol = sum(b.volume for b in bs.blocks if b.role != "platform")
    t = d["generator"]["thickness"]
    assert vol == pytest.approx(1.5 * 0.375 * t, rel=tol.NUMERICAL_REL)
    assert vol * 2300 * 9.81 == pytest.approx(1371, rel=tol.WALL_WEIGHT_REL)
    assert t == pytest.approx(0.1080, abs=tol.WALL_THICKNESS_M)
    first = [b for b in bs.blocks if b.role == "fixed"]
    assert first and all(np.min(b.vertices[:, 2]) == pytest.approx(0.0) for b in first)


def test_reproducible_and_seeded():
    assert iw.tilt_wall(seed=3) == iw.tilt_wall(seed=3)
    assert iw.tilt_wall(seed=3)["blocks"] != iw.tilt_wall(seed=4)["blocks"]


def test_joints_not_vertical_and_staggered():
    """Irregular walls have leaning head joints; head joints of consecutive courses are at
    least stagger x mean stone length apart along their shared bed joint."""
    d = iw.make(seed=5, irregularity=0.5, stagger=0.25)
    bf.parse(d)
    leans, per_course = [], {}
    for b in stones(d):
        v = np.asarray(b["vertices"])[::2]  # the front face (y = -T/2)
        xs = sorted(v[:, 0])
        leans.append(abs(v[3, 0] - v[0, 0]))
        per_course.setdefault(int(b["label"].split()[1]), []).append(v)
    assert max(leans) > 1e-3
    courses = [per_course[k] for k in sorted(per_course)]
    gap = 0.25 * 0.15
    for below, above in zip(courses[:-1], courses[1:]):
        tops = [q[3, 0] for q in below if tol.SLACK < q[3, 0] < 1.5 - tol.SLACK]
        bottoms = [q[0, 0] for q in above if tol.SLACK < q[0, 0] < 1.5 - tol.SLACK]
        for x in bottoms:
            assert min(abs(x - t) for t in tops) >= gap - tol.SLACK_TIGHT


def test_zero_irregularity_is_level_and_vertical():
    d = iw.make(seed=0, irregularity=0.0)
    for b in stones(d):
        v = np.asarray(b["vertices"])
        assert len(set(np.round(v[:, 0], 12))) == 2  # two vertical head joints


def test_bad_parameters():
    with pytest.raises(ValueError, match="irregularity"):
        iw.make(irregularity=1.5)
    with pytest.raises(ValueError, match="stone_length"):
        iw.make(stone_length=(0.3, 0.2))


def test_sacsayhuaman_numbering_roles_control_points(tmp_path):
    """40 stones numbered 1..40 (+ platform 0); 1-7 fixed on the platform; side blocks 8,
    9, 14, 15, 24, 25, 34 at the wall's ends with blocked_dofs 'xYZ'; A-D on top of 35, 38,
    39, 40 at z = 4 m; the stones tile 8.64 x 4 x 0.8 m."""
    from drystone.geometry import sacsayhuaman as sw
    from drystone.postprocess import snapshots
    d = sw.make(seed=1)
    bs = bf.parse(d)
    assert sorted(bs.ids()) == list(range(41))
    assert bs.ids("fixed") == list(range(1, 8))
    assert all(np.min(bs.block(b).vertices[:, 2]) == pytest.approx(0.0) for b in range(1, 8))
    side = sorted(b.id for b in bs.blocks if b.blocked_dofs)
    assert side == [8, 9, 14, 15, 24, 25, 34] and all(bs.block(b).blocked_dofs == "xYZ" for b in side)
    for b in side:
        x = bs.block(b).vertices[:, 0]
        assert x.min() == pytest.approx(0.0) or x.max() == pytest.approx(8.64)
    cps = {c["name"]: c for c in d["control_points"]}
    assert {k: c["block"] for k, c in cps.items()} == {"A": 35, "B": 38, "C": 39, "D": 40}
    assert all(c["position"][2] == pytest.approx(4.0) for c in cps.values())
    vol = sum(b.volume for b in bs.blocks if b.role != "platform")
    assert vol == pytest.approx(8.64 * 4.0 * 0.8, rel=tol.NUMERICAL_REL)
    bf.write(d, tmp_path / "s.json")
    assert_figure(snapshots.elevation(tmp_path / "s.json", tmp_path / "s.png"), (10, 5), dpi=110)


def _depths(d):
    return np.array([np.ptp(np.asarray(b["vertices"])[:, 1]) for b in stones(d)])


@pytest.mark.parametrize("flush", [None, "+y", "-y"])
def test_varying_depth_keeps_face_weight_and_bounds(flush):
    """Stones of varying depth: the same front-face layout as the extruded wall of the same
    seed, a valid block set (convex, no overlaps), the extruded wall's volume (so 1371 N,
    1e-9), depths in the ratio of thickness x (1 +- spread) (the volume rescaling is one
    factor for all), a real spread of depths, and the flush face fair."""
    spread = 1 / 3
    ext = iw.tilt_wall(seed=2, depth_spread=0.0)
    var = iw.tilt_wall(seed=2, depth_spread=spread, flush=flush)
    bs = bf.parse(var)
    t = var["generator"]["thickness"]
    for a, b in zip(stones(ext), stones(var)):
        va, vb = np.asarray(a["vertices"]), np.asarray(b["vertices"])
        assert np.array_equal(va[:, [0, 2]], vb[:, [0, 2]])
    vol = sum(b.volume for b in bs.blocks if b.role != "platform")
    assert vol == pytest.approx(1.5 * 0.375 * t, rel=tol.NUMERICAL_REL)
    d = _depths(var)
    assert d.max() / d.min() <= (1 + spread) / (1 - spread) + tol.SLACK_TIGHT
    assert (1 - tol.DEPTH_MEAN_REL) * t < np.mean(d) < (1 + tol.DEPTH_MEAN_REL) * t
    assert d.std() > tol.DEPTH_SD_MIN_REL * t  # uniform on +-1/3: sd = t / (3 sqrt 3) = 0.19 t
    ys = np.array([[np.min(np.asarray(b["vertices"])[:, 1]), np.max(np.asarray(b["vertices"])[:, 1])]
                   for b in stones(var)])
    if flush is None:
        assert np.allclose(ys.sum(axis=1), 0.0, atol=tol.EXACT_ABS)  # centred on the mid-plane
    elif flush == "+y":
        assert np.allclose(ys[:, 1], t / 2, atol=tol.EXACT_ABS)
    else:
        assert np.allclose(ys[:, 0], -t / 2, atol=tol.EXACT_ABS)
    plat = np.asarray(var["blocks"][0]["vertices"])
    assert plat[:, 1].min() < ys.min() and plat[:, 1].max() > ys.max()  # the platform carries every stone


def test_zero_depth_spread_is_the_extruded_wall():
    """depth_spread = 0 extrudes every stone through the thickness (the generator's default;
    the Santa-Cruz tilt wall varies the depth by default)."""
    assert iw.make(seed=1, depth_spread=0.0) == iw.make(seed=1)
    ext = iw.tilt_wall(seed=1, depth_spread=0.0)
    assert np.allclose(_depths(ext), ext["generator"]["thickness"], rtol=tol.EXACT_REL)
    assert iw.tilt_wall(seed=1)["generator"]["depth_spread"] == pytest.approx(1 / 3)


def test_bad_depth_parameters():
    with pytest.raises(ValueError, match="depth_spread"):
        iw.make(depth_spread=1.0)
    with pytest.raises(ValueError, match="flush"):
        iw.make(depth_spread=0.2, flush="front")
