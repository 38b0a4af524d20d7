"""Issue 25, items 1 and 6: one stone, several convex parts (block file version 2).

A block may give ``parts`` (convex vertex lists) instead of ``vertices``: one rigid body
whose mass, centroid and inertia are the union's (drystone/geometry/massprops.py), checked
here against closed forms for an L- and a T-shaped stone; parts that overlap, that touch
only along an edge or at a corner, or that lie apart are refused naming file, block and
part; version-1 files parse exactly as before."""
import json
from fractions import Fraction as Fr
from pathlib import Path

import numpy as np
import pytest

import tolerances as tol
from conftest import refused_run
from drystone.geometry import blockfile as bf
from drystone.geometry import massprops
from drystone.geometry import polyhedron as ph

ROOT = Path(__file__).resolve().parents[1]
RHO = 2000.0  # kg/m^3


def box(lo, hi):
    """The 8 corners of the axis-aligned box [lo, hi] (m)."""
    return [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]


def stone_file(parts=None, vertices=None, version=2, other=None):
    """A platform (id 0) under block 7 given as ``parts`` and/or ``vertices``; ``other``: a
    third block's vertices (id 8, free)."""
    b = {"id": 7, "role": "free", "material": "stone"}
    if parts is not None:
        b["parts"] = parts
    if vertices is not None:
        b["vertices"] = vertices
    blocks = [{"id": 0, "role": "platform", "material": "stone", "vertices": box((-1, -1, -0.1), (1, 1, 0))}, b]
    if other is not None:
        blocks.append({"id": 8, "role": "free", "material": "stone", "vertices": other})
    return {"format": bf.FORMAT, "version": version, "name": "t",
            "materials": {"stone": {"density": RHO, "kn": 2e8, "kt": 1e8, "mu": 0.4, "damping": 0.8}},
            "blocks": blocks, "control_points": [{"name": "top", "block": 7, "position": [0.0, 0.1, 0.4]}]}


def load(tmp_path, data, name="stone.json"):
    p = tmp_path / name
    p.write_text(json.dumps(data))
    return p, bf.load(p)


# --- closed forms ---------------------------------------------------------------------------

#: the L: a foot [0, 0.4] x [0, 0.2] x [0, 0.1] m and a leg [0, 0.1] x [0, 0.2] x [0.1, 0.4] m
#: on its left end, joined over the 0.1 x 0.2 m face z = 0.1
L_PARTS = [box((0, 0, 0), (0.4, 0.2, 0.1)), box((0, 0, 0.1), (0.1, 0.2, 0.4))]
#: the T: a stem [-0.05, 0.05] x [0, 0.2] x [0, 0.4] m and two arms [-0.25, -0.05] and
#: [0.05, 0.25] (x) x [0, 0.2] x [0.3, 0.4] m, each joined to the stem over a 0.2 x 0.1 m face
T_PARTS = [box((-0.05, 0, 0), (0.05, 0.2, 0.4)), box((-0.25, 0, 0.3), (-0.05, 0.2, 0.4)),
           box((0.05, 0, 0.3), (0.25, 0.2, 0.4))]


def _f(x):
    return float(Fr(x))


