"""Seeded generator of polygonal (Inca-like) dry-stone walls: interlocking polygonal stones
in the face plane (x along the wall, z up), extruded through the thickness.

Method (units m):

1. Seeds in the L x H face rectangle, dart-thrown (Poisson-disk: no two seeds closer than
   ``SPACING_FRACTION`` x the target stone diameter) with a count chosen so the mean stone
   has the equivalent diameter (``sqrt(4 A / pi)``) of the middle of ``stone_size``.
   ``typology = "sacsayhuaman"`` (the paper's typology 1: large stones with small ones
   between): large seeds (target diameter ``stone_size[1]``, covering about half the face)
   first, then small ones (target (3 min + max) / 4) in the gaps, each with the weight
   (``WEIGHT_SHRINK`` x its target radius)^2 of a power diagram (Laguerre), so that the
   large stones stay large next to the small ones.
2. The power diagram (Voronoi diagram for ``typology = "uniform"``: all weights 0) clipped
   to the rectangle: each cell the intersection of half-planes, corners shared between
   neighbours (merged within ``MERGE_REL_TOL`` x the wall's size, so joints are exact: no
   gap, no overlap); ``lloyd`` Lloyd steps move each seed to its cell's centroid.
3. Repairs, in order, until none applies: an edge shorter than ``SHORT_EDGE_FRACTION`` x the
   smallest stone diameter is collapsed to a point (both cells lose a corner); a stone that
   is not within the corner count [``MIN_CORNERS``, ``MAX_CORNERS``] or whose interior
   size is below ``stone_size[0]`` (a border stone's below ``BORDER_MIN_FRACTION`` x it)
   is merged with the neighbour whose union is convex and smallest (a stone over
   ``stone_size[1]`` or one no merge repairs: a new draw). Corners closer than
   ``decompose.FLAT_REL_TOL`` to straight are dropped.
4. ``reentrant`` = r > 0: the fraction of the stones made non-convex: k = round(r n / (1 + r))
   pairs of the n convex cells (k of the n - k stones) whose union is not convex (a
   re-entrant corner at a joint end) are merged, each pair into one stone of at most
   ``MAX_CORNERS`` corners and at most ``stone_size[1]``, in a seeded order (fewer where
   no such pair is left); for that the uniform typology seeds smaller cells
   (``REENTRANT_PAIR_FILL`` x max / sqrt(2), at least ``REENTRANT_CELL_MIN`` x min). Such a
   stone becomes several convex ``parts`` (``decompose.convex_pieces``; block file
   version 2; one rigid body in a run). ``reentrant = 0`` gives convex stones and a version 1 file.

Sizes: every stone not touching the rectangle's boundary has an equivalent diameter within
``stone_size``; stones clipped by the wall's ends, foot or top (border stones) can be
smaller than ``stone_size[0]`` (down to ``BORDER_MIN_FRACTION`` x it) since the clipping
cuts them; none is larger than ``stone_size[1]``. A layout that cannot meet this in
``MAX_TRIES`` draws raises GeometryError (widen ``stone_size``).

Blocks: each stone extruded through ``thickness`` (y from -T/2 to T/2), or with
``depth_spread`` > 0 to a depth of its own (``irregular_wall.stone_depths``). As
``outlines.make``: a 0.1 m platform slab (block 0) under the wall, half a wall length
wider on each side and one thickness deeper on each face; stones touching the platform
``fixed`` when ``fix_bottom`` (default), the rest free. Stones are numbered from the
bottom up (by the lowest point, then x), from 1. Control points: the middle of each top
stone's top edge on its front face (y = -depth/2, z = H), named T1, T2, ... left to right.
"""
from __future__ import annotations

import numpy as np

import drystone
from . import blockfile as bf
from . import decompose as dc
from . import irregular_wall as iw
from . import params as pc

