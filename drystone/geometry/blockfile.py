"""The block-definition file: read, validate, write.

Format ``drystone.blocks`` version 1 or 2, a JSON object (units: metres, kilograms, seconds;
stiffness per unit contact area in N/m^3)::

    {
      "format": "drystone.blocks", "version": 1,
      "name": "one_block", "description": "free text",
      "materials": {
        "stone": {"density": 2300, "kn": 2e8, "kt": 1e8, "mu": 0.4, "damping": 0.8}
      },
      "blocks": [
        {"id": 0, "role": "platform", "material": "stone", "vertices": [[x, y, z], ...]},
        {"id": 1, "role": "free", "material": "stone", "vertices": [...],
         "blocked_dofs": "", "label": "optional"}
      ],
      "joints": [{"blocks": [1, 0], "mu": 0.5}],
      "control_points": [{"name": "A", "block": 1, "position": [x, y, z]}]
    }

Materials: ``density`` kg/m^3; ``kn``, ``kt`` N/m^3 (normal and tangential penalty
stiffness per unit contact area, the paper's K_n, K_t); friction as ``mu`` or
``friction_angle_deg`` (one of them); ``damping`` the contact damping as a fraction of
critical (the paper's mu_0, see docs/physics.md). Between two materials, kn and kt combine in
series (2 k1 k2 / (k1 + k2), equal materials give k), mu is the smaller and damping the
mean. ``joints`` override mu and/or damping for one pair of blocks.

Blocks: ``id`` an integer (the paper's numbering); ``role`` one of ``free`` (moves),
``fixed`` (fixed to the platform, e.g. a wall's first course) or ``platform`` (the
base; fixed); ``vertices`` the corners of a convex block, each listed once, as
[x, y, z] numbers (the block is their convex hull); ``blocked_dofs`` optional
YADE-style subset of ``xyzXYZ`` for free blocks (x, y, z translations and rotations
about them, global axes). Control points are points attached to a block (given in the
initial configuration).

Version 2: a block may give ``parts`` instead of ``vertices``: a list of convex parts,
each a vertex list obeying the rules of ``vertices`` below, ``"parts": [[[x, y, z], ...],
[[x, y, z], ...]]``: one stone, one rigid body, whose shape is the union of the parts (a
non-convex stone cut into convex pieces). A block gives one of the two keys, never both;
a version-1 file may not use ``parts``. The parts of one stone must not overlap each other
by more than ``OVERLAP_TOL`` and must form one solid: every part joined to the others face
to face (``joined``: two parts share a patch of their opposite, coplanar faces more than
``JOIN_MIN_WIDTH`` wide); parts touching only along an edge or at a corner, or apart, are
refused, naming the parts. Parts of one stone never contact each other; material, role,
blocked dofs, joints and control points belong to the stone. Its mass, centroid and
inertia are those of the union (``drystone.geometry.massprops``). At most
``MAX_PARTS_PER_BLOCK`` parts, each of at most ``MAX_VERTICES_PER_BLOCK`` vertices.
``BlockSet.to_dict`` writes version 1 when every block is one part, else version 2.

Convexity: the format has no faces, so YADE builds each block as the convex hull of its
vertices, and a non-convex stone would silently become its hull (an L-shaped block
+17 % mass). Every vertex must therefore be a corner of the hull: a vertex inside it,
on one of its faces or edges (a re-entrant corner; an extruded L has its re-entrant
corners on the hull's faces), or repeating another vertex, is refused (``not_convex``;
tolerance ``CORNER_REL_TOL`` x the block's size). Repeated vertices are refused, not
merged: a file lists each corner once, so that it is the block that runs.

Size: a block (each part, in version 2) has at most ``MAX_VERTICES_PER_BLOCK`` vertices
(80): no convex block with more fits the contact kernel (``drystone/mechanics/overlap.py``).
A block above it is refused before its hull is built; the checks of a block take memory
linear in its vertices.

Numbers: every coordinate, position and material value a finite JSON number (not a
string, not true/false); ids integers; ``density`` within ``DENSITY_RANGE``.

Axes: x along the wall, y through its thickness (out of plane), z up.
"""
from __future__ import annotations

import itertools
import json
import math
import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from drystone import inputfiles

from . import massprops
from . import polyhedron as ph

