"""Block file -> LMGC90 model (no YADE, no LMGC90 needed).

A block of the block file (``drystone.geometry.blockfile``) is the convex hull of its
vertices; LMGC90 takes a rigid body (RBDY3) with one polyhedral contactor (POLYR) given
as vertices relative to the body's reference point and outward triangles. Here:

* faces: the hull's planar faces (``drystone.geometry.polyhedron.faces``, counter-clockwise
  seen from outside) cut into fans of triangles, so each triangle's normal points out and
  coplanar triangles are exactly coplanar (LMGC90's face-to-face detection merges them);
* reference point: the block's volume centroid (LMGC90 computes the centre of inertia of
  the polyhedron itself; giving it the centroid leaves no shift between the two);
* density: the material's (per block); mass, volume, centroid and inertia are recomputed
  from the triangles (``mass_properties``) so that a test can check them against the block
  file's hull (``drystone.geometry.polyhedron.volume_centroid``);
* roles: ``platform`` and ``fixed`` blocks get all six velocities imposed (zero, or the
  base motion), ``free`` blocks move;
* contact: LMGC90's ``IQS_CLB`` law (rigid: Signorini, Coulomb friction mu, no cohesion;
  "inelastic quasi-shock": restitution 0). compas_lmgc90 0.1.11 has one contact law for
  all contacts, so a block file whose contacts would have different friction coefficients
  (materials or joints) is refused (``TranslationError``), never averaged;
* not used, as a rigid model has no use for them: ``kn``, ``kt`` (penalty stiffness) and
  ``damping`` (the restitution is 0 whatever the damping).

``to_lmgc90(blockset, materials=None, joint_overrides=None)`` returns a JSON-serialisable
dict (``MODEL_FORMAT``) that ``drystone.studies.crosscheck.engine`` runs.
"""
from __future__ import annotations

import itertools

import numpy as np

from drystone.geometry import blockfile as bf
from drystone.geometry import polyhedron as ph

MODEL_FORMAT = "drystone.lmgc90_model"
MODEL_VERSION = 1
LAW = "IQS_CLB"  # LMGC90: rigid contact, Coulomb friction, restitution 0
#: LMGC90's alert distance (m): pairs of contactors closer than this are candidate contacts
#: (compas_lmgc90's default). Blocks that share a face are at gap 0, far inside it; it is
#: below a thousandth of every block in the cases here (the smallest stone is ~50 mm).
ALERT_M = 1e-3
#: two friction coefficients closer than this are the same coefficient (round-off in TOML
#: or tan(radians(phi)))
MU_TOL = 1e-12


class TranslationError(ValueError):
    """The block file asks for something the LMGC90 model cannot represent."""


def outward_triangles(vertices) -> np.ndarray:
    """(t, 3) vertex indices of the hull of ``vertices`` as triangles wound
    counter-clockwise seen from outside (outward normals by the right-hand rule): each
    planar face of the hull cut into a fan from its first corner."""
    v = np.asarray(vertices, float)
    fs = ph.faces(v)
    tris = []
    for poly in fs.polygons:
        p = [int(i) for i in poly]
        for k in range(1, len(p) - 1):
            tris.append((p[0], p[k], p[k + 1]))
    return np.array(tris, dtype=int)


def mass_properties(vertices, triangles, density: float = 1.0) -> dict:
    """Volume (m^3), mass (kg), centroid (m) and inertia tensor about the centroid
    (kg m^2) of the closed, outward-wound triangle mesh, by signed tetrahedra from the
    origin (exact for any closed polyhedron)."""
    v = np.asarray(vertices, float)
    t = np.asarray(triangles, int)
    a, b, c = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    o = v.mean(axis=0)  # a reference point inside: smaller round-off than the origin
    a, b, c = a - o, b - o, c - o
    det = np.einsum("ij,ij->i", a, np.cross(b, c))  # 6 x signed volume of (o, a, b, c)
    vol = det.sum() / 6.0
    cen = (det[:, None] * (a + b + c)).sum(axis=0) / (24.0 * vol)
    # second moments sum_tets int x_i x_j dV = det/120 (sum_p sum_q p_i q_j + sum_p p_i p_j)
    s = a + b + c
    m2 = np.zeros((3, 3))
    for p in (a, b, c):
        m2 += np.einsum("k,ki,kj->ij", det, p, p)
    m2 += np.einsum("k,ki,kj->ij", det, s, s)
    m2 /= 120.0
    m2c = m2 - vol * np.outer(cen, cen)  # about the centroid
    inertia = density * (np.trace(m2c) * np.eye(3) - m2c)
    return {"volume": float(vol), "mass": float(density * vol), "centroid": (cen + o).tolist(),
            "inertia": inertia.tolist()}