G = "polygonal_wall"
PLATFORM_THICKNESS = 0.1  # m, as outlines.py
#: no two seeds closer than this x the target diameter (Poisson-disk); a Lloyd step evens them
SPACING_FRACTION = 0.7
#: power-diagram weight of a seed: (target radius x this)^2 (large stones push their joints out)
WEIGHT_SHRINK = 0.8
#: corners of two cells closer than this x the wall's diagonal are one corner (round-off of
#: the half-plane clipping, ~1e-15 relative, far below)
MERGE_REL_TOL = 1e-9
#: an edge shorter than this x stone_size[0] is collapsed (a sliver corner, not a stone's)
SHORT_EDGE_FRACTION = 0.08
MIN_CORNERS, MAX_CORNERS = 4, 12
#: border stones (clipped by the rectangle) may be down to this x stone_size[0]
BORDER_MIN_FRACTION = 0.4
#: with reentrant > 0 (uniform typology) cells are seeded at this x max / sqrt(2) (a merged
#: pair of mean cells then fills the range's top with room for the cells' spread), not
#: below this x min
REENTRANT_PAIR_FILL, REENTRANT_CELL_MIN = 0.9, 1.1
#: draws of a new seed set before giving up
MAX_TRIES = 40
TYPOLOGIES = ("uniform", "sacsayhuaman")


def _diameter(area: float) -> float:
    return float(np.sqrt(4.0 * area / np.pi))


def _area(p: np.ndarray) -> float:
    x, z = p[:, 0], p[:, 1]
    return 0.5 * float(x @ np.roll(z, -1) - z @ np.roll(x, -1))


def _centroid(p: np.ndarray) -> np.ndarray:
    x, z = p[:, 0], p[:, 1]
    c = x * np.roll(z, -1) - np.roll(x, -1) * z
    a = c.sum() / 2.0
    return np.array([((x + np.roll(x, -1)) * c).sum(), ((z + np.roll(z, -1)) * c).sum()]) / (6.0 * a)


def _clip(poly: np.ndarray, n: np.ndarray, c: float) -> np.ndarray:
    """The part of convex ``poly`` with n . x <= c."""
    s = poly @ n - c
    out = []
    for k in range(len(poly)):
        p0, p1, s0, s1 = poly[k], poly[(k + 1) % len(poly)], s[k], s[(k + 1) % len(poly)]
        if s0 <= 0:
            out.append(p0)
        if (s0 <= 0) != (s1 <= 0):
            out.append(p0 + (p1 - p0) * (s0 / (s0 - s1)))
    return np.array(out).reshape(-1, 2)


def _power_cells(pts, w, length, height):
    """Cells (lists of (m, 2) arrays; None where empty) of the power diagram of ``pts``
    with weights ``w`` clipped to the rectangle."""
    rect = np.array([[0.0, 0.0], [length, 0.0], [length, height], [0.0, height]])
    cells = []
    sq = (pts ** 2).sum(axis=1)
    w_max = float(np.max(w)) if len(w) else 0.0
    for i in range(len(pts)):
        poly = rect
        d2 = ((pts - pts[i]) ** 2).sum(axis=1)
        order = np.argsort(d2)
        reach = np.sqrt(((poly - pts[i]) ** 2).sum(axis=1).max())  # farthest corner of the cell from p_i
        for j in order[1:]:
            # the bisector of i and j lies (|d|^2 + w_i - w_j) / (2 |d|) >= (|d|^2 - w_max) / (2 |d|) from p_i,
            # growing with |d|: past the cell's farthest corner no later seed cuts the cell (an exact stop)
            dj = np.sqrt(d2[j])
            if dj > 0 and (d2[j] - w_max) / (2.0 * dj) > reach:
                break
            # |x - p_i|^2 - w_i <= |x - p_j|^2 - w_j  <=>  2 (p_j - p_i) . x <= |p_j|^2 - |p_i|^2 - w_j + w_i
            poly = _clip(poly, 2.0 * (pts[j] - pts[i]), sq[j] - sq[i] - w[j] + w[i])
            if len(poly) < 3:
                break
            reach = np.sqrt(((poly - pts[i]) ** 2).sum(axis=1).max())
        cells.append(poly if len(poly) >= 3 and _area(poly) > 0 else None)
    return cells


