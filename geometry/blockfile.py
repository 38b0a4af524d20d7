"""The block-definition file: read, validate, write.

Format ``drystone.blocks`` version 1, a JSON object (units: metres, kilograms, seconds;
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
critical (the paper's mu_0, see README). Between two materials, kn and kt combine in
series (2 k1 k2 / (k1 + k2), equal materials give k), mu is the smaller and damping the
mean. ``joints`` override mu and/or damping for one pair of blocks.

Blocks: ``id`` an integer (the paper's numbering); ``role`` one of ``free`` (moves),
``fixed`` (fixed to the platform, e.g. a wall's first course) or ``platform`` (the
base; fixed); ``vertices`` the corners of a convex block (the block is their convex
hull; a vertex deeper than the tolerance inside the hull means a non-convex shape and
is refused); ``blocked_dofs`` optional YADE-style subset of ``xyzXYZ`` for free blocks
(x, y, z translations and rotations about them, global axes). Control points are
points attached to a block (given in the initial configuration).

Axes: x along the wall, y through its thickness (out of plane), z up.
"""
from __future__ import annotations

import json
import math
import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import polyhedron as ph

FORMAT = "drystone.blocks"
VERSION = 1
ROLES = ("free", "fixed", "platform")
#: vertex deeper than this inside the hull of its block's vertices: non-convex (m)
CONVEX_TOL = 1e-9
#: largest accepted initial overlap thickness between two blocks (m); 1 um is far below
#: the elastic penetration of any case here (tens of um and more) and far above round-off.
OVERLAP_TOL = 1e-6

MATERIAL_KEYS = {"density", "kn", "kt", "mu", "friction_angle_deg", "damping", "description"}
BLOCK_KEYS = {"id", "role", "material", "vertices", "blocked_dofs", "label"}
JOINT_KEYS = {"blocks", "mu", "damping"}
CP_KEYS = {"name", "block", "position"}
TOP_KEYS = {"format", "version", "name", "description", "source", "units", "materials",
            "blocks", "joints", "control_points", "generator"}


class GeometryError(ValueError):
    """Invalid block definition; the message names the file, block and problem."""


@dataclass
class Material:
    name: str
    density: float  # kg/m^3
    kn: float  # N/m^3
    kt: float  # N/m^3
    mu: float  # -
    damping: float  # fraction of critical


