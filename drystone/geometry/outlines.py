"""Blocks from user outlines: one 2D polygon per stone (x along the wall, z up, metres),
e.g. digitised from a photograph of the wall's face, extruded through the thickness
(y from -T/2 to T/2).

Input: a folder with one text file per stone named ``<id>.csv`` or ``<id>.txt`` (the id is
the stone's number, e.g. the paper's Figure 19c), two columns x z per line (comma, space or
tab separated; ``#`` comments and one header line allowed), at least 3 vertices, the
polygon convex (YADE polyhedra are convex: split a re-entrant stone into convex parts,
each its own file). Repeated points and points on a straight edge between their
neighbours (within ``FLAT_REL_TOL`` x the outline's size) are dropped: they are not
corners, and the block file takes corners only. A 0.1 m platform slab is added under the
lowest stone.

Roles: ``layout = "sacsayhuaman"`` applies the paper's (stones 1-7 fixed, side blocks 8,
9, 14, 15, 24, 25, 34 free only in z, y and about x, control points A-D at the top of
35, 38, 39, 40; ids 1-40 required); otherwise the stones touching the platform are
``fixed`` when ``fix_bottom`` (default) and the rest free.
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
from scipy.spatial import ConvexHull

from . import blockfile as bf
from . import params as pc

PLATFORM_THICKNESS = 0.1  # m
CONVEX_TOL = 1e-9  # m^2: outlines of less area than this are refused
#: a point less than this x the outline's size off the line through its neighbours is not a
#: corner (dropped if on the line, refused if inward); 1e-6 is far below any digitising
#: precision and far above the block file's corner tolerance (blockfile.CORNER_REL_TOL)
FLAT_REL_TOL = 1e-6


class OutlineError(bf.GeometryError):
    """A malformed or non-convex outline; the message names the file and stone."""


def read_outline(path) -> np.ndarray:
    """(n, 2) array of the x, z vertices (m) of one outline file, counter-clockwise."""
    path = Path(path)
    pts = []
    for k, line in enumerate(path.read_text().splitlines(), 1):
        text = line.split("#", 1)[0].strip()
        if not text:
            continue
        parts = [p for p in re.split(r"[,\s;]+", text) if p]
        try:
            vals = [float(p) for p in parts]
        except ValueError:
            if not pts and k <= 2:
                continue  # a header line
            raise OutlineError(f"{path}:{k}: expected two numbers x z, got {line.strip()!r}") from None
        if len(vals) != 2 or not all(np.isfinite(vals)):
            raise OutlineError(f"{path}:{k}: expected two finite numbers x z, got {line.strip()!r}")
        pts.append(vals)
    p = np.array(pts, float).reshape(-1, 2)
    if len(p) > 1 and np.allclose(p[0], p[-1]):
        p = p[:-1]  # closed polygon written with its first vertex repeated
    if len(p) < 3:
        raise OutlineError(f"{path}: a stone outline needs at least 3 vertices, got {len(p)}")
    area2 = _area2(p)
    if abs(area2) < 2 * CONVEX_TOL:
        raise OutlineError(f"{path}: the outline has no area")
    if area2 < 0:
        p = p[::-1]
    tol = FLAT_REL_TOL * float(np.linalg.norm(np.ptp(p, axis=0)))
    out = _outward(p)
    while len(p) > 3 and np.min(np.abs(out)) <= tol:  # drop repeated points and points on an edge
        p = np.delete(p, np.argmin(np.abs(out)), axis=0)
        out = _outward(p)
    bad = np.flatnonzero(out < -tol)
    if len(bad):
        v = p[bad[0]]
        raise OutlineError(f"{path}: stone outline is not convex (re-entrant corner at x = {v[0]:.4g}, "
                           f"z = {v[1]:.4g} m); split it into convex stones")
    area, hull_area = _area2(p) / 2, ConvexHull(p).volume
    if abs(area - hull_area) > FLAT_REL_TOL * hull_area:
        raise OutlineError(f"{path}: stone outline is not convex: its area, {area:.6g} m^2, is not its convex "
                           f"hull's, {hull_area:.6g} m^2 (does it cross itself?)")
    return p


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


def make(folder, thickness: float, layout: str | None = None, fix_bottom: bool = True, density=2300.0, kn=2e8,
         kt=1e8, mu=0.4, damping=0.8, name=None) -> dict:
    """A block-file dict from the outline files in ``folder`` (see the module docstring);
    ``thickness`` > 0 m, ``layout`` None or "sacsayhuaman"."""
    g = "outlines"
    if not isinstance(folder, (str, Path)):
        raise pc.fail(g, "folder", "a folder path", folder)
    pc.positive(g, "thickness", thickness, "m")
    pc.choice(g, "layout", layout, [None, "sacsayhuaman"])
    pc.choice(g, "fix_bottom", fix_bottom, [True, False])
    pc.material(g, density, kn, kt, damping, mu=mu)
    if name is not None and not isinstance(name, str):
        raise pc.fail(g, "name", "a string", name)
    folder = Path(folder)
    files = sorted(f for f in folder.glob("*") if f.suffix.lower() in (".csv", ".txt"))
    if not files:
        raise OutlineError(f"{folder}: no outline files (<id>.csv or <id>.txt)")
    stones = {}
    for f in files:
        if not f.stem.isdigit() or int(f.stem) == 0:
            raise OutlineError(f"{f}: outline files are named by the stone's id, a positive integer (1.csv ...)")
        if int(f.stem) in stones:
            raise OutlineError(f"{f}: a second outline for stone {int(f.stem)}")
        stones[int(f.stem)] = read_outline(f)
    h = thickness / 2.0
    blocks = []
    zmin = min(p[:, 1].min() for p in stones.values())
    for bid in sorted(stones):
        p = stones[bid]
        verts = [[x, y, z] for x, z in p for y in (-h, h)]
        blocks.append({"id": bid, "role": "free", "material": "stone", "vertices": verts})
    xs = np.concatenate([p[:, 0] for p in stones.values()])
    margin = 0.5 * (xs.max() - xs.min())
    x0, x1 = xs.min() - margin, xs.max() + margin
    y0, y1 = -h - thickness, h + thickness
    z0, z1 = zmin - PLATFORM_THICKNESS, zmin
    platform = {"id": 0, "role": "platform", "material": "stone",
                "vertices": [[x, y, z] for x in (x0, x1) for y in (y0, y1) for z in (z0, z1)]}
    control_points = []
    if layout == "sacsayhuaman":
        from . import sacsayhuaman as sw
        missing = sorted(set(range(1, 41)) - set(stones))
        if missing:
            raise OutlineError(f"{folder}: layout 'sacsayhuaman' needs stones 1-40; missing {missing}")
        for b in blocks:
            if b["id"] <= sw.COURSES[0]:
                b["role"] = "fixed"
            elif b["id"] in sw.SIDE_BLOCKS:
                b["blocked_dofs"] = "xYZ"
        for cp, bid in sw.CONTROL.items():
            p = stones[bid]
            top = p[np.isclose(p[:, 1], p[:, 1].max(), atol=1e-6)]
            control_points.append({"name": cp, "block": bid, "position": [float(top[:, 0].mean()), 0.0,
                                                                            float(top[:, 1].max())]})
    elif fix_bottom:
        for b in blocks:
            if np.min(np.asarray(b["vertices"])[:, 2]) <= zmin + 1e-6:
                b["role"] = "fixed"
    d = {"format": "drystone.blocks", "version": 1, "name": name or folder.name,
         "units": {"length": "m", "mass": "kg"},
         "materials": {"stone": {"density": density, "kn": kn, "kt": kt, "mu": mu, "damping": damping}},
         "blocks": [platform] + blocks, "control_points": control_points,
         "generator": {"name": "outlines", "folder": str(folder), "thickness": thickness, "layout": layout},
         "description": f"stones from the outlines in {folder}, extruded to {thickness} m"}
    bf.parse(d, f"outlines in {folder}")  # convex, no overlaps, finite: errors name the stone
    return d