def _seeds(rng, length, height, dmin, dmax, typology, reentrant):
    """Seed points and power weights (see the module docstring)."""
    area = length * height
    if typology == "sacsayhuaman":
        n_big = max(1, int(round(0.5 * area / (np.pi / 4 * dmax ** 2))))  # large stones cover about half the face
        small = 0.75 * dmin + 0.25 * dmax
        n_small = max(1, int(round(0.5 * area / (np.pi / 4 * small ** 2))))
        targets = [dmax] * n_big + [small] * n_small
    else:
        dmean = 0.5 * (dmin + dmax)
        if reentrant > 0:  # cells small enough that a merged pair (sqrt(2) x the diameter) fits under dmax
            dmean = max(REENTRANT_CELL_MIN * dmin, min(dmean, REENTRANT_PAIR_FILL * dmax / np.sqrt(2.0)))
        n = max(1, int(round(area / (np.pi / 4 * dmean ** 2))))
        targets = [dmean] * n
    pts, rad = np.empty((len(targets), 2)), np.empty(len(targets))
    n = 0
    for d in targets:
        r = 0.5 * d
        for _ in range(300):
            p = rng.uniform([0.0, 0.0], [length, height])
            if np.all(np.hypot(p[0] - pts[:n, 0], p[1] - pts[:n, 1]) >= SPACING_FRACTION * (r + rad[:n])):
                pts[n], rad[n] = p, r
                n += 1
                break
    pts, rad = pts[:n], rad[:n]
    w = (WEIGHT_SHRINK * np.array(rad)) ** 2 if typology == "sacsayhuaman" else np.zeros(len(pts))
    return pts, w


def _layout(pts, w, length, height, lloyd):
    for _ in range(lloyd):
        cells = _power_cells(pts, w, length, height)
        keep = [c is not None for c in cells]
        pts = np.array([_centroid(c) for c in cells if c is not None])
        w = w[keep]
    return [c for c in _power_cells(pts, w, length, height) if c is not None]