def contact_friction(bs: bf.BlockSet, materials: dict | None = None, joint_overrides: dict | None = None) -> float:
    """The one friction coefficient of every contact that can occur (a pair with at least
    one free block: non-moving blocks never interact): a pair of materials takes the
    smaller mu (the block file's rule), a joint its own. Several different values raise
    TranslationError: LMGC90 through compas_lmgc90 0.1.11 has a single contact law.
    ``materials``: name -> properties overriding the block file's (a resolved spec's);
    ``joint_overrides``: "a-b" -> {"mu": ...} (spec.json's) instead of the block file's joints."""
    mus = {name: (materials[name]["mu"] if materials and name in materials else m.mu) for name, m in bs.materials.items()}
    role = {b.id: b.role for b in bs.blocks}
    free_mats = {b.material for b in bs.blocks if b.role == "free"}
    all_mats = {b.material for b in bs.blocks}
    values = {}
    for ma, mb in itertools.product(sorted(free_mats), sorted(all_mats)):
        values[f"materials {ma}/{mb}"] = min(mus[ma], mus[mb])
    if joint_overrides is None:
        joints = {f"{min(j['blocks'])}-{max(j['blocks'])}": j for j in bs.joints}
    else:
        joints = joint_overrides
    for key, j in joints.items():
        a, b = (int(x) for x in key.split("-"))
        if "mu" in j and (role.get(a) == "free" or role.get(b) == "free"):
            values[f"joint {key}"] = float(j["mu"])
    distinct = sorted(set(values.values()))
    if not distinct:
        raise TranslationError("no contact can occur: no free block")
    if distinct[-1] - distinct[0] > MU_TOL:
        detail = ", ".join(f"{k}: {v:g}" for k, v in sorted(values.items()))
        raise TranslationError(f"the contacts have different friction coefficients ({detail}); compas_lmgc90 "
                               f"0.1.11 applies one contact law to every contact")
    return float(distinct[0])


def to_lmgc90(bs: bf.BlockSet, materials: dict | None = None, joint_overrides: dict | None = None,
              alert: float = ALERT_M) -> dict:
    """The LMGC90 model of a block set (module docstring). ``materials``: name -> properties
    overriding the block file's (a resolved spec's ``materials``, with a case's overrides);
    ``joint_overrides``: a spec's (``"a-b"`` -> properties) instead of the file's joints."""
    mu = contact_friction(bs, materials, joint_overrides)
    bodies = []
    for b in bs.blocks:
        if b.blocked_dofs:
            raise TranslationError(f"block {b.id}: 'blocked_dofs' = {b.blocked_dofs!r} is not translated to LMGC90")
        rho = float(materials[b.material]["density"]) if materials and b.material in materials \
            else bs.materials[b.material].density
        tri = outward_triangles(b.vertices)
        props = mass_properties(b.vertices, tri, rho)
        c = np.array(props["centroid"])
        bodies.append({"id": b.id, "role": b.role, "imposed": b.role != "free", "material": b.material,
                       "density": rho, "volume": props["volume"], "mass": props["mass"],
                       "centroid": c.tolist(), "inertia": props["inertia"],
                       "vertices": (np.asarray(b.vertices, float) - c).tolist(), "triangles": tri.tolist()})
    not_used = sorted({k for k in ("kn", "kt", "damping")})
    return {"format": MODEL_FORMAT, "version": MODEL_VERSION, "name": bs.name, "law": LAW, "mu": mu,
            "restitution": 0.0, "alert_m": float(alert), "bodies": bodies,
            "not_used": not_used,
            "notes": [f"rigid contacts ({LAW}: Signorini condition, Coulomb friction mu = {mu:g}, restitution 0)",
                      "penalty stiffness (kn, kt) and contact damping are not used by the rigid model",
                      "platform and fixed blocks: all six velocities imposed"]}
