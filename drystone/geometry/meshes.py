"""Blocks from meshes of scanned stones (OBJ, PLY, STL, read with trimesh), placed where
the scan puts them, on a platform slab.

Sources (exactly one): ``files = ["stone_a.obj", "stone_b.ply"]`` (one file per stone),
``folder = "scans"`` (every .obj/.ply/.stl in it, one per stone), or ``file = "wall.stl"``
with ``split = true`` (default): one mesh split into its connected components, one stone
each (ordered by centroid z, then x, then y). Ids: the file stems when all are positive
integers in ASCII digits up to ``blockfile.MAX_ID`` (``3.obj`` is stone 3), else 1, 2, ... in order (``files`` as listed, a folder
sorted by name).

Every mesh (each component, when split) must be closed (watertight: each edge shared by
exactly two faces) and enclose a volume (not flat: ``FLAT_REL``); a mesh with a hole, a
flat one, one with a non-finite (NaN) vertex (named before trimesh's processing drops it),
an unreadable or empty file, and, where a file is one stone (``files``, ``folder``, or
``file`` with ``split = false``), a file of several separate bodies (its hull would bridge
the gap) is refused, one GeometryError line naming the file (and component). A wall or
stone of implausible size (wrong ``units``) gets a ``warning:`` line (``plausible.py``).

Units: meshes carry none, so ``units`` ("mm", "cm", "m", "in", "ft") is required and
scales the file to metres. ``up`` ("z" default, "y" or "x"): the mesh's up axis, turned
onto z by a right-handed rotation (y up: (x, y, z) -> (x, -z, y); x up: (x, y, z) ->
(-z, y, x)).

Shapes (``decomposition``):

* ``"hull"`` (default): the convex hull of the mesh, one block. A hull of more than
  ``max_corners`` corners (default ``MAX_CORNERS`` = 24, the most a triangulated hull may
  have and still fit the contact kernel: blockfile.MAX_VERTICES_PER_BLOCK's note) is
  simplified to the hull of a subset of its corners, grown greedily as quickhull does: a
  first tetrahedron of far corners, then, one at a time, the corner farthest
  outside the hull so far (deterministic). That hull lies inside the full one; the
  volume it loses, and the volume the hull adds over the mesh (its concavities), are stated
  per stone in the block file's description.
* ``"coacd"``: an approximate convex decomposition (coacd, ``threshold`` its concavity
  limit, ``seed``), each part's hull simplified as above, a stone of convex ``parts``
  (block file version 2; one rigid body in a run). coacd's parts only approximately
  tile the mesh (a part's faces may lie ~1e-4 x the size off its neighbour's), so they may
  overlap by more than blockfile.OVERLAP_TOL or fail the face-to-face join rule: such a
  stone is refused by the block file's checks, naming the stone and the parts, not forced.
  (Measured: an extruded L gives its two boxes, accepted; the same L with 2 cm of noise on
  its surface gives 8 parts at threshold 0.05, refused as not joined, 2 at 0.1, accepted.)
  A mesh decomposed into one part gives a plain convex block.

Placement as scanned; a ``PLATFORM_THICKNESS`` (0.1 m) slab (id 0) under the lowest stone,
extending half the stones' extent beyond them in x and 3 x their half-extent in y about
their middle (the outlines' rule). Stones whose bottom is on the platform are fixed when
``fix_bottom`` (default), the rest free. ``control_points``: ``[[name, x, y, z], ...]`` (m,
after units and axes) on the stone containing or nearest to each point; none given: one
``top_<id>`` at the centroid of each top stone (top within ``outlines.TOP_REL`` x the
stones' height of the highest top).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from . import blockfile as bf
from . import outlines as ol
from . import params as pc
from . import plausible
from .blockfile import GeometryError

#: mesh unit -> metres (as the DXF reader's)
UNITS = {"in": 0.0254, "ft": 0.3048, "mm": 0.001, "cm": 0.01, "m": 1.0}
SUFFIXES = (".obj", ".ply", ".stl")
#: most corners of a simplified hull (part): a triangulated hull of V corners has 2V - 4
#: faces, which fit the contact kernel's buffer (faces + largest face's corners <= 48) for
#: V <= 24 (blockfile.MAX_VERTICES_PER_BLOCK's note)
MAX_CORNERS = 24
#: a mesh is flat (no volume) when the spread of its points normal to their best plane (the
#: least singular value of the centred points, about sqrt(n) x their RMS distance to it) is
#: below this x its size x sqrt(n): far below any stone (a 1 m stone 1 um thick)
FLAT_REL = 1e-6
DECOMPOSITIONS = ("hull", "coacd")
UP_AXES = ("z", "y", "x")
PLATFORM_THICKNESS = ol.PLATFORM_THICKNESS


def _fail(path, msg) -> GeometryError:
    return GeometryError(f"{path}: {msg}")


def load(path, what: str | None = None):
    """A trimesh.Trimesh from ``path`` (vertices merged), refused unless readable and non-empty."""
    import trimesh

    path = Path(path)
    if not path.is_file():
        raise _fail(path, "mesh file not found")
    if path.suffix.lower() not in SUFFIXES:
        raise _fail(path, f"not a mesh file of a known kind {list(SUFFIXES)}")
    try:
        m = trimesh.load(str(path), force="mesh", process=False)
    except Exception as err:  # trimesh raises many kinds on bad files
        raise _fail(path, f"not a readable mesh: {' '.join(str(err).split()) or type(err).__name__}") from None
    if not isinstance(m, trimesh.Trimesh) or len(m.faces) == 0:
        raise _fail(path, "not a readable mesh (no triangles)")
    bad = np.flatnonzero(~np.all(np.isfinite(m.vertices), axis=1))
    if len(bad):  # checked before processing, which drops such vertices (and the mesh then has holes)
        raise _fail(path, f"mesh has {len(bad)} vertex(es) with non-finite coordinates (NaN or infinity), "
                          f"the first vertex {bad[0]} at {tuple(float(x) for x in m.vertices[bad[0]])}")
    m.process(validate=False)  # merge duplicate vertices, as trimesh.load(process=True)
    return m


def check_closed(m, where: str) -> None:
    """Refuse a mesh that is not closed (an edge not shared by exactly two faces) or that
    encloses no volume (flat: all its points within ``FLAT_REL`` x its size of a plane)."""
    if not m.is_watertight:
        raise GeometryError(f"{where}: mesh is not closed (watertight): it has a hole or a loose edge; "
                            "close it (fill holes) before use")
    p = np.asarray(m.vertices, float)
    size = float(np.max(p.max(axis=0) - p.min(axis=0))) if len(p) else 0.0
    thin = float(np.linalg.svd(p - p.mean(axis=0), compute_uv=False)[-1]) if len(p) >= 4 else 0.0
    if size == 0.0 or thin <= FLAT_REL * size * np.sqrt(len(p)):
        raise GeometryError(f"{where}: mesh encloses no volume (its points lie in a plane or on a line); "
                            "a stone is a solid")


def check_one_body(m, where: str) -> None:
    """Refuse a mesh of several separate bodies where one stone is meant (its hull would
    bridge the gap: a stone that is not there)."""
    n = len(m.split(only_watertight=False, repair=False))
    if n > 1:
        raise GeometryError(f"{where}: the mesh holds {n} separate bodies, not one stone; give one stone per file "
                            "(or the whole wall as file = ... with split = true, one stone per body)")


def orient(points, units: str, up: str) -> np.ndarray:
    """Points of a mesh in metres, z up."""
    p = np.asarray(points, float) * UNITS[units]
    if up == "y":
        p = np.column_stack([p[:, 0], -p[:, 2], p[:, 1]])
    elif up == "x":
        p = np.column_stack([-p[:, 2], p[:, 1], p[:, 0]])
    return p


def _hull(points):
    from scipy.spatial import ConvexHull

    return ConvexHull(points)


def simplify(points, max_corners: int = MAX_CORNERS) -> tuple[np.ndarray, float, float]:
    """``(corners, hull volume, simplified volume)``: the corners of the convex hull of
    ``points``, or, above ``max_corners``, of the hull of a subset of them
    (grown greedily: see the module docstring)."""
    h = _hull(points)
    corners = np.asarray(points, float)[h.vertices]
    vol = float(h.volume)
    if len(corners) <= max_corners:
        return corners, vol, vol
    # a first tetrahedron as quickhull's: the corner farthest from the centroid, the one
    # farthest from it, from their line, from their plane
    p0 = int(np.argmax(np.linalg.norm(corners - corners.mean(axis=0), axis=1)))
    p1 = int(np.argmax(np.linalg.norm(corners - corners[p0], axis=1)))
    e = (corners[p1] - corners[p0]) / np.linalg.norm(corners[p1] - corners[p0])
    r = corners - corners[p0]
    p2 = int(np.argmax(np.linalg.norm(r - np.outer(r @ e, e), axis=1)))
    nrm = np.cross(corners[p1] - corners[p0], corners[p2] - corners[p0])
    p3 = int(np.argmax(np.abs(r @ nrm)))
    chosen = [p0, p1, p2, p3]
    while len(chosen) < max_corners:  # then the corner farthest outside the hull so far
        h2 = _hull(corners[chosen])
        out = np.max(corners @ h2.equations[:, :3].T + h2.equations[:, 3], axis=1)
        k = int(np.argmax(out))
        if out[k] <= 0:
            break
        chosen.append(k)
    h2 = _hull(corners[chosen])
    return corners[chosen][h2.vertices], vol, float(h2.volume)


def decompose(m, threshold: float = 0.05, seed: int = 0, max_parts: int = bf.MAX_PARTS_PER_BLOCK):
    """coacd's approximate convex decomposition of the closed mesh ``m``: a list of
    (n, 3) point arrays, one per part (in ``m``'s coordinates)."""
    import coacd

    coacd.set_log_level("error")
    parts = coacd.run_coacd(coacd.Mesh(np.asarray(m.vertices, float), np.asarray(m.faces, np.int32)),
                            threshold=float(threshold), max_convex_hull=int(max_parts), seed=int(seed))
    return [np.asarray(v, float) for v, _ in parts]


def _sources(files, folder, file, split):
    """[(path, mesh, label)] one per stone, and their ids."""
    given = [k for k, v in (("files", files), ("folder", folder), ("file", file)) if v is not None]
    if len(given) != 1:
        raise GeometryError(f"geometry generator 'meshes': give exactly one of 'files', 'folder', 'file' "
                            f"(got {given or 'none'})")
    if file is not None:
        path = Path(file)
        m = load(path)
        if not split:
            check_closed(m, str(path))
            check_one_body(m, str(path))
            return [(path, m, str(path))], [1]
        comps = m.split(only_watertight=False, repair=False)  # no hole filling: holes are refused
        out = []
        for c in sorted(comps, key=lambda c: tuple(np.asarray(c.vertices).mean(axis=0)[[2, 0, 1]])):
            out.append((path, c, f"{path} (component {len(out) + 1} of {len(comps)})"))
        for _, c, where in out:
            check_closed(c, where)
        return out, list(range(1, len(out) + 1))
    if folder is not None:
        fp = Path(folder)
        if not fp.is_dir():
            raise GeometryError(f"{fp}: mesh folder not found")
        paths = sorted((p for p in fp.iterdir() if p.suffix.lower() in SUFFIXES), key=lambda p: p.name)
        if not paths:
            raise GeometryError(f"{fp}: no mesh files ({', '.join(SUFFIXES)}) in the folder")
    else:
        paths = [Path(f) for f in files]
    stems = [ol.stone_id(p.stem) for p in paths]
    if all(s is not None for s in stems):
        ids = stems
        dup = sorted({i for i in ids if ids.count(i) > 1})
        if dup:
            raise GeometryError(f"two mesh files for stone(s) {dup}: "
                                f"{[str(p) for p, i in zip(paths, ids) if i in dup]}")
    else:
        ids = list(range(1, len(paths) + 1))
    out = []
    for p in paths:
        m = load(p)
        check_closed(m, str(p))
        check_one_body(m, str(p))
        out.append((p, m, str(p)))
    return out, ids


def _distance(planes, q) -> float:
    """Largest signed distance of ``q`` to a convex block's face planes (<= 0 inside;
    ``polyhedron.planes``: N @ x + d <= 0 inside)."""
    n, d = planes
    return float(np.max(n @ np.asarray(q, float) + d))


def make(files=None, folder=None, file=None, units: str | None = None, up: str = "z", split: bool = True,
         decomposition: str = "hull", threshold: float = 0.05, seed: int = 0, max_corners: int = MAX_CORNERS,
         control_points=None, fix_bottom: bool = True, density=2300.0, kn=2e8, kt=1e8, mu=0.4, damping=0.8,
         name=None) -> dict:
    """A block-file dict from meshes of scanned stones (see the module docstring)."""
    g = "meshes"
    if files is not None and (not isinstance(files, (list, tuple)) or not files
                              or not all(isinstance(f, (str, Path)) for f in files)):
        raise pc.fail(g, "files", "a non-empty list of mesh file paths", files)
    for key, v in (("folder", folder), ("file", file)):
        if v is not None and not isinstance(v, (str, Path)):
            raise pc.fail(g, key, "a path", v)
    pc.choice(g, "up", up, list(UP_AXES))
    pc.choice(g, "split", split, [True, False])
    pc.choice(g, "decomposition", decomposition, list(DECOMPOSITIONS))
    pc.number(g, "threshold", threshold, 0.01, 1.0)
    pc.integer(g, "seed", seed, 0)
    pc.integer(g, "max_corners", max_corners, 4, bf.MAX_VERTICES_PER_BLOCK)
    pc.choice(g, "fix_bottom", fix_bottom, [True, False])
    pc.material(g, density, kn, kt, damping, mu=mu)
    if name is not None and not isinstance(name, str):
        raise pc.fail(g, "name", "a string", name)
    if units is not None and units not in UNITS:
        raise pc.fail(g, "units", f"one of {sorted(UNITS)}", units)
    if control_points is not None:
        ok = isinstance(control_points, (list, tuple)) and all(
            isinstance(c, (list, tuple)) and len(c) == 4 and isinstance(c[0], str)
            and all(bf.is_number(x) for x in c[1:]) for c in control_points)
        if not ok:
            raise pc.fail(g, "control_points", "a list of [name, x, y, z] (m)", control_points)
    sources, ids = _sources(files, folder, file, split)
    if units is None:
        raise _fail(sources[0][0], f"mesh files carry no units; give units = one of {sorted(UNITS)}")

    plausible.check_sizes({bid: orient(m.vertices, units, up) for (_, m, _), bid in zip(sources, ids)},
                          {bid: f"stone {bid} ({where})" for (_, _, where), bid in zip(sources, ids)},
                          str(file or folder or "meshes"), units)
    blocks, notes, stone_points = [], [], {}
    for (path, m, where), bid in zip(sources, ids):
        pts = orient(m.vertices, units, up)
        mesh_vol = abs(float(m.volume)) * UNITS[units] ** 3
        if decomposition == "hull":
            corners, vh, vs = simplify(pts, max_corners)
            pieces = [corners]
            note = (f"stone {bid} ({Path(where).name if where == str(path) else where}): hull of "
                    f"{len(corners)} corners, {100 * (1 - vs / vh):.2f} % of the hull's volume lost to "
                    f"simplification, hull {100 * (vh / mesh_vol - 1):.2f} % above the mesh's volume")
        else:
            raw = decompose(m, threshold, seed)
            pieces, vs = [], 0.0
            for part in raw:
                c, _, v = simplify(orient(part, units, up), max_corners)
                pieces.append(c)
                vs += v
            note = (f"stone {bid}: coacd, {len(pieces)} part(s), total volume "
                    f"{100 * (vs / mesh_vol - 1):+.2f} % against the mesh's")
        notes.append(note)
        stone_points[bid] = np.vstack(pieces)
        block = {"id": bid, "role": "free", "material": "stone"}
        if len(pieces) == 1:
            block["vertices"] = pieces[0].tolist()
        else:
            block["parts"] = [p.tolist() for p in pieces]
        blocks.append(block)

    allp = np.vstack(list(stone_points.values()))
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    zmin = lo[2]
    if fix_bottom:
        for b in blocks:
            if stone_points[b["id"]][:, 2].min() <= zmin + 1e-6:
                b["role"] = "fixed"
    margin = 0.5 * (hi[0] - lo[0])
    ym, hy = 0.5 * (lo[1] + hi[1]), 0.5 * (hi[1] - lo[1])
    pv = [[x, y, z] for x in (lo[0] - margin, hi[0] + margin) for y in (ym - 3 * hy, ym + 3 * hy)
          for z in (zmin - PLATFORM_THICKNESS, zmin)]
    src = {"files": [str(p) for p, _, _ in sources]} if file is None else {"file": str(file), "split": split}
    generator = {"name": "meshes", **src, "units": units, "up": up, "decomposition": decomposition,
                 "max_corners": max_corners}
    if decomposition == "coacd":
        generator.update(threshold=threshold, seed=seed)
    origin = str(sources[0][0]) if file is not None or len(sources) == 1 else f"meshes {generator.get('files')}"
    d = {"format": "drystone.blocks", "version": bf.PARTS_VERSION if any("parts" in b for b in blocks) else bf.VERSION,
         "name": name or (Path(file).stem if file is not None else Path(folder).name if folder is not None
                          else "meshes"),
         "units": {"length": "m", "mass": "kg"},
         "materials": {"stone": {"density": density, "kn": kn, "kt": kt, "mu": mu, "damping": damping}},
         "blocks": [{"id": 0, "role": "platform", "material": "stone", "vertices": pv}] + blocks,
         "control_points": [], "generator": generator,
         "description": f"scanned stones ({units}, {up} up, {decomposition}): " + "; ".join(notes)}
    parsed = bf.parse(d, origin)  # convex parts, no overlaps, parts joined: errors name the stone
    cps = []
    if control_points:
        for cname, x, y, z in control_points:
            q = (float(x), float(y), float(z))
            bid = min(ids, key=lambda b: min(_distance(pl, q) for pl in parsed.block(b).part_planes()))
            cps.append({"name": cname, "block": bid, "position": list(q)})
    else:
        zt = max(p[:, 2].max() for p in stone_points.values())
        for bid in sorted(ids):
            if stone_points[bid][:, 2].max() >= zt - ol.TOP_REL * (zt - zmin):
                cps.append({"name": f"top_{bid}", "block": bid,
                            "position": [float(x) for x in parsed.block(bid).centroid]})
    d["control_points"] = cps
    bf.parse(d, origin)
    return d
