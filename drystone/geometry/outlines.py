"""Blocks from user outlines: one 2D polygon per stone (x along the wall, z up, metres),
e.g. digitised from a photograph of the wall's face, extruded through the thickness
(y from -T/2 to T/2).

Input: a folder with one text file per stone named ``<id>.csv`` or ``<id>.txt`` (the id is
the stone's number, e.g. the paper's Figure 19c: ASCII digits, 1 to ``blockfile.MAX_ID``;
the file UTF-8 or ASCII text), two columns x z per line (comma, space or
tab separated; ``#`` comments and one header line allowed), at least 3 vertices in order
around the stone (either sense; the last joins the first). The rules of an outline are
``drystone.geometry.decompose.check_outline``'s: repeated points and points on a
straight edge between their neighbours (within ``decompose.FLAT_REL_TOL`` x the outline's
size) are dropped (they are not corners, and the block file takes corners only); an
outline with no area (a sliver), one that crosses or touches itself, is pinched at a
repeated corner or doubles back is refused, naming the file and stone. A 0.1 m platform
slab is added under the lowest stone.

Stones: a convex outline is one convex block (``vertices``: each corner at y = -T/2 and
T/2). A non-convex outline (re-entrant corners: a notched or L-shaped stone) becomes one
stone of several convex ``parts`` (block file version 2), the extruded pieces of
``decompose.convex_pieces``: the exact minimum partition by diagonals up to
``decompose.EXACT_MAX_CORNERS`` corners, Hertel-Mehlhorn (at most 4 x the minimum) above.
The file is version 2 only when some stone has parts (validated by ``blockfile``; in a
run one rigid body, a YADE clump of its parts).

Roles: ``layout = "sacsayhuaman"`` applies the paper's (stones 1-7 fixed, side blocks 8,
9, 14, 15, 24, 25, 34 free only in z, y and about x, control points A-D at the top of
35, 38, 39, 40; ids 1-40 required); otherwise the stones touching the platform are
``fixed`` when ``fix_bottom`` (default) and the rest free, and the control points (for the
figures) are ``top_<id>`` at the centroids of the top stones (``top_stones``) on the front
face (y = -T/2). ``build`` turns outlines into the block file for this reader and for the
DXF reader (``drystone/geometry/dxf.py``).
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from . import blockfile as bf
from . import decompose as dc
from . import params as pc
from . import plausible
from .decompose import OutlineError  # the outline rules have one home: decompose.py

PLATFORM_THICKNESS = 0.1  # m


def read_outline(path) -> np.ndarray:
    """(n, 2) array of the x, z corners (m) of one outline file, counter-clockwise
    (``decompose.check_outline``; errors name the file and stone)."""
    path = Path(path)
    try:
        content = path.read_bytes().decode("utf-8")
    except UnicodeDecodeError as err:
        raise OutlineError(f"{path}: not a UTF-8 text file (byte 0x{err.object[err.start]:02x} at position "
                           f"{err.start}); save the outline as plain text (UTF-8 or ASCII)") from None
    except OSError as err:
        raise OutlineError(f"{path}: cannot read the outline file ({err.strerror or err})") from None
    pts = []
    for k, line in enumerate(content.splitlines(), 1):
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
    return dc.check_outline(np.array(pts, float).reshape(-1, 2), _where(path))


#: a stone's id as written in a file name or a label: ASCII digits (``str.isdigit`` also
#: takes superscripts and other scripts' digits, which ``int`` refuses)
ID_DIGITS = re.compile(r"[0-9]+")


def stone_id(text: str) -> int | None:
    """The stone id ``text`` spells (ASCII digits, 1 to ``blockfile.MAX_ID``), else None."""
    if not ID_DIGITS.fullmatch(text):
        return None
    bid = int(text)
    return bid if 1 <= bid <= bf.MAX_ID else None


def _where(path: Path) -> str:
    """An outline file and its stone, for messages."""
    bid = stone_id(path.stem)
    return f"{path} (stone {bid})" if bid is not None else str(path)


def _points(block: dict) -> np.ndarray:
    """Every vertex (m) of a block dict, one part or several."""
    return np.concatenate([np.asarray(v, float) for v in block.get("parts", [block.get("vertices")])])


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
    stones, files_by_id = {}, {}
    for f in files:
        bid = stone_id(f.stem)
        if bid is None:
            raise OutlineError(f"{f}: outline files are named by the stone's id, an integer from 1 to "
                               f"{bf.MAX_ID} in the digits 0-9 (1.csv ...)")
        if bid in stones:
            raise OutlineError(f"{f}: a second outline for stone {bid}")
        stones[bid] = read_outline(f)
        files_by_id[bid] = f
    return build(stones, thickness, {bid: _where(f) for bid, f in files_by_id.items()}, origin=f"outlines in {folder}",
                 layout=layout, fix_bottom=fix_bottom, density=density, kn=kn, kt=kt, mu=mu, damping=damping,
                 name=name or folder.name,
                 generator={"name": "outlines", "folder": str(folder), "thickness": thickness, "layout": layout},
                 description=f"stones from the outlines in {folder}, extruded to {thickness} m")


#: a stone is a "top stone" (default control point at its centroid) when its top lies within
#: TOP_REL x the wall's height of the wall's top
TOP_REL = 0.1


def top_stones(stones: dict) -> list[int]:
    """Ids of the top stones of ``{id: (n, 2) outline}``: those whose highest corner is within
    ``TOP_REL`` x the wall's height of the highest corner of the wall."""
    zmax = max(p[:, 1].max() for p in stones.values())
    zmin = min(p[:, 1].min() for p in stones.values())
    return sorted(b for b, p in stones.items() if p[:, 1].max() >= zmax - TOP_REL * (zmax - zmin))


