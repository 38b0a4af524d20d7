"""Build a YADE scene from a resolved run specification (runs inside YADE only).

Bodies: one Polyhedra body per block, in file order; a stone of several convex parts
(``parts`` in the spec) is a YADE clump of one Polyhedra body per part
(``O.bodies.appendClumped``: its members first, then the clump body, which carries the
stone's state; YADE gives it the union's mass, centroid and principal inertia from its
members', which are exact for polyhedra that do not overlap). Blocks with role ``fixed`` or
``platform`` are non-dynamic; they share a collision-mask bit that the collider's
``avoidSelfInteractionMask`` excludes, so no contact between two non-moving blocks is
ever computed (YADE would otherwise intersect them every step).

Materials: PolyhedraMat as the case's contact law maps them (``ContactLaw.yade_material``
in drystone/mechanics/laws.py): young = 2 K_n so that YADE's volumetric law gives F_n = K_n V; with
the project's law frictionAngle = 0 (the stock law's shared shear is zeroed every step, and
the tangential force and damping come from ``contact_engine``), with the stock law friction
angle atan(mu), shear stiffness ks = K_t A_ref and no damping.
"""
from __future__ import annotations

import numpy as np
import yade
from yade import utils

from drystone.geometry import polyhedron as ph
from drystone.mechanics import laws

DYNAMIC_MASK = 0b01
STATIC_MASK = 0b11  # shares bit 0b10 with every other non-moving body


def _material(mat: dict, law: str, stock_shear_area: float):
    """The law's mapping of a material onto PolyhedraMat (drystone/mechanics/laws.py)."""
    m = laws.get(law).yade_material(mat, stock_shear_area)
    return yade.PolyhedraMat(young=m["young"], poisson=m["poisson"], density=mat["density"],
                             frictionAngle=m["frictionAngle"], label=mat["name"])


def build(spec, integrate: bool = True) -> dict:
    """Create materials, bodies and engines of ``spec`` (a drystone.model.spec.Spec); return lookup tables. ``integrate=False``
    leaves NewtonIntegrator out of the engines (the compiled step moves the bodies).

    Returns dict with ``yid`` (block id -> YADE id: the clump's for a multi-part stone),
    ``bid`` (YADE id -> block id, the members' too), ``dynamic`` (list of YADE ids that
    move), ``members`` (clump's YADE id -> its members' ids), ``newton`` (the NewtonIntegrator).
    """
    O = yade.Omega()
    O.reset()
    law = spec.law
    mats = {}
    for name, m in spec.materials.items():
        ym = _material(dict(m, name=name), law, spec.stock_shear_area)
        O.materials.append(ym)
        mats[name] = ym
    yid, bid, dynamic, members = {}, {}, [], {}
    for b in spec.blocks:
        moving = b["role"] == "free"

        def polyhedron(vertices):
            return utils.polyhedron([yade.Vector3(*p) for p in vertices], material=mats[b["material"]],
                                    fixed=not moving, mask=DYNAMIC_MASK if moving else STATIC_MASK)

        if "parts" in b:
            i, ids = O.bodies.appendClumped([polyhedron(p) for p in b["parts"]])
            O.bodies[i].dynamic = moving
            members[i] = list(ids)
            bid.update((m, b["id"]) for m in ids)
            body = O.bodies[i]
        else:
            body = polyhedron(b["vertices"])
            i = O.bodies.append(body)
        if moving and b.get("blocked_dofs"):
            body.state.blockedDOFs = b["blocked_dofs"]
        yid[b["id"]] = i
        bid[i] = b["id"]
        if moving:
            dynamic.append(i)
    newton = yade.NewtonIntegrator(damping=0.0, gravity=(0, 0, 0), label="newton")
    step = yade.PyRunner(iterPeriod=1, command="_drystone_step()", label="drystone_step")
    if spec.detection == "native":
        # contacts and all their forces come from contact_engine.PenaltyCoulomb (native)
        O.engines = [yade.ForceResetter(), step, newton] if integrate else [yade.ForceResetter(), step]
    else:
        O.engines = [
            yade.ForceResetter(),
            yade.InsertionSortCollider([yade.Bo1_Polyhedra_Aabb()], avoidSelfInteractionMask=0b10,
                                       verletDist=0.0),
            yade.InteractionLoop([yade.Ig2_Polyhedra_Polyhedra_PolyhedraGeom()],
                                 [yade.Ip2_PolyhedraMat_PolyhedraMat_PolyhedraPhys()],
                                 [yade.Law2_PolyhedraGeom_PolyhedraPhys_Volumetric()]),
            step,
            newton,
        ]
    O.dt = spec.dt
    return {"yid": yid, "bid": bid, "dynamic": dynamic, "members": members, "newton": newton}


def shapes(O, blocks: dict, bid: dict, members: dict, pos, rot) -> tuple:
    """The convex shapes the contact laws see, in YADE's body order: a body's Polyhedra,
    or each member of a clump (a multi-part stone) as a shape of the clump body.
    ``owner`` (ns,) each shape's body, ``local_v`` its vertices in that body's frame (m),
    ``shape_size`` its smallest dimension (m); ``size`` per body: its smallest, a
    multi-part stone's smallest part's (the tunnelling check, stability.TUNNEL_FRACTION).
    ``blocks`` the spec's blocks by id, ``bid`` a body's block id, ``members`` a clump's
    members' ids, ``pos`` and ``rot`` the bodies' positions and rotation matrices: returns
    (owner, local_v, shape_size, size)."""
    nb = len(O.bodies)
    clump_of = {m: c for c, ms in members.items() for m in ms}
    owner, local_v, shape_size = [], [], []
    size = np.full(nb, np.inf)
    for i in range(nb):
        if i in members:
            continue
        block = blocks[bid[i]]
        if i in clump_of:  # a part: its vertices into the clump's frame
            c = clump_of[i]
            part = block["parts"][members[c].index(i)]
            x = pos[i] + np.asarray([tuple(v) for v in O.bodies[i].shape.v]) @ rot[i].T
            local_v.append([tuple(v) for v in (x - pos[c]) @ rot[c]])
            owner.append(c)
            part_size = float(ph.extent(np.asarray(part)).min())
        else:
            local_v.append([tuple(v) for v in O.bodies[i].shape.v])
            owner.append(i)
            part_size = float(ph.extent(np.asarray(block["vertices"])).min())
        shape_size.append(part_size)
        size[owner[-1]] = min(size[owner[-1]], part_size)
    return np.array(owner, np.int64), local_v, np.array(shape_size), size
