"""Small hand-checkable models: rectangular blocks on a platform (for tests and examples)."""
from __future__ import annotations

from . import blockfile as bf
from . import params as pc

PLATFORM_THICKNESS = 0.05  # m


def boxes_on_platform(boxes, density=2300.0, kn=2e8, kt=1e8, mu=0.7, damping=0.0,
                      platform_size=(2.0, 2.0)) -> dict:
    """Free boxes resting on a fixed platform whose top is z = 0.

    ``boxes``: list of dicts {id, center_xy: [x, y], size: [lx, ly, lz]} (m), each set on
    the platform (or on ``z0`` if given: the box bottom height, m). Ids are integers >= 1
    (0 is the platform), sizes > 0 m.
    """
    g = "boxes_on_platform"
    if not isinstance(boxes, (list, tuple)) or not boxes:
        raise pc.fail(g, "boxes", "a non-empty list of {id, center_xy, size[, z0]}", boxes)
    ids = set()
    for k, b in enumerate(boxes):
        if not isinstance(b, dict) or not {"id", "center_xy", "size"} <= set(b) <= {"id", "center_xy", "size", "z0"}:
            raise pc.fail(g, f"boxes[{k}]", "a table with keys id, center_xy, size and optionally z0", b)
        pc.integer(g, f"boxes[{k}].id", b["id"], lo=1)
        if b["id"] in ids:
            raise pc.fail(g, f"boxes[{k}].id", "unique", b["id"])
        ids.add(b["id"])
        pc.numbers(g, f"boxes[{k}].center_xy", b["center_xy"], 2, unit="m")
        pc.numbers(g, f"boxes[{k}].size", b["size"], 3, lo=0, lo_open=True, unit="m")
        pc.number(g, f"boxes[{k}].z0", b.get("z0", 0.0), unit="m")
    pc.numbers(g, "platform_size", platform_size, 2, lo=0, lo_open=True, unit="m")
    pc.material(g, density, kn, kt, damping, mu=mu)
    px, py = platform_size
    blocks = [{"id": 0, "role": "platform", "material": "stone",
               "vertices": bf.box_vertices((0, 0, -PLATFORM_THICKNESS / 2), (px, py, PLATFORM_THICKNESS))}]
    for b in boxes:
        lx, ly, lz = b["size"]
        x, y = b["center_xy"]
        z0 = b.get("z0", 0.0)
        blocks.append({"id": int(b["id"]), "role": "free", "material": "stone",
                       "vertices": bf.box_vertices((x, y, z0 + lz / 2), (lx, ly, lz))})
    return {"format": bf.FORMAT, "version": bf.VERSION, "name": "boxes_on_platform",
            "description": "rectangular blocks on a fixed platform", "units": {"length": "m", "mass": "kg"},
            "materials": {"stone": {"density": density, "kn": kn, "kt": kt, "mu": mu, "damping": damping}},
            "blocks": blocks,
            "generator": {"name": "boxes_on_platform", "boxes": boxes, "density": density, "kn": kn,
                          "kt": kt, "mu": mu, "damping": damping, "platform_size": list(platform_size)}}