def centroid(p: np.ndarray) -> np.ndarray:
    """Area centroid (x, z) of a simple polygon (n, 2)."""
    x, z = p[:, 0], p[:, 1]
    xn, zn = np.roll(x, -1), np.roll(z, -1)
    c = x * zn - xn * z
    a = c.sum() / 2.0
    return np.array([((x + xn) * c).sum(), ((z + zn) * c).sum()]) / (6.0 * a)


def _distance(p: np.ndarray, q) -> float:
    """Distance (m) from point ``q`` (x, z) to the polygon ``p`` (0 inside or on it)."""
    q = np.asarray(q, float)
    a, b = p, np.roll(p, -1, axis=0)
    inside = False
    for (x0, z0), (x1, z1) in zip(a, b):
        if (z0 > q[1]) != (z1 > q[1]) and q[0] < x0 + (q[1] - z0) * (x1 - x0) / (z1 - z0):
            inside = not inside
    if inside:
        return 0.0
    ab = b - a
    t = np.clip(np.einsum("ij,ij->i", q - a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300), 0, 1)
    return float(np.min(np.linalg.norm(a + t[:, None] * ab - q, axis=1)))


def stone_at(stones: dict, q) -> int:
    """Id of the stone containing the point ``q`` (x, z), or else the nearest one."""
    return min(sorted(stones), key=lambda b: _distance(stones[b], q))


