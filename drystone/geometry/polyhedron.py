"""Convex polyhedron helpers (numpy/scipy only, no YADE).

A block (or one convex part of a stone) is the convex hull of its vertices (metres). These
functions give the hull's volume (m^3), centroid (m) and second moment (m^5, ``moments``),
its planar faces (``faces``: the one place hull triangles are merged into faces), and the
overlap between two hulls, which is what the block-file validator, the mass properties,
the time-step estimate and the contact kernels need.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
from scipy.optimize import linprog
from scipy.spatial import ConvexHull, QhullError


class HullError(ValueError):
    """A vertex set that does not describe a proper convex solid."""


def hull(vertices) -> ConvexHull:
    """Convex hull of an (n, 3) vertex array; raises HullError if it has no volume."""
    v = np.asarray(vertices, dtype=float)
    if v.ndim != 2 or v.shape[1] != 3:
        raise HullError(f"vertices must be a list of [x, y, z] triples, got shape {v.shape}")
    if len(v) < 4:
        raise HullError(f"a solid needs at least 4 vertices, got {len(v)}")
    if not np.all(np.isfinite(v)):
        raise HullError("vertices contain a non-finite number")
    try:
        return ConvexHull(v)
    except QhullError as exc:
        raise HullError("vertices are coplanar or degenerate (zero volume)") from exc


def planes(h: ConvexHull) -> tuple[np.ndarray, np.ndarray]:
    """Outward unit normals N (m, 3) and offsets d (m) with N @ x + d <= 0 inside: the plane
    of every hull triangle, not merged into faces (a face cut into k triangles gives k equal
    rows; half-space tests need no more, and no rounding); ``faces`` merges them."""
    eq = h.equations
    return eq[:, :3], eq[:, 3]


def corner_gaps(vertices, h: ConvexHull | None = None, rows: int = 256) -> np.ndarray:
    """How far (m) each vertex stands out of the others along its vertex normal (the sum of
    the outward normals of the hull triangles that meet at it): min over j != i of
    n_i . (v_i - v_j). Positive for a corner of the hull; about 0 for a point on a face or
    an edge of the hull (or a repeated point); -inf for a point that Qhull does not list
    as a hull vertex (inside the hull, or on its surface). ``h``: the hull, if at hand.
    Memory: ``rows`` x n products at a time (time n_hull x n), never an n x n matrix."""
    v = np.asarray(vertices, dtype=float)
    h = hull(v) if h is None else h
    nsum = np.zeros_like(v)
    np.add.at(nsum, h.simplices, h.equations[:, None, :3])
    norm = np.linalg.norm(nsum, axis=1)
    unit = nsum / np.where(norm > 0, norm, 1.0)[:, None]
    gaps = np.full(len(v), -np.inf)
    for start in range(0, len(h.vertices), rows):
        idx = h.vertices[start:start + rows]
        p = unit[idx] @ v.T  # p[r, j] = n_i . v_j for i = idx[r]
        r = np.arange(len(idx))
        own = p[r, idx]
        p[r, idx] = -np.inf
        gaps[idx] = own - p.max(axis=1)
    return gaps


def _tetrahedra(vertices, h: ConvexHull | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The hull cut into tetrahedra from c0, the mean of its corners (inside it): c0 (m),
    each hull triangle's corners relative to c0 (f, 3, 3) m and six times each
    tetrahedron's volume (f,) m^3 (positive whatever Qhull's winding: c0 is inside)."""
    v = np.asarray(vertices, dtype=float)
    h = hull(v) if h is None else h
    c0 = v[h.vertices].mean(axis=0)
    tets = v[h.simplices] - c0  # (f, 3, 3): each face triangle with apex c0
    vol6 = np.abs(np.einsum("ij,ij->i", tets[:, 0], np.cross(tets[:, 1], tets[:, 2])))
    return c0, tets, vol6


def volume_centroid(vertices, h: ConvexHull | None = None) -> tuple[float, np.ndarray]:
    """Volume (m^3) and centroid (m) of the convex hull of ``vertices`` (``h``: that hull,
    if at hand)."""
    c0, tets, vol6 = _tetrahedra(vertices, h)
    vol = vol6.sum() / 6.0
    cent = c0 + (vol6[:, None] * tets.sum(axis=1) / 4.0).sum(axis=0) / vol6.sum()
    return float(vol), cent


def moments(vertices, h: ConvexHull | None = None) -> tuple[float, np.ndarray, np.ndarray]:
    """Volume (m^3), centroid (m) and second moment about the centroid
    S = int (x - c)(x - c)^T dV (m^5, a symmetric 3 x 3 tensor in the vertices' axes) of
    the convex hull of ``vertices``, exact (polyhedral integrals): the hull cut into
    tetrahedra from an inside point o, each with corners o, o + a, o + b, o + c and volume
    V gives int (x - o)(x - o)^T dV = V / 20 (a a^T + b b^T + c c^T + s s^T), s = a + b + c.
    Volume and centroid are ``volume_centroid``'s, bit for bit. The inertia tensor of a
    body of density rho is rho (tr(S) I - S) (``drystone.geometry.massprops``)."""
    c0, tets, vol6 = _tetrahedra(vertices, h)
    vol = vol6.sum() / 6.0
    cent = c0 + (vol6[:, None] * tets.sum(axis=1) / 4.0).sum(axis=0) / vol6.sum()
    s = tets.sum(axis=1)
    m2 = np.einsum("k,kpi,kpj->ij", vol6, tets, tets) + np.einsum("k,ki,kj->ij", vol6, s, s)
    m2 /= 120.0  # vol6 / 6 / 20: about c0
    d = cent - c0
    second = m2 - vol * np.outer(d, d)  # about the centroid (parallel axes)
    return float(vol), cent, second


