"""Exact overlap of convex polyhedra, compiled with numba (no YADE import).

For two convex blocks A and B (half-spaces N x + d <= 0), the overlap I = A ∩ B is
bounded by the faces of A clipped to B and the faces of B clipped to A (each clipped face
keeps its block's outward normal, which is outward for I too). From these polygons:

* volume V and centroid of I (tetrahedra from a point of I to each polygon's fan);
* the gradient of V with respect to a translation of B:  dV/dx_B = sum over the faces of B
  inside A of (area x outward normal) = -(the same sum over the faces of A inside B);
* the contact patch (footprint): the faces of B inside A projected on the plane normal to
  n, each weighted by the cosine between its normal and -n (so that faces across the joint
  count as their projection and faces along it not at all). Its area is |dV/dx_B|; its
  centroid p and its second moment J = int (x - p)(x - p)^T dA (m^4, a 3x3 tensor in the
  plane) carry the distributed contact damping (``drystone.mechanics.contact``).

The project's normal force F_n = K_n V (Sacsayhuaman paper Eq. 5 in YADE's volumetric form)
then acts along  n = -dV/dx_B / |dV/dx_B|  (from A to B), the direction in which the
overlap shrinks fastest, and |dV/dx_B| is the contact area A_c: the overlap's footprint,
exact for a flat joint (A_c delta = V) and for a block rocking on an edge (a wedge) alike.

Coplanar faces of A and B with the same outward normal (two stones of a wall, their
front faces in one plane) bound I on the same plane; that boundary is A's face there,
clipped to B's other planes, and B's face is left out (``_coplanar``: normals parallel to
1e-12 and each face's vertices within ``tol`` = 1e-11 m of the other's plane, far above
round-off at wall scale). Clipping A's face to B's plane too would keep or drop all of it on
the sign of round-off distances (~1e-16 m): with B's face left out, the overlap of a bed
joint that reaches the wall's front then lost its front face, and its volume jumped by a
fifth as a stone turned by round-off. Exactly touching faces (opposite normals, one plane)
give two polygons that cancel: V = 0.

Touching. The two polygons cancel exactly only where the faces' vertices have the same
coordinates (boxes on a grid). Two stones that touch on a sloping joint (an irregular wall)
are clipped differently by round-off: one face comes out whole and the other a sliver, and
the "overlap" has V ~ 1e-17 m^3 and |dV/dx_B| ~ 1e-17 m^2, both round-off, their ratio (a
depth) metres, which stops a run as tunnelling. So the contact search takes a pair as no
contact when a face plane of one body has every vertex of the other outside it or on it
within ``tol`` (``_apart``): their overlap is then no thicker than tol, its force below
K_n tol A_c (2 mN per m^2 of joint at K_n = 2e8 N/m^3); the pairs it drops are the
touching ones and the separated ones whose boxes overlap (no clip for them). This rule is
``TOUCHING_IS_NO_CONTACT``; without it the search gives the clip's contacts.

Contact search (``contacts_with_patches``): the bodies' bounding boxes are sorted and swept
(``sweep_pairs``, O(n log n) plus the pairs that overlap along the sweep axis) for the
candidate pairs, in lexicographic order, which are then clipped. A non-convex stone is
several convex shapes of one body (``contacts_of_shapes``: its parts never pair with
each other).

Reference counts. The per-pair kernels (``pair_contact`` and what it calls) allocate
nothing and are compiled without numba's reference counting (``_nrt=False``): every view
of a shape's arrays (``GV[i]``) and of a contact's row would otherwise cost an atomic add
and subtract, a fifth of the time of a pair loop (measured with ``perf``); their callers
pass whole arrays and indices and keep the references.

Units: metres. Arrays: per body, local vertices (nv, 3), face planes (nf, 3) + (nf,),
faces as vertex indices padded with -1, counter-clockwise seen from outside.
"""
from __future__ import annotations

import numpy as np
from numba import njit
from drystone import numba_cache

numba_cache.install()  # numba's cache safe for processes compiling at once

TOL = 1e-11  # m
MAXV = 96  # vertices of a clipped face polygon (a face of k vertices clipped by p planes has <= k + p)


class Shapes:
    """The blocks' local geometry as padded arrays for the kernels (from vertex lists)."""

    def __init__(self, local_vertices: list):
        from drystone.geometry import polyhedron as ph

        nb = len(local_vertices)
        geo = [ph.faces(v) for v in local_vertices]
        maxv = max(len(v) for v in local_vertices)
        maxf = max(len(g.normals) for g in geo)
        maxk = max(len(p) for g in geo for p in g.polygons)
        self.verts = np.zeros((nb, maxv, 3))
        self.nv = np.zeros(nb, np.int64)
        self.normals = np.zeros((nb, maxf, 3))
        self.offsets = np.zeros((nb, maxf))
        self.nf = np.zeros(nb, np.int64)
        self.faces = -np.ones((nb, maxf, maxk), np.int64)
        self.fk = np.zeros((nb, maxf), np.int64)
        for i, (v, (n, d, polys, _)) in enumerate(zip(local_vertices, geo)):
            v = np.asarray(v, float)
            self.verts[i, :len(v)] = v
            self.verts[i, len(v):] = v[0]
            self.nv[i] = len(v)
            self.normals[i, :len(n)] = n
            self.offsets[i, :len(n)] = d
            self.nf[i] = len(n)
            for k, p in enumerate(polys):
                self.faces[i, k, :len(p)] = p
                self.fk[i, k] = len(p)
        if maxk + maxf > MAXV // 2:
            raise ValueError(f"blocks with {maxk}-gon faces and {maxf} faces exceed the overlap kernel's "
                             f"polygon buffer ({MAXV}); simplify the blocks")