def inside(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Which of the points ``q`` (m, 2) lie inside the polygon ``p`` (n, 2) or on its edges
    (``_distance`` 0), vectorised over the points and the edges."""
    q = np.asarray(q, float).reshape(-1, 2)
    a, b = p[None, :, :], np.roll(p, -1, axis=0)[None, :, :]
    x, z = q[:, 0:1], q[:, 1:2]
    z0, z1, x0, x1 = a[..., 1], b[..., 1], a[..., 0], b[..., 0]
    straddle = (z0 > z) != (z1 > z)
    with np.errstate(divide="ignore", invalid="ignore"):
        cross = straddle & (x < x0 + (z - z0) * (x1 - x0) / np.where(straddle, z1 - z0, 1.0))
    odd = np.count_nonzero(cross, axis=1) % 2 == 1
    ab = b - a
    t = np.clip(np.einsum("mnk,mnk->mn", q[:, None, :] - a, np.broadcast_to(ab, (len(q),) + ab.shape[1:]))
                / np.maximum(np.einsum("mnk,mnk->mn", ab, ab), 1e-300), 0, 1)
    on_edge = np.any(np.all(a + t[..., None] * ab == q[:, None, :], axis=2), axis=1)
    return odd | on_edge


def points_in(polygons: list, points) -> list[np.ndarray]:
    """For each polygon of ``polygons`` ((n_i, 2) arrays), the indices of the ``points``
    (m, 2) inside it or on its edges (``inside``). The points are sorted by x once and each
    polygon tests only those within its bounding box: O((n + m) log m) plus the points near
    each polygon, where testing each point against each polygon took 171 s for 1000 stones."""
    pts = np.asarray(points, float).reshape(-1, 2)
    order = np.argsort(pts[:, 0], kind="stable")
    xs = pts[order, 0]
    out = []
    for poly in polygons:
        lo, hi = poly.min(axis=0), poly.max(axis=0)
        cand = order[np.searchsorted(xs, lo[0], side="left"):np.searchsorted(xs, hi[0], side="right")]
        cand = cand[(pts[cand, 1] >= lo[1]) & (pts[cand, 1] <= hi[1])]
        out.append(np.sort(cand[inside(poly, pts[cand])]) if len(cand) else cand)
    return out




def _gap(p: np.ndarray, q: np.ndarray) -> float:
    """Distance (m) between two polygons that do not overlap (0 where they touch): the least
    distance of a corner of one to the other."""
    return min(min(_distance(q, c) for c in p), min(_distance(p, c) for c in q))


def _tol_words(tol: float, stones: dict) -> str:
    allp = np.vstack(list(stones.values()))
    size = float(np.max(allp.max(axis=0) - allp.min(axis=0)))
    return f"{tol:.3g} m" if tol >= bf.STANDING_TOL else f"{tol:.3g} m: {100 * bf.STANDING_REL:g} % of the {size:.3g} m wall"


def _check_standing(stones: dict, platform: np.ndarray, roles: dict, fix_bottom: bool, where: dict,
                    tol: float) -> set:
    """The stones standing on the drawn ``platform`` (a corner within ``tol``, m: a fixed stone
    farther away would hover in place; a wall whose lowest stones are would drop). Refused, naming
    the stone and its gap: a platform no stone stands on (the wall would drop onto it), and
    a stone fixed by ``roles`` that stands neither on the platform nor on fixed stones that
    do (a chain; with ``fix_bottom`` the stones on the platform are fixed)."""
    gaps = {bid: min(_distance(platform, c) for c in p) for bid, p in stones.items()}
    on = {bid for bid, g in gaps.items() if g <= tol}
    if not on:
        low = min(stones, key=lambda b: (stones[b][:, 1].min(), b))
        raise OutlineError(f"{where[low]}: no stone stands on the drawn platform; the lowest, this one, is "
                           f"{gaps[low]:.4g} m from it (tolerance {_tol_words(tol, stones)}): draw the platform under "
                           "the stones")
    fixed = {bid for bid, role in roles.items() if role == "fixed"}
    held = {bid for bid in on if roles.get(bid, "fixed" if fix_bottom else "free") == "fixed"}
    todo = sorted(held)
    while todo:
        a = stones[todo.pop()]
        for bid in sorted(fixed - held):
            b = stones[bid]
            if (np.all(b.min(axis=0) <= a.max(axis=0) + tol)
                    and np.all(a.min(axis=0) <= b.max(axis=0) + tol) and _gap(a, b) <= tol):
                held.add(bid)
                todo.append(bid)
    for bid in sorted(fixed - held):
        raise OutlineError(f"{where[bid]}: a fixed stone must stand on the platform (or on fixed stones that do) "
                           f"within {_tol_words(tol, stones)}; it is {gaps[bid]:.4g} m from the platform: it would hover")
    return on


def build(stones: dict, thickness: float, where: dict, *, origin: str, roles: dict | None = None,
          depths: dict | None = None, platform: np.ndarray | None = None, control_points=None,
          layout: str | None = None, fix_bottom: bool = True, density=2300.0, kn=2e8, kt=1e8, mu=0.4,
          damping=0.8, name: str = "outlines", generator: dict | None = None, description: str = "",
          units: str | None = None) -> dict:
    """The block-file dict of the stones ``{id: (n, 2) counter-clockwise outline (x, z, m)}``
    (as ``decompose.check_outline`` returns them) extruded through ``thickness`` (m; y from
    -T/2 to T/2, or a stone's own ``depths[id]``), shared by the outline folder and DXF
    readers. ``where[id]`` names a stone in messages, ``origin`` the source, ``units`` the
    unit it was read in (``plausible.check_sizes`` warns about an implausible size). ``roles``:
    ``{id: "free" | "fixed"}`` fixes a stone's role; the others are fixed when they stand on
    the platform (within ``blockfile.standing_tol``) and ``fix_bottom``, else free
    (``layout = "sacsayhuaman"`` overrides both). ``platform``: a convex (n, 2) outline for
    the platform (id 0), extruded through 3 x the deepest stone (some stone must stand on it,
    and every stone of role fixed on it or on fixed stones that do: ``_check_standing``);
    default a 0.1 m slab under the lowest stone, 2 x the wall's length wide.
    ``control_points``: ``[(name, x, z)]`` on the stone containing (or nearest to) each point,
    at the front face (y = -T/2); none given: one ``top_<id>`` at the centroid of each top stone
    (``top_stones``)."""
    roles = roles or {}
    depths = depths or {}
    plausible.check_sizes(stones, where, origin, units)
    h = thickness / 2.0
    blocks = []
    zmin = min(p[:, 1].min() for p in stones.values())
    for bid in sorted(stones):
        hb = depths.get(bid, thickness) / 2.0
        pieces = dc.convex_pieces(stones[bid], where[bid])
        extruded = [[[x, y, z] for x, z in q for y in (-hb, hb)] for q in pieces]
        block = {"id": bid, "role": roles.get(bid, "free"), "material": "stone"}
        if len(extruded) == 1:
            block["vertices"] = extruded[0]
        else:
            block["parts"] = extruded
        blocks.append(block)
    hmax = max([h] + [d / 2.0 for d in depths.values()])
    y0, y1 = -3 * hmax, 3 * hmax
    if platform is None:
        xs = np.concatenate([p[:, 0] for p in stones.values()])
        margin = 0.5 * (xs.max() - xs.min())
        x0, x1 = xs.min() - margin, xs.max() + margin
        z0, z1 = zmin - PLATFORM_THICKNESS, zmin
        pv = [[x, y, z] for x in (x0, x1) for y in (y0, y1) for z in (z0, z1)]
    else:
        pv = [[x, y, z] for x, z in platform for y in (y0, y1)]
    platform_block = {"id": 0, "role": "platform", "material": "stone", "vertices": pv}
    cps = []
    if layout == "sacsayhuaman":
        from . import sacsayhuaman as sw
        missing = sorted(set(range(1, 41)) - set(stones))
        if missing:
            raise OutlineError(f"{origin}: layout 'sacsayhuaman' needs stones 1-40; missing {missing}")
        for b in blocks:
            if b["id"] <= sw.COURSES[0]:
                b["role"] = "fixed"
            elif b["id"] in sw.SIDE_BLOCKS:
                b["blocked_dofs"] = "xYZ"
        for cp, bid in sw.CONTROL.items():
            p = stones[bid]
            top = p[np.isclose(p[:, 1], p[:, 1].max(), atol=1e-6)]
            cps.append({"name": cp, "block": bid, "position": [float(top[:, 0].mean()), 0.0,
                                                               float(top[:, 1].max())]})
    else:
        allp = np.vstack(list(stones.values()))
        tol = bf.standing_tol(float(np.max(allp.max(axis=0) - allp.min(axis=0))))
        if platform is None:  # the slab under the lowest stone
            on = {bid for bid, p in stones.items() if p[:, 1].min() <= zmin + tol}
        else:
            on = _check_standing(stones, platform, roles, fix_bottom, where, tol)
        if fix_bottom:
            for b in blocks:
                if b["id"] not in roles and b["id"] in on:
                    b["role"] = "fixed"
        if control_points:
            for cname, x, z in control_points:
                bid = stone_at(stones, (x, z))
                cps.append({"name": cname, "block": bid,
                            "position": [float(x), -depths.get(bid, thickness) / 2.0, float(z)]})
        else:
            for bid in top_stones(stones):
                cx, cz = centroid(stones[bid])
                cps.append({"name": f"top_{bid}", "block": bid,
                            "position": [float(cx), -depths.get(bid, thickness) / 2.0, float(cz)]})
    version = bf.PARTS_VERSION if any("parts" in b for b in blocks) else bf.VERSION
    d = {"format": "drystone.blocks", "version": version, "name": name,
         "units": {"length": "m", "mass": "kg"},
         "materials": {"stone": {"density": density, "kn": kn, "kt": kt, "mu": mu, "damping": damping}},
         "blocks": [platform_block] + blocks, "control_points": cps,
         "generator": generator or {}, "description": description}
    bf.parse(d, origin)  # convex, no overlaps, finite: errors name the stone
    return d
