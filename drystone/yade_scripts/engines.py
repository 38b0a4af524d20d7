"""Step engines: one class per way of stepping a run's scene (inside YADE only), as YADE
composes ``O.engines``. The driver (run_case.py) builds the scene and the state arrays,
then one engine (``ENGINES``, chosen by the case's contact law: ``ContactLaw.engine`` in
drystone/mechanics/laws.py) steps it:

* ``compiled``: the project's law and the leapfrog integration of the bodies in numba over
  arrays (drystone.mechanics.contact_step.CompiledStep), its own time loop; YADE keeps the scene
  and gets the final state written back;
* ``python``: the project's law in numpy (contact_engine.PenaltyCoulomb, YADE's or the
  native contact geometry), YADE's NewtonIntegrator moving the bodies, ``O.run``;
* ``yade``: YADE's stock volumetric law and integrator, ``O.run``.

The interface, the same for each: ``loop`` (advance to the run's end, calling the
driver's ``step`` at every step that needs Python: a recorded sample, a stage's start, an
applied force switched), and inside a step ``forces`` (this step's contact and applied
forces), ``before_sample`` (the state arrays made current), ``finish_step`` (the motion,
where the engine integrates it); ``contacts``, ``elastic_energy`` and ``energy_terms``
for recording, ``set_velocity`` / ``velocity`` for the stages, ``add_work`` for a load's
energy given at once (a velocity jump), ``finish`` (the state written back or read). A new
engine is one class here and a name in ``ENGINES``.

The case's [[loads]] (drystone/model/loads.py, ``run.loads``: an AppliedLoads or None) act at
every step in every engine (applied.py): their coefficients at the step's time (``loads_at``) times
their fixed vectors, a force on each loaded body and a moment about its centroid (fixed in
the platform frame), added to the contact forces (compiled: ``contact_step.applied_wrench``,
also inside ``advance`` with a coefficient row per step) or given to YADE
(``O.forces.addF`` / ``addT``: the python and stock engines); their work enters the energy
balance (``energy.load_work``; the stock law keeps none). Where a load becomes undefined
(the retained soil's Mononobe-Okabe limit) the driver's ``load_limit`` stops the run.

The energy balance (drystone/mechanics/energy.py) is accumulated at every step by the
engines with the project's law: ``compiled`` in its compiled step, ``python`` in an
``energy.Ledger`` that charges step n when YADE has integrated it (the velocities read at
step n + 1); the stock law keeps no shear history nor damping of its own to account: its
``energy_terms`` are None (NaN in the histories).
"""
from __future__ import annotations

import builtins
import time

import numpy as np
import yade

from drystone.mechanics import contact as law
from drystone.mechanics import contact_step as cs
from drystone.mechanics import energy, integration, laws, monitors, rotations, stability
from drystone.yade_scripts import applied
from drystone.yade_scripts import contact_engine as ce
from drystone.yade_scripts import quiet_steps as quiet


def _state_row(s) -> tuple:
    """(pos, vel, angVel, ori as x y z w) of one YADE State. Indexing the vectors is about
    7x faster than unpacking them (``*s.pos`` iterates through IndexError), which made
    this read a quarter of the step on the 40-stone wall."""
    p, v, w, q = s.pos, s.vel, s.angVel, s.ori
    return (p[0], p[1], p[2], v[0], v[1], v[2], w[0], w[1], w[2], q[0], q[1], q[2], q[3])


def pair_properties(run, ya, yb) -> dict:
    """kn, kt, mu, damping of the contact between bodies ``ya`` and ``yb`` (materials and
    joint overrides of the run's spec)."""
    a, b = run.blocks[run.bid[ya]], run.blocks[run.bid[yb]]
    mats = run.spec.materials
    joint = run.spec.joint_overrides.get(f"{min(a['id'], b['id'])}-{max(a['id'], b['id'])}")
    return law.pair_properties(mats[a["material"]], mats[b["material"]], joint)


