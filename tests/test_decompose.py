"""Outlines checked and split into convex pieces (drystone/geometry/decompose.py): piece
counts against the known minimum (L, T, U, combs, stars) and against a brute-force search
over every set of diagonals; on seeded random simple polygons every piece convex,
counter-clockwise, made of outline corners, the pieces tiling the outline (areas summing
to its area, interiors disjoint), Hertel-Mehlhorn within its bounds; refusals naming the
stone."""
import itertools

import numpy as np
import pytest

import tolerances as tol
from drystone.geometry import decompose as dc

WHERE = "stones/7.csv (stone 7)"

L = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]
T = [(0, 0), (1, 0), (1, 2), (2, 2), (2, 3), (-1, 3), (-1, 2), (0, 2)]
U = [(0, 0), (3, 0), (3, 2), (2, 2), (2, 1), (1, 1), (1, 2), (0, 2)]


def comb(k, w=1.0, gap=1.0):
    """A base bar 1 m high with k teeth w wide, gap apart, on top (the outer teeth flush
    with the bar's ends): 2(k - 1) re-entrant corners; minimum k + 1 pieces (each tooth a
    piece: a tooth flush with an end cannot share a convex piece with the bar beside its
    neighbour's gap)."""
    x1 = k * w + (k - 1) * gap
    pts = [(0, 0), (x1, 0)]
    for t in reversed(range(k)):
        x0 = t * (w + gap)
        pts += [(x0 + w, 2), (x0, 2)]
        if t > 0:
            pts += [(x0, 1), (x0 - gap, 1)]
    return pts


def star(m, r0=1.0, r1=0.4):
    """A star of m points: 2m corners, m re-entrant."""
    a = np.pi / 2 + np.pi / m * np.arange(2 * m)
    r = np.where(np.arange(2 * m) % 2 == 0, r0, r1)
    return np.c_[r * np.cos(a), r * np.sin(a)]


def notched(n=12):
    """A regular n-gon with one corner pulled in to half radius: one re-entrant corner,
    minimum 2 pieces; Hertel-Mehlhorn forced gives 3 (its bound 2r + 1)."""
    a = 2 * np.pi * np.arange(n) / n
    r = np.ones(n)
    r[0] = 0.5
    return np.c_[r * np.cos(a), r * np.sin(a)]


def random_star(rng, n):
    """A random polygon star-shaped about the origin (so simple): n angles, one in each
    2 pi / n sector (gaps below pi for n >= 4), radii 0.3-1 m."""
    a = 2 * np.pi * (np.arange(n) + rng.uniform(0, 0.8, n)) / n
    r = rng.uniform(0.3, 1.0, n)
    return np.c_[r * np.cos(a), r * np.sin(a)]


def random_two_opt(rng, n):
    """A random simple polygon, not star-shaped in general: random points in a square,
    crossings undone by 2-opt moves (each shortens the tour, so it ends)."""
    p = rng.uniform(0, 1, (n, 2))
    changed = True
    while changed:
        changed = False
        for i in range(n):
            for j in range(i + 2, n - (i == 0)):
                a, b, c, d = p[i], p[i + 1], p[j], p[(j + 1) % n]
                if dc._cross(a, b, c) * dc._cross(a, b, d) < 0 and dc._cross(c, d, a) * dc._cross(c, d, b) < 0:
                    p[i + 1:j + 1] = p[i + 1:j + 1][::-1].copy()
                    changed = True
    return p


def check_partition(outline, pieces):
    """Every piece counter-clockwise, convex with corners standing out by more than
    FLAT_REL_TOL x the size, its vertices outline corners; areas summing to the outline's;
    interiors pairwise disjoint (a separating axis among the two pieces' edge normals)."""
    p = np.asarray(outline, float)
    eps = dc.FLAT_REL_TOL * float(np.linalg.norm(np.ptp(p, axis=0)))
    corners = {tuple(v) for v in p}
    for q in pieces:
        assert len(q) >= 3 and dc._area2(q) > 0
        assert np.all(dc._outward(q) > eps)
        assert {tuple(v) for v in q} <= corners
    assert sum(dc._area2(q) for q in pieces) == pytest.approx(dc._area2(p), rel=tol.EXACT_REL)
    for a, b in itertools.combinations(pieces, 2):
        assert _separated(a, b), (a, b)