class _Mesh:
    """Stones as rings of shared corner indices."""

    def __init__(self, cells, length, height):
        self.L, self.H = length, height
        self.tol = MERGE_REL_TOL * float(np.hypot(length, height))
        self.xyz: list[np.ndarray] = []
        self.rings: list[list[int]] = []
        for c in cells:
            ring = []
            for p in c:
                k = self._index(p)
                if not ring or ring[-1] != k:
                    ring.append(k)
            if ring[0] == ring[-1]:
                ring.pop()
            if len(ring) >= 3:
                self.rings.append(ring)

    def _index(self, p):
        p = np.array(p, float)
        for ax, hi in ((0, self.L), (1, self.H)):  # snap to the rectangle's sides
            if abs(p[ax]) < self.tol:
                p[ax] = 0.0
            elif abs(p[ax] - hi) < self.tol:
                p[ax] = hi
        for k, q in enumerate(self.xyz):
            if abs(q[0] - p[0]) < self.tol and abs(q[1] - p[1]) < self.tol:
                return k
        self.xyz.append(p)
        return len(self.xyz) - 1

    def poly(self, ring):
        return np.array([self.xyz[k] for k in ring])

    def on_border(self, k):
        x, z = self.xyz[k]
        return x in (0.0, self.L) or z in (0.0, self.H)

    def border(self, ring):
        """Touches the rectangle with an edge (not only a corner)."""
        return any(self.on_border(a) and self.on_border(b) and self._same_side(a, b)
                   for a, b in zip(ring, ring[1:] + ring[:1]))

    def _same_side(self, a, b):
        pa, pb = self.xyz[a], self.xyz[b]
        return any(pa[ax] == pb[ax] == v for ax, v in ((0, 0.0), (0, self.L), (1, 0.0), (1, self.H)))

    def _corner(self, k):
        return self.xyz[k][0] in (0.0, self.L) and self.xyz[k][1] in (0.0, self.H)

    def collapse_short(self, emin):
        """Collapse edges shorter than emin: both ends to one point (their midpoint; a
        border end stays, a rectangle corner stays). Not done where a stone would be left
        with fewer than 3 corners or not convex (the edge then stays)."""
        changed = True
        failed = set()  # short edges that could not be collapsed since the last collapse
        while changed:
            changed = False
            for ring in self.rings:
                for a, b in zip(ring, ring[1:] + ring[:1]):
                    if np.hypot(*(self.xyz[a] - self.xyz[b])) >= emin or (a, b) in failed:
                        continue
                    if self._collapse(a, b):
                        failed.clear()
                        continue
                    # a failed collapse restarts the scan (walls drawn so far depend on this order);
                    # met again before any other collapse, the edge stays (it looped forever before)
                    failed.add((a, b))
                    changed = True
                    break
                if changed:
                    break

    def _collapse(self, a, b) -> bool:
        """Try to collapse edge a-b (see collapse_short); True if done."""
        if self._corner(a) and self._corner(b):
            return False
        if any(a in r and b in r and len(r) <= 3 for r in self.rings):
            return False
        keep, drop = (a, b) if self._corner(a) or (self.on_border(a) and not self.on_border(b)) else (b, a)
        at = self.xyz[keep].copy()
        if not (self._corner(keep) or self.on_border(keep) != self.on_border(drop)):
            if self.on_border(keep) and not self._same_side(keep, drop):
                return False  # two ends on different sides: leave it
            self.xyz[keep] = 0.5 * (self.xyz[a] + self.xyz[b])
        rings = self.rings
        self._replace(drop, keep)
        if len(self.rings) != len(rings) or not all(self.convex(r) for r in self.rings if keep in r):
            self.rings, self.xyz[keep] = rings, at
            return False
        return True

    def _replace(self, drop, keep):
        new = []
        for ring in self.rings:
            r = [keep if k == drop else k for k in ring]
            r = [k for i, k in enumerate(r) if k != r[i - 1]] if len(r) > 1 else r
            if len(r) >= 3:
                new.append(r)
        self.rings = new

    def corners(self, ring):
        """The ring without straight (flat) points."""
        p = self.poly(ring)
        tol = dc.FLAT_REL_TOL * float(np.linalg.norm(np.ptp(p, axis=0)))
        out = list(ring)
        changed = True
        while changed and len(out) > 3:
            changed = False
            for i in range(len(out)):
                a, b, c = self.xyz[out[i - 1]], self.xyz[out[i]], self.xyz[out[(i + 1) % len(out)]]
                e = c - a
                if abs(e[0] * (b[1] - a[1]) - e[1] * (b[0] - a[0])) / max(np.hypot(*e), 1e-300) <= tol:
                    del out[i]
                    changed = True
                    break
        return out

    def convex(self, ring):
        p = self.poly(ring)
        d = np.roll(p, -1, axis=0) - p
        cr = d[:, 0] * np.roll(d[:, 1], -1) - d[:, 1] * np.roll(d[:, 0], -1)
        return bool(np.all(cr > 0))

    def union(self, r1, r2):
        """The union ring (corners only) of two stones sharing a chain of edges, or None."""
        e1 = {(a, b) for a, b in zip(r1, r1[1:] + r1[:1])}
        e2 = {(a, b) for a, b in zip(r2, r2[1:] + r2[:1])}
        shared = {(a, b) for a, b in e1 if (b, a) in e2}
        if not shared:
            return None
        edges = [(a, b) for a, b in e1 if (a, b) not in shared] + [(a, b) for a, b in e2 if (b, a) not in shared]
        nxt = {}
        for a, b in edges:
            if a in nxt:
                return None  # pinched at a corner
            nxt[a] = b
        start = min(nxt)
        out, k = [start], nxt[start]
        while k != start:
            if k not in nxt or len(out) > len(edges):
                return None
            out.append(k)
            k = nxt[k]
        if len(out) != len(edges):
            return None  # two loops (a hole)
        return self.corners(out)

    def neighbours(self, i):
        return [j for j in range(len(self.rings)) if j != i and len(set(self.rings[i]) & set(self.rings[j])) >= 2
                and self.union(self.rings[i], self.rings[j]) is not None]


def _ok(mesh, ring, dmin, dmax):
    d = _diameter(_area(mesh.poly(ring)))
    lo = BORDER_MIN_FRACTION * dmin if mesh.border(ring) else dmin
    return MIN_CORNERS <= len(ring) <= MAX_CORNERS and lo <= d <= dmax


