"""Exact overlap of convex polyhedra (drystone/mechanics/overlap.py) against closed forms, an
independent half-space intersection (scipy/qhull) and finite differences."""
import numpy as np
import pytest
from scipy.spatial import HalfspaceIntersection

import tolerances as tol
from drystone.mechanics import overlap as ov
from drystone.geometry import polyhedron as ph


def box(lo, hi):
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])


def test_boxes_volume_centroid_gradient():
    """Two boxes pressed face to face: V = A delta, centroid mid-overlap, dV/dx_B = -A z."""
    a = box([0, 0, 0], [0.4, 0.2, 0.1])
    b = box([0.1, 0.05, 0.1 - 2e-5], [0.3, 0.15, 0.3])
    v, c, g = ov.overlap(a, b)
    assert v == pytest.approx(0.2 * 0.1 * 2e-5, rel=tol.NUMERICAL_REL)
    assert c == pytest.approx([0.2, 0.1, 0.1 - 1e-5], abs=tol.EXACT_ABS)
    assert g == pytest.approx([0, 0, -0.2 * 0.1], rel=tol.NUMERICAL_REL, abs=tol.ZERO_ABS)


def test_side_by_side_coplanar_faces_counted_once():
    """Stones side by side share their front, back, top and bottom planes: the thin
    overlap is still exactly delta x height x thickness, its normal along x."""
    a = box([0, 0, 0], [1, 0.8, 0.5])
    b = box([1 - 1e-5, 0, 0], [2, 0.8, 0.5])
    v, c, g = ov.overlap(a, b)
    assert v == pytest.approx(1e-5 * 0.8 * 0.5, rel=tol.THIN_OVERLAP_REL)
    assert g == pytest.approx([-0.4, 0, 0], rel=tol.THIN_OVERLAP_REL, abs=tol.EXACT_ABS)