FORMAT = "drystone.blocks"
#: the version written for blocks of one convex part each (``BlockSet.to_dict``) and by the
#: generators: every reader of this package since version 1 reads it
VERSION = 1
#: the first version with multi-part stones (``parts``)
PARTS_VERSION = 2
#: the versions this reader reads
VERSIONS = (VERSION, PARTS_VERSION)
ROLES = ("free", "fixed", "platform")
#: largest block id (in magnitude): YADE numbers bodies with C ints, and ids are stored in
#: integer arrays (histories.npz); a larger one (a 40-digit label) would become an object
#: array no run could load back
MAX_ID = 2**31 - 1
#: a vertex standing out of the block's other vertices by less than this x the block's
#: size (the diagonal of its bounding box) is not a corner (far above round-off, far below
#: any real stone's corner)
CORNER_REL_TOL = 1e-9
#: most vertices a block may have. The contact kernel (drystone/mechanics/overlap.py, ``Shapes``)
#: clips each face of one block against the face planes of the other in a polygon buffer
#: of overlap.MAXV = 96 points: it refuses blocks whose faces plus the corners of their
#: largest face exceed MAXV / 2 = 48. A convex block of V corners has F >= V/2 + 2 faces
#: (every corner joins >= 3 edges; Euler) and, if its largest face has k corners,
#: F >= (2V - 4)/(k - 2): F + k <= 48 needs k <= 5 and V <= 66, or k = 6 and V <= 80
#: (the 80-corner fullerene's shape: 12 pentagons and 30 hexagons), or k >= 7 and V <= 78.
#: So no block above 80 can ever run; a scanned stone's hull must be simplified to fewer
#: corners anyway (a triangulated hull fits up to 24: F = 2V - 4, k = 3; an extruded
#: outline up to 46: F = V/2 + 2, k = V/2). The per-pair cost of the kernel, each face of
#: one block against each face of the other, stays below 48^2 clips with this bound. The
#: limit also bounds the validation's cost: the convexity check compares every vertex
#: with every other (80^2 products); a 10 000-vertex block took 16-30 s and 6.3 GB.
#: tests/test_reliability_vertices.py rederives 80 from overlap.MAXV.
MAX_VERTICES_PER_BLOCK = 80
#: accepted material densities (kg/m^3): from below the lightest solids a block could be
#: made of (pumice, timber, aerated concrete: 300-900) to above the densest metal (osmium,
#: 22590). Outside it is a unit mistake (2.3 for g/cm^3, 2.3e6 for kg/dm^3 read as kg/m^3)
#: or garbage (1e-300 gives weightless blocks and a meaningless time step).
DENSITY_RANGE = (100.0, 100000.0)
#: largest accepted initial overlap thickness between two blocks (m); 1 um is far below
#: the elastic penetration of any case here (tens of um and more) and far above round-off.
OVERLAP_TOL = 1e-6
#: most convex parts a stone (version 2 ``parts``) may have. The outline splitter
#: (drystone/geometry/decompose.py: cuts along diagonals) gives at most 2r + 1 pieces for r
#: re-entrant corners (usually about r + 1), so 32 takes any outline with up to 15
#: re-entrant corners, far more than a dressed or rubble stone's few notches. It bounds the costs quadratic in the parts: the validation's pairwise
#: checks of one stone's parts (at most 496 pairs, each a linear programme at worst) and,
#: once the engines take parts, the K_a x K_b part pairs of a contact between two stones.
MAX_PARTS_PER_BLOCK = 32
#: a block stands on another (a fixed stone on the platform) when they are within
#: ``standing_tol``: STANDING_TOL (m, a drawing's precision, 1 mm), or STANDING_REL x the
#: wall's size where that is less (a 2 cm laboratory model's stones are not 1 mm "on" each
#: other). A fixed block farther from the platform and from every fixed block that stands
#: on it is held in mid-air (``hovering_fixed``)
STANDING_TOL = 1e-3
STANDING_REL = 1e-3


def standing_tol(size: float) -> float:
    """The standing tolerance (m) for a wall ``size`` m across (``STANDING_TOL``)."""
    return min(STANDING_TOL, STANDING_REL * size)
#: two parts of one stone are joined face to face when a face of one and a face of the
#: other have opposite normals, lie within OVERLAP_TOL of each other's plane and overlap in
#: a patch wider than this (m; the width 2 x area / perimeter, a strip's width). Parts
#: touching along an edge or at a corner share a patch of no area, or, misaligned by up to
#: OVERLAP_TOL (which the overlap check lets pass), a strip at most OVERLAP_TOL wide: ten
#: times that refuses them, far below any real joint (centimetres: a stone's thickness).
JOIN_MIN_WIDTH = 10 * OVERLAP_TOL

#: the properties of a material, each a number: density (kg/m^3), kn and kt (N/m^3), mu (-),
#: damping (fraction of critical); the one list of them (``Material``, a case's
#: [materials.NAME] overrides, the resolved spec.json materials)
MATERIAL_PROPERTIES = ("density", "kn", "kt", "mu", "damping")
#: those of a contact: a pair of materials combines them (``drystone.mechanics.contact.pair_properties``)
#: and a case's [contact] section overrides them for every material
CONTACT_PROPERTIES = ("kn", "kt", "mu", "damping")
#: those a joint (one pair of blocks) may override
JOINT_PROPERTIES = ("mu", "damping")
MATERIAL_KEYS = {*MATERIAL_PROPERTIES, "friction_angle_deg", "description"}
BLOCK_KEYS = {"id", "role", "material", "vertices", "parts", "blocked_dofs", "label"}
JOINT_KEYS = {"blocks", *JOINT_PROPERTIES}
CP_KEYS = {"name", "block", "position"}
TOP_KEYS = {"format", "version", "name", "description", "source", "units", "materials",
            "blocks", "joints", "control_points", "generator"}


class GeometryError(ValueError):
    """Invalid block definition; the message names the file, block and problem."""


@dataclass
class Material:
    """A named material: the fields after ``name`` are MATERIAL_PROPERTIES."""
    name: str
    density: float  # kg/m^3
    kn: float  # N/m^3
    kt: float  # N/m^3
    mu: float  # -
    damping: float  # fraction of critical