class Engine:
    """Base of the step engines (module docstring); ``run`` is the driver."""

    name = ""
    #: YADE's NewtonIntegrator moves the bodies (else the engine integrates them itself)
    yade_integrates = True

    def __init__(self, run):
        self.run = run
        self.step = None  # the contact law's step, where this engine has one of its own
        #: after the loop: (elastic energy J, slip work J) of the step after the last one, so that
        #: the run's last sample (taken after its last step) has its energies at that step's end
        self.ahead = None
        self._before = {}  # a moved block's velocity before a stage set it: what brought it to x_n

    def _note_jump(self, i: int, v_old) -> None:
        """A non-moving (kinematically moved) body's velocity is about to be set at a stage's
        start: the step's displacement it is charged with (drystone.mechanics.energy) is
        (v_old + v_new) dt / 2, v_old the velocity that brought it to the step's position."""
        if not np.isfinite(self.run.mass[i]) and i not in self._before:
            self._before[i] = np.array(v_old, float)

    def _velocities_before(self) -> np.ndarray:
        """The velocities (nb, 3) m/s before this step, a moved block's as it arrived."""
        v0 = self.run.vel.copy()
        for i, v in self._before.items():
            v0[i] = v
        self._before = {}
        return v0

    @property
    def max_omega_dt(self) -> float:
        """Largest omega dt of any contact mode so far (run_info.json; 0 without a step of its own)."""
        return 0.0 if self.step is None else self.step.max_omega_dt

    # -- the time loop ---------------------------------------------------------------
    def loop(self) -> None:
        """YADE's: ``O.run`` with a PyRunner calling the driver's step every iteration."""
        run = self.run
        builtins._drystone_step = run.step
        run.O.run(run.steps_total, True)
        run.iter, run.t = run.O.iter, run.O.time

    def clock(self) -> None:
        """The step being taken (YADE's iteration and time)."""
        self.run.iter, self.run.t = self.run.O.iter, self.run.O.time

    def stop(self) -> None:
        self.run.O.pause()

    def finish(self) -> None:
        """After the loop: the state after the last integration into the arrays."""
        if self.run.failure is None:
            self.read(np.concatenate([self.run.dyn, np.array(self.run.moving_static, int)]))

    # -- inside a step ---------------------------------------------------------------
    def forces(self, t: float, g: np.ndarray) -> None:
        raise NotImplementedError

    def before_sample(self) -> None:
        """Bring the state arrays up to date for a recorded sample."""

    def finish_step(self, g: np.ndarray) -> None:
        """What remains of the step after a sample (an engine that integrates: the motion)."""

    # -- state -----------------------------------------------------------------------
    def read(self, ids) -> None:
        """Positions, velocities, angular velocities, orientations of bodies ``ids`` from YADE."""
        run = self.run
        rows = np.array([_state_row(run.states[i]) for i in ids], float).reshape(-1, 13)
        run.pos[ids], run.vel[ids], run.angvel[ids], run.quat[ids] = rows[:, :3], rows[:, 3:6], rows[:, 6:9], rows[:, 9:]
        run.rot[ids] = rotations.to_matrix(run.quat[ids])

    def set_velocity(self, i: int, v) -> None:
        """Set body i's velocity (m/s) where the motion lives."""
        self.run.states[i].vel = yade.Vector3(*v)

    def velocity(self, i: int) -> np.ndarray:
        return np.array(tuple(self.run.states[i].vel))

    def contacts(self) -> cs.ContactState:
        raise NotImplementedError

    def elastic_energy(self) -> float:
        """Elastic energy stored in the contacts (J) at the half step; NaN where the law keeps none."""
        return np.nan

    def energy_terms(self) -> tuple[float, float, float] | None:
        """(work of the loads, dissipated by damping, dissipated by friction), J from the
        run's start (drystone/mechanics/energy.py); None where the engine cannot account."""
        return None

    def add_work(self, J: float) -> None:
        """Work of a load given at once (J): a velocity jump's kinetic energy."""

    def retire(self, i: int) -> None:
        """Take body ``i`` (a free block that left the model) out of the scene: YADE blocks
        every DOF, its velocities are zeroed (it stays where it left, no longer integrated)
        and its shapes interact with nothing (group mask 0: YADE's collider; the native
        geometry's shapes get non-finite vertices, which the broad phase pairs with nothing,
        drystone.mechanics.overlap.sweep_pairs)."""
        run = self.run
        st = run.states[i]
        st.blockedDOFs = "xyzXYZ"
        st.vel = yade.Vector3(0, 0, 0)
        st.angVel = yade.Vector3(0, 0, 0)
        run.vel[i] = 0.0
        run.angvel[i] = 0.0
        for k in [i] + list(run.members.get(i, ())):
            run.O.bodies[k].groupMask = 0
        if self.step is not None and hasattr(self.step, "shapes"):
            self.step.retire(self.step.owner == i)

    def check_depth(self) -> None:
        """Stop the run on a contact deeper than stability.TUNNEL_FRACTION x the smaller
        block's smallest dimension (every step: a tunnelling block can pass through in
        less than a sample)."""
        run, st = self.run, self.contacts()
        if run.failure is None and len(st.fn):
            with np.errstate(divide="ignore", invalid="ignore"):
                deep = st.volume > stability.TUNNEL_FRACTION * st.area * np.minimum(run.size[st.id1], run.size[st.id2])
            if deep.any():
                run.fail(monitors.tunnelling(run, st, run.size))


