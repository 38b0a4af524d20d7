"""The compiled contact step: geometry, law, damping and the bodies' motion in numba over
arrays (no YADE import). ``drystone/yade_scripts/contact_engine.py`` runs it inside YADE.

One call of ``CompiledStep.forces`` does what ``contact_engine.PenaltyCoulomb.step`` does
with numpy (the reference: ``tests/test_compiled_step.py`` checks that both give the same
forces, shear histories and damping to 1e-9): find the overlaps (``drystone.mechanics.overlap``),
match each contact with its shear force of the previous step (contacts are keyed by the
pair of body indices and come out sorted, so one merge walk matches them), apply the
penalty–Coulomb law and the patch damping (``drystone.mechanics.contact``), and sum the forces and
torques on every body (the work per contact and per body: ``drystone.mechanics.contact_rows``,
on numba's threads). ``drystone.mechanics.integration.integrate`` then advances the
bodies one leapfrog step as YADE's NewtonIntegrator does; ``CompiledStep.advance`` runs
contact steps and integration one after another in one call. Every step also adds to the
energy balance (``drystone.mechanics.energy``: the loads' work, the damping's and the slip's
dissipation; the contacts' elastic energy at the steps a sample records), in both steps.

Units SI; quaternions (x, y, z, w) like YADE's; body arrays indexed by YADE body id.
"""
from __future__ import annotations

import numba
import numpy as np
from numba import njit

from drystone.mechanics import contact as law
from drystone.mechanics import contact_rows as rows
from drystone.mechanics import energy
from drystone.mechanics import neighbours as nbr
from drystone.mechanics import overlap as ov
from drystone.mechanics.integration import integrate
from drystone.geometry import polyhedron as ph
from drystone import numba_cache

numba_cache.install()  # numba's cache safe for processes compiling at once


# -- the numpy reference ---------------------------------------------------------------

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


