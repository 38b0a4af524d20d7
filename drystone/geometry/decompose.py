"""Stone outlines (2D polygons, x along the wall and z up, metres): checked, and split into
convex pieces (numpy only, no YADE).

``check_outline(xz, where)`` is the one home of the outline rules: the points as a
counter-clockwise (n, 2) array of corners. Repeated points and points on a straight edge
between their neighbours (within ``FLAT_REL_TOL`` x the outline's size, the diagonal of its
bounding box) are dropped: they are not corners, and a block file takes corners only. The
polygon closes itself (its last point joins its first: a list of points cannot be open;
a first point repeated at the end is dropped). Refused, with one line naming ``where``
(the file and stone): fewer than 3 points, no area (less than ``AREA_TOL``, or corners
all within ``FLAT_REL_TOL`` x the size of one line: a sliver), an outline that doubles
back on itself (a spike of no width), one that repeats a corner elsewhere (pinched: two
loops joined at a point), and one whose edges cross or touch (any two edges that are not
neighbours closer than ``FLAT_REL_TOL`` x the size; O(n^2) segment tests).

``convex_pieces(xz)`` partitions a checked outline (a simple polygon, no holes) into
convex pieces by diagonals (the pieces' corners are outline corners: no new points):

* a convex outline is its own one piece (the same array);
* up to ``EXACT_MAX_CORNERS`` (32) corners: the **exact minimum** over partitions by
  diagonals, a dynamic programme on sub-polygons (the piece on a sub-polygon's closing
  diagonal is a convex chain of its vertices, each side an edge or a diagonal closing a
  smaller sub-polygon, solved the same way; ``_exact_pieces``). O(n^5) at worst, measured
  at most 0.05 s on random 32-corner outlines and 0.3 s on a 32-gon with one notch (the
  most diagonals). The minimum with new points allowed (Steiner points, Chazelle's
  algorithm) can be smaller; it is not computed;
* above: **Hertel-Mehlhorn**: an ear-clipping triangulation (each step clips the ear
  whose smallest angle is largest), then every diagonal removed whose two pieces merge
  into a convex piece; the fewest pieces of four orders of trying the diagonals. Each
  diagonal left is essential at one of its ends (a re-entrant corner there, which keeps
  at most 2 of them), so at most 2r + 1 pieces for r re-entrant corners; any partition
  into convex pieces, even with new points, needs ceil(r/2) + 1 (each cut resolves at most
  two re-entrant corners): **at most 4 x the minimum**. O(n^3): 0.6 s at 120 corners.

Measured with the shapes and generators of tests/test_decompose.py (which asserts the
shapes' counts, and the exact minimum against a brute-force search over every set of
diagonals on the small shapes and 25 random polygons): L 2 pieces (minimum 2), T 2 (2),
U 3 (3), comb of k teeth k + 1 (k + 1, k = 2..5; the lower bound ceil(r/2) + 1 is only k:
a tooth flush with the comb's end needs its own cut), 5-point star 4 (4), 10-point star
11 (11; lower bound 6), a 12-gon with one corner pulled in 2 (2); Hertel-Mehlhorn forced
on the same shapes gives the same counts but 3 for the notched 12-gon (its 2r + 1).
Once, seed 2024: on 200 random star-shaped outlines of 6-32 corners (0-17 re-entrant)
Hertel-Mehlhorn gave the minimum in 56 %, one piece more in 29 %, two in 13 %, three or
four in 3.5 % (mean 1.08 x, at most 1.5 x the minimum); on 200 random 2-opt outlines of
6-20 corners the minimum in 77 % (mean 1.05 x, at most 2 x); the minimum itself was on
average 1.3-1.6 x the lower bound, at most 2.5 x. By diagonals alone the minimum can
exceed r + 1 (cuts ending inside an edge always reach r + 1): in 96 of 600 random
outlines, by up to 4 pieces.

Pieces: counter-clockwise, every vertex a corner by more than ``FLAT_REL_TOL`` x the size
(points exactly on a straight side of a piece, within ``COLLINEAR_REL_TOL``, are dropped
from it: the pieces tile the outline to round-off). A merge or a piece that would leave a
vertex less than that far from straight, but not on it, is not made (a vertex YADE's hull
and the block file's corner check could read either way); this can keep a diagonal
Hertel-Mehlhorn would remove, only for outlines with such near-straight corners.
"""
from __future__ import annotations