def test_l_shaped_stone_mass_properties_by_hand(tmp_path):
    """rho = 2000 kg/m^3. A box of sides a, b, c (x, y, z) and mass m has, about its centre,
    I = m/12 diag(b^2 + c^2, a^2 + c^2, a^2 + b^2); the union by the parallel-axis theorem
    I = sum_i [I_i + m_i (|d_i|^2 1 - d_i d_i^T)], d_i = c_i - c, products I_xz = -sum m d_x d_z.

    foot: 0.4 x 0.2 x 0.1, m = 16 kg, c = (0.2, 0.1, 0.05); I = (1/15, 17/75, 4/15)
    leg:  0.1 x 0.2 x 0.3, m = 12 kg, c = (0.05, 0.1, 0.25); I = (13/100, 1/10, 1/20)
    M = 28 kg; c = ((16 * 0.2 + 12 * 0.05) / 28, 0.1, (16 * 0.05 + 12 * 0.25) / 28) = (19/140, 0.1, 19/140)
    d_foot = (9/140, 0, -12/140), d_leg = (-12/140, 0, 16/140)  (m)
    I_xx = 1/15 + 16 (12/140)^2 + 13/100 + 12 (16/140)^2 = 989/2100
    I_yy = 17/75 + 16 (225/140^2) + 1/10 + 12 (400/140^2) = 793/1050
    I_zz = 4/15 + 16 (9/140)^2 + 1/20 + 12 (12/140)^2 = 989/2100   (x <-> z symmetric L)
    I_xz = -(16 (9)(-12) + 12 (-12)(16)) / 140^2 = 4032/19600 = 36/175; I_xy = I_yz = 0
    principal (the L is symmetric in x <-> z): I_xx - I_xz = 557/2100 about (1, 0, -1)/sqrt 2,
    I_xx + I_xz = 1421/2100 about (1, 0, 1)/sqrt 2, I_yy = 1586/2100 about y.
    Tolerance: EXACT_REL (a closed form against sums over ~50 tetrahedra)."""
    p, bs = load(tmp_path, stone_file(L_PARTS))
    mp = bs.mass_properties(7)
    assert mp.volume == pytest.approx(0.014, rel=tol.EXACT_REL)
    assert mp.mass == pytest.approx(28.0, rel=tol.EXACT_REL) and bs.mass(7) == pytest.approx(28.0, rel=tol.EXACT_REL)
    assert np.allclose(mp.centroid, [_f("19/140"), 0.1, _f("19/140")], rtol=0, atol=tol.EXACT_ABS)
    want = np.array([[_f("989/2100"), 0, _f("36/175")], [0, _f("793/1050"), 0], [_f("36/175"), 0, _f("989/2100")]])
    scale = np.abs(want).max()
    assert np.allclose(mp.inertia, want, rtol=0, atol=tol.EXACT_REL * scale), mp.inertia
    assert np.allclose(mp.principal_moments, [_f("557/2100"), _f("1421/2100"), _f("1586/2100")],
                       rtol=0, atol=tol.EXACT_REL * scale)
    s = np.sqrt(0.5)
    for k, axis in enumerate(([s, 0, -s], [s, 0, s], [0, 1, 0])):
        assert abs(abs(float(mp.principal_axes[:, k] @ axis)) - 1) < tol.EXACT_REL
    assert np.linalg.det(mp.principal_axes) == pytest.approx(1.0, rel=tol.EXACT_REL)


def test_t_shaped_stone_of_three_parts_mass_properties_by_hand(tmp_path):
    """rho = 2000 kg/m^3; boxes about their centres as in the L's test.

    stem: 0.1 x 0.2 x 0.4, m = 16 kg, c = (0, 0.1, 0.2);     I = (4/15, 17/75, 1/15)
    arms: 0.2 x 0.2 x 0.1, m = 8 kg,  c = (-+0.15, 0.1, 0.35); I = (1/30, 1/30, 4/75) each
    M = 32 kg; c = (0, 0.1, (16 * 0.2 + 16 * 0.35) / 32) = (0, 0.1, 11/40)
    d_stem = (0, 0, -0.075), d_arms = (-+0.15, 0, 0.075)
    I_xx = 4/15 + 16 (0.075^2) + 2 (1/30 + 8 (0.075^2)) = 77/150
    I_yy = 17/75 + 16 (0.075^2) + 2 (1/30 + 8 (0.15^2 + 0.075^2)) = 5/6
    I_zz = 1/15 + 2 (4/75 + 8 (0.15^2)) = 8/15
    products: 0 (the T is symmetric about x = 0 and y = 0.1). The arms touch each other
    nowhere: the stone is one solid through the stem (a chain 1 - 0 - 2)."""
    p, bs = load(tmp_path, stone_file(T_PARTS))
    mp = bs.mass_properties(7)
    assert mp.mass == pytest.approx(32.0, rel=tol.EXACT_REL)
    assert np.allclose(mp.centroid, [0.0, 0.1, _f("11/40")], rtol=0, atol=tol.EXACT_ABS)
    want = np.diag([_f("77/150"), _f("5/6"), _f("8/15")])
    assert np.allclose(mp.inertia, want, rtol=0, atol=tol.EXACT_REL * want.max()), mp.inertia
    assert np.allclose(mp.principal_moments, [_f("77/150"), _f("8/15"), _f("5/6")], rtol=0,
                       atol=tol.EXACT_REL * want.max())


