"""Blocks from a CAD drawing (DXF, read with ezdxf): the wall's face drawn in its plane
(DXF x -> wall x, DXF y -> z up), each stone a closed polyline, extruded through the
thickness (y from -T/2 to T/2) exactly as the outline files of ``outlines.py`` are
(``outlines.build``: a convex stone is one block, a re-entrant one a stone of convex
``parts``, block file version 2).

Model space only. Layers (names case-insensitive, as in CAD):

* ``stones``: closed LWPOLYLINE or 2D POLYLINE (closed flag, or first point = last), a
  stone fixed when it stands on the platform (``fix_bottom``, default) and free otherwise;
  ``free`` / ``fixed``: a stone with that role whatever its place;
* ``platform``: at most one closed convex polyline, the platform (id 0), extruded through
  3 x the wall's thickness; without one, a 0.1 m slab under the lowest stone;
* ``control_points``: POINT (named P1, P2, ... in drawing order) or TEXT/MTEXT (named by
  its text) at a control point, put on the stone that contains it (or the nearest) at the
  wall's front face (y = -T/2); without any, one ``top_<id>`` at the centroid of each top
  stone (``outlines.top_stones``);
* any other layer is ignored (listed in the block file's ``description``).

Ids: a TEXT or MTEXT (any layer but ``control_points``) whose insertion point lies inside
a stone and reads a positive integer (``7`` or ``id=7``), or a block reference (INSERT)
placed inside it with an attribute ``ID``. A stone without one, with two, or an id used
twice is refused naming the polyline's handle and layer. A text ``depth=0.6`` (or an
INSERT attribute ``DEPTH``) inside a stone gives that stone its own depth (m) instead of
``thickness``.

Units: the header's ``$INSUNITS`` (in, ft, mm, cm, m) scales the drawing to metres; a
unitless drawing (0, the default of many programs) is refused unless ``units`` ("mm",
"cm", "m", "in", "ft") is given, and ``units`` that contradict the header are refused.
Polylines with arcs (bulges) are refused (draw the stone with straight edges). Every error
is one GeometryError line naming the file (and the handle, layer or stone).
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from . import decompose as dc
from . import outlines as ol
from . import params as pc
from .blockfile import GeometryError

#: layer name (lower case) -> role given to its stones (None: fixed on the platform, else free)
STONE_LAYERS = {"stones": None, "free": "free", "fixed": "fixed"}
PLATFORM_LAYER = "platform"
CONTROL_LAYER = "control_points"
#: drawing unit -> metres
UNITS = {"in": 0.0254, "ft": 0.3048, "mm": 0.001, "cm": 0.01, "m": 1.0}
#: $INSUNITS code -> unit name (other codes are refused)
INSUNITS = {1: "in", 2: "ft", 4: "mm", 5: "cm", 6: "m"}
_ID = re.compile(r"^\s*(?:id\s*=\s*)?(\d+)\s*$", re.I)
_DEPTH = re.compile(r"^\s*depth\s*=\s*([0-9.eE+-]+)\s*$", re.I)


def _fail(path, msg) -> GeometryError:
    return GeometryError(f"{path}: {msg}")


def _polyline(e, path, scale):
    """(n, 2) corners (m) of a closed polyline entity, or None when it is not closed."""
    h, lay = e.dxf.handle, e.dxf.layer
    if e.dxftype() == "LWPOLYLINE":
        pts = [(x, y, b) for x, y, b in e.get_points("xyb")]
        closed = bool(e.closed)
    else:
        if e.is_poly_face_mesh or e.is_polygon_mesh:
            raise _fail(path, f"POLYLINE handle {h} on layer {lay!r} is a mesh, not an outline")
        pts = [(v.dxf.location[0], v.dxf.location[1], v.dxf.get("bulge", 0.0)) for v in e.vertices]
        closed = bool(e.is_closed)
    if any(abs(b) > 1e-12 for _, _, b in pts[:-1]) or (closed and pts and abs(pts[-1][2]) > 1e-12):
        raise _fail(path, f"{e.dxftype()} handle {h} on layer {lay!r} has arcs (bulges); draw stones "
                          "with straight edges")
    xy = np.array([(x, y) for x, y, _ in pts], float).reshape(-1, 2) * scale
    if not closed and len(xy) > 3 and np.allclose(xy[0], xy[-1], atol=1e-12 * (1 + np.abs(xy).max())):
        closed = True
    if not closed:
        return None
    if len(xy) > 1 and np.allclose(xy[0], xy[-1]):
        xy = xy[:-1]
    return xy


def _text(e) -> str:
    return e.plain_text() if e.dxftype() == "MTEXT" else e.dxf.text


def _text_point(e):
    """Where a TEXT/MTEXT sits: its insertion (or, for aligned TEXT, alignment) point."""
    if e.dxftype() == "TEXT" and (e.dxf.get("halign", 0) or e.dxf.get("valign", 0)) and e.dxf.hasattr("align_point"):
        return e.dxf.align_point
    return e.dxf.insert


def _units(doc, path, units):
    code = int(doc.header.get("$INSUNITS", 0) or 0)
    if units is not None and units not in UNITS:
        raise pc.fail("dxf", "units", f"one of {sorted(UNITS)}", units)
    if code == 0:
        if units is None:
            raise _fail(path, "the drawing has no units ($INSUNITS = 0, unitless); give units = "
                              f"one of {sorted(UNITS)}")
        return units, UNITS[units]
    if code not in INSUNITS:
        raise _fail(path, f"drawing units $INSUNITS = {code} not supported; use one of "
                          f"{sorted(UNITS)} (codes {sorted(INSUNITS)})")
    if units is not None and units != INSUNITS[code]:
        raise _fail(path, f"units = {units!r} contradicts the drawing's $INSUNITS = {code} ({INSUNITS[code]})")
    return INSUNITS[code], UNITS[INSUNITS[code]]


def read(file, units: str | None = None) -> dict:
    """The stones of a DXF drawing (see the module docstring) as ``{"stones": {id: (n, 2)
    counter-clockwise corners, m}, "roles": {id: role}, "depths": {id: m}, "where": {id:
    message label}, "platform": (n, 2) or None, "control_points": [(name, x, z)],
    "ignored": sorted layer names, "units": unit name}``."""
    import ezdxf

    path = Path(file)
    if not path.is_file():
        raise _fail(path, "DXF file not found")
    try:
        doc = ezdxf.readfile(str(path))
    except (OSError, ezdxf.DXFError, UnicodeDecodeError, ValueError) as err:
        raise _fail(path, f"not a readable DXF file: {' '.join(str(err).split()) or type(err).__name__}") from None
    unit, scale = _units(doc, path, units)
    msp = doc.modelspace()
    polys, platforms, labels, cps, ignored = [], [], [], [], set()
    for e in msp:
        lay = e.dxf.get("layer", "0")
        low = lay.lower()
        kind = e.dxftype()
        if kind in ("LWPOLYLINE", "POLYLINE") and (low in STONE_LAYERS or low == PLATFORM_LAYER):
            xy = _polyline(e, path, scale)
            if xy is None:
                raise _fail(path, f"{kind} handle {e.dxf.handle} on layer {lay!r} is not closed")
            (platforms if low == PLATFORM_LAYER else polys).append((e.dxf.handle, lay, xy))
        elif low == CONTROL_LAYER and kind == "POINT":
            loc = e.dxf.location
            cps.append((None, loc[0] * scale, loc[1] * scale))
        elif low == CONTROL_LAYER and kind in ("TEXT", "MTEXT"):
            p = _text_point(e)
            cps.append((_text(e).strip(), p[0] * scale, p[1] * scale))
        elif kind in ("TEXT", "MTEXT"):
            p = _text_point(e)
            labels.append((_text(e).strip(), p[0] * scale, p[1] * scale, f"{kind} handle {e.dxf.handle}"))
        elif kind == "INSERT":
            p = e.dxf.insert
            for tag in ("ID", "DEPTH"):
                if e.has_attrib(tag):
                    val = e.get_attrib_text(tag).strip()
                    labels.append((val if tag == "ID" else f"depth={val}", p[0] * scale, p[1] * scale,
                                   f"INSERT handle {e.dxf.handle} attribute {tag}"))
        else:
            ignored.add(lay)
    if not polys:
        raise _fail(path, f"no closed polylines on the stone layers {sorted(STONE_LAYERS)} (model space)")
    if len(platforms) > 1:
        raise _fail(path, f"{len(platforms)} polylines on layer 'platform' (handles "
                          f"{[h for h, _, _ in platforms]}); draw at most one")
    stones, roles, depths, where, handles = {}, {}, {}, {}, {}
    for h, lay, xy in polys:
        poly_where = f"{path} (polyline handle {h}, layer {lay!r})"
        corners = dc.check_outline(xy, poly_where)
        inside = [lab for lab in labels if ol._distance(corners, lab[1:3]) == 0.0]
        ids = [(int(m.group(1)), src) for t, _, _, src in inside for m in [_ID.match(t)] if m]
        if not ids:
            raise _fail(path, f"polyline handle {h} on layer {lay!r} has no id label (a text with a positive "
                              "integer, or an INSERT with attribute ID, inside it)")
        if len({i for i, _ in ids}) > 1:
            raise _fail(path, f"polyline handle {h} on layer {lay!r} has several id labels: "
                              f"{sorted({i for i, _ in ids})}")
        bid = ids[0][0]
        if bid == 0:
            raise _fail(path, f"polyline handle {h} on layer {lay!r}: id 0 is the platform's; stones are 1, 2, ...")
        if bid in stones:
            raise _fail(path, f"stone {bid} drawn twice: polyline handles {handles[bid]} and {h}")
        for t, _, _, src in inside:
            m = _DEPTH.match(t)
            if m:
                try:
                    depth = float(m.group(1))
                except ValueError:
                    depth = float("nan")
                if not (np.isfinite(depth) and depth > 0):
                    raise _fail(path, f"stone {bid}: depth must be a number > 0 (m), got {t!r} ({src})")
                depths[bid] = depth
        stones[bid], handles[bid] = corners, h
        where[bid] = f"{path} (stone {bid}, polyline handle {h}, layer {lay!r})"
        if STONE_LAYERS[lay.lower()] is not None:
            roles[bid] = STONE_LAYERS[lay.lower()]
    platform = None
    if platforms:
        h, lay, xy = platforms[0]
        pw = f"{path} (platform, polyline handle {h}, layer {lay!r})"
        platform = dc.check_outline(xy, pw)
        if len(dc.convex_pieces(platform, pw)) != 1:
            raise _fail(path, f"the platform (polyline handle {h}) must be convex")
    named = [(n if n else f"P{k}", x, z) for k, (n, x, z) in enumerate(cps, 1)]
    return {"stones": stones, "roles": roles, "depths": depths, "where": where, "platform": platform,
            "control_points": named, "ignored": sorted(ignored), "units": unit}


def make(file, thickness: float, units: str | None = None, fix_bottom: bool = True, density=2300.0, kn=2e8,
         kt=1e8, mu=0.4, damping=0.8, name=None) -> dict:
    """A block-file dict from the DXF drawing ``file`` (see the module docstring);
    ``thickness`` > 0 m, ``units`` for a unitless drawing."""
    g = "dxf"
    if not isinstance(file, (str, Path)):
        raise pc.fail(g, "file", "a DXF file path", file)
    pc.positive(g, "thickness", thickness, "m")
    pc.choice(g, "fix_bottom", fix_bottom, [True, False])
    pc.material(g, density, kn, kt, damping, mu=mu)
    if name is not None and not isinstance(name, str):
        raise pc.fail(g, "name", "a string", name)
    path = Path(file)
    r = read(path, units)
    note = f"; ignored layers {r['ignored']}" if r["ignored"] else ""
    return ol.build(r["stones"], thickness, r["where"], origin=str(path), roles=r["roles"], depths=r["depths"],
                    platform=r["platform"], control_points=r["control_points"], fix_bottom=fix_bottom,
                    density=density, kn=kn, kt=kt, mu=mu, damping=damping, name=name or path.stem,
                    generator={"name": "dxf", "file": str(path), "thickness": thickness, "units": r["units"]},
                    description=f"stones from the DXF drawing {path} ({r['units']}), extruded to {thickness} m"
                                + note)