import numpy as np

from .blockfile import GeometryError

#: outlines of less area than this (m^2) are refused
AREA_TOL = 1e-9
#: a point less than this x the outline's size off the line through its neighbours is not a
#: corner (dropped if between them, refused if it doubles back); also the least gap between
#: two edges that are not neighbours (closer: the outline touches itself) and the least
#: height of a piece's corner; 1e-6 is far below any digitising precision and far above
#: the block file's corner tolerance (blockfile.CORNER_REL_TOL, 1e-9 of the block's size)
FLAT_REL_TOL = 1e-6
#: a piece's vertex within this x the size of the line through its neighbours in the piece
#: is on that line (an outline corner on a straight side of the piece, exactly in exact
#: coordinates): dropped from that piece; round-off on sizes of order one is ~1e-16
COLLINEAR_REL_TOL = 1e-12
#: outlines of up to this many corners get the exact minimum partition (O(n^5) at worst:
#: 0.01 s at 12 corners, at most 0.3 s at 32 measured), larger ones Hertel-Mehlhorn
EXACT_MAX_CORNERS = 32


class OutlineError(GeometryError):
    """A malformed outline; the message names the file and stone."""


def _area2(p: np.ndarray) -> float:
    """Twice the signed area (m^2) of a polygon (n, 2): > 0 counter-clockwise."""
    return float(np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1]))


def _outward(p: np.ndarray) -> np.ndarray:
    """Per vertex of a counter-clockwise polygon (n, 2), its distance (m) outside the line
    through its two neighbours (< 0: a re-entrant corner; -inf: the neighbours coincide)."""
    prev, nxt = np.roll(p, 1, axis=0), np.roll(p, -1, axis=0)
    chord = nxt - prev
    length = np.linalg.norm(chord, axis=1)
    d = p - prev
    cross = d[:, 0] * chord[:, 1] - d[:, 1] * chord[:, 0]
    return np.where(length > 0, cross / np.where(length > 0, length, 1.0), -np.inf)


def _xz(v) -> str:
    return f"x = {v[0]:.6g}, z = {v[1]:.6g} m"


def _point_segment(p, a, b):
    """Distance (m) from points p to segments a-b (arrays (..., 2), broadcast)."""
    ab = b - a
    ll = np.sum(ab * ab, axis=-1)
    t = np.clip(np.sum((p - a) * ab, axis=-1) / np.where(ll > 0, ll, 1.0), 0.0, 1.0)
    return np.linalg.norm(a + t[..., None] * ab - p, axis=-1)


def _cross(o, a, b):
    """z of (a - o) x (b - o), broadcast over (..., 2) arrays: > 0 when o, a, b turn left."""
    return (a[..., 0] - o[..., 0]) * (b[..., 1] - o[..., 1]) - (a[..., 1] - o[..., 1]) * (b[..., 0] - o[..., 0])


def _segment_gaps(a, b, c, d):
    """Distance (m) between segments a-b and c-d (arrays (..., 2), broadcast): 0 when they cross."""
    o1, o2 = _cross(a, b, c), _cross(a, b, d)
    o3, o4 = _cross(c, d, a), _cross(c, d, b)
    crossing = (o1 * o2 < 0) & (o3 * o4 < 0)
    gap = np.minimum(np.minimum(_point_segment(c, a, b), _point_segment(d, a, b)),
                     np.minimum(_point_segment(a, c, d), _point_segment(b, c, d)))
    return np.where(crossing, 0.0, gap)