def too_large(vertices) -> str | None:
    """Why a convex block (its corners, m) does not fit the kernel's polygon buffer (its
    largest face's corners plus its faces above ``MAXV // 2``: ``Shapes``), or None. By
    Euler's formula a block of V corners with a k-gon face has at most 2V - 1 - k faces,
    so blocks of up to MAXV // 4 corners always fit and are not looked at (a box: 8)."""
    if 2 * len(vertices) - 1 <= MAXV // 2:
        return None
    from drystone.geometry import polyhedron as ph

    g = ph.faces(np.asarray(vertices, float))
    k, nf = max(len(p) for p in g.polygons), len(g.normals)
    if k + nf <= MAXV // 2:
        return None
    return (f"{nf} faces and a {k}-gon face exceed the contact kernel's polygon buffer ({MAXV}: faces + the "
            f"largest face's corners <= {MAXV // 2}); give the block fewer corners")


@njit(cache=True, _nrt=False)
def _twice_area_vector(polys, s, k):
    """Twice the area vector (m^2) of the planar polygon polys[s, :k] (counter-clockwise about it)."""
    ax = 0.0
    ay = 0.0
    az = 0.0
    for q in range(k):
        j = q + 1 if q + 1 < k else 0
        ax += polys[s, q, 1] * polys[s, j, 2] - polys[s, q, 2] * polys[s, j, 1]
        ay += polys[s, q, 2] * polys[s, j, 0] - polys[s, q, 0] * polys[s, j, 2]
        az += polys[s, q, 0] * polys[s, j, 1] - polys[s, q, 1] * polys[s, j, 0]
    return ax, ay, az


@njit(cache=True, _nrt=False)
def _clip(P, k, S, Q):
    """Sutherland-Hodgman: keep the part of polygon P[:k] whose signed distances S[:k] to
    a plane are <= 0; into Q. Returns the new vertex count."""
    m = 0
    for i in range(k):
        j = i + 1 if i + 1 < k else 0
        sa = S[i]
        sb = S[j]
        if sa <= 0.0:
            Q[m, 0] = P[i, 0]
            Q[m, 1] = P[i, 1]
            Q[m, 2] = P[i, 2]
            m += 1
        if (sa < 0.0 < sb) or (sb < 0.0 < sa):
            t = sa / (sa - sb)
            Q[m, 0] = P[i, 0] + t * (P[j, 0] - P[i, 0])
            Q[m, 1] = P[i, 1] + t * (P[j, 1] - P[i, 1])
            Q[m, 2] = P[i, 2] + t * (P[j, 2] - P[i, 2])
            m += 1
    return m


@njit(cache=True, _nrt=False)
def _coplanar(NA, DA, VA, FA, FKA, f, NB, DB, VB, FB, FKB, p, tol):
    """Face f of A and face p of B lie in one plane with the same outward normal: normals
    parallel to 1e-12 (their cosine), every vertex of each face within ``tol`` of the other
    face's plane (module docstring). A's face is always the first argument, so both bodies'
    passes of ``_clip_pair`` get the same answer from the same arithmetic."""
    if NA[f, 0] * NB[p, 0] + NA[f, 1] * NB[p, 1] + NA[f, 2] * NB[p, 2] <= 1.0 - 1e-12:
        return False
    for q in range(FKA[f]):
        v = FA[f, q]
        if not abs(NB[p, 0] * VA[v, 0] + NB[p, 1] * VA[v, 1] + NB[p, 2] * VA[v, 2] + DB[p]) < tol:
            return False
    for q in range(FKB[p]):
        v = FB[p, q]
        if not abs(NA[f, 0] * VB[v, 0] + NA[f, 1] * VB[v, 1] + NA[f, 2] * VB[v, 2] + DA[f]) < tol:
            return False
    return True