class StockEngine(Engine):
    """YADE's stock volumetric law and integrator: YADE does everything; the contacts are
    read back for recording."""

    name = "yade"

    def forces(self, t, g):
        self.run.newton.gravity = yade.Vector3(*g)
        applied.give_yade(self.run, t, g)

    def before_sample(self):
        self.read(self.run.moving)

    def contacts(self):
        return ce.stock_contacts(self.run.O)


class NumpyEngine(Engine):
    """The project's law in numpy (the reference) on YADE's or the native contact geometry;
    YADE's NewtonIntegrator moves the bodies."""

    name = "python"

    def __init__(self, run):
        super().__init__(run)
        self.step = ce.PenaltyCoulomb(lambda a, b: pair_properties(run, a, b), run.mass, run.local_v,
                                      run.spec.detection, run.inertia, run.owner,
                                      area_scaling=laws.get(run.spec.law).area_scaling)
        self.ledger = energy.Ledger(run.mass, applied.free_directions(run)[0])

    def forces(self, t, g):
        run = self.run
        run.newton.gravity = yade.Vector3(*g)
        self.read(run.moving)
        self.ledger.complete(run.vel, run.angvel)  # the previous step, now that YADE has integrated it
        self.step.step(run.O, (run.pos, run.vel, run.angvel, run.rot))
        self.check_depth()
        wrench = applied.give_yade(run, t, g)
        last = self.step.last
        F_ext, T_ext = applied.external(run, t), None
        if wrench is not None:
            F_ext, T_ext = F_ext + wrench[0], wrench[1]
        self.ledger.begin(run.O.dt, g, last["F"], np.zeros_like(last["F"]), last["Fd"], last["Td"], F_ext,
                          self._velocities_before(), run.angvel, last["slip"], T_ext)

    def set_velocity(self, i, v):
        if self.ledger.pending:  # the step before was integrated with the velocities YADE holds: charge it first
            self.read(self.run.moving)
            self.ledger.complete(self.run.vel, self.run.angvel)
        self._note_jump(i, self.velocity(i))
        super().set_velocity(i, v)

    def finish(self):
        super().finish()
        run = self.run
        if run.failure is None:
            self.ledger.complete(run.vel, run.angvel)
            bs = (run.pos, run.vel, run.angvel, run.rot)
            # (YADE's geometry: its interactions of the last step, the nearest it has)
            geo = self.step.native_geometry(bs) if self.step.native else self.step.yade_geometry(self.step.gather(run.O), bs)
            self.ahead = self.step.peek(geo, bs, run.O.dt)

    def contacts(self):
        return self.step.state

    def elastic_energy(self):
        return 0.5 * (self.step.elastic[1] + (self.step.elastic[0] if self.ahead is None else self.ahead[0]))

    def energy_terms(self):
        acc = self.ledger.acc + (0.0, 0.0, 0.0 if self.ahead is None else 0.5 * self.ahead[1])
        return tuple(float(x) for x in acc)

    def add_work(self, J):
        self.ledger.add_work(J)

    def retire(self, i):
        super().retire(i)
        self.ledger.lin_free[i] = 0.0  # no work on it from here on: its kinetic energy leaves with it
        if self.ledger.pending:  # the step under way is charged with its velocities zeroed
            self.ledger._pending[7][i] = 0.0
            self.ledger._pending[8][i] = 0.0