class NumpyStep:
    """The project's contact law in numpy, stateful over steps (the reference for
    ``CompiledStep``).

    ``pairs(id1, id2) -> dict(kn, kt, mu, damping)`` gives joint properties by YADE ids;
    ``mass`` (n_bodies,) kg with inf for non-moving bodies; ``local_vertices`` per shape
    in its body's frame and ``owner`` (ns,) each shape's body (default: one shape per
    body), as ``CompiledStep``'s (native detection only: YADE's geometry is per body).

    Contact geometry (``detection``): ``native`` computes every overlap itself
    (``drystone.mechanics.overlap``: exact volume and centroid, normal and area from the volume's
    gradient) and applies the normal force K_n V too, so YADE only integrates the motion;
    ``yade`` reads the overlaps of YADE's ``Ig2_Polyhedra_Polyhedra_PolyhedraGeom`` (CGAL)
    and YADE's volumetric law applies K_n V along YADE's normal, A_c being estimated from
    the overlap's extent (``drystone.mechanics.contact.contact_area``).
    """

    def __init__(self, pair_props, mass, local_vertices, detection, inertia=None, owner=None, area_scaling=False):
        self.pair_props = pair_props
        self.area_scaling = area_scaling  # the carried force scaled by the patch (contact.carried_share)
        self.mass = np.asarray(mass, float)
        self.moving = np.isfinite(self.mass)
        # principal moments (kg m^2) in the body frame; non-moving bodies: no inverse
        inertia = np.ones((len(self.mass), 3)) if inertia is None else np.asarray(inertia, float)
        self.inv_inertia_local = np.where(self.moving[:, None], 1.0 / inertia, 0.0)
        self.inv_mass = np.where(self.moving, 1.0 / self.mass, 0.0)
        self.native = detection == "native"
        self.shapes = ov.Shapes(local_vertices)  # overlaps (native) and contact patches (both)
        ns = len(local_vertices)
        self.owner = np.arange(ns, dtype=np.int64) if owner is None else np.asarray(owner, np.int64)
        self.shared = len(np.unique(self.owner)) < ns  # a body of several shapes
        if not (self.native or np.array_equal(self.owner, np.arange(len(self.mass)))):
            raise ValueError("YADE's contact geometry takes one convex shape per body (no parts)")
        if not self.native:  # for the contact-area estimate on YADE's geometry
            self.vloc = _padded(local_vertices)  # repeated entries leave min/max/argmax unchanged
            self.nloc = _padded([ph.faces(v).normals for v in local_vertices])
        self._shear: dict[tuple[int, int], np.ndarray] = {}
        self._props: dict[tuple[int, int], tuple] = {}
        self.state = ContactState()
        self.elastic = (0.0, 0.0)  # elastic energy (J) at the previous and current step
        #: the last step's terms of the energy balance (drystone.mechanics.energy): the damping
        #: wrenches summed on each body ``Fd``, ``Td`` (nb, 3), every contact force ``F`` on
        #: each body (nb, 3, YADE's normal force too) and the slip work ``slip`` (J)
        nb = len(self.mass)
        self.last = {"Fd": np.zeros((nb, 3)), "Td": np.zeros((nb, 3)), "F": np.zeros((nb, 3)), "slip": 0.0}
        #: largest omega dt of any contact mode so far (central differences are stable
        #: below 2 (sqrt(1 + xi^2) - xi))
        self.max_omega_dt = 0.0

    def retire(self, shapes) -> None:
        """Take ``shapes`` (a mask or indices) out of the contact search (non-finite vertices)."""
        self.shapes.verts[shapes] = np.nan

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

    def yade_geometry(self, rows, bodies_state):
        """Overlaps from YADE's interactions (``rows`` (m, 9): id1, id2, volume, normal,
        point): (ia, ib, volume, normal, point, area, patch area, centroid, second moment,
        the contacts' keys)."""
        rows = np.asarray(rows, float).reshape(-1, 9)
        # YADE may keep interactions between two non-moving bodies: no force, no geometry needed
        rows = rows[self.moving[rows[:, 0].astype(int)] | self.moving[rows[:, 1].astype(int)]]
        pos, vel, angvel, rot = bodies_state
        ia = rows[:, 0].astype(int)
        ib = rows[:, 1].astype(int)
        vol = rows[:, 2]
        n = rows[:, 3:6]
        c = rows[:, 6:9]
        if len(rows) == 0:
            return ia, ib, vol, n, c, np.zeros(0), np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3, 3)), []
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
        return ia, ib, vol, n, c, law.contact_area(vol, hi - lo, e), pa, pc, pj, list(zip(ia.tolist(), ib.tolist()))

    def peek(self, geometry, bodies_state, dt) -> tuple[float, float]:
        """(elastic energy J, slip work J) of a step from ``geometry`` and ``bodies_state``
        (as ``forces``), this object's state unchanged (``CompiledStep.peek``)."""
        kept = (self._shear, self.state, self.elastic, self.last, self.max_omega_dt)
        self.state = ContactState()
        self.forces(geometry, bodies_state, dt)
        out = self.elastic[1], self.last["slip"]
        self._shear, self.state, self.elastic, self.last, self.max_omega_dt = kept
        return out

    def native_geometry(self, bodies_state):
        """Overlaps computed here (drystone.mechanics.overlap): (ia, ib (bodies), volume, normal,
        point, area, patch area, patch centroid, patch second moment, the contacts' keys: their
        pairs of shapes)."""
        pos, _, _, rot = bodies_state
        s = self.shapes
        sa, sb, vol, c, n, area, pc, pj = ov.contacts_of_shapes(s.verts, s.nv, s.normals, s.offsets, s.nf, s.faces,
                                                                s.fk, self.owner, pos, rot, self.moving, ov.TOL)
        keys = list(zip(sa.tolist(), sb.tolist()))
        return self.owner[sa], self.owner[sb], vol, n, c, area, area, pc, pj, keys

    def forces(self, geometry, bodies_state, dt):
        """This step's contact forces and torques (nb, 3) on every body (N, N m), from
        ``geometry`` (``native_geometry`` or ``yade_geometry``) and ``bodies_state``
        (pos, vel, angvel, R) over all bodies (m, m/s, rad/s, rotation matrices). With
        YADE's geometry the elastic normal force is applied by YADE's law, not here."""
        ia, ib, vol, n, c, area, parea, pc, pj, keys = geometry
        st = self.state
        nb = len(self.mass)
        if len(ia) == 0:
            st.clear()
            self._shear = {}
            self.elastic = (self.elastic[1], 0.0)
            self.last = {"Fd": np.zeros((nb, 3)), "Td": np.zeros((nb, 3)), "F": np.zeros((nb, 3)), "slip": 0.0}
            return np.zeros((nb, 3)), np.zeros((nb, 3))
        pos, vel, angvel, rot = bodies_state
        kn, kt, mu, xi = self._props_arrays(list(zip(ia.tolist(), ib.tolist())))
        if self.shared:  # a body of several shapes: its joints' contacts share the damping ratio
            xi = xi * law.joint_share(ia, ib, nb, area)

        ra = c - pos[ia]
        rb = c - pos[ib]
        v_rel = (vel[ib] + law.cross(angvel[ib], rb)) - (vel[ia] + law.cross(angvel[ia], ra))
        fn = kn * vol
        # each contact's history: its shear force (N) and twisting moment about n (N m)
        # (with ``area_scaling``, its area A_c and polar moment J_p too: contact.carried_share)
        ncol = 6 if self.area_scaling else 4
        hist = np.array([self._shear.get(k, (0.0,) * ncol) for k in keys], float).reshape(-1, ncol)
        fs_prev = hist[:, :3]
        jp = np.array([law.polar_moment(n[k], pj[k]) for k in range(len(ia))])
        slip = 0.0
        if self.area_scaling:
            for k in range(len(ia)):
                r, e_drop = law.carried_share(hist[k, 4], area[k], float(fs_prev[k] @ fs_prev[k]), kt[k])
                rj, e_twist = law.carried_share(hist[k, 5], jp[k], hist[k, 3] ** 2, kt[k])
                fs_prev[k] *= r
                hist[k, 3] *= rj
                slip += e_drop + e_twist
        fs_new, slipping = law.shear_spring(n, v_rel, fs_prev, area, kt, mu, fn, dt)
        # the slip's plastic work: the elastic trial of shear_spring against its capped force
        f0 = law.rotate_into_plane(fs_prev, n)
        f_trial = f0 - (kt * area)[:, None] * (v_rel - law.dot(v_rel, n)[:, None] * n) * dt
        slip += float(np.sum(energy.slip_work(f0, f_trial, fs_new, kt, area)))
        # the twist spring on the patch (contact.twist_spring)
        wn = law.dot(angvel[ib] - angvel[ia], n)
        fs_mag = np.linalg.norm(fs_new, axis=1)
        tw = [law.twist_spring(hist[k, 3], wn[k], jp[k], parea[k], kt[k], mu[k], fn[k], fs_mag[k], dt)
              for k in range(len(ia))]
        mt = np.array([t[0] for t in tw])
        slip += float(sum(t[1] for t in tw))
        kept = [fs_new, mt[:, None]] + ([area[:, None], jp[:, None]] if self.area_scaling else [])
        self._shear = dict(zip(keys, np.concatenate(kept, axis=1)))

        # damping distributed over the patch, at its centroid p
        pa_, pb_ = pc - pos[ia], pc - pos[ib]
        twist = np.concatenate([(vel[ib] + law.cross(angvel[ib], pb_)) - (vel[ia] + law.cross(angvel[ia], pa_)),
                                angvel[ib] - angvel[ia]], axis=1)
        ia_inv = np.matmul(rot[ia] * self.inv_inertia_local[ia][:, None, :], rot[ia].transpose(0, 2, 1))
        ib_inv = np.matmul(rot[ib] * self.inv_inertia_local[ib][:, None, :], rot[ib].transpose(0, 2, 1))
        fd, md, om = law.damping_wrenches(n, parea, pj, kn, kt, xi, ~slipping, pa_, pb_, self.inv_mass[ia],
                                          self.inv_mass[ib], ia_inv, ib_inv, twist, fn, fs_new, mu, c - pc)
        self.max_omega_dt = max(self.max_omega_dt, float(om.max()) * dt)
        f_b = fs_new + fd  # the force this law adds on B besides K_n V (resultant)

        st.id1, st.id2, st.normal, st.point, st.volume = ia, ib, n, c, vol
        st.area, st.fn, st.f_extra, st.shear, st.slipping = area, fn, f_b, fs_new + fd - law.dot(fd, n)[:, None] * n, slipping
        ok = area > 0
        sa, sb = (np.array([k[0] for k in keys], int), np.array([k[1] for k in keys], int)) if self.native else (ia, ib)
        sa, sb = sa[ok], sb[ok]
        sh = self.shapes
        e_el = float(np.sum(energy.normal_energies(kn[ok], vol[ok], c[ok], n[ok], sh.normals[sa], sh.offsets[sa],
                                                   sh.normals[sb], sh.offsets[sb], rot[ia[ok]], rot[ib[ok]],
                                                   pos[ia[ok]], pos[ib[ok]]))
                     + np.sum(np.sum(fs_new[ok] ** 2, axis=1) / (2.0 * kt[ok] * area[ok]))
                     + np.sum(np.divide(mt ** 2, 2.0 * kt * jp, out=np.zeros_like(mt), where=kt * jp > 0)[ok]))
        self.elastic = (self.elastic[1], e_el)

        # the forces applied here: shear spring at c, damping at p (+ its moment), and with
        # native detection the elastic normal force at c too
        f_c = fs_new + fn[:, None] * n if self.native else fs_new
        idx = np.concatenate([ib, ia])
        F = np.concatenate([f_c + fd, -(f_c + fd)])
        m_t = mt[:, None] * n  # the twisting moment on B
        T = np.concatenate([law.cross(rb, f_c) + law.cross(pb_, fd) + md + m_t,
                            -law.cross(ra, f_c) - law.cross(pa_, fd) - md - m_t])
        Fs = np.stack([np.bincount(idx, F[:, k], nb) for k in range(3)], 1)
        Ts = np.stack([np.bincount(idx, T[:, k], nb) for k in range(3)], 1)

        def on_bodies(x):
            return np.stack([np.bincount(idx, x[:, k], nb) for k in range(3)], 1)

        md_b = law.cross(pb_, fd) + md
        md_a = law.cross(pa_, fd) + md
        F_all = Fs if self.native else Fs + on_bodies(np.concatenate([fn[:, None] * n, -fn[:, None] * n]))
        self.last = {"Fd": on_bodies(np.concatenate([fd, -fd])), "Td": on_bodies(np.concatenate([md_b, -md_a])),
                     "F": F_all, "slip": slip}
        return Fs, Ts


