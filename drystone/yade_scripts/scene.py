"""Build a YADE scene from a resolved run specification (runs inside YADE only).

Bodies: one Polyhedra body per block, in file order. Blocks with role ``fixed`` or
``platform`` are non-dynamic; they share a collision-mask bit that the collider's
``avoidSelfInteractionMask`` excludes, so no contact between two non-moving blocks is
ever computed (YADE would otherwise intersect them every step).

Materials: PolyhedraMat with young = 2 K_n so that YADE's volumetric law gives
F_n = K_n V (its pair stiffness is young1 young2 / (young1 + young2)). With the
project's law (``penalty_coulomb``) frictionAngle = 0, which makes the stock law zero its
(shared, leaking) shear force every step, and the tangential force and all damping come
from ``contact_engine.PenaltyCoulomb``. With ``stock_volumetric`` the stock law does
everything: friction angle atan(mu), shear stiffness ks = K_t A_ref (N/m, per contact,
A_ref from the run specification) and no damping.
"""
from __future__ import annotations

import math

import yade
from yade import utils

DYNAMIC_MASK = 0b01
STATIC_MASK = 0b11  # shares bit 0b10 with every other non-moving body


def _material(mat: dict, law: str, stock_shear_area: float):
    young = 2.0 * mat["kn"]
    if law == "stock_volumetric":
        # Ip2: ks = (E nu)(E nu)/(E nu + E nu) = E nu / 2 = K_n nu  ->  nu = K_t A_ref / K_n
        nu = mat["kt"] * stock_shear_area / mat["kn"]
        phi = math.atan(mat["mu"])
    else:
        nu, phi = 0.5, 0.0  # nu unused (shear zeroed) but must be > 0: 0 gives NaN in Ip2
    return yade.PolyhedraMat(young=young, poisson=nu, density=mat["density"], frictionAngle=phi,
                             label=mat["name"])


def build(spec: dict, integrate: bool = True) -> dict:
    """Create materials, bodies and engines; return lookup tables. ``integrate=False``
    leaves NewtonIntegrator out of the engines (the compiled step moves the bodies).

    Returns dict with ``yid`` (block id -> YADE id), ``bid`` (YADE id -> block id),
    ``dynamic`` (list of YADE ids that move), ``newton`` (the NewtonIntegrator).
    """
    O = yade.Omega()
    O.reset()
    law = spec["law"]
    mats = {}
    for name, m in spec["materials"].items():
        ym = _material(dict(m, name=name), law, spec.get("stock_shear_area", 0.0))
        O.materials.append(ym)
        mats[name] = ym
    yid, bid, dynamic = {}, {}, []
    for b in spec["blocks"]:
        verts = [yade.Vector3(*p) for p in b["vertices"]]
        moving = b["role"] == "free"
        body = utils.polyhedron(verts, material=mats[b["material"]], fixed=not moving,
                                mask=DYNAMIC_MASK if moving else STATIC_MASK)
        if moving and b.get("blocked_dofs"):
            body.state.blockedDOFs = b["blocked_dofs"]
        i = O.bodies.append(body)
        yid[b["id"]] = i
        bid[i] = b["id"]
        if moving:
            dynamic.append(i)
    newton = yade.NewtonIntegrator(damping=0.0, gravity=(0, 0, 0), label="newton")
    step = yade.PyRunner(iterPeriod=1, command="_drystone_step()", label="drystone_step")
    if spec["detection"] == "native":
        # contacts and all their forces come from contact_engine.PenaltyCoulomb (native)
        O.engines = [yade.ForceResetter(), step, newton] if integrate else [yade.ForceResetter(), step]
    else:
        O.engines = [
            yade.ForceResetter(),
            yade.InsertionSortCollider([yade.Bo1_Polyhedra_Aabb()], avoidSelfInteractionMask=0b10,
                                       verletDist=spec.get("verlet_dist", 0.0)),
            yade.InteractionLoop([yade.Ig2_Polyhedra_Polyhedra_PolyhedraGeom()],
                                 [yade.Ip2_PolyhedraMat_PolyhedraMat_PolyhedraPhys()],
                                 [yade.Law2_PolyhedraGeom_PolyhedraPhys_Volumetric()]),
            step,
            newton,
        ]
    O.dt = spec["dt"]
    return {"yid": yid, "bid": bid, "dynamic": dynamic, "newton": newton}
