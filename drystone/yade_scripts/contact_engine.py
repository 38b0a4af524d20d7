"""Per-contact tangential force and damping for polyhedra, run every step before
NewtonIntegrator (inside YADE only). The law itself is ``drystone.contact``; this module
gathers YADE's contact geometry into arrays, calls it, and applies the forces.

Why not the stock law alone: ``Law2_PolyhedraGeom_PolyhedraPhys_Volumetric`` (YADE
2023.02a) keeps the running shear force in one member of the functor, shared by all
contacts, so shear history leaks from one contact to another, and it has no damping.
Its volumetric normal force (K_n V at the overlap centroid) is right and is kept.

Forces per contact: the elastic normal force K_n V at the overlap centroid c (applied by
YADE's law with ``detection = yade``, here with ``native``), the shear spring at c, and
the damping wrench distributed over the contact patch, at the patch centroid p
(``drystone.contact``: force and moment).
"""
from __future__ import annotations

import numpy as np
import yade

from drystone import contact as law
from drystone import overlap as ov
from drystone.geometry import polyhedron as ph


def _padded(rows) -> np.ndarray:
    """Stack lists of 3-vectors of different lengths, padding with the first entry."""
    n = max(len(r) for r in rows)
    out = np.zeros((len(rows), n, 3))
    for i, r in enumerate(rows):
        r = np.asarray(r, float)
        out[i, : len(r)] = r
        out[i, len(r):] = r[0]
    return out


class ContactState:
    """Arrays describing the contacts of the current step (forces act on body B = id2)."""

    def __init__(self):
        self.clear()

    def clear(self):
        self.id1 = np.zeros(0, int)
        self.id2 = np.zeros(0, int)
        self.normal = np.zeros((0, 3))
        self.point = np.zeros((0, 3))
        self.volume = np.zeros(0)
        self.area = np.zeros(0)
        self.fn = np.zeros(0)  # elastic normal force magnitude, N
        self.f_extra = np.zeros((0, 3))  # this law's force on B (damping + shear), N
        self.shear = np.zeros((0, 3))  # total tangential force on B, N
        self.slipping = np.zeros(0, bool)

    def force_on_b(self) -> np.ndarray:
        """Total contact force on body B (N): elastic normal + this law's part."""
        return self.fn[:, None] * self.normal + self.f_extra