@dataclass
class Block:
    """A stone: one rigid body, the union of its convex ``parts`` (one for a convex block).

    ``Block(id, role, material, vertices)`` with an (n, 3) array makes a one-part block, as
    before version 2. ``vertices`` is that one part's array; a multi-part stone has no
    ``vertices`` (GeometryError: it is not one convex body, and every consumer of
    ``vertices`` builds one from it, the hull, which would be a bigger stone); ``points``
    holds every part's vertices for bounding boxes and extents."""
    id: int
    role: str
    material: str
    parts: tuple  # of (n_i, 3) arrays, m: convex parts, each its corners
    blocked_dofs: str = ""
    label: str = ""
    _part_planes: tuple | None = field(default=None, repr=False, compare=False)
    _moments: massprops.Moments | None = field(default=None, repr=False, compare=False)

    def __post_init__(self):
        if isinstance(self.parts, np.ndarray):  # one part given as its vertex array
            self.parts = (self.parts,)
        self.parts = tuple(np.asarray(p, dtype=float) for p in self.parts)

    def _one_part(self, what: str) -> None:
        if len(self.parts) != 1:
            raise GeometryError(
                f"block {self.id} has {len(self.parts)} parts: its {what} is not one convex body "
                "(use .parts, or .points for bounding boxes)")

    @property
    def vertices(self) -> np.ndarray:
        """(n, 3) m: the corners of a one-part block (GeometryError for a multi-part one)."""
        self._one_part("vertices")
        return self.parts[0]

    @property
    def points(self) -> np.ndarray:
        """(n, 3) m: every part's vertices, in part order (a one-part block's ``vertices``):
        for bounding boxes and extents, not a convex body."""
        return self.parts[0] if len(self.parts) == 1 else np.vstack(self.parts)

    def part_planes(self) -> tuple:
        """Per part, the outward unit face normals (f, 3) and offsets (f,) m (cached)."""
        if self._part_planes is None:
            self._part_planes = tuple(ph.planes(ph.hull(p)) for p in self.parts)
        return self._part_planes

    def planes(self) -> tuple[np.ndarray, np.ndarray]:
        """Outward unit face normals (f, 3) and offsets (f,) m of a one-part block (cached)."""
        self._one_part("face planes")
        return self.part_planes()[0]

    def moments(self) -> massprops.Moments:
        """Volume (m^3), centroid (m) and second moment about it (m^5) of the union of the
        parts (cached)."""
        if self._moments is None:
            self._moments = massprops.union_moments(self.parts)
        return self._moments

    def mass_properties(self, density: float) -> massprops.MassProperties:
        """Mass (kg), centroid (m), inertia about it (kg m^2), principal moments and axes at
        ``density`` (kg/m^3)."""
        return massprops.of_moments(self.moments(), density)

    @property
    def volume(self) -> float:
        return self.moments().volume

    @property
    def centroid(self) -> np.ndarray:
        return self.moments().centroid


@dataclass
class BlockSet:
    name: str
    materials: dict[str, Material]
    blocks: list[Block]
    joints: list[dict] = field(default_factory=list)
    control_points: list[dict] = field(default_factory=list)
    description: str = ""
    source: str = ""
    generator: dict = field(default_factory=dict)

    def block(self, bid: int) -> Block:
        for b in self.blocks:
            if b.id == bid:
                return b
        raise KeyError(f"no block with id {bid}")

    def ids(self, role: str | None = None) -> list[int]:
        return [b.id for b in self.blocks if role is None or b.role == role]

    def mass(self, bid: int) -> float:
        b = self.block(bid)
        return self.materials[b.material].density * b.volume

    def mass_properties(self, bid: int) -> massprops.MassProperties:
        """Block ``bid``'s mass properties at its material's density (the union of its parts)."""
        b = self.block(bid)
        return b.mass_properties(self.materials[b.material].density)

    def to_dict(self) -> dict:
        mats = {}
        for m in self.materials.values():
            mats[m.name] = {k: getattr(m, k) for k in MATERIAL_PROPERTIES}
        blocks = []
        for b in self.blocks:
            d = {"id": b.id, "role": b.role, "material": b.material}
            if len(b.parts) == 1:
                d["vertices"] = [[float(x) for x in p] for p in b.parts[0]]
            else:
                d["parts"] = [[[float(x) for x in p] for p in part] for part in b.parts]
            if b.blocked_dofs:
                d["blocked_dofs"] = b.blocked_dofs
            if b.label:
                d["label"] = b.label
            blocks.append(d)
        version = VERSION if all(len(b.parts) == 1 for b in self.blocks) else PARTS_VERSION
        out = {"format": FORMAT, "version": version, "name": self.name,
               "description": self.description, "units": {"length": "m", "mass": "kg"},
               "materials": mats, "blocks": blocks}
        if self.source:
            out["source"] = self.source
        if self.generator:
            out["generator"] = self.generator
        if self.joints:
            out["joints"] = self.joints
        if self.control_points:
            out["control_points"] = self.control_points
        return out


def is_number(x) -> bool:
    """A finite int or float (numpy's too), not a bool and not a string."""
    return (isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(x, (bool, np.bool_))
            and math.isfinite(x))


def is_int(x) -> bool:
    """An int (numpy's too), not a bool and not a float such as 1.0."""
    return isinstance(x, (int, np.integer)) and not isinstance(x, (bool, np.bool_))