@njit(cache=True, _nrt=False)
def _faces_inside(V, F, FK, nf, N1, D1, V2, F2, FK2, nv2, N2, D2, nf2, dedup, tol, polys, counts, start, A, B, S, r0, r1,
                  r2, npts):
    """Clip every face of one body (global vertices V, faces F, FK, planes N1, D1) to the
    other body's half-spaces (N2 x + D2 <= 0; its vertices V2[:nv2], faces F2, FK2); store
    the non-empty polygons from index ``start``. A face whose plane the other body does not
    reach (all its vertices more than ``tol`` inside the plane) is skipped without a clip:
    no part of it can be in the other body. Coplanar faces (``_coplanar``): in A's pass
    (``dedup`` False) a face is not clipped to the other body's plane it lies in; in B's
    pass (``dedup``) the face is skipped: A's face bounds the overlap there. A, B: (MAXV, 3)
    work arrays; S (MAXV,) the signed distances. Returns (the next index, r0, r1, r2, npts):
    the sums r0, r1, r2 of the stored vertices' coordinates and their number npts, continued
    from those given (``_volume``)."""
    c = start
    for f in range(nf):
        reached = False  # a vertex of the other body within tol of the plane or beyond it
        for q in range(nv2):
            sq = N1[f, 0] * V2[q, 0] + N1[f, 1] * V2[q, 1] + N1[f, 2] * V2[q, 2] + D1[f]
            if not sq < -tol:  # NaN too (a blown-up body): then the clip decides
                reached = True
                break
        if not reached:
            continue
        if dedup:
            dup = False
            for p in range(nf2):
                if _coplanar(N2, D2, V2, F2, FK2, p, N1, D1, V, F, FK, f, tol):  # (A's face first)
                    dup = True
                    break
            if dup:
                continue
        k = FK[f]
        P = A
        Q = B
        for q in range(k):
            P[q, 0] = V[F[f, q], 0]
            P[q, 1] = V[F[f, q], 1]
            P[q, 2] = V[F[f, q], 2]
        for p in range(nf2):
            # a plane with the whole polygon on its inner side leaves it unchanged (the clip
            # would copy it as it is), one with all of it strictly outside removes it
            n0, n1, n2, d = N2[p, 0], N2[p, 1], N2[p, 2], D2[p]
            smax = -np.inf
            smin = np.inf
            total = 0.0  # NaN if a distance is (a blown-up body): then the clip decides
            for q in range(k):
                sq = n0 * P[q, 0] + n1 * P[q, 1] + n2 * P[q, 2] + d
                S[q] = sq
                total += sq
                if sq > smax:
                    smax = sq
                if sq < smin:
                    smin = sq
            if total == total:
                if smax <= 0.0:
                    continue
                if not dedup and _coplanar(N1, D1, V, F, FK, f, N2, D2, V2, F2, FK2, p, tol):
                    continue  # the face lies in this plane: it bounds the overlap there
                if smin > 0.0:
                    k = 0
                    break
            k = _clip(P, k, S, Q)
            P, Q = Q, P  # the clipped polygon is the next one to clip
            if k < 3:
                break
        if k >= 3:
            for q in range(k):
                x0 = P[q, 0]
                x1 = P[q, 1]
                x2 = P[q, 2]
                polys[c, q, 0] = x0
                polys[c, q, 1] = x1
                polys[c, q, 2] = x2
                r0 += x0
                r1 += x1
                r2 += x2
            npts += k
            counts[c] = k
            c += 1
    return c, r0, r1, r2, npts


@njit(cache=True)
def _work(maxf):
    """(polys, counts, A, B, S, areas): the work arrays of ``_clip_pair`` (polys .. S) and
    of ``_volume`` and ``_patch`` (areas: the polygons' twice area vectors) for bodies of
    <= maxf faces."""
    return (np.empty((2 * maxf, MAXV, 3)), np.zeros(2 * maxf, np.int64), np.empty((MAXV, 3)), np.empty((MAXV, 3)),
            np.empty(MAXV), np.empty((2 * maxf, 3)))


@njit(cache=True, _nrt=False)
def _clip_pair(VA, nva, FA, FKA, nfa, NA, DA, VB, nvb, FB, FKB, nfb, NB, DB, tol, polys, counts, A, B, S):
    """The polygons bounding A ∩ B into ``polys``: A's faces clipped to B (the first
    ``na``), then B's faces clipped to A (to ``nt``); returns (na, nt, r0, r1, r2, npts):
    the sums of the coordinates of the vertices of ``polys[:nt]``, added up polygon by
    polygon as they are stored, and their number (``_volume``)."""
    na, r0, r1, r2, npts = _faces_inside(VA, FA, FKA, nfa, NA, DA, VB, FB, FKB, nvb, NB, DB, nfb, False, tol, polys,
                                         counts, 0, A, B, S, 0.0, 0.0, 0.0, 0)
    nt, r0, r1, r2, npts = _faces_inside(VB, FB, FKB, nfb, NB, DB, VA, FA, FKA, nva, NA, DA, nfa, True, tol, polys,
                                         counts, na, A, B, S, r0, r1, r2, npts)
    return na, nt, r0, r1, r2, npts