def check_outline(xz, where: str = "<outline>") -> np.ndarray:
    """The outline ``xz`` (points (n, 2), m, either sense) as a counter-clockwise (n, 2)
    array of its corners; OutlineError naming ``where`` if it is not a simple polygon
    with area (see the module docstring)."""
    try:
        p = np.array(xz, dtype=float)
    except (TypeError, ValueError):
        raise OutlineError(f"{where}: an outline is a list of (x, z) number pairs") from None
    if p.ndim != 2 or p.shape[1] != 2:
        raise OutlineError(f"{where}: an outline is a list of (x, z) number pairs, got shape {p.shape}")
    if not np.all(np.isfinite(p)):
        raise OutlineError(f"{where}: the outline has a non-finite coordinate")
    if len(p) > 1 and np.allclose(p[0], p[-1]):
        p = p[:-1]  # closed polygon written with its first vertex repeated
    if len(p) < 3:
        raise OutlineError(f"{where}: a stone outline needs at least 3 vertices, got {len(p)}")
    area2 = _area2(p)
    if abs(area2) < 2 * AREA_TOL:
        distinct = p[np.any(p != np.roll(p, 1, axis=0), axis=1)]
        far = distinct[np.argmax(np.linalg.norm(distinct - distinct[0], axis=1))]
        if len(distinct) > 3 and np.any(_cross(distinct[0], far, distinct) != 0):  # not all on one line
            _check_simple(distinct, 0.0, where)  # a bow-tie has no area either: say that it crosses itself
        raise OutlineError(f"{where}: the outline has no area")
    if area2 < 0:
        p = p[::-1]
    tol = FLAT_REL_TOL * float(np.linalg.norm(np.ptp(p, axis=0)))
    out = _outward(p)
    while len(p) > 3 and np.min(np.abs(out)) <= tol:  # drop repeated points and points on an edge
        k = int(np.argmin(np.abs(out)))
        if _point_segment(p[k], p[k - 1], p[(k + 1) % len(p)]) > tol:
            raise OutlineError(f"{where}: stone outline doubles back on itself at {_xz(p[k])} (a spike of no width)")
        p = np.delete(p, k, axis=0)
        out = _outward(p)
    if len(p) == 3 and np.min(np.abs(out)) <= tol:
        raise OutlineError(f"{where}: the outline has no area: its corners lie within {tol:.3g} m of one line "
                           "(a sliver)")
    _check_simple(p, tol, where)
    return p


def _check_simple(p: np.ndarray, tol: float, where: str) -> None:
    """OutlineError unless the counter-clockwise polygon ``p`` is simple: no corner within
    ``tol`` of another, no two edges that are not neighbours within ``tol`` of each other."""
    n = len(p)
    i, j = np.triu_indices(n, 1)
    close = np.flatnonzero(np.linalg.norm(p[i] - p[j], axis=1) <= tol)
    if len(close):
        k = close[0]
        raise OutlineError(f"{where}: stone outline touches itself: corners {i[k]} and {j[k]} coincide at "
                           f"{_xz(p[i[k]])} (pinched; a stone outline is one simple polygon)")
    sep = (j - i) % n
    keep = (sep > 1) & (sep < n - 1)  # edges that are not neighbours
    i, j = i[keep], j[keep]
    a, b = p[i], p[(i + 1) % n]
    c, d = p[j], p[(j + 1) % n]
    bad = np.flatnonzero(_segment_gaps(a, b, c, d) <= tol)
    if len(bad):
        k = bad[0]
        raise OutlineError(f"{where}: stone outline crosses or touches itself: edge ({_xz(a[k])}) - ({_xz(b[k])}) "
                           f"meets edge ({_xz(c[k])}) - ({_xz(d[k])}) (a stone outline is one simple polygon)")


# --- convex pieces --------------------------------------------------------------------

