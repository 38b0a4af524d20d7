"""Blocks from a CAD drawing (DXF, read with ezdxf): the wall's face drawn in its plane
(DXF x -> wall x, DXF y -> z up), each stone a closed polyline, extruded through the
thickness (y from -T/2 to T/2) exactly as the outline files of ``outlines.py`` are
(``outlines.build``: a convex stone is one block, a re-entrant one a stone of convex
``parts``, block file version 2).

Model space only. Layers (names case-insensitive, as in CAD):

* ``stones``: closed LWPOLYLINE or 2D POLYLINE (closed flag, or first point = last), a
  stone fixed when it stands on the platform (``fix_bottom``, default) and free otherwise;
  ``free`` / ``fixed``: a stone with that role (a fixed stone must stand on the platform, or
  on fixed stones that do, within ``blockfile.standing_tol``, 1 mm or 0.1 % of the wall's
  size if less; else it is refused: it would hover);
* ``platform``: at most one closed convex polyline, the platform (id 0), extruded through
  3 x the wall's thickness; some stone must stand on it (within ``blockfile.standing_tol``),
  else the drawing is refused; without one, a 0.1 m slab under the lowest stone;
* ``control_points``: POINT (named P1, P2, ... in drawing order) or TEXT/MTEXT (named by
  its text) at a control point, put on the stone that contains it (or the nearest) at the
  wall's front face (y = -T/2); without any, one ``top_<id>`` at the centroid of each top
  stone (``outlines.top_stones``);
* any other layer is ignored (listed in the block file's ``description``).

Ids: a TEXT or MTEXT (any layer but ``control_points``) whose insertion point lies inside
a stone and reads a positive integer (``7`` or ``id=7``; at most ``blockfile.MAX_ID``), or
a block reference (INSERT) with an attribute ``ID`` whose text lies inside it. A stone
without one, with two, or an id used twice is refused naming the polyline's handle and
layer. A text ``depth=0.6`` (or an INSERT attribute ``DEPTH``) inside a stone gives that
stone its own depth (m) instead of ``thickness``. A label that starts with ``id`` or
``depth`` but does not read (``id: 7``, ``depth=0,3``, ``depth=0.3m``) is refused naming
the stone, not ignored.

Every entity on a role layer (``stones``, ``free``, ``fixed``, ``platform``,
``control_points``) is read or refused naming its handle and type (a SPLINE, CIRCLE, HATCH
... on a stone layer was silently dropped). Block references (INSERT, MINSERT) are exploded
(ezdxf's virtual entities: the reference's insertion point, scale, rotation and extrusion
applied, nested references too): a stone drawn in a block is read where the reference puts
it; an entity of a block on layer ``0`` takes the reference's layer, as CAD draws it.
Coordinates are world coordinates (WCS): an entity's object coordinate system (its
extrusion, (0, 0, -1) for a stone mirrored in CAD) is applied; an entity drawn out of the
XY plane (extrusion not along z) is refused.

Units: the header's ``$INSUNITS`` (in, ft, mm, cm, m) scales the drawing to metres; a
unitless drawing (0, the default of many programs) is refused unless ``units`` ("mm",
"cm", "m", "in", "ft") is given, and ``units`` that contradict the header are refused.
Polylines with arcs (bulges) are refused (draw the stone with straight edges). A wall or
stone of implausible size for masonry (a drawing in the wrong unit) gets a ``warning:``
line (``plausible.py``). Every error is one GeometryError line naming the file (and the
handle, layer or stone).
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from . import decompose as dc
from . import outlines as ol
from . import blockfile as bf
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
#: a label that means an id or a depth but does not read as one (``id: 7``, ``depth=0,3``,
#: ``depth=0.3m``, ``depth: 0.3``) is refused, not ignored
_ID_WORD = re.compile(r"^\s*id\b", re.I)
_DEPTH_WORD = re.compile(r"^\s*depth\b", re.I)
#: every layer with a role: each entity on one is read or refused (never dropped)
ROLE_LAYERS = {*STONE_LAYERS, PLATFORM_LAYER, CONTROL_LAYER}


def _fail(path, msg) -> GeometryError:
    return GeometryError(f"{path}: {msg}")


def _poly(what: str) -> str:
    """``polyline handle 2F`` (or ``polyline in block ...``) from ``LWPOLYLINE handle 2F``."""
    return "polyline " + what.split(" ", 1)[1]


def _short(text: str) -> str:
    return repr(text if len(text) <= 40 else text[:37] + "...")


def _plane(e, what, path):
    """Refuse an entity not drawn in (or parallel to) the drawing's XY plane: its extrusion
    (the normal of its object coordinate system) must be +z or -z (a mirrored copy)."""
    ext = e.dxf.get("extrusion", (0.0, 0.0, 1.0))
    if abs(abs(float(ext[2])) - 1.0) > 1e-9:
        raise _fail(path, f"{what} is not drawn in the XY plane (extrusion {tuple(round(float(c), 6) for c in ext)}); "
                          "draw the wall's face in plan view (XY)")


def _polyline(e, what, path, scale):
    """(n, 2) corners (m, world coordinates: the entity's OCS/extrusion applied) of a closed
    polyline entity, or None when it is not closed."""
    if e.dxftype() == "LWPOLYLINE":
        bulges = [b for _, _, b in e.get_points("xyb")]
        wcs = list(e.vertices_in_wcs())
        closed = bool(e.closed)
    else:
        if e.is_poly_face_mesh or e.is_polygon_mesh:
            raise _fail(path, f"{what} is a mesh, not an outline")
        bulges = [v.dxf.get("bulge", 0.0) for v in e.vertices]
        wcs = list(e.points_in_wcs())
        closed = bool(e.is_closed)
    _plane(e, what, path)
    if any(abs(b) > 1e-12 for b in bulges[:-1]) or (closed and bulges and abs(bulges[-1]) > 1e-12):
        raise _fail(path, f"{what} has arcs (bulges); draw stones with straight edges")
    xyz = np.array([(v[0], v[1], v[2]) for v in wcs], float).reshape(-1, 3) * scale
    if not np.all(np.isfinite(xyz)):
        raise _fail(path, f"{what} has non-finite coordinates")
    if len(xyz) and np.ptp(xyz[:, 2]) > 1e-9 * (1.0 + np.ptp(xyz[:, :2])):  # a 3D polyline off the XY plane
        raise _fail(path, f"{what} is not flat in the XY plane (its z spans {np.ptp(xyz[:, 2]):.3g} m); draw the "
                          "wall's face in plan view (XY)")
    xy = xyz[:, :2]
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
    """Where a TEXT/MTEXT sits, in world coordinates: its insertion (or, for aligned TEXT,
    alignment) point; a TEXT's is in its OCS (a mirrored text has extrusion (0, 0, -1))."""
    if e.dxftype() == "MTEXT":
        return e.dxf.insert
    if (e.dxf.get("halign", 0) or e.dxf.get("valign", 0)) and e.dxf.hasattr("align_point"):
        return e.ocs().to_wcs(e.dxf.align_point)
    return e.ocs().to_wcs(e.dxf.insert)


#: most levels of block references inside block references followed
MAX_NESTING = 16


def _entities(msp, path):
    """``(entity, layer, what)`` for every entity of model space and, recursively, of the
    block references (INSERT, MINSERT) in it, exploded: ezdxf's virtual entities, the
    reference's transform (insertion point, scale, rotation, extrusion) applied. An entity
    of a block on layer ``0`` takes the reference's layer (as CAD draws it). ``what`` names
    the entity in messages: ``LWPOLYLINE handle 2F``, or ``LWPOLYLINE in block 'STONE'
    (INSERT handle 3A)``."""
    def expand(e, layer, what, depth):
        yield e, layer, what
        if e.dxftype() != "INSERT":
            return
        if depth >= MAX_NESTING:
            raise _fail(path, f"{what}: block references nested more than {MAX_NESTING} deep")
        name = e.dxf.get("name", "?")
        try:
            refs = list(e.multi_insert()) if e.mcount > 1 else [e]
            for ref in refs:
                def skipped(ent, reason):
                    lay = ent.dxf.get("layer", "0")
                    lay = layer if lay == "0" else lay
                    if lay.lower() in ROLE_LAYERS:
                        raise _fail(path, f"{ent.dxftype()} in block {name!r} ({what}) on layer {lay!r} cannot be "
                                          f"placed by its block reference ({reason}); explode it in CAD")
                for v in ref.virtual_entities(skipped_entity_callback=skipped):
                    lay = v.dxf.get("layer", "0")
                    yield from expand(v, layer if lay == "0" else lay,
                                      f"{v.dxftype()} in block {name!r} ({what})", depth + 1)
        except GeometryError:
            raise
        except Exception as err:  # ezdxf: a missing block definition, a transform it cannot apply
            raise _fail(path, f"{what} (block {name!r}) cannot be exploded: "
                              f"{' '.join(str(err).split()) or type(err).__name__}") from None

    for e in msp:
        yield from expand(e, e.dxf.get("layer", "0"), f"{e.dxftype()} handle {e.dxf.handle}", 0)


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
    polys, platforms, labels, cps, ignored = [], [], [], [], set()
    for e, lay, what in _entities(doc.modelspace(), path):
        low = lay.lower()
        kind = e.dxftype()
        if kind == "INSERT":  # exploded by _entities; its attributes ID and DEPTH label a stone
            for tag in ("ID", "DEPTH"):
                att = e.get_attrib(tag)
                if att is not None:  # where its text is (a stone's block has its origin at a corner)
                    val, p = att.dxf.text.strip(), _text_point(att)
                    labels.append((val if tag == "ID" else f"depth={val}", p[0] * scale, p[1] * scale,
                                   f"{what} attribute {tag}"))
        elif kind in ("LWPOLYLINE", "POLYLINE") and (low in STONE_LAYERS or low == PLATFORM_LAYER):
            xy = _polyline(e, f"{what} on layer {lay!r}", path, scale)
            if xy is None:
                raise _fail(path, f"{what} on layer {lay!r} is not closed")
            (platforms if low == PLATFORM_LAYER else polys).append((what, lay, xy))
        elif low == CONTROL_LAYER and kind == "POINT":
            loc = e.dxf.location  # world coordinates
            cps.append((None, loc[0] * scale, loc[1] * scale))
        elif low == CONTROL_LAYER and kind in ("TEXT", "MTEXT"):
            _plane(e, f"{what} on layer {lay!r}", path)
            p = _text_point(e)
            cps.append((_text(e).strip(), p[0] * scale, p[1] * scale))
        elif kind in ("TEXT", "MTEXT"):
            p = _text_point(e)
            labels.append((_text(e).strip(), p[0] * scale, p[1] * scale, what))
        elif low in ROLE_LAYERS:
            allowed = ("closed LWPOLYLINE or 2D POLYLINE (straight edges)" if low != CONTROL_LAYER
                       else "POINT, TEXT or MTEXT")
            raise _fail(path, f"{what} on layer {lay!r} cannot be read: that layer takes {allowed} (and "
                              f"id/depth labels), not a {kind}; redraw it or move it to another layer")
        else:
            ignored.add(lay)
    if not polys:
        raise _fail(path, f"no closed polylines on the stone layers {sorted(STONE_LAYERS)} (model space)")
    if len(platforms) > 1:
        raise _fail(path, f"{len(platforms)} polylines on layer 'platform' "
                          f"({', '.join(w for w, _, _ in platforms)}); draw at most one")
    stones, roles, depths, where, names = {}, {}, {}, {}, {}
    checked = [(what, lay, dc.check_outline(xy, f"{path} ({_poly(what)}, layer {lay!r})")) for what, lay, xy in polys]
    label_xy = np.array([(x, z) for _, x, z, _ in labels], float).reshape(-1, 2)
    for (what, lay, corners), idx in zip(checked, ol.points_in([c for _, _, c in checked], label_xy)):
        name = f"{_poly(what)} on layer {lay!r}"
        inside = [labels[i] for i in idx]
        ids = []
        for t, _, _, src in inside:
            m = _ID.match(t)
            if m:
                bid = ol.stone_id(m.group(1))
                if bid is None:
                    raise _fail(path, f"{name}: id label {_short(t)} ({src}) is not an id: ids are integers 1 to "
                                      f"{bf.MAX_ID} (0 is the platform's)")
                ids.append((bid, src))
            elif _ID_WORD.match(t):
                raise _fail(path, f"{name}: cannot read the id label {_short(t)} ({src}); write a positive integer "
                                  "(7) or id=7")
        if not ids:
            raise _fail(path, f"{name} has no id label (a text with a positive "
                              "integer, or an INSERT with attribute ID, inside it)")
        if len({i for i, _ in ids}) > 1:
            raise _fail(path, f"{name} has several id labels: {sorted({i for i, _ in ids})}")
        bid = ids[0][0]
        if bid in stones:
            raise _fail(path, f"stone {bid} drawn twice: {names[bid]} and {_poly(what)}")
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
            elif _DEPTH_WORD.match(t):
                raise _fail(path, f"stone {bid} ({_poly(what)}): cannot read the depth label {_short(t)} ({src}); "
                                  "write depth=0.3 (metres, a point for decimals, no unit)")
        stones[bid], names[bid] = corners, _poly(what)
        where[bid] = f"{path} (stone {bid}, {_poly(what)}, layer {lay!r})"
        if STONE_LAYERS[lay.lower()] is not None:
            roles[bid] = STONE_LAYERS[lay.lower()]
    platform = None
    if platforms:
        what, lay, xy = platforms[0]
        pw = f"{path} (platform, {_poly(what)}, layer {lay!r})"
        platform = dc.check_outline(xy, pw)
        if len(dc.convex_pieces(platform, pw)) != 1:
            raise _fail(path, f"the platform ({_poly(what)}) must be convex")
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
                    density=density, kn=kn, kt=kt, mu=mu, damping=damping, name=name or path.stem, units=r["units"],
                    generator={"name": "dxf", "file": str(path), "thickness": thickness, "units": r["units"]},
                    description=f"stones from the DXF drawing {path} ({r['units']}), extruded to {thickness} m"
                                + note)