def test_rotated_l_has_the_rotated_tensor():
    """The L turned by a rotation R about a point: centroid R c + t, inertia R I R^T (the
    joins found on faces of any orientation, the integrals exact off the axes)."""
    ang = np.radians([20.0, -35.0, 50.0])
    rx = np.array([[1, 0, 0], [0, np.cos(ang[0]), -np.sin(ang[0])], [0, np.sin(ang[0]), np.cos(ang[0])]])
    ry = np.array([[np.cos(ang[1]), 0, np.sin(ang[1])], [0, 1, 0], [-np.sin(ang[1]), 0, np.cos(ang[1])]])
    rz = np.array([[np.cos(ang[2]), -np.sin(ang[2]), 0], [np.sin(ang[2]), np.cos(ang[2]), 0], [0, 0, 1]])
    r, t = rz @ ry @ rx, np.array([0.3, -0.2, 1.5])
    parts = [(np.array(p) @ r.T + t).tolist() for p in L_PARTS]
    bs = bf.parse(stone_file(parts))
    mp, ref = bs.mass_properties(7), massprops.mass_properties([np.array(p, float) for p in L_PARTS], RHO)
    assert np.allclose(mp.centroid, r @ ref.centroid + t, rtol=0, atol=tol.EXACT_ABS)
    assert np.allclose(mp.inertia, r @ ref.inertia @ r.T, rtol=0, atol=tol.EXACT_REL * np.abs(ref.inertia).max())


@pytest.mark.parametrize("cut", [0, 1, 2])
def test_one_box_as_one_part_and_as_two_halves(cut):
    """A 0.4 x 0.2 x 0.3 m box cut in two along axis ``cut`` (at an uneven 0.3 of its
    length) has the box's mass properties to round-off: m/12 (b^2 + c^2) etc."""
    lo, hi = np.array([0.1, -0.2, 0.05]), np.array([0.5, 0.0, 0.35])
    mid = lo.copy()
    mid[cut] = lo[cut] + 0.3 * (hi[cut] - lo[cut])
    hi1, lo2 = hi.copy(), lo.copy()
    hi1[cut], lo2[cut] = mid[cut], mid[cut]
    whole = massprops.mass_properties([np.array(box(lo, hi))], RHO)
    halves = massprops.mass_properties([np.array(box(lo, hi1)), np.array(box(lo2, hi))], RHO)
    a, b, c = hi - lo
    m = RHO * a * b * c
    closed = m / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    for mp in (whole, halves):
        assert mp.mass == pytest.approx(m, rel=tol.EXACT_REL)
        assert np.allclose(mp.centroid, (lo + hi) / 2, rtol=0, atol=tol.EXACT_ABS)
        assert np.allclose(mp.inertia, closed, rtol=0, atol=tol.EXACT_REL * closed.max())
    assert np.allclose(halves.inertia, whole.inertia, rtol=0, atol=tol.EXACT_REL * closed.max())


def test_single_part_agrees_with_the_other_mass_property_codes():
    """For a convex stone the one home (massprops) agrees with the package's two earlier
    convex-only codes (modal analysis, LMGC90 translation; YADE's Polyhedra compute their own,
    from the same hull), and its volume and centroid are polyhedron.volume_centroid's bit
    for bit (convex walls keep their numbers)."""
    from drystone.mechanics import modal
    from drystone.studies.crosscheck import translate

    rng = np.random.default_rng(3)
    pts = rng.normal(size=(30, 3)) * [0.3, 0.2, 0.15] + [1.0, 0.5, 0.2]
    v = pts[ph.hull(pts).vertices]
    mp = massprops.mass_properties([v], RHO)
    m, c, inertia = modal.mass_properties(v, RHO)
    t = translate.mass_properties(v, translate.outward_triangles(v), RHO)
    scale = np.abs(inertia).max()
    for mass, cent, i in ((m, c, inertia), (t["mass"], t["centroid"], t["inertia"])):
        assert mp.mass == pytest.approx(mass, rel=tol.EXACT_REL)
        assert np.allclose(mp.centroid, cent, rtol=0, atol=tol.EXACT_ABS)
        assert np.allclose(mp.inertia, i, rtol=0, atol=tol.EXACT_REL * scale)
    vol, cent = ph.volume_centroid(v)
    assert mp.volume == vol and np.array_equal(mp.centroid, cent)


# --- version 1 unchanged, version 2 round trip ----------------------------------------------