class PenaltyCoulomb:
    """The project's contact law, stateful over steps.

    ``pairs(id1, id2) -> dict(kn, kt, mu, damping)`` gives joint properties by YADE ids;
    ``mass`` (n_bodies,) kg with inf for non-moving bodies.

    Contact geometry (``detection``): ``native`` computes every overlap itself
    (``drystone.overlap``: exact volume and centroid, normal and area from the volume's
    gradient) and applies the normal force K_n V too, so YADE only integrates the motion;
    ``yade`` reads the overlaps of YADE's ``Ig2_Polyhedra_Polyhedra_PolyhedraGeom`` (CGAL)
    and YADE's volumetric law applies K_n V along YADE's normal, A_c being estimated from
    the overlap's extent (``drystone.contact.contact_area``).
    """

    def __init__(self, pair_props, mass, local_vertices, detection, inertia=None):
        self.pair_props = pair_props
        self.mass = np.asarray(mass, float)
        self.moving = np.isfinite(self.mass)
        # principal moments (kg m^2) in the body frame; non-moving bodies: no inverse
        inertia = np.ones((len(self.mass), 3)) if inertia is None else np.asarray(inertia, float)
        self.inv_inertia_local = np.where(self.moving[:, None], 1.0 / inertia, 0.0)
        self.inv_mass = np.where(self.moving, 1.0 / self.mass, 0.0)
        self.native = detection == "native"
        self.shapes = ov.Shapes(local_vertices)  # overlaps (native) and contact patches (both)
        if not self.native:  # for the contact-area estimate on YADE's geometry
            self.vloc = _padded(local_vertices)  # repeated entries leave min/max/argmax unchanged
            self.nloc = _padded([ph.faces(v).normals for v in local_vertices])
        self._shear: dict[tuple[int, int], np.ndarray] = {}
        self._props: dict[tuple[int, int], tuple] = {}
        self.state = ContactState()
        self.elastic = (0.0, 0.0)  # elastic energy (J) at the previous and current step
        #: largest omega dt of any contact mode so far (central differences are stable
        #: below 2 (sqrt(1 + xi^2) - xi))
        self.max_omega_dt = 0.0

    def _props_arrays(self, keys):
        out = []
        for k in keys:
            p = self._props.get(k)
            if p is None:
                d = self.pair_props(*k)
                p = (d["kn"], d["kt"], d["mu"], d["damping"])
                self._props[k] = p
            out.append(p)
        a = np.array(out, float).reshape(-1, 4)
        return a[:, 0], a[:, 1], a[:, 2], a[:, 3]

    def gather(self, O):
        """Read the real contacts with a positive overlap and the bodies' states."""
        rows = []
        for i in O.interactions:
            g = i.geom
            v = g.penetrationVolume
            if not (g.equivalentPenetrationDepth > law.MIN_DEPTH and v > 0):
                continue
            rows.append((i.id1, i.id2, v) + tuple(g.normal) + tuple(g.contactPoint))
        return np.array(rows, float).reshape(-1, 9)

    def _yade_geometry(self, O, bodies_state):
        """Overlaps from YADE's interactions: (ia, ib, volume, normal, point, area)."""
        rows = self.gather(O)
        # YADE may keep interactions between two non-moving bodies: no force, no geometry needed
        rows = rows[self.moving[rows[:, 0].astype(int)] | self.moving[rows[:, 1].astype(int)]]
        pos, vel, angvel, rot = bodies_state
        ia = rows[:, 0].astype(int)
        ib = rows[:, 1].astype(int)
        vol = rows[:, 2]
        n = rows[:, 3:6]
        c = rows[:, 6:9]
        if len(rows) == 0:
            return ia, ib, vol, n, c, np.zeros(0), np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3, 3))
        # contact area from the overlap extent along the joint's face normal
        # face normals in the global frame, then vertex projections x.m = x_local.(R^T m) + pos.m
        fa = np.matmul(self.nloc[ia], rot[ia].transpose(0, 2, 1))
        fb = np.matmul(self.nloc[ib], rot[ib].transpose(0, 2, 1))
        m, face_of_a = law.projection_direction(n, fa, fb)
        pa = np.matmul(self.vloc[ia], np.matmul(rot[ia].transpose(0, 2, 1), m[:, :, None]))[:, :, 0]
        pb = np.matmul(self.vloc[ib], np.matmul(rot[ib].transpose(0, 2, 1), m[:, :, None]))[:, :, 0]
        pa += law.dot(pos[ia], m)[:, None]
        pb += law.dot(pos[ib], m)[:, None]
        lo = np.maximum(pa.min(1), pb.min(1))
        hi = np.minimum(pa.max(1), pb.max(1))
        cm = law.dot(c, m)
        # the centroid's distance from the flat face the overlap presses into
        e = np.where(face_of_a, hi - cm, cm - lo)
        s = self.shapes
        pa, pc, pj = ov.patches_of_pairs(s.verts, s.nv, s.normals, s.offsets, s.nf, s.faces, s.fk, pos, rot,
                                         ia, ib, ov.TOL)
        return ia, ib, vol, n, c, law.contact_area(vol, hi - lo, e), pa, pc, pj

    def _native_geometry(self, bodies_state):
        """Overlaps computed here (drystone.overlap): (ia, ib, volume, normal, point, area,
        patch area, patch centroid, patch second moment)."""
        pos, _, _, rot = bodies_state
        s = self.shapes
        ia, ib, vol, c, n, area, pc, pj = ov.contacts_with_patches(s.verts, s.nv, s.normals, s.offsets, s.nf, s.faces,
                                                                   s.fk, pos, rot, self.moving, ov.TOL)
        return ia, ib, vol, n, c, area, area, pc, pj

    def step(self, O, bodies_state):
        """Compute and apply this step's forces. ``bodies_state``: (pos, vel, angvel, R)
        arrays over all bodies (m, m/s, rad/s, rotation matrices)."""
        if self.native:
            ia, ib, vol, n, c, area, parea, pc, pj = self._native_geometry(bodies_state)
        else:
            ia, ib, vol, n, c, area, parea, pc, pj = self._yade_geometry(O, bodies_state)
        st = self.state
        if len(ia) == 0:
            st.clear()
            self._shear = {}
            self.elastic = (self.elastic[1], 0.0)
            return
        pos, vel, angvel, rot = bodies_state
        keys = list(zip(ia.tolist(), ib.tolist()))
        kn, kt, mu, xi = self._props_arrays(keys)

        ra = c - pos[ia]
        rb = c - pos[ib]
        v_rel = (vel[ib] + law.cross(angvel[ib], rb)) - (vel[ia] + law.cross(angvel[ia], ra))
        fn = kn * vol
        fs_prev = np.array([self._shear.get(k, (0.0, 0.0, 0.0)) for k in keys], float).reshape(-1, 3)
        fs_new, slipping = law.shear_spring(n, v_rel, fs_prev, area, kt, mu, fn, O.dt)
        self._shear = dict(zip(keys, fs_new))

        # damping distributed over the patch, at its centroid p
        pa_, pb_ = pc - pos[ia], pc - pos[ib]
        twist = np.concatenate([(vel[ib] + law.cross(angvel[ib], pb_)) - (vel[ia] + law.cross(angvel[ia], pa_)),
                                angvel[ib] - angvel[ia]], axis=1)
        ia_inv = np.matmul(rot[ia] * self.inv_inertia_local[ia][:, None, :], rot[ia].transpose(0, 2, 1))
        ib_inv = np.matmul(rot[ib] * self.inv_inertia_local[ib][:, None, :], rot[ib].transpose(0, 2, 1))
        fd, md, om = law.damping_wrenches(n, parea, pj, kn, kt, xi, ~slipping, pa_, pb_, self.inv_mass[ia],
                                          self.inv_mass[ib], ia_inv, ib_inv, twist, fn, fs_new, mu, c - pc)
        self.max_omega_dt = max(self.max_omega_dt, float(om.max()) * O.dt)
        f_b = fs_new + fd  # the force this law adds on B besides K_n V (resultant)

        st.id1, st.id2, st.normal, st.point, st.volume = ia, ib, n, c, vol
        st.area, st.fn, st.f_extra, st.shear, st.slipping = area, fn, f_b, fs_new + fd - law.dot(fd, n)[:, None] * n, slipping
        ok = area > 0
        e_el = float(np.sum(0.5 * fn[ok] * vol[ok] / area[ok])
                     + np.sum(np.sum(fs_new[ok] ** 2, axis=1) / (2.0 * kt[ok] * area[ok])))
        self.elastic = (self.elastic[1], e_el)

        # the forces applied here: shear spring at c, damping at p (+ its moment), and with
        # native detection the elastic normal force at c too
        f_c = fs_new + fn[:, None] * n if self.native else fs_new
        nb = len(self.mass)
        idx = np.concatenate([ib, ia])
        F = np.concatenate([f_c + fd, -(f_c + fd)])
        T = np.concatenate([law.cross(rb, f_c) + law.cross(pb_, fd) + md, -law.cross(ra, f_c) - law.cross(pa_, fd) - md])
        Fs = np.stack([np.bincount(idx, F[:, k], nb) for k in range(3)], 1)
        Ts = np.stack([np.bincount(idx, T[:, k], nb) for k in range(3)], 1)
        V3 = yade.Vector3
        for i in np.flatnonzero(self.moving & (np.bincount(idx, minlength=nb) > 0)).tolist():
            O.forces.addF(i, V3(*Fs[i].tolist()))
            O.forces.addT(i, V3(*Ts[i].tolist()))


def stock_contacts(O) -> ContactState:
    """Contact forces of YADE's stock volumetric law, read back for recording."""
    st = ContactState()
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
