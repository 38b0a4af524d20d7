"""A Verlet (skin) neighbour list for the compiled contact search (no YADE import).

``overlap.contacts_of_shapes`` finds a step's contacts from scratch: every shape's box,
a sort and sweep of all of them, then the exact clip of every candidate pair. Between
two steps the stones of a wall move micrometres, so the sort and sweep finds the same
pairs again and again. Here it runs only now and then, on the boxes grown by half a
``skin`` on every side: the list then holds every pair of shapes whose boxes are within
``skin`` of each other (of different bodies, at least one of them moving, neither
having left the model), and it stays complete while no body has moved since its last
build by more than half the skin. Each step tests the listed pairs' own boxes (the same
closed-box test as the sort and sweep) and clips those that pass, in the list's order
(lexicographic, as the sweep's): the contacts, their order and every number computed
from them are the full search's bit for bit, the list only spares the sort.

Rebuild rule (as YADE's collider ``verletDist`` and the skins of LAMMPS/LIGGGHTS): a
body's vertices have moved since the build by at most
``|x - x0| + ||R - R0||_F r`` (``r`` the largest distance of its shapes' vertices from
its origin; the Frobenius norm of the rotation's change is at least the chord
2 sin(theta/2) by which a point at unit distance moves); the list is rebuilt before a
step in which this bound exceeds ``skin / 2`` for some body, or when a shape's geometry
changed (a stone taken out of the model: its vertices made non-finite, ``invalidate``).
Two boxes that overlap now were each within that bound of their boxes at the build,
so their grown boxes overlapped then: the list holds them.

``skin`` (m, ``SKIN`` by default; the case key ``contact.skin``): a larger skin makes
rebuilds rarer and the list longer (each listed pair costs a box test per step). The
state is plain arrays (``NeighbourList.arrays``) passed to and returned by the compiled
step; the work arrays of the search (global vertices and planes of every shape, the
contacts' outputs, the clip's polygons) are allocated once and grown with the list.

Units: metres.
"""
from __future__ import annotations

import numpy as np
import numba
from numba import njit, prange

from drystone.mechanics import overlap as ov
from drystone.mechanics.contact_rows import range_count
from drystone import numba_cache
from drystone.numba_cache import FIRST, PARALLEL

numba_cache.install()  # numba's cache safe for processes compiling at once

#: default skin (m): a few times a wall's motion over the steps between two samples under
#: a strong record, small beside a stone (0.25-0.6 m): a list a few percent longer than
#: the pairs whose boxes touch (``make bench`` measures the rebuilds' share)
SKIN = 0.02


def body_radius(verts, nv, owner, nb) -> np.ndarray:
    """(nb,) the largest distance (m) of any vertex of a body's shapes from the body's
    origin; -1 for a body without shapes (its motion moves no shape)."""
    r = np.full(nb, -1.0)
    for s in range(len(nv)):
        v = np.asarray(verts[s, :nv[s]], float)
        d = float(np.sqrt((v * v).sum(axis=1)).max()) if len(v) else 0.0
        b = int(owner[s])
        r[b] = max(r[b], d if np.isfinite(d) else 0.0)
    return r


class NeighbourList:
    """The list's state for ``ns`` shapes (``shapes``: ``overlap.Shapes``) of ``nb``
    bodies: the candidate pairs, the bodies' positions and rotations at the last build,
    their radii, the skin, and the work arrays of the search. ``arrays`` is the tuple the
    compiled step takes (and returns, grown); ``builds`` counts the rebuilds."""

    def __init__(self, shapes, owner, moving, nb: int, skin: float = SKIN):
        skin = float(skin)
        if not (np.isfinite(skin) and skin >= 0.0):
            raise ValueError(f"contact skin {skin!r} m: a finite length >= 0")
        self.skin = skin
        ns, maxv, maxf = len(shapes.nv), shapes.verts.shape[1], shapes.normals.shape[1]
        owner = np.asarray(owner, np.int64)
        # meta: [pairs listed, rebuilds, rebuild at the next step (1)]
        meta = np.array([0, 0, 1], np.int64)
        self.arrays = (np.zeros(0, np.int64), np.zeros(0, np.int64), meta, np.full((nb, 3), np.nan),
                       np.full((nb, 3, 3), np.nan), body_radius(shapes.verts, shapes.nv, owner, nb),
                       np.array([0.5 * skin]), np.asarray(moving, np.bool_)[owner],
                       # per shape: global vertices, planes, box, finite
                       np.empty((ns, maxv, 3)), np.empty((ns, maxf, 3)), np.empty((ns, maxf)), np.empty((ns, 3)),
                       np.empty((ns, 3)), np.zeros(ns, np.bool_))
        self.contacts = contact_buffers(0, maxf)

    @property
    def builds(self) -> int:
        return int(self.arrays[2][1])

    def __len__(self) -> int:
        return int(self.arrays[2][0])

    def invalidate(self) -> None:
        """A shape's geometry changed (a stone left the model): rebuild before the next step."""
        self.arrays[2][2] = 1


