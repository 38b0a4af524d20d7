"""Split multi-part stones into independent convex blocks (a block-file transform).

``split_parts(data)`` takes a block-file dict (``drystone.blocks``, version 1 or 2) and
returns a new one in which every stone given as ``parts`` (one rigid body of several
convex parts, blockfile.py version 2) becomes one block per part, each its own rigid
body: the structure the package forced before multi-part stones (a re-entrant stone cut
into convex blocks that move independently). Everything else is kept:

* the first part keeps the stone's ``id``; the others get new ids after the largest id
  of the file, in stone order then part order;
* each part keeps the stone's ``role``, ``material`` and ``blocked_dofs``, and gets the
  ``label`` "stone N part k of m" (the stone's own label, if any, after it);
* ``joints`` naming a split stone are repeated for every part of it (a joint's
  friction or damping applies to every contact between the two stones, so it does to
  their parts);
* a control point on a split stone goes to the part that holds it (the part whose
  hull contains its position within ``CONTAINS_REL_TOL`` x the stone's size; the first
  such part), else to the part with the nearest centroid;
* ``generator`` gets ``split``: ``{"stones": {"N": [ids of its parts]}, "blocks_before": n,
  "blocks_after": m}``, and the name and description say it was split.

The parts tile the stone (validated when the file was parsed: no overlap beyond
``blockfile.OVERLAP_TOL``), so the total volume, and at equal density the weight, does
not change (to round-off), nor the union's centroid; each part's inertia is its own. The
result is validated with ``blockfile.parse``; a file with no multi-part stone comes back
unchanged (a copy). Returns a version-1 dict when every block is then one part.
"""
from __future__ import annotations

import copy

import numpy as np

from . import blockfile as bf
from . import polyhedron as ph

#: a control point within this x the stone's size (bounding-box diagonal) of a part's
#: hull counts as inside it (points on a shared face belong to the first part holding them)
CONTAINS_REL_TOL = 1e-9


def _inside(point: np.ndarray, part: np.ndarray, tol: float) -> bool:
    n, d = ph.planes(ph.hull(part))
    return bool(np.all(n @ point + d <= tol))


def _owner(position, parts: list[np.ndarray], ids: list[int]) -> int:
    """The id of the part that holds ``position`` (see the module docstring)."""
    p = np.asarray(position, float)
    pts = np.vstack(parts)
    tol = CONTAINS_REL_TOL * float(np.linalg.norm(np.ptp(pts, axis=0)))
    for part, bid in zip(parts, ids):
        if _inside(p, part, tol):
            return bid
    cents = [ph.volume_centroid(part)[1] for part in parts]
    return ids[int(np.argmin([np.linalg.norm(c - p) for c in cents]))]


def split_parts(data: dict, where: str = "<blocks>") -> dict:
    """The block-file dict ``data`` with every multi-part stone split into one block per
    part (module docstring). ``data`` is not changed; GeometryError (naming ``where``) if
    it or the result is not a valid block file."""
    bf.parse(data, where, check_overlaps=False)
    out = copy.deepcopy(data)
    blocks = out["blocks"]
    next_id = max(int(b["id"]) for b in blocks) + 1
    new_blocks, stones = [], {}
    for b in blocks:
        if "parts" not in b:
            new_blocks.append(b)
            continue
        parts = b["parts"]
        ids = [int(b["id"])] + list(range(next_id, next_id + len(parts) - 1))
        next_id += len(parts) - 1
        stones[int(b["id"])] = ids
        for k, (bid, verts) in enumerate(zip(ids, parts)):
            nb = {key: v for key, v in b.items() if key not in ("parts", "id", "label")}
            label = f"stone {b['id']} part {k + 1} of {len(parts)}"
            nb = {"id": bid, **nb, "vertices": verts, "label": f"{label}: {b['label']}" if b.get("label") else label}
            new_blocks.append(nb)
    if not stones:
        return out
    out["blocks"] = new_blocks
    joints = []
    for j in out.get("joints", []):
        a, c = j["blocks"]
        for pa in stones.get(int(a), [a]):
            for pc in stones.get(int(c), [c]):
                joints.append({**j, "blocks": [pa, pc]})
    if joints:
        out["joints"] = joints
    by_id = {int(b["id"]): b for b in data["blocks"]}
    for cp in out.get("control_points", []):
        ids = stones.get(int(cp["block"]))
        if ids:
            parts = [np.asarray(p, float) for p in by_id[int(cp["block"])]["parts"]]
            cp["block"] = _owner(cp["position"], parts, ids)
    n_before = len(data["blocks"])
    out["generator"] = dict(out.get("generator", {}),
                            split={"stones": {str(k): v for k, v in stones.items()}, "blocks_before": n_before,
                                   "blocks_after": len(new_blocks)})
    out["version"] = bf.VERSION if all("parts" not in b for b in new_blocks) else bf.PARTS_VERSION
    if out.get("name"):
        out["name"] = f"{out['name']}_split"
    out["description"] = (f"{out.get('description', '')} -- every multi-part stone split into independent "
                          f"convex blocks ({len(stones)} stones -> {sum(len(v) for v in stones.values())} "
                          "blocks; drystone/geometry/split.py)").lstrip(" -")
    bf.parse(out, f"{where} (split)", check_overlaps=False)
    return out