def law_tables(run) -> tuple[list, np.ndarray, dict]:
    """(material index of each body, the (nm, nm, 4) table of kn, kt, mu, damping of each pair
    of materials, the joint overrides {(ia, ib): [kn, kt, mu, damping]} by body) of a run,
    as ``CompiledStep`` takes them."""
    spec, mats = run.spec, run.spec.materials
    names = sorted(mats)
    keys = ("kn", "kt", "mu", "damping")
    table = np.array([[[law.pair_properties(mats[a], mats[b])[k] for k in keys] for b in names] for a in names])
    material = [names.index(run.blocks[run.bid[i]]["material"]) for i in range(len(run.mass))]
    joints = {}
    for key in spec.joint_overrides:
        a, b = (int(x) for x in key.split("-"))
        p = pair_properties(run, run.yid[a], run.yid[b])
        joints[(run.yid[a], run.yid[b])] = [p[k] for k in keys]
    return material, table, joints


class CompiledEngine(Engine):
    """The project's law on the native geometry and the integration in numba, in its own
    time loop in place of YADE's (drystone.mechanics.contact_step); the scene is written back at the end."""

    name = "compiled"
    yade_integrates = False

    def __init__(self, run):
        super().__init__(run)
        nb = len(run.mass)
        self.lin_free, self.rot_free = applied.free_directions(run)
        # YADE's exactAsphericalRot: aspherical bodies free to rotate about every axis
        self.aspherical = np.array([bool(np.isfinite(run.mass[i])) and run.O.bodies[i].aspherical
                                    and self.rot_free[i].all() for i in range(nb)])
        self.angmom = np.zeros((nb, 3))
        self.mass_int = np.where(np.isfinite(run.mass), run.mass, 1.0)  # never divided for non-moving bodies
        self.inertia_int = np.where(np.isfinite(run.mass)[:, None], run.inertia, 1.0)
        self.step = ce.Compiled(run.mass, run.inertia, run.local_v, *law_tables(run),
                                run.shape_size * stability.TUNNEL_FRACTION, run.owner,
                                area_scaling=laws.get(run.spec.law).area_scaling, threads=int(run.O.numThreads))
        self.F = self.T = self.F_ext = None
        self.c = None  # the loads' coefficients of the step being taken (None: no loads)
        self._normalise_orientations()

    def _normalise_orientations(self):
        """YADE's first step (PyRunner does not run at step 0, NewtonIntegrator does)
        normalises the orientation of every body the driver reads; this engine does the
        same, with Eigen's arithmetic, so that both engines start from the same state
        (contacts across exactly touching faces are sensitive to its round-off)."""
        run = self.run
        for i in run.dyn.tolist() + list(run.moving_static):
            q = run.states[i].ori
            q.normalize()
            run.states[i].ori = q
            run.quat[i] = (q[0], q[1], q[2], q[3])
        run.rot = rotations.to_matrix(run.quat)

    def motion(self):
        """What ``integrate`` needs beside the state (mass, inertia, free directions, angular momentum)."""
        return (self.mass_int, self.inertia_int, self.lin_free, self.rot_free, self.aspherical, self.angmom)

    # -- the time loop ---------------------------------------------------------------
    def loop(self):
        """What ``O.run`` with the PyRunner did, step for step and bit for bit: YADE's
        iteration 0 moves nothing (the PyRunner does not run at iteration 0 and there is no
        integrator), each later iteration is one step. A step that needs Python goes
        through the driver's ``step``; the steps between them run in one compiled call
        (``CompiledStep.advance``): one Python call per recorded sample."""
        run = self.run
        t_py = time.perf_counter()
        dt = run.O.dt
        run.iter, run.t = 1, 0.0 + dt
        while run.iter < run.steps_total and not run.done and run.failure is None:
            run.step()
            run.iter += 1
            run.t += dt
            if run.done or run.failure is not None:
                break
            quiet.advance_quietly(self, dt)
        run.python_time += time.perf_counter() - t_py

    def clock(self):
        pass  # this engine keeps YADE's iteration and time itself (loop)

    def stop(self):
        pass

    def integrate(self, dt, g, F, T, F_ext, c=None):
        """One step of the motion (F, T: contact plus applied F_ext, plus the loads' wrench of
        coefficients ``c``), then its energy terms."""
        run = self.run
        v0, w0 = self._velocities_before(), run.angvel.copy()
        integration.integrate(dt, g, F, T, self.mass_int, self.inertia_int, self.lin_free, self.rot_free, self.aspherical,
                              run.pos, run.vel, run.angvel, self.angmom, run.quat, run.rot, 1)
        loads = None if c is None else (c, run.loads.force, run.loads.moment, self.rot_free)
        self.step.account(dt, g, F, T, F_ext, self.lin_free, v0, w0, run.vel, run.angvel, loads)

    # -- inside a step ---------------------------------------------------------------
    def forces(self, t, g):
        run = self.run
        t_k = time.perf_counter()
        self.F, self.T = self.step.step(run.O, (run.pos, run.vel, run.angvel, run.rot), apply_forces=False)
        run.kernel_time += time.perf_counter() - t_k
        if self.step.depth_ratio > 1.0:  # deeper than TUNNEL_FRACTION x the smaller block
            self.check_depth()
        for y, f, start, end in run.forces:
            if start <= t < end:
                self.F[y] += tuple(f)
        self.F_ext = applied.external(run, t)  # for the loads' work
        self.c = applied.loads_at(run, t, g)
        if self.c is not None:
            cs.applied_wrench(self.c, run.loads.force, run.loads.moment, self.F, self.T)

    def finish_step(self, g):
        t_k = time.perf_counter()
        self.integrate(self.run.O.dt, g, self.F, self.T, self.F_ext, self.c)
        self.run.kernel_time += time.perf_counter() - t_k

    def finish(self):
        """Write the arrays' state into YADE's bodies; the energies of the step after the last (``ahead``)."""
        run = self.run
        if run.failure is None:
            self.ahead = self.step.peek(run.pos, run.rot, run.vel, run.angvel, run.O.dt)
        for i in np.flatnonzero(np.isfinite(run.mass) | np.any(run.vel != 0, axis=1)).tolist():
            st = run.states[i]
            st.pos = yade.Vector3(*run.pos[i])
            st.vel = yade.Vector3(*run.vel[i])
            st.angVel = yade.Vector3(*run.angvel[i])
            x, y, z, w = run.quat[i]
            st.ori = yade.Quaternion(w, x, y, z)

    # -- state -----------------------------------------------------------------------
    def set_velocity(self, i, v):
        self._note_jump(i, self.run.vel[i])
        self.run.vel[i] = v

    def velocity(self, i):
        return self.run.vel[i].copy()

    def contacts(self):
        return self.step.state

    def elastic_energy(self):
        return 0.5 * (self.step.elastic[1] + (self.step.elastic[0] if self.ahead is None else self.ahead[0]))

    def energy_terms(self):
        acc = self.step.energy + (0.0, 0.0, 0.0 if self.ahead is None else 0.5 * self.ahead[1])
        return tuple(float(x) for x in acc)

    def add_work(self, J):
        self.step.energy[0] += float(J)

    def retire(self, i):
        super().retire(i)
        self.lin_free[i] = 0.0  # integrate() and energy.account: it moves no more, no work on it
        self.rot_free[i] = 0.0
        self.aspherical[i] = False
        self.angmom[i] = 0.0


#: the step engines by name (``ContactLaw.engines`` in drystone/mechanics/laws.py names them)
ENGINES = {e.name: e for e in (CompiledEngine, NumpyEngine, StockEngine)}