def contact_buffers(cap: int, maxf: int) -> tuple:
    """The search's output and clip work arrays for ``cap`` candidate pairs (``search``),
    the clip's work arrays once per thread numba may run (``numba.config.NUMBA_NUM_THREADS``)."""
    return _buffers(cap, maxf, max(1, int(numba.config.NUMBA_NUM_THREADS)))


@njit(cache=True)
def _buffers(cap, maxf, nt):
    """``contact_buffers``: id1 .. pj (entries 0-7), then per thread the clip's work arrays
    (``overlap._work``: entries 8-12 and 15, polys first) and g (13), and the pairs' hit
    flags (14)."""
    polys, counts, A, B, S, areas = ov._work(maxf)
    return (np.empty(cap, np.int64), np.empty(cap, np.int64), np.empty(cap), np.empty((cap, 3)),
            np.empty((cap, 3)), np.empty(cap), np.empty((cap, 3)), np.empty((cap, 3, 3)),
            np.empty((nt,) + polys.shape), np.zeros((nt,) + counts.shape, np.int64), np.empty((nt,) + A.shape),
            np.empty((nt,) + B.shape), np.empty((nt,) + S.shape), np.empty((nt, 3)), np.zeros(cap, np.bool_),
            np.empty((nt,) + areas.shape))


@njit(cache=True)
def _shape_range(r0, r1, verts, nv, normals, offsets, nf, owner, pos, rot, GV, GN, GD, lo, hi, ok):
    """Shapes r0 <= s < r1 of ``_shape_geometry``."""
    for s in range(r0, r1):
        b = owner[s]
        V = GV[s]
        ov.place_shape(verts, nv, normals, offsets, nf, pos, rot, s, b, V, GN[s], GD[s])
        good = True
        for a in range(3):
            mn = V[0, a]
            mx = V[0, a]
            for q in range(nv[s]):
                x = V[q, a]
                if not np.isfinite(x):
                    good = False
                if x < mn:
                    mn = x
                if x > mx:
                    mx = x
            lo[s, a] = mn
            hi[s, a] = mx
        ok[s] = good


@njit(cache=True, parallel=PARALLEL)
def _shape_geometry(verts, nv, normals, offsets, nf, owner, pos, rot, GV, GN, GD, lo, hi, ok, chunks):
    """Every shape's vertices, face planes and box in the global frame, into the work
    arrays (``overlap.place_shape`` at pos[owner], rot[owner]);
    ``ok``: the shape's vertices are finite (a shape of a stone that left the model, or of
    a blown-up body, pairs with nothing). ``chunks`` ranges of shapes shared among numba's
    threads, each shape into its own rows (``contact_rows.range_count``)."""
    ns = len(nv)
    nt = range_count(ns, chunks)
    if nt == 1:
        _shape_range(FIRST, ns, verts, nv, normals, offsets, nf, owner, pos, rot, GV, GN, GD, lo, hi, ok)
    else:
        for t in prange(nt):
            _shape_range(t * ns // nt, (t + 1) * ns // nt, verts, nv, normals, offsets, nf, owner, pos, rot, GV, GN, GD,
                         lo, hi, ok)


@njit(cache=True)
def _stale(pos, rot, ref_pos, ref_rot, radius, half_skin):
    """Whether some body may have moved a vertex by more than ``half_skin`` since the
    last build (module docstring); non-finite states count as moved."""
    for b in range(len(radius)):
        if radius[b] < 0.0:
            continue
        d = 0.0
        for a in range(3):
            x = pos[b, a] - ref_pos[b, a]
            d += x * x
        r = 0.0
        for a in range(3):
            for c in range(3):
                x = rot[b, a, c] - ref_rot[b, a, c]
                r += x * x
        if not (np.sqrt(d) + np.sqrt(r) * radius[b] <= half_skin):
            return True
    return False


@njit(cache=True)
def _build(lo, hi, ok, moving_s, owner, half_skin):
    """The listed pairs (a, b), a < b, in lexicographic order: shapes of different bodies,
    both finite, one moving, whose boxes grown by ``half_skin`` overlap."""
    ns = len(ok)
    glo = np.empty((ns, 3))
    ghi = np.empty((ns, 3))
    for s in range(ns):
        for a in range(3):
            glo[s, a] = lo[s, a] - half_skin if ok[s] else np.nan
            ghi[s, a] = hi[s, a] + half_skin if ok[s] else np.nan
    ia, ib = ov.sweep_pairs(glo, ghi, moving_s)
    m = 0
    for k in range(len(ia)):
        if owner[ia[k]] != owner[ib[k]]:
            ia[m] = ia[k]
            ib[m] = ib[k]
            m += 1
    return ia[:m].copy(), ib[:m].copy()