class _Poly:
    """A checked counter-clockwise outline and its tolerances (m)."""

    def __init__(self, p: np.ndarray):
        self.p = p
        self.n = len(p)
        size = float(np.linalg.norm(np.ptp(p, axis=0)))
        self.eps = FLAT_REL_TOL * size
        self.eps0 = COLLINEAR_REL_TOL * size

    def clean(self, idx: list[int]) -> list[int] | None:
        """The corners of the convex polygon with vertex indices ``idx`` (counter-clockwise):
        vertices exactly on a straight side dropped; None if one is re-entrant or less than
        ``eps`` from straight without being on it."""
        idx = list(idx)
        while len(idx) >= 3:
            out = _outward(self.p[idx])
            flat = np.flatnonzero(np.abs(out) <= self.eps0)
            if len(flat) == 0:
                return idx if np.all(out > self.eps) else None
            k = int(flat[0])
            a, b, c = self.p[idx[k - 1]], self.p[idx[k]], self.p[idx[(k + 1) % len(idx)]]
            if np.dot(b - a, c - b) <= 0:  # doubles back: not a side of a convex piece
                return None
            del idx[k]
        return None

    def diagonals(self) -> np.ndarray:
        """(n, n) bool: a-b is a diagonal of the outline (``diagonal_ok`` on the whole
        outline, for every pair at once)."""
        p, n = self.p, self.n
        a, b = np.triu_indices(n, 2)
        keep = (b - a) < n - 1
        a, b = a[keep], b[keep]
        pa, pb = p[a][:, None, :], p[b][:, None, :]
        k = np.arange(n)
        near = _point_segment(p[None, :, :], pa, pb) <= self.eps  # (pairs, vertices)
        near[np.arange(len(a)), a] = near[np.arange(len(a)), b] = False
        k1 = (k + 1) % n
        at_end = (k[None, :] == a[:, None]) | (k[None, :] == b[:, None]) | (k1[None, :] == a[:, None]) \
            | (k1[None, :] == b[:, None])
        meets = (_segment_gaps(pa, pb, p[None, k, :], p[None, k1, :]) <= self.eps) & ~at_end
        prev, nxt = p[(a - 1) % n], p[(a + 1) % n]
        pa, pb = p[a], p[b]
        convex = _cross(prev, pa, nxt) >= 0
        inside = np.where(convex, (_cross(pa, pb, prev) > 0) & (_cross(pb, pa, nxt) > 0),
                          ~((_cross(pa, pb, nxt) >= 0) & (_cross(pb, pa, prev) >= 0)))
        ok = inside & ~near.any(axis=1) & ~meets.any(axis=1)
        valid = np.zeros((n, n), dtype=bool)
        valid[a[ok], b[ok]] = valid[b[ok], a[ok]] = True
        return valid

    def diagonal_ok(self, a: int, b: int, ring: list[int]) -> bool:
        """Whether a-b is a diagonal of the polygon of vertex indices ``ring``
        (counter-clockwise): inside it and clear, by ``eps``, of every other vertex and
        every edge not at a or b."""
        p = self.p
        m = len(ring)
        pos = {v: k for k, v in enumerate(ring)}
        ia, ib = pos[a], pos[b]
        if (ib - ia) % m in (0, 1, m - 1):
            return False
        pa, pb = p[a], p[b]
        others = np.array([v for v in ring if v != a and v != b])
        if np.any(_point_segment(p[others], pa, pb) <= self.eps):
            return False
        e0 = np.array(ring)
        e1 = np.roll(e0, -1)
        free = (e0 != a) & (e0 != b) & (e1 != a) & (e1 != b)
        if np.any(_segment_gaps(pa, pb, p[e0[free]], p[e1[free]]) <= self.eps):
            return False
        # inside: the direction a -> b within the interior angle at a (O'Rourke's InCone)
        prev, nxt = p[ring[ia - 1]], p[ring[(ia + 1) % m]]
        if _cross(prev, pa, nxt) >= 0:  # convex at a
            return bool(_cross(pa, pb, prev) > 0 and _cross(pb, pa, nxt) > 0)
        return not (_cross(pa, pb, nxt) >= 0 and _cross(pb, pa, prev) >= 0)


def convex_pieces(xz, where: str = "<outline>", exact_max: int = EXACT_MAX_CORNERS) -> list[np.ndarray]:
    """Convex pieces (each a counter-clockwise (k, 2) array of corners) that tile the
    outline ``xz`` (a counter-clockwise simple polygon of corners, as ``check_outline``
    returns); a convex outline is returned as its one piece. The exact minimum (by
    diagonals) when it has at most ``exact_max`` corners, else Hertel-Mehlhorn (at most
    4 x the minimum); see the module docstring. OutlineError naming ``where`` if no
    partition with clear corners is found (near-degenerate outlines)."""
    p = np.asarray(xz, dtype=float)
    if _area2(p) < 0:
        p = p[::-1]
    poly = _Poly(p)
    if np.all(_outward(p) > poly.eps):
        return [p]
    pieces = None
    if poly.n <= exact_max:
        pieces = _exact_pieces(poly)
    if pieces is None:
        pieces = _hertel_mehlhorn(poly, where)
    out = [p[idx] for idx in pieces]
    total = sum(_area2(q) for q in out)
    if abs(total - _area2(p)) > 1e-9 * abs(_area2(p)):  # the pieces tile the outline (internal check)
        raise OutlineError(f"{where}: its convex pieces do not tile it (areas {total / 2:.9g} and "
                           f"{_area2(p) / 2:.9g} m^2)")
    return out


def reflex_count(xz) -> int:
    """Re-entrant corners of a counter-clockwise outline of corners."""
    p = np.asarray(xz, dtype=float)
    return int(np.sum(_outward(p) < 0))