def _repair(mesh, dmin, dmax):
    """Merge stones that break the corner or size rules into a neighbour (convex union);
    False if some stone cannot be repaired."""
    for _ in range(4 * len(mesh.rings) + 10):
        mesh.rings = [mesh.corners(r) for r in mesh.rings]
        bad = [i for i, r in enumerate(mesh.rings) if not _ok(mesh, r, dmin, dmax)]
        if not bad:
            return True
        i = min(bad, key=lambda k: _area(mesh.poly(mesh.rings[k])))
        r = mesh.rings[i]
        if len(r) > MAX_CORNERS or _diameter(_area(mesh.poly(r))) > dmax:
            return False
        best = None
        for j in mesh.neighbours(i):
            u = mesh.union(r, mesh.rings[j])
            if u is None or not mesh.convex(u) or len(u) > MAX_CORNERS:
                continue
            d = _diameter(_area(mesh.poly(u)))
            if d > dmax:
                continue
            if best is None or d < best[0]:
                best = (d, j, u)
        if best is None:
            return False
        _, j, u = best
        mesh.rings = [x for k, x in enumerate(mesh.rings) if k not in (i, j)] + [u]
    return False


def _reentrant(mesh, rng, fraction, dmax):
    """Merge pairs of convex stones into non-convex ones (see the module docstring)."""
    target = int(round(fraction * len(mesh.rings) / (1.0 + fraction)))  # k pairs of n cells: k / (n - k) stones
    done = 0
    order = list(rng.permutation(len(mesh.rings)))
    used: set[int] = set()
    merged = []
    for i in order:
        if done >= target:
            break
        if i in used:
            continue
        best = None
        for j in mesh.neighbours(i):
            if j in used:
                continue
            u = mesh.union(mesh.rings[i], mesh.rings[j])
            if u is None or mesh.convex(u) or len(u) > MAX_CORNERS:
                continue
            d = _diameter(_area(mesh.poly(u)))
            if d <= dmax and (best is None or d < best[0]):
                best = (d, j, u)
        if best is not None:
            used |= {i, best[1]}
            merged.append(best[2])
            done += 1
    mesh.rings = [r for k, r in enumerate(mesh.rings) if k not in used] + merged


def outlines(length=2.0, height=1.0, stone_size=(0.2, 0.4), seed=0, reentrant=0.0, typology="uniform", lloyd=3,
             _generator=G) -> list[np.ndarray]:
    """The stones' face outlines (counter-clockwise (n, 2) arrays of x, z corners, m),
    unnumbered; parameters as ``make`` (not checked here)."""
    dmin, dmax = stone_size
    rng = np.random.default_rng(seed)
    for _ in range(MAX_TRIES):
        pts, w = _seeds(rng, length, height, dmin, dmax, typology, reentrant)
        cells = _layout(pts, w, length, height, lloyd)
        mesh = _Mesh(cells, length, height)
        mesh.collapse_short(SHORT_EDGE_FRACTION * dmin)
        if not _repair(mesh, dmin, dmax):
            continue
        if reentrant > 0:
            _reentrant(mesh, rng, reentrant, dmax)
        return [mesh.poly(r) for r in mesh.rings]
    raise bf.GeometryError(f"geometry generator {_generator!r}: no layout of stones of {dmin:g}-{dmax:g} m and "
                           f"{MIN_CORNERS}-{MAX_CORNERS} corners found in a {length:g} x {height:g} m face in "
                           f"{MAX_TRIES} draws: widen 'stone_size'")