@njit(cache=True)
def pair(VA, nva, FA, FKA, nfa, NA, DA, VB, nvb, FB, FKB, nfb, NB, DB, tol):
    """Overlap of bodies A and B (global frame; vertices VA[:nva], faces FA as vertex
    indices, FKA vertices per face, planes NA x + DA <= 0, the same for B). Returns (V, centroid (3,), g (3,)) with
    g = dV/dx_B (m^2); V = 0 when they do not overlap."""
    polys, counts, A, B, S, areas = _work(max(nfa, nfb))
    na, nt, r0, r1, r2, npts = _clip_pair(VA, nva, FA, FKA, nfa, NA, DA, VB, nvb, FB, FKB, nfb, NB, DB, tol, polys,
                                          counts, A, B, S)
    cen = np.zeros(3)
    g = np.zeros(3)
    v = _volume(polys, counts, na, nt, r0, r1, r2, npts, cen, g, areas)
    return v, cen, g


@njit(cache=True, _nrt=False)
def _volume(polys, counts, na, nt, r0, r1, r2, npts, cen, g, areas):
    """Volume (returned) of the overlap bounded by ``polys[:nt]`` (the first ``na`` from
    A's faces); its centroid into ``cen`` and dV/dx_B into ``g`` ((3,) each; zero when the
    volume is zero). The tetrahedra share the apex r, the mean of the polygons' vertices:
    (r0, r1, r2) / npts, their coordinates' sums and number (``_clip_pair``). The twice
    area vectors of B's faces (``polys[na:nt]``) into ``areas[na:nt]`` for ``_patch``.
    Scalar arithmetic (no temporaries: this runs for every pair)."""
    for a in range(3):
        cen[a] = 0.0
        g[a] = 0.0
    if nt == 0:
        return 0.0
    r0 /= npts
    r1 /= npts
    r2 /= npts
    vol = 0.0
    c0 = c1 = c2 = 0.0
    for s in range(nt):
        k = counts[s]
        if s >= na:  # a face of B inside A
            ax, ay, az = _twice_area_vector(polys, s, k)
            areas[s, 0] = ax
            areas[s, 1] = ay
            areas[s, 2] = az
            g[0] += 0.5 * ax
            g[1] += 0.5 * ay
            g[2] += 0.5 * az
        ux = polys[s, 0, 0] - r0
        uy = polys[s, 0, 1] - r1
        uz = polys[s, 0, 2] - r2
        for q in range(1, k - 1):
            vx = polys[s, q, 0] - r0
            vy = polys[s, q, 1] - r1
            vz = polys[s, q, 2] - r2
            wx = polys[s, q + 1, 0] - r0
            wy = polys[s, q + 1, 1] - r1
            wz = polys[s, q + 1, 2] - r2
            v6 = ux * (vy * wz - vz * wy) + uy * (vz * wx - vx * wz) + uz * (vx * wy - vy * wx)
            vol += v6
            c0 += v6 * (ux + vx + wx)
            c1 += v6 * (uy + vy + wy)
            c2 += v6 * (uz + vz + wz)
    if vol <= 0.0:
        g[0] = g[1] = g[2] = 0.0
        return 0.0
    cen[0] = r0 + c0 / (4.0 * vol)
    cen[1] = r1 + c1 / (4.0 * vol)
    cen[2] = r2 + c2 / (4.0 * vol)
    return vol / 6.0