@pytest.mark.parametrize("front", [0.0, 1e-13, -1e-13, 3e-11, -3e-11, 1e-6])
def test_coplanar_faces_in_any_orientation(front):
    """A bed joint 1e-4 m deep whose upper stone's front face is ``front`` metres behind
    the lower stone's (0 and +-1e-13: one plane within overlap.TOL; +-3e-11 and 1e-6: two),
    both stones turned and moved as one by 200 seeded rigid motions. Turned, the coplanar
    faces lie on either side of each other's planes by round-off: the front face is counted
    once all the same (not lost, not doubled), and the volume, centroid and dV/dx_B are the
    axis-aligned pair's turned with it."""
    a = box([0, 0, 0], [1.0, 0.6, 0.8])
    b = box([front, 0.2, 0.8 - 1e-4], [1.0, 0.7, 1.6])
    v0, c0, g0 = ov.overlap(a, b)
    assert v0 == pytest.approx(1e-4 * 0.4 * (1.0 - max(front, 0.0)), rel=tol.THIN_OVERLAP_REL)
    rng = np.random.default_rng(7)
    for _ in range(200):
        q = rng.normal(size=4)
        x, y, z, w = q / np.linalg.norm(q)
        r = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                      [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                      [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
        t = rng.uniform(-5.0, 5.0, 3)
        v, c, g = ov.overlap(a @ r.T + t, b @ r.T + t)
        assert v == pytest.approx(v0, rel=tol.THIN_OVERLAP_REL)
        assert c == pytest.approx(r @ c0 + t, abs=tol.THIN_OVERLAP_REL)
        assert g == pytest.approx(r @ g0, abs=tol.THIN_OVERLAP_REL * np.linalg.norm(g0))


def test_separated_and_touching_give_nothing():
    a = box([0, 0, 0], [1, 1, 1])
    assert ov.overlap(a, box([1.001, 0, 0], [2, 1, 1]))[0] == 0.0
    assert ov.overlap(a, box([1.0, 0, 0], [2, 1, 1]))[0] == pytest.approx(0.0, abs=tol.ZERO_ABS)


def test_wedge_area_is_the_footprint():
    """A block rocking on an edge: the overlap is a wedge of volume L w d / 2 and the
    area |dV/dx_B| is its footprint L w (the projected contact area), not V/d."""
    base = box([-1, -1, -0.1], [1, 1, 0])
    theta, d = 1e-3, 1e-4  # rotated about y, deepest edge d below z = 0
    blk = box([0, -0.1, 0], [0.2, 0.1, 0.3])
    r = np.array([[np.cos(theta), 0, np.sin(theta)], [0, 1, 0], [-np.sin(theta), 0, np.cos(theta)]])
    blk = blk @ r.T
    blk[:, 2] -= blk[:, 2].min() + d
    v, c, g = ov.overlap(base, blk)
    foot = d / np.tan(theta)  # length of the footprint along x
    assert v == pytest.approx(0.5 * foot * d * 0.2, rel=tol.WEDGE_REL)
    assert np.linalg.norm(g) == pytest.approx(foot * 0.2, rel=tol.WEDGE_REL)


def random_block(rng, centre, size):
    pts = rng.normal(size=(12, 3)) * size
    r = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    return pts @ r.T + centre


def qhull_overlap(va, vb):
    """Independent reference: half-space intersection by qhull, then its hull."""
    na, da = ph.planes(ph.hull(va))
    nb, db = ph.planes(ph.hull(vb))
    hs = np.vstack([np.hstack([na, da[:, None]]), np.hstack([nb, db[:, None]])])
    # an interior point: Chebyshev centre
    from scipy.optimize import linprog
    n = hs[:, :3]
    res = linprog([0, 0, 0, -1], A_ub=np.hstack([n, np.ones((len(n), 1))]), b_ub=-hs[:, 3],
                  bounds=[(None, None)] * 3 + [(0, None)], method="highs")
    inter = HalfspaceIntersection(hs, res.x[:3]).intersections
    return ph.volume_centroid(inter)


@pytest.mark.parametrize("seed", range(8))
def test_random_polyhedra_against_qhull_and_finite_differences(seed):
    rng = np.random.default_rng(seed)
    va = random_block(rng, np.zeros(3), 0.5)
    vb = random_block(rng, rng.normal(size=3) * 0.3, 0.5)
    v, c, g = ov.overlap(va, vb)
    ref_v, ref_c = qhull_overlap(va, vb)
    assert v == pytest.approx(ref_v, rel=tol.NUMERICAL_REL)
    assert c == pytest.approx(ref_c, abs=tol.NUMERICAL_ABS)
    h = 1e-6
    fd = [(ov.overlap(va, vb + h * e)[0] - ov.overlap(va, vb - h * e)[0]) / (2 * h) for e in np.eye(3)]
    assert g == pytest.approx(fd, rel=tol.GRADIENT_FD_REL, abs=tol.GRADIENT_FD_ABS)


def test_all_contacts_finds_pairs_with_a_moving_body():
    """Three stacked boxes, the bottom one fixed: two contacts, normals up, areas exact;
    two non-moving bodies are never paired."""
    shapes = [box([-0.5, -0.5, -0.5], [0.5, 0.5, 0.5])] * 4
    s = ov.Shapes(shapes)
    pos = np.array([[0, 0, 0], [0, 0, 1 - 1e-5], [0, 0, 2 - 3e-5], [3, 0, 0.0]])
    pos2 = pos.copy()
    pos2[3] = [0, 0, -1 + 1e-5]  # a second fixed body touching the first: ignored
    rot = np.repeat(np.eye(3)[None], 4, axis=0)
    moving = np.array([False, True, True, False])
    id1, id2, vol, cen, nrm, area = ov.all_contacts(s.verts, s.nv, s.normals, s.offsets, s.nf, s.faces, s.fk,
                                                    pos2, rot, moving, ov.TOL)
    assert list(zip(id1, id2)) == [(0, 1), (1, 2)]
    assert vol == pytest.approx([1e-5, 2e-5], rel=tol.THIN_OVERLAP_REL)
    assert nrm == pytest.approx(np.array([[0, 0, 1.0], [0, 0, 1.0]]), abs=tol.NUMERICAL_ABS)
    assert area == pytest.approx([1.0, 1.0], rel=tol.THIN_OVERLAP_REL)