def make(length=2.0, height=1.0, thickness=0.4, stone_size=(0.2, 0.4), seed=0, reentrant=0.0, typology="uniform",
         lloyd=3, depth_spread=0.0, fix_bottom=True, density=2300.0, kn=2e8, kt=1e8, mu=0.4, damping=0.8,
         name="polygonal_wall") -> dict:
    """A polygonal wall as a block-file dict (see the module docstring).

    ``length``, ``height``, ``thickness`` > 0 (m); ``stone_size`` [min, max] equivalent
    diameters (m) with 0 < min < max <= min(length, height); ``seed`` an integer >= 0;
    ``reentrant`` in [0, 1] (fraction of the stones made non-convex by merging pairs of
    cells; 1: every cell paired where it can be); ``typology`` "uniform" or
    "sacsayhuaman"; ``lloyd`` an integer in [0, 50] (Lloyd steps); ``depth_spread`` in [0, 1);
    ``fix_bottom`` true or false; material as the other generators. Bad values raise
    GeometryError naming the parameter and what is allowed."""
    g = G
    for k, v in (("length", length), ("height", height), ("thickness", thickness)):
        pc.positive(g, k, v, "m")
    pc.numbers(g, "stone_size", stone_size, 2, lo=0, lo_open=True, unit="m")
    dmin, dmax = stone_size
    if not dmin < dmax <= min(length, height):
        raise pc.fail(g, "stone_size", f"[min, max] equivalent diameters with 0 < min < max <= min(length, height) "
                                       f"({min(length, height):g} m)", stone_size)
    if length * height / (np.pi / 4 * dmin ** 2) > 2000:
        raise pc.fail(g, "stone_size", f"[min, max] with at most about 2000 stones of the min size in the face "
                                       f"(min >= {np.sqrt(length * height / 2000 / (np.pi / 4)):.3g} m)", stone_size)
    pc.integer(g, "seed", seed, lo=0)
    pc.number(g, "reentrant", reentrant, 0, 1)
    pc.choice(g, "typology", typology, list(TYPOLOGIES))
    pc.integer(g, "lloyd", lloyd, 0, 50)
    pc.number(g, "depth_spread", depth_spread, 0, 1, hi_open=True)
    pc.choice(g, "fix_bottom", fix_bottom, [True, False])
    pc.material(g, density, kn, kt, damping, mu=mu)
    if not isinstance(name, str) or not name:
        raise pc.fail(g, "name", "a non-empty string", name)
    stones = outlines(length, height, tuple(stone_size), seed, reentrant, typology, lloyd)
    stones = [dc.check_outline(s, f"{g} stone") for s in stones]
    stones.sort(key=lambda p: (round(float(p[:, 1].min()), 9), float(_centroid(p)[0])))
    rng = np.random.default_rng([seed, 1])  # depths drawn apart from the face layout
    depths = iw.stone_depths(rng, [_area(p) for p in stones], thickness, depth_spread)
    blocks = []
    for bid, (p, dep) in enumerate(zip(stones, depths), 1):
        h = float(dep) / 2.0
        pieces = dc.convex_pieces(p, f"{g} stone {bid}")
        extruded = [[[float(x), y, float(z)] for x, z in q for y in (-h, h)] for q in pieces]
        block = {"id": bid, "role": "fixed" if fix_bottom and p[:, 1].min() <= 0.0 else "free", "material": "stone"}
        if len(extruded) == 1:
            block["vertices"] = extruded[0]
        else:
            block["parts"] = extruded
        blocks.append(block)
    half = float(np.max(depths)) / 2.0
    x0, x1 = -0.5 * length, 1.5 * length
    y0, y1 = -half - thickness, half + thickness
    platform = {"id": 0, "role": "platform", "material": "stone",
                "vertices": [[x, y, z] for x in (x0, x1) for y in (y0, y1) for z in (-PLATFORM_THICKNESS, 0.0)]}
    control_points = []
    tops = [(bid, p) for bid, p in enumerate(stones, 1) if np.isclose(p[:, 1], height).sum() >= 2]
    for k, (bid, p) in enumerate(sorted(tops, key=lambda t: float(_centroid(t[1])[0])), 1):
        top = p[np.isclose(p[:, 1], height), 0]
        control_points.append({"name": f"T{k}", "block": bid,
                               "position": [float(top.mean()), -float(depths[bid - 1]) / 2.0, float(height)]})
    version = bf.PARTS_VERSION if any("parts" in b for b in blocks) else bf.VERSION
    params = dict(length=length, height=height, thickness=thickness, stone_size=list(stone_size), seed=seed,
                  reentrant=reentrant, typology=typology, lloyd=lloyd, depth_spread=depth_spread,
                  fix_bottom=fix_bottom, density=density, kn=kn, kt=kt, mu=mu, damping=damping)
    d = {"format": bf.FORMAT, "version": version, "name": name,
         "description": f"polygonal dry-stone wall ({typology}), seed {seed} (drystone/geometry/polygonal_wall.py)",
         "units": {"length": "m", "mass": "kg"},
         "materials": {"stone": {"density": density, "kn": kn, "kt": kt, "mu": mu, "damping": damping}},
         "blocks": [platform] + blocks, "control_points": control_points,
         "generator": dict(params, name=G, drystone_version=drystone.__version__)}
    bf.parse(d, f"geometry generator {G!r}")
    return d