@njit(cache=True)
def update(nl, verts, nv, normals, offsets, nf, owner, pos, rot, chunks):
    """The shapes' global geometry into the list's work arrays, and the list rebuilt if it
    is stale (``_stale``) or invalidated; returns the list's arrays (new pair arrays after
    a rebuild). ``chunks``: ranges of shapes for numba's threads (``_shape_geometry``)."""
    la, lb, meta, ref_pos, ref_rot, radius, hs, moving_s, GV, GN, GD, lo, hi, ok = nl
    _shape_geometry(verts, nv, normals, offsets, nf, owner, pos, rot, GV, GN, GD, lo, hi, ok, chunks)
    if meta[2] == 0 and not _stale(pos, rot, ref_pos, ref_rot, radius, hs[0]):
        return nl
    la, lb = _build(lo, hi, ok, moving_s, owner, hs[0])
    meta[0] = len(la)
    meta[1] += 1
    meta[2] = 0
    ref_pos[:, :] = pos
    ref_rot[:, :, :] = rot
    return (la, lb, meta, ref_pos, ref_rot, radius, hs, moving_s, GV, GN, GD, lo, hi, ok)


@njit(cache=True, parallel=PARALLEL)
def search(nl, buf, nv, nf, faces, fk, tol, touching):
    """This step's contacts among the listed pairs (``update`` first): the pairs whose
    closed boxes overlap and whose shapes are finite, clipped (``overlap.pair_contact``)
    as ``overlap._contacts_of_pairs`` on the sweep's candidates. Returns (the number of
    contacts m, ``buf``: its first m rows of id1, id2, vol, cen, nrm, area, pc, pj hold
    them, in the list's order; grown to the list's length where it was shorter).

    Threads: the listed pairs are shared among numba's threads (``numba.set_num_threads``),
    each clipping with its own work arrays into the pair's own row; the rows that hold a
    contact are then moved up in the list's order by one thread. A pair's arithmetic does
    not depend on the thread that does it: the contacts are the same bit for bit for any
    number of threads."""
    la, lb, meta, ref_pos, ref_rot, radius, hs, moving_s, GV, GN, GD, lo, hi, ok = nl
    n = meta[0]
    if len(buf[0]) < n:
        buf = _buffers(n + n // 4 + 16, GN.shape[1], buf[8].shape[0])
    id1, id2, vol, cen, nrm, area, pc, pj, polys, counts, A, B, S, g, hit, areas = buf
    nt = range_count(n, polys.shape[0])
    if nt == 1:
        _search_range(FIRST, n, la, lb, ok, lo, hi, GV, GN, GD, nv, nf, faces, fk, tol, touching, polys[0], counts[0],
                      A[0], B[0], S[0], areas[0], g[0], id1, id2, vol, cen, nrm, area, pc, pj, hit)
    else:
        for r in prange(nt):
            t = numba.get_thread_id()
            _search_range(r * n // nt, (r + 1) * n // nt, la, lb, ok, lo, hi, GV, GN, GD, nv, nf, faces, fk, tol,
                          touching, polys[t], counts[t], A[t], B[t], S[t], areas[t], g[t], id1, id2, vol, cen, nrm,
                          area, pc, pj, hit)
    m = np.int64(0)  # not the literal 0 (overlap.TOUCHING_IS_NO_CONTACT)
    for k in range(n):
        if hit[k]:
            if m < k:
                _move_row(buf, k, m)
            m += 1
    return m, buf


@njit(cache=True, _nrt=False)
def _search_range(k0, k1, la, lb, ok, lo, hi, GV, GN, GD, nv, nf, faces, fk, tol, touching, polys, counts, A, B, S, areas,
                  g, id1, id2, vol, cen, nrm, area, pc, pj, hit):
    """``search``'s listed pairs k0 <= k < k1, with one thread's work arrays (polys .. g).
    Compiled without numba's reference counts (``_nrt=False``: it allocates nothing): the
    views of each pair's shapes and rows then cost nothing, where counting them (an atomic
    add and subtract per view) took a fifth of the search."""
    for k in range(k0, k1):
        i = la[k]
        j = lb[k]
        hit[k] = False
        if ok[i] and ok[j] and not (lo[i, 0] > hi[j, 0] or lo[j, 0] > hi[i, 0] or lo[i, 1] > hi[j, 1]
                                    or lo[j, 1] > hi[i, 1] or lo[i, 2] > hi[j, 2] or lo[j, 2] > hi[i, 2]):
            hit[k] = ov.pair_contact(GV, GN, GD, nv, nf, faces, fk, i, j, tol, touching, polys, counts, A, B, S, areas,
                                     g, id1, id2, vol, cen, nrm, area, pc, pj, k)


@njit(cache=True)
def _move_row(buf, k, m):
    """Row k of the contacts' outputs into row m (a copy: the same numbers)."""
    id1, id2, vol, cen, nrm, area, pc, pj = buf[:8]
    id1[m] = id1[k]
    id2[m] = id2[k]
    vol[m] = vol[k]
    area[m] = area[k]
    for a in range(3):
        cen[m, a] = cen[k, a]
        nrm[m, a] = nrm[k, a]
        pc[m, a] = pc[k, a]
        for b in range(3):
            pj[m, a, b] = pj[k, a, b]