def _positive(where: str, key: str, value, allow_zero=False) -> float:
    if not is_number(value):
        raise GeometryError(f"{where}: '{key}' must be a finite number, got {value!r}")
    if value < 0 or (value == 0 and not allow_zero):
        raise GeometryError(f"{where}: '{key}' must be {'>= 0' if allow_zero else '> 0'}, got {value}")
    return float(value)


def _material(where: str, name: str, d: dict) -> Material:
    w = f"{where}: material '{name}'"
    if not isinstance(d, dict):
        raise GeometryError(f"{w}: must be an object")
    unknown = set(d) - MATERIAL_KEYS
    if unknown:
        raise GeometryError(f"{w}: unknown key(s) {sorted(unknown)}; allowed {sorted(MATERIAL_KEYS)}")
    for k in ("density", "kn", "kt"):
        if k not in d:
            raise GeometryError(f"{w}: missing '{k}'")
    if ("mu" in d) == ("friction_angle_deg" in d):
        raise GeometryError(f"{w}: give exactly one of 'mu' or 'friction_angle_deg'")
    if "mu" in d:
        mu = _positive(w, "mu", d["mu"], allow_zero=True)
    else:
        phi = _positive(w, "friction_angle_deg", d["friction_angle_deg"], allow_zero=True)
        if phi >= 90:
            raise GeometryError(f"{w}: 'friction_angle_deg' must be below 90, got {phi}")
        mu = math.tan(math.radians(phi))
    damping = _positive(w, "damping", d.get("damping", 0.0), allow_zero=True)
    density = _positive(w, "density", d["density"])
    lo, hi = DENSITY_RANGE
    if not lo <= density <= hi:
        raise GeometryError(f"{w}: 'density' must be in [{lo:g}, {hi:g}] kg/m^3, got {density:g}")
    return Material(name, density, _positive(w, "kn", d["kn"]), _positive(w, "kt", d["kt"]), mu, damping)


def _not_a_number(x) -> str:
    return "a non-finite number" if isinstance(x, (float, np.floating)) else f"{x!r}, which is not a number"


def _point(where: str, key: str, value) -> np.ndarray:
    """[x, y, z] finite numbers (m) as an array, or GeometryError naming ``key``."""
    if not isinstance(value, (list, tuple, np.ndarray)) or len(value) != 3:
        raise GeometryError(f"{where}: '{key}' must be [x, y, z] (three numbers, m), got {value!r}")
    for x in value:
        if not is_number(x):
            raise GeometryError(f"{where}: '{key}' contains {_not_a_number(x)}: {list(value)!r}")
    return np.array(value, dtype=float)


def _vertices(where: str, value, key: str = "'vertices'") -> np.ndarray:
    """The (n, 3) vertex array of a block or part (m), or GeometryError naming the vertex
    (``key``: how the message names the list)."""
    if not isinstance(value, (list, tuple, np.ndarray)):
        raise GeometryError(f"{where}: {key} must be a list of [x, y, z] numbers, got {value!r}")
    if len(value) > MAX_VERTICES_PER_BLOCK:  # before any work on them (hull, convexity)
        raise GeometryError(f"{where}: {len(value)} vertices, more than {MAX_VERTICES_PER_BLOCK} vertices "
                            "(drystone.geometry.blockfile.MAX_VERTICES_PER_BLOCK: no convex block with more corners "
                            "fits the contact kernel); give the stone's hull fewer corners")
    for i, p in enumerate(value):
        if not isinstance(p, (list, tuple, np.ndarray)) or len(p) != 3:
            raise GeometryError(f"{where}: {key}: vertex {i} must be [x, y, z] (three numbers, m), got {p!r}")
        for x in p:
            if not is_number(x):
                raise GeometryError(f"{where}: vertices contain {_not_a_number(x)}: vertex {i} = {list(p)!r}")
    return np.array(value, dtype=float).reshape(-1, 3)


def not_convex(verts: np.ndarray, h=None) -> str | None:
    """Why ``verts`` (m) are not the distinct corners of their convex hull, naming the
    vertex index and coordinates; None if they are. ``h``: their hull, if at hand."""
    v = np.asarray(verts, dtype=float)
    h = ph.hull(v) if h is None else h
    tol = CORNER_REL_TOL * float(np.linalg.norm(np.ptp(v, axis=0)))
    # pairs (i < j) at most tol apart, from a k-d tree (no n x n distance matrix); the
    # first in file order
    pairs = cKDTree(v).query_pairs(tol, output_type="ndarray")
    if len(pairs):
        i, j = pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))[0]]
        return (f"vertices {i} and {j} coincide at ({_xyz(v[i])}) m: list each corner once "
                "(repeated vertices are refused, not merged)")
    bad = np.flatnonzero(~(ph.corner_gaps(v, h) > tol))
    if len(bad):
        which = ", ".join(f"vertex {k} at ({_xyz(v[k])}) m" for k in bad[:4]) + (", ..." if len(bad) > 4 else "")
        return (f"not convex: {which} {'is not a corner' if len(bad) == 1 else 'are not corners'} of the block's convex hull "
                "(inside it, or on a face or an edge of it: a re-entrant corner); YADE would build the hull, a "
                "bigger block: split the stone into convex blocks")
    return None