def test_version_1_file_parses_as_before():
    """cases/examples/one_block.json: each block one part, its ``vertices`` the file's
    array, the face planes and volume those of its hull, the file's blocks written back as
    they are, version 1."""
    path = ROOT / "cases/examples/one_block.json"
    data = json.loads(path.read_text())
    bs = bf.load(path)
    assert [b.id for b in bs.blocks] == [0, 1] and bs.ids("free") == [1]
    for b, d in zip(bs.blocks, data["blocks"]):
        assert len(b.parts) == 1 and b.parts[0] is b.vertices and b.points is b.vertices
        assert b.vertices.dtype == float and np.array_equal(b.vertices, np.array(d["vertices"], float))
        assert (b.role, b.material, b.blocked_dofs, b.label) == (d["role"], d["material"], "", "")
        h = ph.hull(b.vertices)
        assert all(np.array_equal(x, y) for x, y in zip(b.planes(), ph.planes(h)))
        assert b.volume == ph.volume_centroid(b.vertices)[0]
        assert np.array_equal(b.centroid, ph.volume_centroid(b.vertices)[1])
    assert bs.mass(1) == pytest.approx(2300 * 0.2 ** 3, rel=tol.EXACT_REL)
    out = bs.to_dict()
    assert out["version"] == 1 and all("parts" not in b for b in out["blocks"])
    assert out["blocks"] == data["blocks"] and out["control_points"] == data["control_points"]
    assert out["materials"] == data["materials"] and out["name"] == data["name"]


def test_version_2_round_trip(tmp_path):
    """An L (two parts) written and read back: the same parts, bit for bit, version 2; a
    one-part block of a version-2 file is written as ``vertices``."""
    p, bs = load(tmp_path, stone_file(L_PARTS, other=box((0.5, 0, 0), (0.7, 0.2, 0.2))))
    q = bf.write(bs, tmp_path / "again.json")
    raw = json.loads(q.read_text())
    assert raw["version"] == 2
    assert raw["blocks"][1]["parts"] == [[[float(x) for x in v] for v in part] for part in L_PARTS]
    assert "vertices" not in raw["blocks"][1] and "parts" not in raw["blocks"][2]
    again = bf.load(q)
    for a, b in zip(bs.blocks, again.blocks):
        assert len(a.parts) == len(b.parts) and all(np.array_equal(x, y) for x, y in zip(a.parts, b.parts))
    assert again.mass_properties(7).inertia.tolist() == bs.mass_properties(7).inertia.tolist()
    assert again.control_points == bs.control_points
    # a version-2 file whose blocks are each one part is written as version 1
    one = bf.parse(stone_file(vertices=box((0, 0, 0), (0.1, 0.1, 0.1))))
    assert one.to_dict()["version"] == 1


def test_multi_part_stone_has_no_vertices_but_points():
    """``vertices`` is one convex body: a multi-part stone refuses it (its hull would be a
    bigger stone), naming the block; ``points`` hold every part's corners."""
    bs = bf.parse(stone_file(L_PARTS))
    b = bs.block(7)
    with pytest.raises(bf.GeometryError, match="block 7 has 2 parts"):
        b.vertices
    with pytest.raises(bf.GeometryError, match="block 7 has 2 parts"):
        b.planes()
    assert b.points.shape == (16, 3) and np.array_equal(b.points.max(axis=0), [0.4, 0.2, 0.4])
    assert len(b.part_planes()) == 2


# --- refusals -------------------------------------------------------------------------------

EDGE = [box((0, 0, 0), (0.2, 0.2, 0.1)), box((0.2, 0, 0.1), (0.4, 0.2, 0.2))]  # share the edge x = 0.2, z = 0.1
CORNER = [box((0, 0, 0), (0.2, 0.2, 0.1)), box((0.2, 0.2, 0.1), (0.4, 0.4, 0.2))]  # share the corner (0.2, 0.2, 0.1)
APART = [box((0, 0, 0), (0.2, 0.2, 0.1)), box((0.3, 0, 0), (0.5, 0.2, 0.1))]
#: the edge pair pushed 0.5 um into each other along x: an overlap the 1 um tolerance lets
#: pass, a shared strip 0.5 um wide, not a face
EDGE_MISALIGNED = [box((0, 0, 0), (0.2, 0.2, 0.1)), box((0.2 - 5e-7, 0, 0.1), (0.4, 0.2, 0.2))]
OVERLAPPING = [box((0, 0, 0), (0.2, 0.2, 0.1)), box((0.15, 0, 0), (0.35, 0.2, 0.1))]
#: three parts: 0 and 1 joined, 2 apart
TWO_AND_ONE = [box((0, 0, 0), (0.2, 0.2, 0.1)), box((0.2, 0, 0), (0.4, 0.2, 0.1)), box((0.6, 0, 0), (0.7, 0.2, 0.1))]