@njit(cache=True, _nrt=False)
def _patch(polys, counts, first, last, cen, g, p, J, areas):
    """Footprint of the overlap (module docstring) from the faces of B inside A
    (``polys[first:last]``, their twice area vectors ``areas[first:last]`` from
    ``_volume``), projected on the plane normal to n = -g/|g|: returns its area (m^2),
    writes its centroid into p (3,) and its second moment about p into J (3, 3) (m^4).
    Scalar arithmetic, as ``_volume``."""
    ga = np.sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2])
    for a in range(3):
        p[a] = cen[a]
        for b in range(3):
            J[a, b] = 0.0
    if ga <= 0.0:
        return 0.0
    n = (-g[0] / ga, -g[1] / ga, -g[2] / ga)
    s0 = 0.0
    s10 = s11 = s12 = 0.0
    s00_ = s01_ = s02_ = s11_ = s12_ = s22_ = 0.0  # the symmetric sum of second moments
    for s in range(first, last):
        k = counts[s]
        ax = areas[s, 0]
        ay = areas[s, 1]
        az = areas[s, 2]
        am = np.sqrt(ax * ax + ay * ay + az * az)
        if am <= 0.0:
            continue
        w = -(ax * n[0] + ay * n[1] + az * n[2]) / am  # cosine between the face normal and -n
        x00 = polys[s, 0, 0] - cen[0]
        x01 = polys[s, 0, 1] - cen[1]
        x02 = polys[s, 0, 2] - cen[2]
        for q in range(1, k - 1):
            x10 = polys[s, q, 0] - cen[0]
            x11 = polys[s, q, 1] - cen[1]
            x12 = polys[s, q, 2] - cen[2]
            x20 = polys[s, q + 1, 0] - cen[0]
            x21 = polys[s, q + 1, 1] - cen[1]
            x22 = polys[s, q + 1, 2] - cen[2]
            cx = (x11 - x01) * (x22 - x02) - (x12 - x02) * (x21 - x01)
            cy = (x12 - x02) * (x20 - x00) - (x10 - x00) * (x22 - x02)
            cz = (x10 - x00) * (x21 - x01) - (x11 - x01) * (x20 - x00)
            at = 0.5 * np.sqrt(cx * cx + cy * cy + cz * cz) * w
            m0 = x00 + x10 + x20
            m1 = x01 + x11 + x21
            m2 = x02 + x12 + x22
            s0 += at
            s10 += at * m0 / 3.0
            s11 += at * m1 / 3.0
            s12 += at * m2 / 3.0
            f = at / 12.0
            s00_ += f * (x00 * x00 + x10 * x10 + x20 * x20 + m0 * m0)
            s01_ += f * (x00 * x01 + x10 * x11 + x20 * x21 + m0 * m1)
            s02_ += f * (x00 * x02 + x10 * x12 + x20 * x22 + m0 * m2)
            s11_ += f * (x01 * x01 + x11 * x11 + x21 * x21 + m1 * m1)
            s12_ += f * (x01 * x02 + x11 * x12 + x21 * x22 + m1 * m2)
            s22_ += f * (x02 * x02 + x12 * x12 + x22 * x22 + m2 * m2)
    if s0 <= 0.0:
        return 0.0
    # projections on the plane normal to n: centroid and second moment about it
    c = (s10 / s0, s11 / s0, s12 / s0)
    m2s = (s00_ - s0 * (c[0] * c[0]), s01_ - s0 * (c[0] * c[1]), s02_ - s0 * (c[0] * c[2]),
           s11_ - s0 * (c[1] * c[1]), s12_ - s0 * (c[1] * c[2]), s22_ - s0 * (c[2] * c[2]))
    for a in range(3):
        p[a] = cen[a] + (_pr(n, a, 0) * c[0] + _pr(n, a, 1) * c[1] + _pr(n, a, 2) * c[2])
    for a in range(3):  # J = pr m2 pr, row by row
        t0 = _pr(n, a, 0) * _sym(m2s, 0, 0) + _pr(n, a, 1) * _sym(m2s, 1, 0) + _pr(n, a, 2) * _sym(m2s, 2, 0)
        t1 = _pr(n, a, 0) * _sym(m2s, 0, 1) + _pr(n, a, 1) * _sym(m2s, 1, 1) + _pr(n, a, 2) * _sym(m2s, 2, 1)
        t2 = _pr(n, a, 0) * _sym(m2s, 0, 2) + _pr(n, a, 1) * _sym(m2s, 1, 2) + _pr(n, a, 2) * _sym(m2s, 2, 2)
        for b in range(3):
            J[a, b] = t0 * _pr(n, 0, b) + t1 * _pr(n, 1, b) + t2 * _pr(n, 2, b)
    return s0


@njit(cache=True, inline="always")
def _pr(n, a, b):
    """Element (a, b) of the projector 1 - n n^T."""
    return (1.0 if a == b else 0.0) - n[a] * n[b]