def _xyz(p) -> str:
    return ", ".join(f"{x:.6g}" for x in p)


def _part(where: str, value, key: str = "'vertices'"):
    """One convex part's (n, 3) vertex array (m) and hull, or GeometryError."""
    verts = _vertices(where, value, key)
    try:
        h = ph.hull(verts)
    except ph.HullError as exc:
        raise GeometryError(f"{where}: {exc}") from None
    problem = not_convex(verts, h)
    if problem:
        raise GeometryError(f"{where}: {problem}")
    vol = ph.volume_centroid(verts, h)[0]
    if not vol > 0:
        raise GeometryError(f"{where}: volume must be positive, got {vol}")
    return verts, h


def _parts(where: str, value) -> tuple[tuple, tuple]:
    """A version-2 stone's convex parts (m) and their hulls: each part valid as a block's
    ``vertices``, no two overlapping by more than OVERLAP_TOL, all joined face to face
    (GeometryError naming the part otherwise)."""
    if not isinstance(value, (list, tuple)) or not value:
        raise GeometryError(f"{where}: 'parts' must be a non-empty list of parts, each a list of [x, y, z] "
                            f"numbers, got {value!r}")
    if len(value) > MAX_PARTS_PER_BLOCK:  # before any work on them
        raise GeometryError(f"{where}: {len(value)} parts, more than {MAX_PARTS_PER_BLOCK} "
                            "(drystone.geometry.blockfile.MAX_PARTS_PER_BLOCK: checks and contacts cost the square of "
                            "the parts); cut the stone into fewer convex parts")
    parts, hulls = [], []
    for k, p in enumerate(value):
        v, h = _part(f"{where}: part {k}", p, "its vertices")
        parts.append(v)
        hulls.append(h)
    if len(parts) > 1:
        _check_parts(where, parts, hulls)
    return tuple(parts), tuple(hulls)


def _check_parts(where: str, parts: list, hulls: list) -> None:
    """Refuse parts of one stone that overlap by more than OVERLAP_TOL, or that are not all
    joined face to face (``joined``), naming the parts."""
    pl = [ph.planes(h) for h in hulls]
    lo = np.array([p.min(axis=0) for p in parts])
    hi = np.array([p.max(axis=0) for p in parts])
    for i, j in candidate_pairs(lo, hi, OVERLAP_TOL):
        if _face_separates(pl[i], parts[j], OVERLAP_TOL) or _face_separates(pl[j], parts[i], OVERLAP_TOL):
            continue
        t = ph.planes_overlap(pl[i], pl[j])
        if t > OVERLAP_TOL:
            raise GeometryError(f"{where}: parts {i} and {j} interpenetrate by {t:.3g} m "
                                f"(tolerance {OVERLAP_TOL:g} m): the parts of one stone must not overlap")
    faces = [ph.faces(p, h) for p, h in zip(parts, hulls)]
    neighbours: dict[int, set[int]] = {k: set() for k in range(len(parts))}
    for i, j in candidate_pairs(lo, hi, -OVERLAP_TOL):  # boxes that touch (within OVERLAP_TOL)
        if joined(parts[i], faces[i], parts[j], faces[j]):
            neighbours[i].add(j)
            neighbours[j].add(i)
    reached, todo = {0}, [0]
    while todo:
        for n in neighbours[todo.pop()] - reached:
            reached.add(n)
            todo.append(n)
    if len(reached) < len(parts):
        rest = sorted(set(range(len(parts))) - reached)
        raise GeometryError(
            f"{where} (a stone of {len(parts)} parts): part{'s' if len(rest) > 1 else ''} "
            f"{{{', '.join(map(str, rest))}}} {'are' if len(rest) > 1 else 'is'} not joined face to face to the rest "
            f"(part 0 and the parts joined to it: {{{', '.join(map(str, sorted(reached)))}}}): the parts of one stone "
            f"must share faces (a patch wider than {JOIN_MIN_WIDTH:g} m); touching along an edge or at a corner, or "
            "apart, they are not one solid")


def _clip_convex(poly: np.ndarray, clip: np.ndarray) -> np.ndarray:
    """The intersection (m, 2) of two convex polygons given counter-clockwise (Sutherland-Hodgman)."""
    out = poly
    for k in range(len(clip)):
        if len(out) == 0:
            break
        a, b = clip[k], clip[(k + 1) % len(clip)]
        e = b - a
        side = e[0] * (out[:, 1] - a[1]) - e[1] * (out[:, 0] - a[0])  # >= 0: left of a->b, inside
        nxt = []
        for q in range(len(out)):
            p0, p1, s0, s1 = out[q], out[(q + 1) % len(out)], side[q], side[(q + 1) % len(out)]
            if s0 >= 0:
                nxt.append(p0)
            if (s0 >= 0) != (s1 >= 0):
                nxt.append(p0 + (p1 - p0) * (s0 / (s0 - s1)))
        out = np.array(nxt).reshape(-1, 2)
    return out


def _ccw(p: np.ndarray) -> np.ndarray:
    q = np.concatenate((p[1:], p[:1]))
    twice = float(np.dot(p[:, 0], q[:, 1]) - np.dot(q[:, 0], p[:, 1]))
    return p if twice >= 0 else p[::-1]