def lower_bound(xz) -> int:
    """The fewest convex pieces any partition of the outline can have, new points
    allowed: ceil(r/2) + 1 for r re-entrant corners (each cut resolves at most two), 1
    when convex."""
    r = reflex_count(xz)
    return 1 if r == 0 else -(-r // 2) + 1


# --- Hertel-Mehlhorn --------------------------------------------------------------------

def _triangulate(poly: _Poly, where: str) -> tuple[list[list[int]], list[tuple[int, int]]]:
    """Ear clipping: triangles (vertex index triples, counter-clockwise) and the diagonals
    between them. Each step clips the ear whose smallest angle is largest and whose
    three heights all exceed ``eps``."""
    p = poly.p
    ring = list(range(poly.n))
    tris, diags = [], []
    while len(ring) > 3:
        best, best_q = None, -1.0
        m = len(ring)
        for k in range(m):
            u, i, w = ring[k - 1], ring[k], ring[(k + 1) % m]
            q = _ear_quality(p[u], p[i], p[w], poly.eps)
            if q > best_q and poly.diagonal_ok(u, w, ring):
                best, best_q = k, q
        if best is None:
            raise OutlineError(f"{where}: the outline could not be split into convex pieces: no corner can be cut "
                               f"off clear of the others by {poly.eps:.3g} m (a near-degenerate outline)")
        u, i, w = ring[best - 1], ring[best], ring[(best + 1) % m]
        tris.append([u, i, w])
        diags.append((u, w))
        del ring[best]
    if _ear_quality(*p[ring], poly.eps) <= 0:
        raise OutlineError(f"{where}: the outline could not be split into convex pieces: its last triangle is a "
                           "sliver (a near-degenerate outline)")
    tris.append(ring)
    return tris, diags


def _ear_quality(a, b, c, eps: float) -> float:
    """Smallest angle (rad) of triangle a, b, c (counter-clockwise), or -1 if it turns the
    wrong way or has a height of at most ``eps``."""
    area2 = float(_cross(a, b, c))
    sides = [np.linalg.norm(b - c), np.linalg.norm(c - a), np.linalg.norm(a - b)]
    if area2 <= 0 or area2 / max(sides) <= eps:
        return -1.0
    la, lb, lc = sides
    cos = [(lb * lb + lc * lc - la * la) / (2 * lb * lc), (la * la + lc * lc - lb * lb) / (2 * la * lc),
           (la * la + lb * lb - lc * lc) / (2 * la * lb)]
    return float(np.arccos(np.clip(max(cos), -1.0, 1.0)))


def _hertel_mehlhorn(poly: _Poly, where: str) -> list[list[int]]:
    """Triangulate, then remove each diagonal whose two pieces merge into a convex piece
    with clear corners; the fewest pieces of four orders of trying the diagonals (longest
    first, shortest first, clipping order and its reverse: each order's result has the
    2r + 1 bound). Vertex index lists, counter-clockwise, cleaned."""
    tris, diags = _triangulate(poly, where)
    p = poly.p
    length = [float(np.linalg.norm(p[u] - p[w])) for u, w in diags]
    by_length = sorted(range(len(diags)), key=lambda d: length[d])
    orders = (by_length[::-1], by_length, list(range(len(diags))), list(range(len(diags)))[::-1])
    best = min((_merge(poly, tris, diags, order) for order in orders), key=len)
    out = []
    for idx in best:
        c = poly.clean(idx)
        if c is None:
            raise OutlineError(f"{where}: the outline could not be split into convex pieces with clear corners "
                               "(a near-degenerate outline)")
        out.append(c)
    return out


def _merge(poly: _Poly, tris: list[list[int]], diags: list[tuple[int, int]], order: list[int]) -> list[list[int]]:
    """Hertel-Mehlhorn's merges of the triangles ``tris`` across the diagonals, tried in
    ``order``: the pieces as vertex index lists (counter-clockwise, not cleaned)."""
    pieces = {k: list(t) for k, t in enumerate(tris)}
    owner = list(range(len(tris)))

    def find(k):
        while owner[k] != k:
            owner[k] = owner[owner[k]]
            k = owner[k]
        return k

    side = {}  # each diagonal's two triangles
    for k, t in enumerate(tris):
        for e in range(3):
            side.setdefault(frozenset((t[e], t[(e + 1) % 3])), []).append(k)
    for d in order:
        u, w = diags[d]
        k1, k2 = (find(k) for k in side[frozenset((u, w))])
        a, b = pieces[k1], pieces[k2]
        x, y = (u, w) if _has_side(a, u, w) else (w, u)  # a has the side x -> y, b the side y -> x
        merged = _rotate_to(a, y) + _rotate_to(b, x)[1:-1]  # y ... x, then b's vertices between x and y
        if poly.clean(merged) is None:
            continue
        pieces[k1] = merged
        del pieces[k2]
        owner[k2] = k1
    return list(pieces.values())


def _has_side(idx: list[int], u: int, w: int) -> bool:
    k = idx.index(u)
    return idx[(k + 1) % len(idx)] == w


def _rotate_to(idx: list[int], v: int) -> list[int]:
    k = idx.index(v)
    return idx[k:] + idx[:k]


# --- exact minimum (by diagonals) ---------------------------------------------------------

def _exact_pieces(poly: _Poly) -> list[list[int]] | None:
    """A minimum partition of the outline into convex pieces by diagonals (vertex index
    lists, counter-clockwise, cleaned), or None if none has clear corners.

    Sub-polygon (a, b), a < b: vertices a, a+1, ..., b closed by the diagonal b-a (the
    whole outline is (0, n-1), closed by an edge). Its piece on b-a is a convex chain
    a = c0 < c1 < ... < cm = b, each c_t-c_t+1 an edge or a diagonal closing the
    sub-polygon (c_t, c_t+1), solved the same way: cost(a, b) = 1 + min over chains of
    the sum of their sub-polygons' costs (a DP over the chain's last two vertices)."""
    p, n = poly.p, poly.n
    valid = poly.diagonals()
    k = np.arange(n)
    valid[k, (k + 1) % n] = valid[(k + 1) % n, k] = True  # the edges
    # ok[a, b, c]: b may be a vertex of a piece between a and c: a corner by more than eps,
    # or on the straight line a-c (dropped later); re-entrant or nearly straight is not
    A, B, C = np.meshgrid(np.arange(n), np.arange(n), np.arange(n), indexing="ij")
    chord = p[C] - p[A]
    length = np.linalg.norm(chord, axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = _cross(p[A], p[B], p[C]) / length
    between = np.sum((p[B] - p[A]) * (p[C] - p[B]), axis=-1) > 0
    ok = (length > 0) & ((out > poly.eps) | ((np.abs(out) <= poly.eps0) & between))
    memo: dict[tuple[int, int], tuple[float, list[int] | None]] = {}
    inf = float("inf")

    def cost(a: int, b: int) -> float:
        return 0.0 if b == a + 1 else solve(a, b)[0]

    def solve(a: int, b: int):
        if (a, b) in memo:
            return memo[(a, b)]
        states = [dict() for _ in range(b + 1)]  # states[q][p] = (cost, previous p) of chains ..., p, q
        for c1 in range(a + 1, b):
            if valid[a, c1] and ok[b, a, c1]:
                c = cost(a, c1)
                if c < inf:
                    states[c1][a] = (c, None)
        best, best_end = inf, None
        for q in range(a + 1, b):
            for pv, (c, _) in states[q].items():
                for r in range(q + 1, b + 1):
                    if not (valid[q, r] and ok[pv, q, r]):
                        continue
                    cr = c + cost(q, r)
                    if r == b:
                        if ok[q, b, a] and cr + 1 < best:
                            best, best_end = cr + 1, (q, pv)
                    elif cr < states[r].get(q, (inf,))[0]:
                        states[r][q] = (cr, pv)
        chain = None
        if best_end is not None:
            q, pv = best_end
            chain = [b, q]
            while pv is not None:
                chain.append(pv)
                q, pv = pv, states[q][pv][1]
            chain.reverse()
        memo[(a, b)] = (best, chain)
        return memo[(a, b)]

    total, _ = solve(0, n - 1)
    if total == inf:
        return None
    pieces, todo = [], [(0, n - 1)]
    while todo:
        a, b = todo.pop()
        chain = memo[(a, b)][1]
        clean = poly.clean(chain)
        if clean is None:
            return None
        pieces.append(clean)
        todo += [(x, y) for x, y in zip(chain, chain[1:]) if y > x + 1]
    return pieces