@dataclass
class Block:
    id: int
    role: str
    material: str
    vertices: np.ndarray  # (n, 3) m
    blocked_dofs: str = ""
    label: str = ""

    @property
    def volume(self) -> float:
        return ph.volume_centroid(self.vertices)[0]

    @property
    def centroid(self) -> np.ndarray:
        return ph.volume_centroid(self.vertices)[1]


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

    def to_dict(self) -> dict:
        mats = {}
        for m in self.materials.values():
            mats[m.name] = {"density": m.density, "kn": m.kn, "kt": m.kt, "mu": m.mu,
                            "damping": m.damping}
        blocks = []
        for b in self.blocks:
            d = {"id": b.id, "role": b.role, "material": b.material,
                 "vertices": [[float(x) for x in p] for p in b.vertices]}
            if b.blocked_dofs:
                d["blocked_dofs"] = b.blocked_dofs
            if b.label:
                d["label"] = b.label
            blocks.append(d)
        out = {"format": FORMAT, "version": VERSION, "name": self.name,
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


def _positive(where: str, key: str, value, allow_zero=False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
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
    return Material(name, _positive(w, "density", d["density"]), _positive(w, "kn", d["kn"]),
                    _positive(w, "kt", d["kt"]), mu, damping)


def parse(data: dict, where: str = "<blocks>", check_overlaps: bool = True) -> BlockSet:
    """Validate a block-definition object and return a BlockSet (raises GeometryError)."""
    if not isinstance(data, dict):
        raise GeometryError(f"{where}: top level must be a JSON object")
    unknown = set(data) - TOP_KEYS
    if unknown:
        raise GeometryError(f"{where}: unknown key(s) {sorted(unknown)}; allowed {sorted(TOP_KEYS)}")
    if data.get("format") != FORMAT:
        raise GeometryError(f"{where}: 'format' must be '{FORMAT}', got {data.get('format')!r}")
    if data.get("version") != VERSION:
        raise GeometryError(f"{where}: unsupported 'version' {data.get('version')!r} (this reader: {VERSION})")
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
        if isinstance(bid, bool) or not isinstance(bid, int):
            raise GeometryError(f"{where}: blocks[{k}]: 'id' must be an integer, got {bid!r}")
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
        if mat not in materials:
            raise GeometryError(f"{w}: unknown material {mat!r} (defined: {sorted(materials)})")
        try:
            verts = np.array(b.get("vertices"), dtype=float)
        except (TypeError, ValueError) as exc:
            raise GeometryError(f"{w}: 'vertices' must be a list of [x, y, z] numbers ({exc})") from None
        try:
            ph.hull(verts)
            inner = ph.inner_vertices(verts, CONVEX_TOL)
        except ph.HullError as exc:
            raise GeometryError(f"{w}: {exc}") from None
        if inner:
            raise GeometryError(
                f"{w}: not convex: vertex index(es) {inner} lie inside the hull of the others "
                "(YADE polyhedra are convex; split the stone into convex blocks)")
        vol = ph.volume_centroid(verts)[0]
        if not vol > 0:
            raise GeometryError(f"{w}: volume must be positive, got {vol}")
        dofs = b.get("blocked_dofs", "")
        if not isinstance(dofs, str) or set(dofs) - set("xyzXYZ") or len(set(dofs)) != len(dofs):
            raise GeometryError(f"{w}: 'blocked_dofs' must be a subset of 'xyzXYZ', got {dofs!r}")
        if dofs and role != "free":
            raise GeometryError(f"{w}: 'blocked_dofs' only applies to free blocks (role is {role!r})")
        blocks.append(Block(bid, role, mat, verts, dofs, str(b.get("label", ""))))

    if not any(b.role == "free" for b in blocks):
        raise GeometryError(f"{where}: no block has role 'free': nothing would move")

    joints = data.get("joints", [])
    for k, j in enumerate(joints):
        w = f"{where}: joints[{k}]"
        if not isinstance(j, dict) or set(j) - JOINT_KEYS or "blocks" not in j:
            raise GeometryError(f"{w}: must be an object with 'blocks' and any of 'mu', 'damping'")
        pair = j["blocks"]
        if not (isinstance(pair, list) and len(pair) == 2 and all(p in seen for p in pair) and pair[0] != pair[1]):
            raise GeometryError(f"{w}: 'blocks' must name two different existing block ids, got {pair!r}")
        for key in ("mu", "damping"):
            if key in j:
                _positive(w, key, j[key], allow_zero=True)
    cps = data.get("control_points", [])
    names = set()
    for k, c in enumerate(cps):
        w = f"{where}: control_points[{k}]"
        if not isinstance(c, dict) or set(c) != CP_KEYS:
            raise GeometryError(f"{w}: must have exactly the keys {sorted(CP_KEYS)}")
        if c["block"] not in seen:
            raise GeometryError(f"{w}: block {c['block']!r} does not exist")
        pos = np.asarray(c["position"], dtype=float)
        if pos.shape != (3,) or not np.all(np.isfinite(pos)):
            raise GeometryError(f"{w}: 'position' must be three finite numbers")
        if c["name"] in names:
            raise GeometryError(f"{w}: duplicate control point name {c['name']!r}")
        names.add(c["name"])

    bs = BlockSet(str(data.get("name", "")), materials, blocks, list(joints), list(cps),
                  str(data.get("description", "")), str(data.get("source", "")),
                  dict(data.get("generator", {})))
    if check_overlaps:
        check_no_overlaps(bs, where)
    return bs


def check_no_overlaps(bs: BlockSet, where: str = "<blocks>", tol: float = OVERLAP_TOL) -> None:
    """Refuse two blocks overlapping by more than ``tol`` (m). Pairs of non-moving
    blocks (fixed/platform) are not checked: they never interact."""
    lo = {b.id: b.vertices.min(axis=0) for b in bs.blocks}
    hi = {b.id: b.vertices.max(axis=0) for b in bs.blocks}
    bl = bs.blocks
    for i in range(len(bl)):
        for j in range(i + 1, len(bl)):
            a, b = bl[i], bl[j]
            if a.role != "free" and b.role != "free":
                continue
            if np.any(lo[a.id] >= hi[b.id] - tol) or np.any(lo[b.id] >= hi[a.id] - tol):
                continue
            t = ph.overlap_thickness(a.vertices, b.vertices)
            if t > tol:
                raise GeometryError(
                    f"{where}: blocks {a.id} and {b.id} interpenetrate by {t:.3g} m "
                    f"(tolerance {tol:g} m)")


def load(path, check_overlaps: bool = True) -> BlockSet:
    """Read and validate a block file; errors name the file."""
    p = Path(path)
    if not p.is_file():
        raise GeometryError(f"{p}: block file not found")
    try:
        data = json.loads(p.read_text())
    except json.JSONDecodeError as exc:
        raise GeometryError(f"{p}: not valid JSON: line {exc.lineno}, column {exc.colno}: {exc.msg}") from None
    return parse(data, str(p), check_overlaps)


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