def _face_max(dist: np.ndarray, polygons: list) -> np.ndarray:
    """Per face (its corner indices in ``polygons``), the largest of its corners' rows of ``dist``."""
    sizes = [len(p) for p in polygons]
    starts = np.r_[0, np.cumsum(sizes)[:-1]]
    return np.maximum.reduceat(dist[np.concatenate(polygons)], starts, axis=0)


def face_patches(va, fa: ph.Faces, vb, fb: ph.Faces, tol: float = OVERLAP_TOL):
    """The patches where two convex bodies (vertices m and ``ph.faces``) touch face to face:
    for each face of one and face of the other with opposite normals, each face's corners
    within ``tol`` (m) of the other's plane, their common polygon (Sutherland-Hodgman in the
    plane). Yields (outward normal of the face of ``va`` (3,), the patch (k, 3) m,
    counter-clockwise about that normal, in that face's plane, area m^2, perimeter m)."""
    va, vb = np.asarray(va, float), np.asarray(vb, float)
    # all face pairs at once: opposite normals, each face's corners within tol of the other's plane
    far_b = _face_max(np.abs(vb @ fa.normals.T + fa.offsets), fb.polygons)  # (faces of b, faces of a)
    far_a = _face_max(np.abs(va @ fb.normals.T + fb.offsets), fa.polygons)  # (faces of a, faces of b)
    touch = (fa.normals @ fb.normals.T < 0) & (far_b.T <= tol) & (far_a <= tol)
    for i, j in zip(*np.nonzero(touch)):
        na, da, pa = fa.normals[i], fa.offsets[i], fa.polygons[i]
        qa, qb = va[pa], vb[fb.polygons[j]]
        e1 = ph._cross(na, [1.0, 0, 0] if abs(na[0]) < 0.9 else [0, 1.0, 0])
        e1 /= np.linalg.norm(e1)
        e2 = ph._cross(na, e1)
        basis = np.stack([e1, e2], axis=1)
        patch = _clip_convex(_ccw(qa @ basis), _ccw(qb @ basis))
        if len(patch) < 3:
            continue
        nxt = np.concatenate((patch[1:], patch[:1]))
        area = 0.5 * abs(float(np.dot(patch[:, 0], nxt[:, 1]) - np.dot(nxt[:, 0], patch[:, 1])))
        perimeter = float(np.sqrt(((nxt - patch) ** 2).sum(axis=1)).sum())
        yield np.asarray(na, float), patch @ basis.T - da * np.asarray(na, float), area, perimeter


def joined(va, fa: ph.Faces, vb, fb: ph.Faces, tol: float = OVERLAP_TOL, min_width: float = JOIN_MIN_WIDTH) -> bool:
    """Whether two convex parts (vertices m and ``ph.faces``) are joined face to face: a face
    of one and a face of the other with opposite normals, each face's corners within ``tol``
    (m) of the other's plane, overlapping in a patch wider than ``min_width`` (m; the width
    2 x area / perimeter; ``face_patches``). Parts touching along an edge or at a corner are not."""
    return any(perimeter > 0 and 2.0 * area / perimeter > min_width
               for _, _, area, perimeter in face_patches(va, fa, vb, fb, tol))