def _separated(a, b) -> bool:
    for q in (a, b):
        e = np.roll(q, -1, axis=0) - q
        normals = np.c_[e[:, 1], -e[:, 0]]
        for nrm in normals:
            pa, pb = a @ nrm, b @ nrm
            if min(pa.max(), pb.max()) - max(pa.min(), pb.min()) <= tol.EXACT_ABS:
                return True
    return False


def brute_force_minimum(p) -> int:
    """The fewest pieces of any partition by diagonals, by trying every set of
    non-crossing diagonals, smallest first: at every corner the rays along its two edges
    and its diagonals must leave no gap wider than pi (exactly pi: a straight side)."""
    n = len(p)
    valid = dc._Poly(p).diagonals()
    diags = [(a, b) for a in range(n) for b in range(a + 1, n) if valid[a, b]]

    def cross(d, e):
        if set(d) & set(e):
            return False
        a, b, c, f = p[d[0]], p[d[1]], p[e[0]], p[e[1]]
        return dc._cross(a, b, c) * dc._cross(a, b, f) < 0 and dc._cross(c, f, a) * dc._cross(c, f, b) < 0

    def convex(chosen):
        for x in range(n):
            nxt, prev = (x + 1) % n, (x - 1) % n
            rays = [nxt, prev] + [b if a == x else a for a, b in chosen if x in (a, b)]
            base = np.arctan2(*(p[nxt] - p[x])[::-1])
            th = sorted((np.arctan2(*(p[y] - p[x])[::-1]) - base) % (2 * np.pi) for y in rays)
            if any(g > np.pi - 1e-9 and abs(g - np.pi) > 1e-12 for g in np.diff(th)):
                return False
        return True

    for k in range(len(diags) + 1):
        for chosen in itertools.combinations(diags, k):
            if not any(cross(d, e) for d, e in itertools.combinations(chosen, 2)) and convex(chosen):
                return k + 1
    raise AssertionError("no convex partition")


# --- known shapes -------------------------------------------------------------------------

SHAPES = [("L", L, 2), ("T", T, 2), ("U", U, 3)] + [(f"comb{k}", comb(k), k + 1) for k in range(2, 6)] + [
    ("star5", star(5), 4), ("star10", star(10), 11), ("notched12", notched(), 2)]


@pytest.mark.parametrize("name, outline, minimum", SHAPES, ids=[s[0] for s in SHAPES])
def test_known_shapes_get_their_minimum(name, outline, minimum):
    """The exact search finds the minimum; Hertel-Mehlhorn (forced) stays within 2r + 1
    and 4 x the lower bound, never below the minimum; both tile the outline."""
    p = dc.check_outline(outline, WHERE)
    exact = dc.convex_pieces(p, WHERE)
    assert len(exact) == minimum
    check_partition(p, exact)
    hm = dc.convex_pieces(p, WHERE, exact_max=0)
    r = dc.reflex_count(p)
    assert minimum <= len(hm) <= min(2 * r + 1, 4 * dc.lower_bound(p))
    assert dc.lower_bound(p) <= minimum
    check_partition(p, hm)


def test_known_minimums_by_brute_force():
    """The minimums the shapes above assert (small ones) are the brute-force search's."""
    for outline, minimum in [(L, 2), (T, 2), (U, 3), (comb(2), 3), (comb(3), 4), (star(4), 3), (notched(), 2)]:
        assert brute_force_minimum(dc.check_outline(outline, WHERE)) == minimum


def test_exact_search_matches_brute_force_on_random_polygons():
    rng = np.random.default_rng(5)
    for _ in range(25):
        p = dc.check_outline(random_star(rng, int(rng.integers(5, 10))), WHERE)
        assert len(dc.convex_pieces(p, WHERE)) == brute_force_minimum(p)


def test_convex_outline_is_its_own_piece():
    p = dc.check_outline([(0, 0), (2, 0), (2.5, 1), (1, 2), (-0.5, 1)], WHERE)
    (piece,) = dc.convex_pieces(p, WHERE)
    assert piece is p