@njit(cache=True, inline="always")
def _sym(m, a, b):
    """Element (a, b) of a symmetric 3 x 3 stored as (00, 01, 02, 11, 12, 22)."""
    i = min(a, b)
    j = max(a, b)
    return m[3 * i - i * (i - 1) // 2 + (j - i)]


@njit(cache=True)
def pair_patch(VA, nva, FA, FKA, nfa, NA, DA, VB, nvb, FB, FKB, nfb, NB, DB, tol):
    """``pair`` plus the contact patch: (V, centroid, g, patch area, patch centroid p,
    patch second moment J about p)."""
    polys, counts, A, B, S, areas = _work(max(nfa, nfb))
    na, nt, r0, r1, r2, npts = _clip_pair(VA, nva, FA, FKA, nfa, NA, DA, VB, nvb, FB, FKB, nfb, NB, DB, tol, polys,
                                          counts, A, B, S)
    c = np.zeros(3)
    g = np.zeros(3)
    p = np.zeros(3)
    J = np.zeros((3, 3))
    v = _volume(polys, counts, na, nt, r0, r1, r2, npts, c, g, areas)
    if v <= 0.0:
        return 0.0, c, g, 0.0, c.copy(), J
    a = _patch(polys, counts, na, nt, c, g, p, J, areas)
    return v, c, g, a, p, J


@njit(cache=True)
def place_shape(verts, nv, normals, offsets, nf, pos, rot, s, b, V, N, D):
    """Shape ``s``'s vertices V, face normals N and plane offsets D in the global frame, at
    body ``b``'s position and rotation (a shape of a multi-part stone sits at its stone's)."""
    for q in range(nv[s]):
        for a in range(3):
            V[q, a] = pos[b, a] + rot[b, a, 0] * verts[s, q, 0] + rot[b, a, 1] * verts[s, q, 1] \
                + rot[b, a, 2] * verts[s, q, 2]
    for f in range(nf[s]):
        for a in range(3):
            N[f, a] = rot[b, a, 0] * normals[s, f, 0] + rot[b, a, 1] * normals[s, f, 1] + rot[b, a, 2] * normals[s, f, 2]
        D[f] = offsets[s, f] - (N[f, 0] * pos[b, 0] + N[f, 1] * pos[b, 1] + N[f, 2] * pos[b, 2])


@njit(cache=True)
def _to_global(verts, nv, normals, offsets, nf, pos, rot, i, V, N, D):
    place_shape(verts, nv, normals, offsets, nf, pos, rot, i, i, V, N, D)


def all_contacts(verts, nv, normals, offsets, nf, faces, fk, pos, rot, moving, tol):
    """Every overlapping pair with at least one moving body. ``pos`` (nb, 3) and ``rot``
    (nb, 3, 3) place each body's local geometry. Returns arrays over contacts: id1, id2
    (id1 < id2, in lexicographic order), volume (m^3), centroid (m), normal (A->B), area
    A_c = |dV/dx_B| (m^2); pairs touching within ``tol`` are none (module docstring).
    ``contacts_with_patches`` adds each contact patch's centroid and second moment."""
    return contacts_with_patches(verts, nv, normals, offsets, nf, faces, fk, pos, rot, moving, tol)[:6]


@njit(cache=True)
def _global_geometry(verts, nv, normals, offsets, nf, pos, rot):
    """Every body's vertices (nb, maxv, 3) and face planes (nb, maxf, 3) + (nb, maxf) in
    the global frame, and its axis-aligned bounding box lo, hi (nb, 3) (m)."""
    nb = len(nv)
    maxv = verts.shape[1]
    maxf = normals.shape[1]
    GV = np.empty((nb, maxv, 3))
    GN = np.empty((nb, maxf, 3))
    GD = np.empty((nb, maxf))
    lo = np.empty((nb, 3))
    hi = np.empty((nb, 3))
    for i in range(nb):
        _to_global(verts, nv, normals, offsets, nf, pos, rot, i, GV[i], GN[i], GD[i])
        for a in range(3):
            lo[i, a] = GV[i, :nv[i], a].min()
            hi[i, a] = GV[i, :nv[i], a].max()
    return GV, GN, GD, lo, hi


@njit(cache=True)
def sweep_pairs(lo, hi, moving):
    """Broad phase by sort and sweep: the pairs (ia, ib), ia < ib, in lexicographic order,
    whose closed bounding boxes [lo, hi] (nb, 3) overlap on all three axes and of which at
    least one body is ``moving`` -- exactly the pairs the all-pairs test passes on.

    The boxes are sorted by their lower bound along the axis on which the box centres
    spread most (x for a wall); each box is paired with the following ones until their
    lower bound passes its upper bound, and the other two axes are tested: O(n log n)
    plus the pairs that overlap along the sweep axis. Bodies with a non-finite box (a
    blown-up state) pair with nothing: the exact test finds no overlap with them either.
    """
    nb = len(lo)
    ok = np.empty(nb, np.bool_)
    nok = 0
    for i in range(nb):
        ok[i] = True
        for a in range(3):
            if not (np.isfinite(lo[i, a]) and np.isfinite(hi[i, a])):
                ok[i] = False
        if ok[i]:
            nok += 1
    ax = 0
    if nok > 1:  # the axis along which the box centres spread most
        best = -1.0
        for a in range(3):
            mean = 0.0
            for i in range(nb):
                if ok[i]:
                    mean += 0.5 * (lo[i, a] + hi[i, a])
            mean /= nok
            var = 0.0
            for i in range(nb):
                if ok[i]:
                    d = 0.5 * (lo[i, a] + hi[i, a]) - mean
                    var += d * d
            if var > best:
                best = var
                ax = a
    b1 = (ax + 1) % 3
    b2 = (ax + 2) % 3
    key = np.empty(nb)
    for i in range(nb):
        key[i] = lo[i, ax] if ok[i] else np.inf
    order = np.argsort(key, kind="mergesort")
    cap = 8 * nb + 16
    keys = np.empty(cap, np.int64)
    m = 0
    for k in range(nok):
        i = order[k]
        top = hi[i, ax]
        for q in range(k + 1, nok):
            j = order[q]
            if lo[j, ax] > top:
                break
            if not (moving[i] or moving[j]):
                continue
            if lo[i, b1] > hi[j, b1] or lo[j, b1] > hi[i, b1] or lo[i, b2] > hi[j, b2] or lo[j, b2] > hi[i, b2]:
                continue
            if m == cap:
                cap *= 2
                keys = _grow_i(keys, cap)
            keys[m] = min(i, j) * nb + max(i, j)
            m += 1
    keys = np.sort(keys[:m])
    return keys // nb, keys % nb


@njit(cache=True, _nrt=False)
def _apart(VA, nva, NA, DA, nfa, VB, nvb, NB, DB, nfb, tol):
    """True when a face plane of A has every vertex of B outside it or on it within
    ``tol`` (signed distance >= -tol), or a face plane of B every vertex of A: the bodies
    are separated, or touch, their overlap no thicker than ``tol``."""
    for f in range(nfa):
        out = True
        for q in range(nvb):
            if NA[f, 0] * VB[q, 0] + NA[f, 1] * VB[q, 1] + NA[f, 2] * VB[q, 2] + DA[f] < -tol:
                out = False
                break
        if out:
            return True
    for f in range(nfb):
        out = True
        for q in range(nva):
            if NB[f, 0] * VA[q, 0] + NB[f, 1] * VA[q, 1] + NB[f, 2] * VA[q, 2] + DB[f] < -tol:
                out = False
                break
        if out:
            return True
    return False


@njit(cache=True, _nrt=False)
def pair_contact(GV, GN, GD, nv, nf, faces, fk, i, j, tol, touching, polys, counts, A, B, S, areas, g, id1, id2, vol,
                 cen, nrm, area, pc, pj, m):
    """A listed pair's contact: shapes i and j (their global vertices GV, planes GN, GD)
    clipped (``_clip_pair``, the work arrays polys .. areas of ``_work``, and g (3,)), and where the overlap's
    volume and its gradient are positive, the contact written into row m of id1, id2, vol,
    cen, nrm, area, pc, pj (as ``pair_patch``); returns whether it was. ``touching``: a
    pair that touches within ``tol`` or is apart (``_apart``) is no contact, without a
    clip (module docstring, "Touching"). Row m of cen may be written when it is not."""
    if touching and _apart(GV[i], nv[i], GN[i], GD[i], nf[i], GV[j], nv[j], GN[j], GD[j], nf[j], tol):
        return False
    na, nt, r0, r1, r2, npts = _clip_pair(GV[i], nv[i], faces[i], fk[i], nf[i], GN[i], GD[i], GV[j], nv[j], faces[j],
                                          fk[j], nf[j], GN[j], GD[j], tol, polys, counts, A, B, S)
    v = _volume(polys, counts, na, nt, r0, r1, r2, npts, cen[m], g, areas)
    if v <= 0.0:
        return False
    ga = np.sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2])
    if ga <= 0.0:
        return False
    _patch(polys, counts, na, nt, cen[m], g, pc[m], pj[m], areas)  # its area is |g| (module docstring)
    id1[m] = i
    id2[m] = j
    vol[m] = v
    for a in range(3):
        nrm[m, a] = -g[a] / ga
    area[m] = ga
    return True