def parse(data: dict, where: str = "<blocks>", check_overlaps: bool = True) -> BlockSet:
    """Validate a block-definition object and return a BlockSet (raises GeometryError)."""
    if not isinstance(data, dict):
        raise GeometryError(f"{where}: top level must be a JSON object")
    unknown = set(data) - TOP_KEYS
    if unknown:
        raise GeometryError(f"{where}: unknown key(s) {sorted(unknown)}; allowed {sorted(TOP_KEYS)}")
    if data.get("format") != FORMAT:
        raise GeometryError(f"{where}: 'format' must be '{FORMAT}', got {data.get('format')!r}")
    version = data.get("version")
    if not is_int(version) or version not in VERSIONS:
        raise GeometryError(f"{where}: unsupported 'version' {version!r} (this reader: "
                            f"{' or '.join(str(v) for v in VERSIONS)})")
    units = data.get("units", {"length": "m", "mass": "kg"})
    if units != {"length": "m", "mass": "kg"}:
        raise GeometryError(f"{where}: 'units' must be {{'length': 'm', 'mass': 'kg'}}, got {units}")
    mats_in = data.get("materials")
    if not isinstance(mats_in, dict) or not mats_in:
        raise GeometryError(f"{where}: 'materials' must be a non-empty object")
    materials = {n: _material(where, n, d) for n, d in mats_in.items()}
    blocks_in = data.get("blocks")
    if not isinstance(blocks_in, list) or not blocks_in:
        raise GeometryError(f"{where}: 'blocks' must be a non-empty list")

    blocks: list[Block] = []
    seen: set[int] = set()
    for k, b in enumerate(blocks_in):
        if not isinstance(b, dict):
            raise GeometryError(f"{where}: blocks[{k}] must be an object")
        bid = b.get("id")
        if not is_int(bid):
            raise GeometryError(f"{where}: blocks[{k}]: 'id' must be an integer, got {bid!r}")
        bid = int(bid)
        if abs(bid) > MAX_ID:
            raise GeometryError(f"{where}: blocks[{k}]: 'id' {bid} is beyond {MAX_ID} (ids are integers up to "
                                f"{MAX_ID} in magnitude)")
        w = f"{where}: block {bid}"
        unknown = set(b) - BLOCK_KEYS
        if unknown:
            raise GeometryError(f"{w}: unknown key(s) {sorted(unknown)}; allowed {sorted(BLOCK_KEYS)}")
        if bid in seen:
            raise GeometryError(f"{w}: duplicate id")
        seen.add(bid)
        role = b.get("role", "free")
        if role not in ROLES:
            raise GeometryError(f"{w}: 'role' must be one of {ROLES}, got {role!r}")
        mat = b.get("material")
        if not isinstance(mat, str) or mat not in materials:
            raise GeometryError(f"{w}: unknown material {mat!r} (defined: {sorted(materials)})")
        if "parts" in b:
            if version < PARTS_VERSION:
                raise GeometryError(f"{w}: 'parts' needs version {PARTS_VERSION} (this file is version {version}): "
                                    f"set \"version\": {PARTS_VERSION}, or give one convex part as 'vertices'")
            if "vertices" in b:
                raise GeometryError(f"{w}: give either 'vertices' (one convex part) or 'parts' (several), not both")
            parts, hulls = _parts(w, b["parts"])
        else:
            verts, h = _part(w, b.get("vertices"))
            parts, hulls = (verts,), (h,)
        dofs = b.get("blocked_dofs", "")
        if not isinstance(dofs, str) or set(dofs) - set("xyzXYZ") or len(set(dofs)) != len(dofs):
            raise GeometryError(f"{w}: 'blocked_dofs' must be a subset of 'xyzXYZ', got {dofs!r}")
        if dofs and role != "free":
            raise GeometryError(f"{w}: 'blocked_dofs' only applies to free blocks (role is {role!r})")
        label = b.get("label", "")
        if not isinstance(label, str):
            raise GeometryError(f"{w}: 'label' must be a string, got {label!r}")
        blocks.append(Block(bid, role, mat, parts, dofs, label, tuple(ph.planes(h) for h in hulls)))

    if not any(b.role == "free" for b in blocks):
        raise GeometryError(f"{where}: no block has role 'free': nothing would move")
    if all(b.role == "free" for b in blocks):
        raise GeometryError(f"{where}: no block has role 'platform' or 'fixed': nothing holds the free blocks (they "
                            "would fall for ever); add the platform they stand on")

    joints = data.get("joints", [])
    if not isinstance(joints, list):
        raise GeometryError(f"{where}: 'joints' must be a list, got {joints!r}")
    for k, j in enumerate(joints):
        w = f"{where}: joints[{k}]"
        if not isinstance(j, dict) or set(j) - JOINT_KEYS or "blocks" not in j:
            raise GeometryError(f"{w}: must be an object with 'blocks' and any of 'mu', 'damping'")
        pair = j["blocks"]
        if not (isinstance(pair, list) and len(pair) == 2 and all(is_int(p) for p in pair)):
            raise GeometryError(f"{w}: 'blocks' must be two integer block ids, got {pair!r}")
        if not (all(p in seen for p in pair) and pair[0] != pair[1]):
            raise GeometryError(f"{w}: 'blocks' must name two different existing block ids, got {pair!r}")
        for key in JOINT_PROPERTIES:
            if key in j:
                _positive(w, key, j[key], allow_zero=True)
    cps = data.get("control_points", [])
    if not isinstance(cps, list):
        raise GeometryError(f"{where}: 'control_points' must be a list, got {cps!r}")
    names = set()
    for k, c in enumerate(cps):
        w = f"{where}: control_points[{k}]"
        if not isinstance(c, dict) or set(c) != CP_KEYS:
            raise GeometryError(f"{w}: must have exactly the keys {sorted(CP_KEYS)}")
        if not isinstance(c["name"], str) or not c["name"]:
            raise GeometryError(f"{w}: 'name' must be a non-empty string, got {c['name']!r}")
        w = f"{where}: control point {c['name']!r}"
        if not is_int(c["block"]):
            raise GeometryError(f"{w}: 'block' must be an integer block id, got {c['block']!r}")
        if c["block"] not in seen:
            raise GeometryError(f"{w}: block {c['block']!r} does not exist")
        _point(w, "position", c["position"])
        if c["name"] in names:
            raise GeometryError(f"{w}: duplicate control point name {c['name']!r}")
        names.add(c["name"])
    gen = data.get("generator", {})
    if not isinstance(gen, dict):
        raise GeometryError(f"{where}: 'generator' must be an object, got {gen!r}")

    bs = BlockSet(str(data.get("name", "")), materials, blocks, list(joints), list(cps),
                  str(data.get("description", "")), str(data.get("source", "")), dict(gen))
    if check_overlaps:
        check_no_overlaps(bs, where)
    return bs


