"""Per-contact tangential force and damping for polyhedra, run every step before
NewtonIntegrator (inside YADE only). The law itself is ``drystone.mechanics.contact``; this module
gathers YADE's contact geometry into arrays, calls it, and applies the forces.

Why not the stock law alone: ``Law2_PolyhedraGeom_PolyhedraPhys_Volumetric`` (YADE
2023.02a) keeps the running shear force in one member of the functor, shared by all
contacts, so shear history leaks from one contact to another, and it has no damping.
Its volumetric normal force (K_n V at the overlap centroid) is right and is kept.

Forces per contact: the elastic normal force K_n V at the overlap centroid c (applied by
YADE's law with ``detection = yade``, here with ``native``), the shear spring at c, and
the damping wrench distributed over the contact patch, at the patch centroid p
(``drystone.mechanics.contact``: force and moment).
"""
from __future__ import annotations

import numpy as np
import yade

from drystone.mechanics import contact as law
from drystone.mechanics import contact_step as cs
from drystone.mechanics.contact_step import ContactState  # noqa: F401 (recording reads it from here)


class PenaltyCoulomb(cs.NumpyStep):
    """The project's law in numpy (``drystone.mechanics.contact_step.NumpyStep``) on YADE's
    contact geometry or the native one; forces applied body by body."""

    def gather(self, O):
        """Read the real contacts with a positive overlap (rows: id1, id2, volume, normal, point)."""
        rows = []
        for i in O.interactions:
            g = i.geom
            v = g.penetrationVolume
            if not (g.equivalentPenetrationDepth > law.MIN_DEPTH and v > 0):
                continue
            rows.append((i.id1, i.id2, v) + tuple(g.normal) + tuple(g.contactPoint))
        return np.array(rows, float).reshape(-1, 9)

    def step(self, O, bodies_state):
        """Compute and apply this step's forces (``bodies_state``: pos, vel, angvel, R)."""
        geo = self.native_geometry(bodies_state) if self.native else self.yade_geometry(self.gather(O), bodies_state)
        apply(O, *self.forces(geo, bodies_state, O.dt), self.moving)


class Compiled(cs.CompiledStep):
    """The compiled step (``drystone.mechanics.contact_step.CompiledStep``, native geometry), its
    contacts exposed as a ``ContactState`` for recording."""

    def step(self, O, bodies_state, apply_forces=True):
        """This step's forces (nb, 3) and torques; applied to YADE's bodies unless the
        caller integrates the motion itself (``apply_forces=False``)."""
        pos, vel, angvel, rot = bodies_state
        F, T = self.forces(pos, rot, vel, angvel, O.dt)
        if apply_forces:
            apply(O, F, T, self.moving)
        return F, T


def apply(O, F, T, moving):
    """Add forces and torques (nb, 3) to YADE's moving bodies that have any (one call per body)."""
    V3 = yade.Vector3
    for i in np.flatnonzero(moving & (np.any(F != 0.0, axis=1) | np.any(T != 0.0, axis=1))).tolist():
        O.forces.addF(i, V3(*F[i].tolist()))
        O.forces.addT(i, V3(*T[i].tolist()))


def stock_contacts(O) -> ContactState:
    """Contact forces of YADE's stock volumetric law, read back for recording."""
    st = cs.ContactState()
    rows = []
    for i in O.interactions:
        g, p = i.geom, i.phys
        if not (g.equivalentPenetrationDepth > law.MIN_DEPTH and g.penetrationVolume > 0):
            continue
        rows.append((i.id1, i.id2, g.penetrationVolume) + tuple(g.normal) + tuple(g.contactPoint)
                    + tuple(p.normalForce) + tuple(p.shearForce))
    if not rows:
        return st
    r = np.array(rows, float)
    st.id1, st.id2, st.volume = r[:, 0].astype(int), r[:, 1].astype(int), r[:, 2]
    st.normal, st.point = r[:, 3:6], r[:, 6:9]
    st.fn = np.linalg.norm(r[:, 9:12], axis=1)
    st.shear = r[:, 12:15]
    st.f_extra = st.shear
    st.area = np.full(len(r), np.nan)
    st.slipping = np.zeros(len(r), bool)
    return st