@pytest.mark.parametrize("data, words", [
    (stone_file(OVERLAPPING), ["block 7: parts 0 and 1 interpenetrate by 0.05 m"]),
    (stone_file(EDGE), ["block 7 (a stone of 2 parts): part {1} is not joined face to face to the rest",
                        "{0}", "edge or at a corner"]),
    (stone_file(CORNER), ["block 7 (a stone of 2 parts): part {1} is not joined face to face"]),
    (stone_file(APART), ["block 7 (a stone of 2 parts): part {1} is not joined face to face"]),
    (stone_file(EDGE_MISALIGNED), ["block 7 (a stone of 2 parts): part {1} is not joined face to face"]),
    (stone_file(TWO_AND_ONE), ["block 7 (a stone of 3 parts): part {2} is not joined", "{0, 1}"]),
    (stone_file([EDGE[1], EDGE[0], box((0.6, 0, 0), (0.7, 0.2, 0.1))]),
     ["block 7 (a stone of 3 parts): parts {1, 2} are not joined"]),
    (stone_file(L_PARTS, version=1), ["block 7: 'parts' needs version 2 (this file is version 1)"]),
    (stone_file(L_PARTS, vertices=L_PARTS[0]), ["block 7: give either 'vertices'", "not both"]),
    (stone_file([L_PARTS[0], L_PARTS[1] + [[0.05, 0.1, 0.3]]]), ["block 7: part 1: not convex"]),
    (stone_file([L_PARTS[0], L_PARTS[1][:3]]), ["block 7: part 1: a solid needs at least 4 vertices"]),
    (stone_file([L_PARTS[0], [[0, 0, "x"]] + L_PARTS[1][1:]]), ["block 7: part 1: vertices contain"]),
    (stone_file([L_PARTS[0], 5]), ["block 7: part 1: its vertices must be a list"]),
    (stone_file([]), ["block 7: 'parts' must be a non-empty list"]),
    (stone_file(L_PARTS, other=box((0.05, 0.05, 0.3), (0.3, 0.3, 0.5))),
     ["blocks 7 and 8 interpenetrate by", "(part 1 of block 7 and part 0 of block 8)"]),
    (stone_file(L_PARTS, version=3), ["unsupported 'version' 3 (this reader: 1 or 2)"]),
])
def test_refusals_name_file_stone_and_part(tmp_path, data, words):
    p = tmp_path / "stone.json"
    p.write_text(json.dumps(data))
    with pytest.raises(bf.GeometryError) as err:
        bf.load(p)
    msg = str(err.value)
    assert msg.startswith(f"{p}: ") and "\n" not in msg, msg
    for w in words:
        assert w in msg, msg


def test_joined_parts_with_round_off_gaps_are_accepted():
    """Parts 0.5 um apart (within OVERLAP_TOL) across a full face are one solid; a stone of
    an L whose foot is cut again in two (three parts, a chain) too."""
    gap = [box((0, 0, 0), (0.2, 0.2, 0.1)), box((0.2 + 5e-7, 0, 0), (0.4, 0.2, 0.1))]
    assert len(bf.parse(stone_file(gap)).block(7).parts) == 2
    chain = [box((0, 0, 0), (0.1, 0.2, 0.1)), box((0.1, 0, 0), (0.4, 0.2, 0.1)), L_PARTS[1]]
    mp = bf.parse(stone_file(chain)).mass_properties(7)
    ref = massprops.mass_properties([np.array(p, float) for p in L_PARTS], RHO)
    assert mp.mass == pytest.approx(ref.mass, rel=tol.EXACT_REL)
    assert np.allclose(mp.inertia, ref.inertia, rtol=0, atol=tol.EXACT_REL * np.abs(ref.inertia).max())


def test_too_many_parts_refused_before_any_hull(tmp_path, monkeypatch):
    """MAX_PARTS_PER_BLOCK + 1 parts: refused naming file, block and limit, before any hull."""
    hull, hulled = ph.hull, []

    def counted(v, *args, **kwargs):
        hulled.append(len(v))
        return hull(v, *args, **kwargs)

    n = bf.MAX_PARTS_PER_BLOCK + 1
    parts = [box((0.01 * k, 0, 0), (0.01 * (k + 1), 0.2, 0.1)) for k in range(n)]
    p = tmp_path / "many.json"
    p.write_text(json.dumps(stone_file(parts)))
    monkeypatch.setattr(ph, "hull", counted)
    with pytest.raises(bf.GeometryError) as err:
        bf.load(p)
    assert hulled == [8]  # the platform's (block 0, listed before the stone), no part's
    assert str(err.value).startswith(f"{p}: block 7: {n} parts, more than {bf.MAX_PARTS_PER_BLOCK}")
    monkeypatch.undo()
    ok = stone_file(parts[:-1])
    assert len(bf.parse(ok).block(7).parts) == bf.MAX_PARTS_PER_BLOCK