@njit(cache=True)
def _contacts_of_pairs(GV, GN, GD, nv, nf, faces, fk, ia, ib, tol, touching):
    """The exact overlaps (as ``pair_patch``) of the candidate pairs (ia, ib), kept where the
    volume and its gradient are positive, in the candidates' order. ``touching``: pairs
    that touch within ``tol`` or are apart (``_apart``) are no contact, without a clip
    (module docstring, "Touching")."""
    cap = len(ia)
    id1 = np.empty(cap, np.int64)
    id2 = np.empty(cap, np.int64)
    vol = np.empty(cap)
    cen = np.empty((cap, 3))
    nrm = np.empty((cap, 3))
    area = np.empty(cap)
    pc = np.empty((cap, 3))
    pj = np.empty((cap, 3, 3))
    polys, counts, A, B, S, areas = _work(GN.shape[1])
    g = np.empty(3)
    m = np.int64(0)  # not the literal 0: pair_contact would be compiled for it too (TOUCHING_IS_NO_CONTACT)
    for k in range(cap):
        if pair_contact(GV, GN, GD, nv, nf, faces, fk, ia[k], ib[k], tol, touching, polys, counts, A, B, S, areas, g,
                        id1, id2, vol, cen, nrm, area, pc, pj, m):
            m += 1
    return id1[:m], id2[:m], vol[:m], cen[:m], nrm[:m], area[:m], pc[:m], pj[:m]


#: pairs touching within TOL are no contact (module docstring, "Touching"); False gives the
#: contacts of the clip alone (round-off overlaps of touching faces included). Compiled code passes
#: it, and any constant flag, as ``bool(...)``: numba compiles a kernel called with a constant for
#: that constant's literal type, again for each constant, the whole clip with it (~10 s of a core each)
TOUCHING_IS_NO_CONTACT = True


@njit(cache=True)
def contacts_with_patches(verts, nv, normals, offsets, nf, faces, fk, pos, rot, moving, tol):
    """``all_contacts`` plus, per contact, the patch centroid p (m, (m, 3)) and the patch
    second moment J about p (m^4, (m, 3, 3)); see the module docstring. Candidate pairs
    come from the sort-and-sweep broad phase (``sweep_pairs``), so the cost grows as
    n log n plus the contacts, not n^2. The output is the all-pairs search's
    (``_contacts_all_pairs``) bit for bit, less the pairs touching within ``tol``
    (``TOUCHING_IS_NO_CONTACT``)."""
    GV, GN, GD, lo, hi = _global_geometry(verts, nv, normals, offsets, nf, pos, rot)
    ia, ib = sweep_pairs(lo, hi, moving)
    return _contacts_of_pairs(GV, GN, GD, nv, nf, faces, fk, ia, ib, tol, bool(TOUCHING_IS_NO_CONTACT))