def candidate_pairs(lo: np.ndarray, hi: np.ndarray, tol: float = 0.0) -> list[tuple[int, int]]:
    """Pairs (i, j), i < j, of axis-aligned boxes (corners ``lo``, ``hi``, (n, 3) m) that
    overlap by more than ``tol`` (m) along every axis, sorted. Sort and sweep on x:
    O(n log n) plus the pairs that overlap along x."""
    order = np.argsort(lo[:, 0], kind="stable")
    lo_x = lo[order, 0]
    pairs = []
    for k, i in enumerate(order.tolist()):
        end = np.searchsorted(lo_x, hi[i, 0] - tol, side="left")  # boxes starting before i ends
        near = order[k + 1:end]
        hit = near[np.all(lo[near] < hi[i] - tol, axis=1) & np.all(lo[i] < hi[near] - tol, axis=1)]
        pairs += [(min(i, j), max(i, j)) for j in hit.tolist()]
    return sorted(pairs)


def _face_separates(planes, vertices, tol: float) -> bool:
    """Whether a face plane of one block has all ``vertices`` of the other at most ``tol``
    (m) inside it: their overlap then lies in a slab ``tol`` thick, so it is <= tol thick
    (the exact test could not refuse the pair)."""
    n, d = planes
    return bool(np.max(np.min(vertices @ n.T + d, axis=0)) >= -tol)


def check_no_overlaps(bs: BlockSet, where: str = "<blocks>", tol: float = OVERLAP_TOL) -> None:
    """Refuse two blocks overlapping by more than ``tol`` (m), naming the first such pair in
    file order. Pairs of non-moving blocks (fixed/platform) are not checked: they never
    interact. Only pairs whose bounding boxes overlap by more than ``tol`` (found by a sort
    and sweep: O(n log n) for n blocks) and that no face plane of either separates (within
    ``tol``) get the exact, linear-programme, test. Multi-part stones part by part: two
    stones overlap if a part of one overlaps a part of the other (bounding boxes over all
    parts first, then each pair of parts whose boxes overlap)."""
    bl = bs.blocks
    lo = np.array([b.points.min(axis=0) for b in bl]).reshape(-1, 3)
    hi = np.array([b.points.max(axis=0) for b in bl]).reshape(-1, 3)
    for i, j in candidate_pairs(lo, hi, tol):
        a, b = bl[i], bl[j]
        if a.role != "free" and b.role != "free":
            continue
        single = len(a.parts) == 1 and len(b.parts) == 1
        for (ka, va, pa), (kb, vb, pb) in itertools.product(zip(range(len(a.parts)), a.parts, a.part_planes()),
                                                             zip(range(len(b.parts)), b.parts, b.part_planes())):
            if not single and not (np.all(va.min(axis=0) < vb.max(axis=0) - tol)
                                   and np.all(vb.min(axis=0) < va.max(axis=0) - tol)):
                continue
            if _face_separates(pa, vb, tol) or _face_separates(pb, va, tol):
                continue
            t = ph.planes_overlap(pa, pb)
            if t > tol:
                which = "" if single else (
                    f" (part {ka} of block {a.id} and part {kb} of block {b.id})")
                raise GeometryError(
                    f"{where}: blocks {a.id} and {b.id} interpenetrate by {t:.3g} m{which} "
                    f"(tolerance {tol:g} m)")


def hovering_fixed(bs: BlockSet, tol: float | None = None) -> list[int]:
    """Ids of the fixed blocks that stand neither on a platform block nor on a fixed block that
    does (a chain), judged by bounding boxes: a block whose box is more than ``tol`` (m; default
    ``standing_tol`` of the non-platform blocks' extent) from
    every such block's box certainly touches none of them (a conservative test: a block
    listed hovers; one not listed may still only nearly touch). A geometry without a
    platform block has its fixed blocks as its ground (the four-block model): none listed."""
    box = {b.id: (b.points.min(axis=0), b.points.max(axis=0)) for b in bs.blocks}

    def near(a, b):
        return bool(np.all(box[a][0] <= box[b][1] + tol) and np.all(box[b][0] <= box[a][1] + tol))

    held = [b.id for b in bs.blocks if b.role == "platform"]
    if not held:
        return []
    if tol is None:
        pts = np.vstack([b.points for b in bs.blocks if b.role != "platform"])
        tol = standing_tol(float(np.max(pts.max(axis=0) - pts.min(axis=0))))
    rest = [b.id for b in bs.blocks if b.role == "fixed"]
    todo = list(held)
    while todo and rest:
        a = todo.pop()
        reached = [b for b in rest if near(a, b)]
        rest = [b for b in rest if b not in reached]
        todo += reached
    return sorted(rest)


def load(path, check_overlaps: bool = True) -> BlockSet:
    """Read and validate a block file; errors name the file."""
    p = Path(path)
    return parse(inputfiles.load_json(p, GeometryError, "block file"), str(p), check_overlaps)


def write(bs: BlockSet | dict, path) -> Path:
    """Validate, then write atomically (nothing is written if validation fails)."""
    data = bs.to_dict() if isinstance(bs, BlockSet) else bs
    p = Path(path)
    parse(data, str(p))
    p.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=p.parent, prefix=p.name, suffix=".tmp")
    with os.fdopen(fd, "w") as f:
        json.dump(data, f, indent=1)
        f.write("\n")
    os.replace(tmp, p)
    return p


def box_vertices(center, size) -> list[list[float]]:
    """The 8 corners of an axis-aligned box (m)."""
    c = np.asarray(center, dtype=float)
    s = np.asarray(size, dtype=float) / 2.0
    return [[c[0] + i * s[0], c[1] + j * s[1], c[2] + k * s[2]]
            for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)]