def extent(vertices) -> np.ndarray:
    """Axis-aligned size (dx, dy, dz) in m."""
    v = np.asarray(vertices, dtype=float)
    return v.max(axis=0) - v.min(axis=0)


def overlap_thickness(va, vb) -> float:
    """Thickness (m) of the overlap of two convex hulls: twice the radius of the largest
    ball inside both (0 when they are disjoint or only touch).

    For two blocks pressed face to face by a depth d this is exactly d; for blocks that
    share a face it is 0. Solved as a Chebyshev-centre linear programme.
    """
    return planes_overlap(planes(hull(va)), planes(hull(vb)))


def planes_overlap(pa: tuple[np.ndarray, np.ndarray], pb: tuple[np.ndarray, np.ndarray]) -> float:
    """``overlap_thickness`` (m) of two hulls given by their ``planes``."""
    (na, da), (nb, db) = pa, pb
    n = np.vstack([na, nb])
    d = np.concatenate([da, db])
    # maximise r subject to n.x + d + r <= 0 (unit normals), r >= 0
    c = np.array([0.0, 0.0, 0.0, -1.0])
    a_ub = np.hstack([n, np.ones((len(n), 1))])
    res = linprog(c, A_ub=a_ub, b_ub=-d, bounds=[(None, None)] * 3 + [(0, None)], method="highs")
    if res.status == 2:  # infeasible: separated
        return 0.0
    if not res.success:
        raise HullError(f"overlap test failed: {res.message}")
    return float(2.0 * res.x[3])


#: decimals to which a hull triangle's plane (unit normal; offset, m) is rounded to tell
#: which triangles make up one planar face: 1e-9 is far above Qhull's round-off on
#: block-sized coordinates (~1e-15) and far below the angle (rad) or the step (m) between
#: two faces of a real block
FACE_DECIMALS = 9


def _cross(a, b) -> np.ndarray:
    """a x b for 3-vectors or (n, 3) arrays (np.cross's overhead dominates on small arrays)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    return np.stack([a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1], a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
                     a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]], axis=-1)


class Faces(NamedTuple):
    """The planar faces of a convex hull (``faces``)."""
    normals: np.ndarray  # (f, 3) outward unit normals
    offsets: np.ndarray  # (f,) m: normals @ x + offsets <= 0 inside
    polygons: list  # per face, its vertex indices counter-clockwise seen from outside
    areas: np.ndarray  # (f,) m^2


def faces(vertices, h: ConvexHull | None = None) -> Faces:
    """The hull's planar faces: the hull triangles whose planes agree to FACE_DECIMALS
    decimals merged, each face with the plane of its first triangle, its vertices ordered
    counter-clockwise seen from outside and its area (the sum of its triangles', in Qhull's
    order). ``h``: the hull of ``vertices``, if at hand."""
    v = np.asarray(vertices, dtype=float)
    h = hull(v) if h is None else h
    tri = v[h.simplices]
    tri_area = 0.5 * np.linalg.norm(_cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    # the triangles of one face: equal rounded planes, faces in the order of their first triangle
    _, first, which = np.unique(np.round(h.equations, FACE_DECIMALS), axis=0, return_index=True,
                                return_inverse=True)
    order = np.argsort(first, kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    tri_face = rank[which.ravel()]
    nf = len(order)
    eq = h.equations[first[order]]
    normals, offsets = eq[:, :3], eq[:, 3]
    areas = np.bincount(tri_face, tri_area, minlength=nf)
    # each face's distinct vertices, sorted by angle about its centroid
    pairs = np.unique(tri_face[:, None] * len(v) + h.simplices)
    face, idx = pairs // len(v), pairs % len(v)
    count = np.bincount(face, minlength=nf)
    c = np.stack([np.bincount(face, v[idx, k], minlength=nf) for k in range(3)], axis=1) / count[:, None]
    ref = np.where((np.abs(normals[:, 0]) < 0.9)[:, None], [1.0, 0, 0], [0, 1.0, 0])
    a = _cross(normals, ref)
    a /= np.linalg.norm(a, axis=1)[:, None]
    b = _cross(normals, a)  # (a, b, n) right-handed: increasing angle is counter-clockwise about n
    d = v[idx] - c[face]
    angle = np.arctan2(np.einsum("ij,ij->i", d, b[face]), np.einsum("ij,ij->i", d, a[face]))
    idx = idx[np.lexsort((angle, face))]
    polys = np.split(idx, np.cumsum(count)[:-1])
    return Faces(normals, offsets, polys, areas)