@pytest.mark.parametrize("family", [random_star, random_two_opt])
def test_random_simple_polygons_tile_with_convex_pieces(family):
    """Seeded random polygons of 5-40 corners, exact and Hertel-Mehlhorn: valid
    partitions, counts between the lower bound ceil(r/2) + 1 and Hertel-Mehlhorn's bounds
    (2r + 1, 4 x the lower bound), the exact one never above Hertel-Mehlhorn."""
    rng = np.random.default_rng(11)
    for _ in range(30):
        p = dc.check_outline(family(rng, int(rng.integers(5, 41 if family is random_star else 21))), WHERE)
        r, low = dc.reflex_count(p), dc.lower_bound(p)
        hm = dc.convex_pieces(p, WHERE, exact_max=0)
        check_partition(p, hm)
        assert low <= len(hm) <= min(2 * r + 1, 4 * low)
        exact = dc.convex_pieces(p, WHERE, exact_max=len(p))
        check_partition(p, exact)
        assert low <= len(exact) <= len(hm)


def test_large_outline_uses_hertel_mehlhorn():
    """Above EXACT_MAX_CORNERS corners the default is Hertel-Mehlhorn, a valid partition."""
    rng = np.random.default_rng(3)
    p = dc.check_outline(random_star(rng, 120), WHERE)
    assert len(p) > dc.EXACT_MAX_CORNERS
    pieces = dc.convex_pieces(p, WHERE)
    check_partition(p, pieces)
    assert len(pieces) <= 2 * dc.reflex_count(p) + 1


# --- check_outline ------------------------------------------------------------------------

def test_outline_cleaned_and_counter_clockwise():
    """Clockwise input is reversed; a closing repeat, repeated points and points on an
    edge are dropped; the corners are kept."""
    raw = [(0, 2), (1, 2), (1, 2), (1, 1), (2, 1), (2, 0), (1, 0), (0, 0), (0, 1), (0, 2)]  # clockwise L
    p = dc.check_outline(raw, WHERE)
    assert dc._area2(p) == pytest.approx(2 * 3.0, rel=tol.EXACT_REL)
    assert {tuple(v) for v in p} == {tuple(map(float, v)) for v in L}


@pytest.mark.parametrize("outline, words", [
    ([(0, 0), (1, 1), (1, 0), (0, 1)], "crosses or touches itself"),  # bow-tie
    (star(5)[[0, 4, 8, 2, 6]], "crosses or touches itself"),  # pentagram
    ([(0, 0), (4, 0), (4, 3), (2, 0), (0, 3)], "crosses or touches itself"),  # a corner on another edge
    ([(0, 0), (1, 0), (1, 1), (2, 1), (2, 2), (1, 2), (1, 1), (0, 1)], "coincide at x = 1, z = 1 m (pinched"),
    ([(0, 0), (2, 0), (2, 2), (1.5, 2), (1.5, 3), (1.5, 2.5), (1, 2), (0, 2)], "doubles back"),  # a spike
    ([(0, 0), (1, 0)], "at least 3 vertices, got 2"),  # two points
    ([(0, 0), (1, 0), (2, 0)], "no area"),  # collinear
    ([(1, 0), (0, 0), (3, 0), (2, 0)], "the outline has no area"),  # collinear, doubling back
    ([(0, 0), (1, 0), (1, 1e-10), (0, 1e-10)], "no area"),  # a zero-area sliver
    ([(0, 0), (1, 0), (0.5, 1e-7)], "no area: its corners lie within"),  # a sliver with area
    ([(0, 0), (1, np.nan), (0, 1)], "non-finite"),
])
def test_bad_outlines_are_refused_naming_the_stone(outline, words):
    with pytest.raises(dc.OutlineError) as err:
        dc.check_outline(outline, WHERE)
    msg = str(err.value)
    assert msg.startswith(WHERE + ": ") and words in msg and "\n" not in msg


def test_outline_error_is_a_geometry_error():
    from drystone.geometry import blockfile as bf
    from drystone.geometry import outlines as ol
    assert issubclass(dc.OutlineError, bf.GeometryError) and ol.OutlineError is dc.OutlineError