@njit(cache=True)
def contacts_of_shapes(verts, nv, normals, offsets, nf, faces, fk, owner, pos, rot, moving, tol):
    """``contacts_with_patches`` over shapes (the convex parts of stones): shape s is body
    ``owner[s]``'s part, its vertices ``verts[s]`` in that body's frame, so it moves with
    ``pos[owner[s]]``, ``rot[owner[s]]``, ``moving[owner[s]]`` (arrays over bodies).
    Pairs of shapes of one body are no candidates: a stone's parts never contact each other.
    Returns the contacts as ``contacts_with_patches`` does, ia and ib shape indices. With
    one shape per body (``owner`` the identity) the result is ``contacts_with_patches``'s
    bit for bit."""
    pos_s = pos[owner]
    rot_s = rot[owner]
    moving_s = moving[owner]
    GV, GN, GD, lo, hi = _global_geometry(verts, nv, normals, offsets, nf, pos_s, rot_s)
    ia, ib = sweep_pairs(lo, hi, moving_s)
    keep = owner[ia] != owner[ib]
    return _contacts_of_pairs(GV, GN, GD, nv, nf, faces, fk, ia[keep], ib[keep], tol, bool(TOUCHING_IS_NO_CONTACT))


@njit(cache=True)
def _contacts_all_pairs(verts, nv, normals, offsets, nf, faces, fk, pos, rot, moving, tol):
    """Reference for ``contacts_with_patches``: every pair i < j tested on its bounding
    boxes, then clipped (the O(n^2) search it replaced, without the touching rule; for
    tests and the bench)."""
    GV, GN, GD, lo, hi = _global_geometry(verts, nv, normals, offsets, nf, pos, rot)
    nb = len(nv)
    keys = np.empty(nb * (nb - 1) // 2 + 1, np.int64)
    m = 0
    for i in range(nb):
        for j in range(i + 1, nb):
            if not (moving[i] or moving[j]):
                continue
            if lo[i, 0] > hi[j, 0] or lo[j, 0] > hi[i, 0] or lo[i, 1] > hi[j, 1] or lo[j, 1] > hi[i, 1] \
                    or lo[i, 2] > hi[j, 2] or lo[j, 2] > hi[i, 2]:
                continue
            keys[m] = i * nb + j
            m += 1
    keys = keys[:m]
    return _contacts_of_pairs(GV, GN, GD, nv, nf, faces, fk, keys // nb, keys % nb, tol, bool(False))


@njit(cache=True)
def patches_of_pairs(verts, nv, normals, offsets, nf, faces, fk, pos, rot, ia, ib, tol):
    """Contact patches (area m^2, centroid m, second moment m^4) of the given pairs of
    bodies, for contacts whose geometry comes from elsewhere (YADE's intersection)."""
    m = len(ia)
    maxv = verts.shape[1]
    maxf = normals.shape[1]
    area = np.zeros(m)
    pc = np.zeros((m, 3))
    pj = np.zeros((m, 3, 3))
    VA = np.empty((maxv, 3))
    NA = np.empty((maxf, 3))
    DA = np.empty(maxf)
    VB = np.empty((maxv, 3))
    NB = np.empty((maxf, 3))
    DB = np.empty(maxf)
    for k in range(m):
        i = ia[k]
        j = ib[k]
        _to_global(verts, nv, normals, offsets, nf, pos, rot, i, VA, NA, DA)
        _to_global(verts, nv, normals, offsets, nf, pos, rot, j, VB, NB, DB)
        v, c, g, a, p, J = pair_patch(VA, nv[i], faces[i], fk[i], nf[i], NA, DA, VB, nv[j], faces[j], fk[j], nf[j], NB,
                                      DB, tol)
        area[k] = a
        pc[k] = p
        pj[k] = J
    return area, pc, pj


@njit(cache=True)
def _grow_i(a, cap):
    b = np.empty(cap, np.int64)
    b[:len(a)] = a
    return b


def overlap(va, vb, tol: float = TOL, patch: bool = False) -> tuple:
    """Overlap of two convex blocks given by their vertices in one frame (convenience for
    tests and tools): (volume m^3, centroid m, dV/dx_B m^2); with ``patch`` also the
    contact patch (area m^2, centroid m, second moment m^4 about it)."""
    s = Shapes([np.asarray(va, float), np.asarray(vb, float)])
    i = np.eye(3)
    pos = np.zeros((2, 3))
    out = []
    for b in range(2):
        V = np.empty((s.verts.shape[1], 3))
        N = np.empty((s.normals.shape[1], 3))
        D = np.empty(s.normals.shape[1])
        _to_global(s.verts, s.nv, s.normals, s.offsets, s.nf, pos, np.stack([i, i]), b, V, N, D)
        out.append((V, N, D))
    (VA, NA, DA), (VB, NB, DB) = out
    fn = pair_patch if patch else pair
    return fn(VA, s.nv[0], s.faces[0], s.fk[0], s.nf[0], NA, DA, VB, s.nv[1], s.faces[1], s.fk[1], s.nf[1], NB, DB, tol)