# -- contact forces -------------------------------------------------------------------

@njit(cache=True)
def _previous(keys, prev_keys):
    """Index of each contact among the previous step's (-1 for a new contact); both key
    arrays sorted ascending (one merge walk)."""
    m = len(keys)
    out = np.full(m, -1, np.int64)
    j = 0
    for c in range(m):
        while j < len(prev_keys) and prev_keys[j] < keys[c]:
            j += 1
        if j < len(prev_keys) and prev_keys[j] == keys[c]:
            out[c] = j
    return out


class CompiledStep:
    """The project's law (native contact geometry) as one compiled call per step.

    ``mass`` (nb,) kg, inf for non-moving bodies; ``inertia`` (nb, 3) principal moments in
    the body frame, kg m^2; ``local_vertices`` per shape (a convex body, or a convex part
    of a non-convex one) in its body's frame, m; ``owner`` (ns,) the body of each shape
    (default: shape i is body i); ``material`` (nb,) index into ``table`` (nm, nm, 4): kn,
    kt (N/m^3), mu, damping of each pair of materials; ``joints`` {(ia, ib): (kn, kt, mu,
    damping)} overrides for pairs of bodies; ``size`` (ns,) each shape's smallest
    dimension (m): ``depth_ratio`` is the largest contact depth V/A over the smaller size
    of its two shapes (the tunnelling check, ``drystone.mechanics.stability``). A
    contact is a pair of shapes of different bodies, its shear history kept per pair of
    shapes; its forces act on the shapes' bodies. ``state`` is the last step's contacts
    as a ``ContactState`` (built when asked for; ids of bodies). ``skin`` (m): the
    neighbour list's (``drystone.mechanics.neighbours``; ``neighbours``). ``threads``: the
    threads the shapes' placement, the contact search's clip, the law, the damping and the
    sums on the bodies run on (``drystone.mechanics.contact_rows``; 1 by default; at most numba's,
    ``numba.config.NUMBA_NUM_THREADS``, the machine's cores unless set: more are not
    started); every result is the same bit for bit for any number (``neighbours.search``)."""

    def __init__(self, mass, inertia, local_vertices, material, table, joints=None, size=None, owner=None,
                 skin=nbr.SKIN, area_scaling=False, threads: int = 1):
        if int(threads) != threads or threads < 1:
            raise ValueError(f"threads {threads!r}: a whole number >= 1")
        self.threads = min(int(threads), max(1, int(numba.config.NUMBA_NUM_THREADS)))
        self.mass = np.asarray(mass, float)
        self.moving = np.isfinite(self.mass)
        self.inv_mass = np.where(self.moving, 1.0 / np.where(self.moving, self.mass, 1.0), 0.0)
        inertia = np.asarray(inertia, float)
        self.inv_inertia_local = np.where(self.moving[:, None], 1.0 / inertia, 0.0)
        self.shapes = ov.Shapes(local_vertices)
        ns = len(local_vertices)
        self.owner = np.arange(ns, dtype=np.int64) if owner is None else np.asarray(owner, np.int64)
        self.shared = len(np.unique(self.owner)) < ns  # a body of several shapes
        self.material = np.asarray(material, np.int64)
        self.table = np.asarray(table, float)
        nb = len(self.mass)
        joints = joints or {}
        keys = sorted((min(a, b) * nb + max(a, b), tuple(v)) for (a, b), v in joints.items())
        self.jkeys = np.array([k for k, _ in keys], np.int64)
        self.jvals = np.array([v for _, v in keys], float).reshape(-1, 4)
        self.keys = np.zeros(0, np.int64)
        # shear force (N) and twisting moment (N m) per contact; with ``area_scaling`` (the
        # carried force scaled by the patch, contact.carried_share) its area and polar moment too
        self.shear_store = np.zeros((0, 6 if area_scaling else 4))
        self.basis_store = np.zeros((0, 6, 6))  # each contact's damping modes (contact.damping_wrenches_warm)
        self.size = np.full(ns, np.inf) if size is None else np.asarray(size, float)
        self.depth_ratio = 0.0
        self._raw = None
        self._state = None
        self.elastic = (0.0, 0.0)
        self.max_omega_dt = 0.0
        #: the energy accumulators (W_loads, D_damp, D_fric), J from the start (drystone.mechanics.energy)
        self.energy = np.zeros(3)
        #: the last step's damping wrenches summed on each body ``Fd``, ``Td`` (nb, 3) and slip work ``slip`` (J)
        self.last = {"Fd": np.zeros((nb, 3)), "Td": np.zeros((nb, 3)), "slip": 0.0}
        #: the contact search's neighbour list and its buffers
        self.neighbours = nbr.NeighbourList(self.shapes, self.owner, self.moving, nb, skin)
        # ``_advance``'s arguments for no step (``_contacts``): g, F_ext, the loads' (no column); the
        # accumulators; the motion's, unread but of the types ``advance`` is given (one compiled kernel)
        self._idle = (np.zeros((0, 3)), np.zeros((nb, 3))) + self._no_loads(0)
        self._idle_acc = np.zeros(3)
        self._idle_motion = (np.ones(nb), np.ones((nb, 3)), np.zeros((nb, 3)), np.zeros((nb, 3)), np.zeros(nb, np.bool_),
                             np.zeros((nb, 3)), np.tile([0.0, 0.0, 0.0, 1.0], (nb, 1)))

    def retire(self, shapes) -> None:
        """Take ``shapes`` (a mask or indices) out of the contact search: their vertices
        made non-finite, the neighbour list rebuilt before the next step."""
        self.shapes.verts[shapes] = np.nan
        self.neighbours.invalidate()

    def _search_state(self) -> tuple:
        """The neighbour list's arrays and the search's buffers, one tuple (the kernels take them one
        by one: the note above ``_advance``)."""
        numba.set_num_threads(self.threads)  # the search's (numba's setting is per calling thread)
        nl = self.neighbours
        return nl.arrays + nl.contacts

    def _keep_search_state(self, arrays, contacts) -> None:
        self.neighbours.arrays, self.neighbours.contacts = arrays, contacts

    def _keep_raw(self, raw) -> None:
        """The last step's contacts for ``state`` (copies: the search's buffers are reused)."""
        self._raw = tuple(np.array(x) for x in raw)
        self._state = None

    def _contacts(self, pos, rot, vel, angvel, dt) -> tuple:
        """``_advance`` asked for no step: the contacts and forces of the state given, the
        neighbour list kept, the rest of this object unchanged. Returns (ia, ib, vol, c, n,
        area, fn, fs, fd, slipping, keys, basis, F, T, e_prev, e_last, om_max, depth_ratio,
        slip, Fd, Td)."""
        s = self.shapes
        out = _advance(
            s.verts, s.nv, s.normals, s.offsets, s.nf, s.faces, s.fk, self.owner, pos, rot, vel, angvel, self.moving,
            self.inv_mass, self.inv_inertia_local, self.material, self.table, self.jkeys, self.jvals, self.keys,
            self.shear_store, self.basis_store, dt, ov.TOL, self.size, self.shared, *self._idle,
            self.elastic[1], self._idle_acc, *self._idle_motion, *self._search_state())
        self._keep_search_state(out[-2], out[-1])
        return out[1:-2]

    def forces(self, pos, rot, vel, angvel, dt):
        """Contact forces and torques (nb, 3) on every body (N, N m) for the state given;
        updates the shear history, ``state``, ``elastic``, ``max_omega_dt`` and half of the
        step's slip work in ``energy`` (the rest and the work: ``account`` once the step is
        integrated)."""
        (ia, ib, vol, c, n, area, fn, fs, fd, slipping, keys, basis, F, T, _, e_el, om_max, self.depth_ratio, slip, Fd,
         Td) = self._contacts(pos, rot, vel, angvel, dt)
        self.keys, self.shear_store, self.basis_store = keys, fs, basis
        self.elastic = (self.elastic[1], e_el)
        self.max_omega_dt = max(self.max_omega_dt, om_max * dt)
        self._keep_raw((ia, ib, vol, c, n, area, fn, fs, fd, slipping))
        self.energy[2] += 0.5 * slip
        self.last = {"Fd": Fd, "Td": Td, "slip": slip}
        return F, T

    def peek(self, pos, rot, vel, angvel, dt) -> tuple[float, float]:
        """(elastic energy J, slip work J) of the next step from the state given, the
        state of this object unchanged: the last sample of a run, after its last step,
        centres its energies at that step's end (drystone.mechanics.energy)."""
        out = self._contacts(pos, rot, vel, angvel, dt)
        return float(out[15]), float(out[18])

    def account(self, dt, g, F, T, F_ext, lin_free, v0, w0, v1, w1, loads=None):
        """Add the step last computed by ``forces``, now integrated with the forces F, T
        (nb, 3) (contact plus applied F_ext, plus the loads' wrench) and body acceleration g
        (3,), to ``energy``: the velocities (nb, 3) before (v0, w0) and after it (v1, w1),
        lin_free (nb, 3) the free directions (drystone.mechanics.energy.account); ``loads``:
        None or (c (J,), Fb, Tb, rot_free) of the wrench added to F, T (``applied_wrench``),
        whose work is added too (drystone.mechanics.energy.load_work)."""
        Fd, Td, slip = self.last["Fd"], self.last["Td"], self.last["slip"]
        energy.account(dt, np.asarray(g, float), F, T, Fd, Td, F_ext, self.moving, np.where(self.moving, self.mass, 1.0),
                       lin_free, v0, w0, v1, w1, 0.5 * slip, self.energy)
        if loads is not None and len(loads[0]):
            c, Fb, Tb, rot_free = loads
            self.energy[0] += energy.load_work(dt, c, Fb, Tb, self.moving, lin_free, rot_free, v0, w0, v1, w1)

    def advance(self, pos, rot, vel, angvel, dt, g, F_ext, motion, loads=None):
        """Steps one after another, each as ``forces`` then ``integrate`` (in place), with
        the body accelerations ``g`` (n, 3) m/s^2 of the steps and the external forces
        ``F_ext`` (nb, 3) N added to the contact forces of each; ``loads``: None or (c (n, J),
        Fb (J, nb, 3) N, Tb (J, nb, 3) N m), the wrench sum_j c[s, j] (Fb[j], Tb[j]) added at
        step s (``applied_wrench``) and its work to the energy balance. ``motion``: the remaining
        arguments of ``integrate`` (mass, inertia, lin_free, rot_free, aspherical, angmom,
        quat). Stops before integrating a step whose contact depth ratio exceeds 1 (the
        caller checks it). Returns (steps completed, F, T of the last step computed, that
        step integrated?); ``state``, ``elastic``, ``max_omega_dt``, ``depth_ratio`` and the
        shear history as after the same calls of ``forces``, and ``energy`` as after those of
        ``forces`` and ``account`` (a step not integrated: half its slip work, as ``forces``),
        except ``elastic[0]`` after a call stopped on the depth check before its last two
        steps: NaN (the elastic energy is summed at the last two steps only, ``_advance``)."""
        s = self.shapes
        coef, Fb, Tb = self._no_loads(len(g)) if loads is None else loads
        (done, ia, ib, vol, c, n, area, fn, fs, fd, slipping, keys, basis, F, T, e_prev, e_last, om_max,
         self.depth_ratio, slip, Fd, Td, nl, buf) = _advance(
            s.verts, s.nv, s.normals, s.offsets, s.nf, s.faces, s.fk, self.owner, pos, rot, vel, angvel, self.moving,
            self.inv_mass, self.inv_inertia_local, self.material, self.table, self.jkeys, self.jvals, self.keys,
            self.shear_store, self.basis_store, dt, ov.TOL, self.size, self.shared, g, F_ext, coef, Fb, Tb,
            self.elastic[1], self.energy, *motion, *self._search_state())
        self._keep_search_state(nl, buf)
        self.last = {"Fd": Fd, "Td": Td, "slip": slip}
        self.keys, self.shear_store, self.basis_store = keys, fs, basis
        self.elastic = (e_prev, e_last)
        self.max_omega_dt = max(self.max_omega_dt, om_max * dt)
        self._keep_raw((ia, ib, vol, c, n, area, fn, fs, fd, slipping))
        return done, F, T, done == len(g)

    def _no_loads(self, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The ``loads`` of ``advance`` when there are none (no column: nothing is added)."""
        nb = len(self.mass)
        return np.zeros((n, 0)), np.zeros((0, nb, 3)), np.zeros((0, nb, 3))

    @property
    def state(self) -> ContactState:
        if self._state is None:
            st = ContactState()
            if self._raw is not None and len(self._raw[0]):
                ia, ib, vol, c, n, area, fn, fs, fd, slipping = self._raw
                st.id1, st.id2, st.normal, st.point, st.volume, st.area, st.fn = (self.owner[ia], self.owner[ib], n, c,
                                                                                  vol, area, fn)
                st.f_extra = fs[:, :3] + fd
                st.shear = fs[:, :3] + fd - law.dot(fd, n)[:, None] * n
                st.slipping = slipping
            self._state = st
        return self._state


# -- many steps in one call ----------------------------------------------------------

@njit(cache=True)
def applied_wrench(c, Fb, Tb, F, T):
    """Add the loads' wrench sum_j c[j] Fb[j] to F and sum_j c[j] Tb[j] to T (nb, 3), in
    place: c (J,) the step's coefficients, Fb (J, nb, 3) N and Tb (J, nb, 3) N m their
    vectors (drystone/model/loads.py). The same arithmetic in ``advance`` and in a step
    taken from Python."""
    nj = len(c)
    for i in range(F.shape[0]):
        for q in range(3):
            f = 0.0
            t = 0.0
            for j in range(nj):
                f += c[j] * Fb[j, i, q]
                t += c[j] * Tb[j, i, q]
            F[i, q] += f
            T[i, q] += t


# The neighbour list's arrays (14: ``NeighbourList.arrays``) and the search's buffers (16:
# ``neighbours.contact_buffers``) reach ``_advance`` one per argument, not as two tuples: numba
# 0.58 types an argument whose type fingerprint outgrows 40 bytes (a tuple of more than four
# arrays) in Python at every call, 0.1 to 0.4 ms, more than a small wall's whole step (the
# fingerprint's first bytes are lost when its buffer grows, so its cache never hits:
# github.com/numba/numba/issues/9097); an array argument is typed in C (about 0.1 us). Within
# compiled code they travel as tuples. The step's contact forces are written into ``_advance``
# itself, not called: numba emits a kernel's callees again in each kernel compiled on its own
# (a ``_contact_forces`` of its own: 109 s of a core for the step's first compile), and a
# function inlined by numba (``inline="always"``) is copied statement by statement, each copy
# taking every variable of its scope with it: 17 s of the compile for this one.
@njit(cache=True)
def _advance(verts, nv, normals, offsets, nf, faces, fk, owner, pos, rot, vel, angvel, moving, inv_mass, inv_inertia_local,
             mat, table, jkeys, jvals, keys, shear, basis, dt, tol, size, shared, g, F_ext, coef, Fb, Tb, e_last,
             acc, mass, inertia, lin_free, rot_free, aspherical, angmom, quat,
             l0, l1, l2, l3, l4, l5, l6, l7, l8, l9, l10, l11, l12, l13,
             b0, b1, b2, b3, b4, b5, b6, b7, b8, b9, b10, b11, b12, b13, b14, b15):
    """``CompiledStep.advance``: len(g) steps, each the step's contacts between shapes and the
    forces and torques on the bodies, then ``integrate`` (+ ``energy.account`` into ``acc``),
    without leaving compiled code, the arithmetic of each step that of one call of
    ``CompiledStep.forces`` and one of each kernel (the same results bit for bit); with no step
    (len(g) = 0: ``CompiledStep.forces``, ``peek``) the contacts of the state given, ``acc``
    unchanged and the neighbour list's arrays and the search's buffers the only state kept.

    A contact is a pair of shapes (ia, ib: shape indices; shape s a convex part of body
    ``owner[s]``, ``size`` per shape; ``shared``: some body has several shapes); ``keys``,
    ``shear``, ``basis``: the last step's contacts' keys and histories. The contacts come from
    the neighbour list's arrays (``drystone.mechanics.neighbours``: the full search's contacts,
    in its order), into the search's buffers; both are returned last (grown, rebuilt). The work
    per contact and per body runs on numba's threads (``drystone.mechanics.contact_rows``: the
    same numbers for any number). The loads' wrench of step s is ``applied_wrench(coef[s], Fb,
    Tb)`` (nothing when coef has no column). The elastic energy (``e_prev``, ``e_last``) of the
    last two steps only (what a sample after them records), else NaN: a step that stops the
    call on the depth check (``depth_ratio`` > 1, the largest depth V/A over the smaller
    shape's size) has its own, the step before it NaN unless it was one of the last two. l0 ..
    l13, b0 .. b15: the neighbour list's arrays and the search's buffers one by one (the note
    above)."""
    nl = (l0, l1, l2, l3, l4, l5, l6, l7, l8, l9, l10, l11, l12, l13)
    buf = (b0, b1, b2, b3, b4, b5, b6, b7, b8, b9, b10, b11, b12, b13, b14, b15)
    n_steps = len(g)
    loaded = coef.shape[1] > 0
    e_prev = e_last
    om_max = 0.0
    s = 0
    v0 = np.empty_like(vel)
    w0 = np.empty_like(angvel)
    nb = len(pos)
    ns = len(nv)
    nt = buf[8].shape[0]  # ranges of rows for the threads: one per thread numba may run
    while True:
        # -- the step's contacts and their forces (``CompiledStep.forces``) --
        nl = nbr.update(nl, verts, nv, normals, offsets, nf, owner, pos, rot, nt)
        m, buf = nbr.search(nl, buf, nv, nf, faces, fk, tol, bool(ov.TOUCHING_IS_NO_CONTACT))  # bool(): see the constant
        ia = buf[0][:m]
        ib = buf[1][:m]
        vol = buf[2][:m]
        c = buf[3][:m]
        nrm = buf[4][:m]
        area = buf[5][:m]
        pc = buf[6][:m]
        pj = buf[7][:m]
        prev_keys = keys
        keys = ia * ns + ib  # a contact's history is its pair of shapes'
        oa = owner[ia]
        ob = owner[ib]
        # each contact's history: its shear force (columns 0-2) and twisting moment about n (3),
        # and its damping's modal basis (zeros for a new contact: no basis, a cold solve, also at
        # the next step if it is not damped now); with the carried force scaled by the patch
        # (``area_scaling``, contact.carried_share), two more columns: the contact's area A_c (4)
        # and polar moment J_p (5) at the step
        prev = _previous(keys, prev_keys)
        warm = prev >= 0
        kn = np.empty(m)
        kt = np.empty(m)
        mu = np.empty(m)
        xi = np.empty(m)
        fn = np.empty(m)
        fs = np.empty((m, shear.shape[1]))
        prev_basis = basis
        basis = np.empty((m, 6, 6))
        jp = np.empty(m)
        slipping = np.empty(m, np.bool_)
        ra = np.empty((m, 3))
        rb = np.empty((m, 3))
        pa = np.empty((m, 3))
        pb = np.empty((m, 3))
        lever = np.empty((m, 3))
        twist = np.empty((m, 6))
        iia = np.empty((m, 3, 3))
        iib = np.empty((m, 3, 3))
        slip_terms = np.empty((m, 4))
        rows.law_rows(oa, ob, c, nrm, area, pc, pj, vol, pos, vel, angvel, rot, inv_inertia_local, mat, table, jkeys,
                      jvals, prev, shear, prev_basis, dt, kn, kt, mu, xi, fn, fs, basis, jp, slipping, ra, rb, pa, pb,
                      lever, twist, iia, iib, slip_terms, nt)
        slip = rows.slip_work(slip_terms)  # plastic work of Coulomb slip over the step, J (energy.slip_work)
        if shared:  # a body of several shapes: its joints' contacts share the damping ratio
            xi *= law.joint_share(oa, ob, nb, area)
        fd, md, om = law.damping_wrenches_warm(nrm, area, pj, kn, kt, xi, ~slipping, pa, pb, inv_mass[oa],
                                               inv_mass[ob], iia, iib, twist, fn, fs, mu, lever, basis, warm,
                                               rows.range_count(m, nt))
        F, T, Fd, Td = rows.body_sums(oa, ob, nb, fs, fn, nrm, fd, md, ra, rb, pa, pb, nt)
        shear = fs
        depth = 0.0  # largest depth V/A over the smaller shape's size
        for k in range(m):
            if area[k] > 0.0:
                r = vol[k] / area[k] / min(size[ia[k]], size[ib[k]])
                if r > depth:
                    depth = r
            if om[k] > om_max:
                om_max = om[k]
        e_prev = e_last
        e_last = np.nan
        if s >= n_steps - 2 or depth > 1.0:  # (a step too deep ends the call: its energy is the last)
            e_last = rows.elastic_energy(ia, ib, oa, ob, kn, kt, vol, c, nrm, area, fs, jp, normals, offsets, nf, rot,
                                         pos)
        if s == n_steps:  # no step asked for (``forces``, ``peek``): the contacts of the state given
            return (s, ia, ib, vol, c, nrm, area, fn, fs, fd, slipping, keys, basis, F, T, e_prev, e_last, om_max, depth,
                    slip, Fd, Td, nl, buf)
        # -- the step --
        F += F_ext
        if loaded:
            applied_wrench(coef[s], Fb, Tb, F, T)
        acc[2] += 0.5 * slip
        if depth > 1.0:  # the caller checks it before this step is integrated
            return (s, ia, ib, vol, c, nrm, area, fn, fs, fd, slipping, keys, basis, F, T, e_prev, e_last, om_max, depth,
                    slip, Fd, Td, nl, buf)
        v0[:] = vel
        w0[:] = angvel
        integrate(dt, g[s], F, T, mass, inertia, lin_free, rot_free, aspherical, pos, vel, angvel, angmom, quat, rot, nt)
        energy.account(dt, g[s], F, T, Fd, Td, F_ext, moving, mass, lin_free, v0, w0, vel, angvel, 0.5 * slip, acc)
        if loaded:
            acc[0] += energy.load_work(dt, coef[s], Fb, Tb, moving, lin_free, rot_free, v0, w0, vel, angvel)
        s += 1
        if s == n_steps:
            return (s, ia, ib, vol, c, nrm, area, fn, fs, fd, slipping, keys, basis, F, T, e_prev, e_last, om_max, depth,
                    slip, Fd, Td, nl, buf)
