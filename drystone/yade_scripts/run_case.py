"""Run one resolved case inside YADE:  yade -n -x drystone/yade_scripts/run_case.py SPEC.json [ENGINE]

SPEC.json is written by ``python -m drystone run CASE.toml`` (drystone/runner.py), which
validates the case and the geometry first; this script only simulates and writes
``histories.npz`` and ``run_info.json`` into the output folder (under temporary names,
renamed when complete). Units SI; the simulation runs in the platform frame
(drystone/loading.py).

ENGINE (the project's law on its native contact geometry only; ``ENGINES``):
``compiled`` (default) runs the whole contact step and the leapfrog integration of the
bodies in numba over arrays (``drystone.contact_step``), YADE keeping the time and the
scene; ``python`` is the numpy law with YADE's NewtonIntegrator, each body's state read
and its forces added one by one (the reference, and what the package did before).
"""
from __future__ import annotations

import builtins
import json
import os
import sys
import time
from pathlib import Path

import numpy as np
import yade
from yade import log

# drystone is installed in the interpreter YADE runs (make setup: pip install -e .)
from drystone.loading import LoadProgramme  # noqa: E402
from drystone import contact as law  # noqa: E402
from drystone import contact_step as cs  # noqa: E402
from drystone import rotations, stability  # noqa: E402
from drystone.geometry import polyhedron as ph  # noqa: E402
from drystone.yade_scripts import contact_engine as ce  # noqa: E402
from drystone.yade_scripts import scene as sc  # noqa: E402

# YADE's polyhedra intersection warns "Unhandled switch case" on exactly touching faces,
# every step; it is harmless (the contact is then treated as no overlap).
log.setLevel("Polyhedra_support.cpp", log.ERROR)


#: histories.npz's format name and version (arrays ``format`` and ``version``)
HISTORIES_FORMAT, HISTORIES_VERSION = "drystone-histories", 1
#: step engines for the project's law on native geometry (module docstring)
ENGINES = ("compiled", "python")


def _state_row(s) -> tuple:
    """(pos, vel, angVel, ori as x y z w) of one YADE State. Indexing the vectors is about
    7x faster than unpacking them (``*s.pos`` iterates through IndexError), which made
    this read a quarter of the step on the 40-stone wall."""
    p, v, w, q = s.pos, s.vel, s.angVel, s.ori
    return (p[0], p[1], p[2], v[0], v[1], v[2], w[0], w[1], w[2], q[0], q[1], q[2], q[3])


class Driver:
    def __init__(self, spec: dict, out: Path | None = None, engine: str = "compiled"):
        if engine not in ENGINES:
            raise SystemExit(f"unknown engine {engine!r}; allowed: {', '.join(ENGINES)}")
        self.spec = spec
        self.O = yade.Omega()
        self.out = Path(out if out is not None else spec["out_dir"])  # the folder of spec.json
        # the compiled step integrates the motion itself; it needs the native geometry
        self.compiled = engine == "compiled" and spec["law"] == "penalty_coulomb" and spec["detection"] == "native"
        self.engine_name = "compiled" if self.compiled else ("python" if spec["law"] == "penalty_coulomb" else "yade")
        self.tables = sc.build(spec, integrate=not self.compiled)
        self.newton = self.tables["newton"]
        self.yid, self.bid = self.tables["yid"], self.tables["bid"]
        self.dyn = np.array(self.tables["dynamic"], int)
        O = self.O
        nb = len(O.bodies)
        self.states = [O.bodies[i].state for i in range(nb)]
        self.mass = np.array([O.bodies[i].state.mass if O.bodies[i].dynamic else np.inf for i in range(nb)])
        self.blocks = {b["id"]: b for b in spec["blocks"]}
        local_v = [[tuple(v) for v in O.bodies[i].shape.v] for i in range(nb)]
        self.pos = np.array([tuple(O.bodies[i].state.pos) for i in range(nb)])
        self.pos0 = self.pos.copy()
        self.vel = np.zeros((nb, 3))
        self.angvel = np.zeros((nb, 3))
        self.quat = np.array([tuple(O.bodies[i].state.ori) for i in range(nb)])
        self.quat0 = self.quat.copy()
        self.rot = rotations.to_matrix(self.quat)
        self.vloc = local_v
        self.law_name = spec["law"]
        inertia = np.array([tuple(O.bodies[i].state.inertia) for i in range(nb)])
        self.inertia = inertia
        if self.compiled:
            self.engine = self._compiled_engine(local_v, inertia)
        else:
            self.engine = ce.PenaltyCoulomb(self._pair_props, self.mass, local_v, spec["detection"], inertia)
        # any spec version; excitation samples loaded from the run folder
        self.prog = LoadProgramme.from_spec(spec, self.out)
        self.moving_static = [self.yid[b] for b in self.prog.moving_blocks()]
        if self.compiled:
            self._normalise_orientations()
        self.stage = -1
        self.forces = [(self.yid[f["block"]], yade.Vector3(*f["force"]), f["start"],
                        f["end"] if f["end"] is not None else np.inf) for f in spec["forces"]]
        out = spec["output"]
        self.rec_every = max(1, int(round(out["interval"] / spec["dt"])))
        self.steps_total = int(np.ceil(self.prog.end / spec["dt"] - 1e-9))
        self.cp = [(c["name"], self.yid[c["block"]], np.asarray(c["position"], float)) for c in spec["control_points"]]
        # control point offsets in each body's local frame
        self.cp_local = [self.rot[y].T @ (p - self.pos0[y]) for _, y, p in self.cp]
        self.named = [(c["name"], self.yid[c["blocks"][0]], self.yid[c["blocks"][1]]) for c in out["contacts"]]
        self.h = {k: [] for k in ("t", "tilt_deg", "g_eff", "base_acc", "pos", "quat", "vel", "angvel",
                                  "cp", "reaction", "n_contacts", "kinetic", "potential", "elastic")}
        self.hc = {name: {k: [] for k in ("fn", "ft", "normal", "point", "slipping", "area", "volume")} for name, _, _ in self.named}
        self.w_free = float(np.sum(self.mass[self.dyn])) * spec["gravity"]
        self.collapse = None
        self.stop_at = None
        self.jumps = []  # velocity jumps applied at stage starts (run_info.json)
        self.settle = None  # early end of a last rest stage on low kinetic energy (run_info.json)
        self.below_since = None
        # a stone whose centroid is below the platform's underside has fallen off the model:
        # its free fall is left out of the settling criterion
        self.z_floor = min((min(v[2] for v in b["vertices"]) for b in spec["blocks"] if b["role"] == "platform"),
                           default=-np.inf)
        self.max_contacts = 0
        self.t_wall0 = time.time()
        self.t_print = self.t_wall0
        self.done = False
        # the step being taken: YADE's iteration and time (the compiled engine keeps them
        # itself, as YADE would: time accumulated by dt per iteration)
        self.iter, self.t = 0, 0.0
        self.python_time = 0.0  # s spent in this per-step Python engine
        self.kernel_time = 0.0  # of which in the compiled contact step and integration
        # blow-up checks at every recorded sample (drystone/stability.py)
        self.energy = stability.EnergyWatch(self.w_free)
        self.failure = None
        # the speed bound: integral of |g_eff| dt over the steps taken (m/s), velocity jumps so
        # far, the energy at the first sample (stability.speed_budget)
        self.g_integral = 0.0
        self.jump_dvs = []
        self.e0 = None
        # free blocks that left the model (stability.ModelRegion): summary marks them unbounded;
        # once every free block has, the run stops (the rest would be meaningless)
        self.region = stability.ModelRegion.from_blocks(spec["blocks"])
        self.left = {}  # YADE id -> {"block", "time_s", "where", "position_m", "speed_m_s"}
        self.all_left_s = None
        sizes = {b["id"]: float(ph.extent(np.asarray(b["vertices"])).min()) for b in spec["blocks"]}
        self.size = np.array([sizes[self.bid[i]] for i in range(nb)])

    # -- helpers ----------------------------------------------------------------
    def _pair_props(self, ya, yb):
        a, b = self.blocks[self.bid[ya]], self.blocks[self.bid[yb]]
        mats = self.spec["materials"]
        joint = self.spec["joint_overrides"].get(f"{min(a['id'], b['id'])}-{max(a['id'], b['id'])}")
        return law.pair_properties(mats[a["material"]], mats[b["material"]], joint)

    def _compiled_engine(self, local_v, inertia):
        """The compiled step and the arrays its integration needs (``drystone.contact_step``)."""
        nb = len(self.mass)
        names = sorted(self.spec["materials"])
        mats = self.spec["materials"]
        keys = ("kn", "kt", "mu", "damping")
        table = np.array([[[law.pair_properties(mats[a], mats[b])[k] for k in keys] for b in names] for a in names])
        material = [names.index(self.blocks[self.bid[i]]["material"]) for i in range(nb)]
        joints = {}
        for key in self.spec["joint_overrides"]:
            a, b = (int(x) for x in key.split("-"))
            p = self._pair_props(self.yid[a], self.yid[b])
            joints[(self.yid[a], self.yid[b])] = [p[k] for k in keys]
        free = [cs.free_directions(self.states[i].blockedDOFs or "", bool(np.isfinite(self.mass[i]))) for i in range(nb)]
        self.lin_free = np.array([f[0] for f in free])
        self.rot_free = np.array([f[1] for f in free])
        # YADE's exactAsphericalRot: aspherical bodies free to rotate about every axis
        self.aspherical = np.array([bool(np.isfinite(self.mass[i])) and self.O.bodies[i].aspherical
                                    and self.rot_free[i].all() for i in range(nb)])
        self.angmom = np.zeros((nb, 3))
        self.mass_int = np.where(np.isfinite(self.mass), self.mass, 1.0)  # never divided for non-moving bodies
        self.inertia_int = np.where(np.isfinite(self.mass)[:, None], inertia, 1.0)
        sizes = {b["id"]: float(ph.extent(np.asarray(b["vertices"])).min()) for b in self.spec["blocks"]}
        size = np.array([sizes[self.bid[i]] for i in range(nb)]) * stability.TUNNEL_FRACTION
        return ce.Compiled(self.mass, inertia, local_v, material, table, joints, size)

    def _normalise_orientations(self):
        """YADE's first step (PyRunner does not run at step 0, NewtonIntegrator does)
        normalises the orientation of every body the Driver reads; the compiled engine does
        the same, with Eigen's arithmetic, so that both engines start from the same state
        (contacts across exactly touching faces are sensitive to its round-off)."""
        for i in self.dyn.tolist() + list(self.moving_static):
            q = self.states[i].ori
            q.normalize()
            self.states[i].ori = q
            self.quat[i] = (q[0], q[1], q[2], q[3])
        self.rot = rotations.to_matrix(self.quat)

    def _set_velocity(self, i, v):
        """Set body i's velocity (m/s) where the motion lives (arrays or YADE)."""
        if self.compiled:
            self.vel[i] = v
        else:
            self.states[i].vel = yade.Vector3(*v)

    def _velocity(self, i) -> np.ndarray:
        return self.vel[i].copy() if self.compiled else np.array(tuple(self.states[i].vel))

    def _sync_yade(self):
        """Write the arrays' state into YADE's bodies (compiled engine: at the end)."""
        for i in np.flatnonzero(np.isfinite(self.mass) | np.any(self.vel != 0, axis=1)).tolist():
            st = self.states[i]
            st.pos = yade.Vector3(*self.pos[i])
            st.vel = yade.Vector3(*self.vel[i])
            st.angVel = yade.Vector3(*self.angvel[i])
            x, y, z, w = self.quat[i]
            st.ori = yade.Quaternion(w, x, y, z)

    def _read_states(self, ids):
        """Positions, velocities, angular velocities, orientations of bodies ``ids``."""
        rows = np.array([_state_row(self.states[i]) for i in ids], float).reshape(-1, 13)
        self.pos[ids], self.vel[ids], self.angvel[ids], self.quat[ids] = rows[:, :3], rows[:, 3:6], rows[:, 6:9], rows[:, 9:]
        self.rot[ids] = rotations.to_matrix(self.quat[ids])

    def _contacts(self) -> ce.ContactState:
        if self.law_name == "penalty_coulomb":
            return self.engine.state
        return ce.stock_contacts(self.O)

    # -- every step ---------------------------------------------------------------
    def step(self):
        """One step with every per-step check (YADE's PyRunner calls it each iteration;
        the compiled engine's loop, ``_run_compiled``, for the steps that need Python)."""
        t_py = time.perf_counter()
        O = self.O
        if not self.compiled:
            self.iter, self.t = O.iter, O.time
        t = self.t
        g = self.prog.body_acceleration(t)
        self.g_integral += float(np.linalg.norm(g)) * O.dt  # the speed bound (stability.speed_budget)
        k = self.prog.stage_index(t)
        if k != self.stage:
            self._enter_stage(k)
        if self.compiled:
            t_k = time.perf_counter()
            F, T = self.engine.step(O, (self.pos, self.vel, self.angvel, self.rot), apply_forces=False)
            self.kernel_time += time.perf_counter() - t_k
            if self.engine.depth_ratio > 1.0:  # deeper than TUNNEL_FRACTION x the smaller block
                self._check_depth()
            for y, f, start, end in self.forces:
                if start <= t < end:
                    F[y] += tuple(f)
            if self.iter % self.rec_every == 0:
                self._record(t)
            t_k = time.perf_counter()
            cs.integrate(O.dt, g, F, T, self.mass_int, self.inertia_int, self.lin_free, self.rot_free,
                         self.aspherical, self.pos, self.vel, self.angvel, self.angmom, self.quat, self.rot)
            self.kernel_time += time.perf_counter() - t_k
        else:
            self.newton.gravity = yade.Vector3(*g)
            ids = np.concatenate([self.dyn, np.array(self.moving_static, int)]) if self.moving_static else self.dyn
            if self.law_name == "penalty_coulomb":
                self._read_states(ids)
                self.engine.step(O, (self.pos, self.vel, self.angvel, self.rot))
                self._check_depth()
            for y, f, start, end in self.forces:
                if start <= t < end:
                    O.forces.addF(y, f)
            if self.iter % self.rec_every == 0:
                if self.law_name != "penalty_coulomb":
                    self._read_states(ids)
                self._record(t)
        self._progress(t, k)
        if self.stop_at is not None and t >= self.stop_at:
            self.done = True
            if not self.compiled:
                O.pause()
        if not self.compiled:
            self.python_time += time.perf_counter() - t_py

    def _progress(self, t, k):
        """A progress line every 5 s of wall time."""
        now = time.time()
        if now - self.t_print > 5.0:
            self.t_print = now
            frac = t / self.prog.end
            eta = (now - self.t_wall0) * (1 - frac) / max(frac, 1e-9)
            st = self.prog.stages[k]
            print(f"[{self.spec['name']}] t = {t:7.3f} / {self.prog.end:.3f} s ({100 * frac:5.1f} %)  "
                  f"stage {k + 1}/{len(self.prog.stages)} {st.type}  tilt {self.prog.tilt_deg(t):6.2f} deg  "
                  f"contacts {len(self._contacts().fn)}  ETA {eta:6.0f} s", flush=True)

    def _run_compiled(self):
        """The compiled engine's time loop, in place of YADE's (its scene is written back
        at the end, ``_sync_yade``). It does what ``O.run`` with the PyRunner did, step
        for step and bit for bit: YADE's iteration 0 moves nothing (the PyRunner does not
        run at iteration 0 and there is no integrator), each later iteration is one step.
        A step that needs Python (a recorded sample, a stage's start, an external force
        switched on or off) goes through ``step``; the steps between them run in one
        compiled call (``CompiledStep.advance``): one Python call per recorded sample."""
        t_py = time.perf_counter()
        dt = self.O.dt
        self.iter, self.t = 1, 0.0 + dt
        while self.iter < self.steps_total and not self.done and self.failure is None:
            self.step()
            self.iter += 1
            self.t += dt
            if self.done or self.failure is not None:
                break
            self._advance_quietly(dt)
        self.python_time += time.perf_counter() - t_py

    def _quiet_steps(self, dt) -> np.ndarray:
        """Times (s) of the steps from ``self.iter`` on that need no Python: up to the next
        recorded sample, stage start or switch of an external force, and to the step
        after which the run stops (``stop_at``), at most the run's end."""
        i = self.iter
        nxt = min((i // self.rec_every + 1) * self.rec_every if i % self.rec_every else i, self.steps_total)
        if nxt <= i:
            return np.zeros(0)
        ts = np.add.accumulate(np.concatenate([[self.t], np.full(nxt - i - 1, dt)]))  # as YADE adds dt
        ends = np.array([st.end for st in self.prog.stages])
        k = np.minimum(np.searchsorted(ends, ts, side="right"), len(ends) - 1)  # prog.stage_index
        cut = len(ts) if np.all(k == k[0]) else int(np.argmax(k != k[0]))
        for _, _, start, end in self.forces:
            on = (start <= ts) & (ts < end)
            if not np.all(on == on[0]):
                cut = min(cut, int(np.argmax(on != on[0])))
        if k[0] != self.stage:  # step() enters a stage
            cut = 0
        if self.stop_at is not None:
            past = np.flatnonzero(ts[:cut] >= self.stop_at)
            if len(past):
                cut = int(past[0]) + 1  # the run stops after that step
        return ts[:cut]

    def _advance_quietly(self, dt):
        """The steps of ``_quiet_steps`` in one compiled call (the depth check stops it,
        ``CompiledStep.advance``)."""
        ts = self._quiet_steps(dt)
        if len(ts) == 0:
            return
        g = self.prog.body_acceleration_at(ts)  # bit for bit the per-step values
        F_ext = np.zeros_like(self.pos)
        for y, f, start, end in self.forces:
            if start <= ts[0] < end:
                F_ext[y] += tuple(f)
        t_k = time.perf_counter()
        done, F, T, integrated = self.engine.advance(
            self.pos, self.rot, self.vel, self.angvel, dt, g, F_ext,
            (self.mass_int, self.inertia_int, self.lin_free, self.rot_free, self.aspherical, self.angmom, self.quat))
        self.kernel_time += time.perf_counter() - t_k
        if not integrated:  # stopped on the depth check before integrating step ts[done]
            self._check_depth()
            if self.failure is not None:
                return
            cs.integrate(dt, g[done], F, T, self.mass_int, self.inertia_int, self.lin_free, self.rot_free,
                         self.aspherical, self.pos, self.vel, self.angvel, self.angmom, self.quat, self.rot)
            done += 1
        self.g_integral += float(np.sum(np.linalg.norm(g[:done], axis=1))) * dt  # the speed bound
        self.iter += done
        last = ts[done - 1]  # the time of the last step taken
        self.t = last + dt
        if self.stop_at is not None and last >= self.stop_at:
            self.done = True
        self._progress(self.t, self.stage)

    def _enter_stage(self, k):
        self.stage = k
        st = self.prog.stages[k]
        print(f"[{self.spec['name']}] stage {k + 1}/{len(self.prog.stages)}: {st.type} "
              f"{st.start:.3f}-{st.end:.3f} s", flush=True)
        for block, v in self.prog.imposed_velocities(self.t).items():
            self._set_velocity(self.yid[block], v)
        dv = self.prog.velocity_jump(k)
        if np.any(dv):
            # Eq. 9 as a displacement: the base's velocity jump, as a relative velocity of every
            # free block (drystone.runner.initial_relative_velocity); blocked translations keep theirs
            for i in self.dyn:
                state = self.states[int(i)]
                free = np.array([c not in (state.blockedDOFs or "") for c in "xyz"], float)
                v0 = self._velocity(int(i))
                self._set_velocity(int(i), v0 + dv * free)
                self.energy.inject(0.5 * self.mass[i] * (np.sum((v0 + dv * free) ** 2) - np.sum(v0 ** 2)))
            self.jumps.append({"stage": k + 1, "time_s": float(self.t), "relative_velocity_m_s": dv.tolist()})
            self.jump_dvs.append(np.asarray(dv, float))
            print(f"[{self.spec['name']}] stage {k + 1}: base velocity jump, free blocks get {dv.tolist()} m/s "
                  "relative to the platform", flush=True)
        cfg = self.prog.settle(k, self.w_free)
        if cfg is not None:
            self.settle = dict(cfg, stage=k + 1, reached=False, time_s=None, max_end_s=st.end,
                               final_kinetic_J=None)
            self.below_since = None

    def _record(self, t):
        O = self.O
        st = self._contacts()
        h = self.h
        h["t"].append(t)
        h["tilt_deg"].append(self.prog.tilt_deg(t))
        g = self.prog.body_acceleration(t)
        h["g_eff"].append(g)
        h["base_acc"].append(self.prog.base_acceleration(t))
        d = self.dyn
        h["pos"].append(self.pos[d].copy())
        h["quat"].append(self.quat[d].copy())
        h["vel"].append(self.vel[d].copy())
        h["angvel"].append(self.angvel[d].copy())
        h["cp"].append([self.pos[y] + self.rot[y] @ loc for (_, y, _), loc in zip(self.cp, self.cp_local)])
        fb = st.force_on_b() if len(st.fn) else np.zeros((0, 3))
        R = np.zeros(3)  # force of the moving blocks on the non-moving ones, N
        if len(st.fn):
            static_a = ~np.isfinite(self.mass[st.id1])
            static_b = ~np.isfinite(self.mass[st.id2])
            R -= fb[static_a].sum(axis=0)
            R += fb[static_b].sum(axis=0)
        h["reaction"].append(R)
        h["n_contacts"].append(len(st.fn))
        self.max_contacts = max(self.max_contacts, len(st.fn))
        # energies at the half step t - dt/2, where leapfrog velocities live (J)
        m = self.mass[d]
        ke_b = 0.5 * m * np.sum(self.vel[d] ** 2, axis=1)  # per free block
        w_loc = np.einsum("bji,bj->bi", self.rot[d], self.angvel[d])  # R^T w per block
        ke_b += 0.5 * np.sum(self.inertia[d] * w_loc ** 2, axis=1)
        ke = float(ke_b.sum())
        h["kinetic"].append(ke)
        self._check_settled(t, ke_b)
        x_half = self.pos[d] - 0.5 * O.dt * self.vel[d]
        h["potential"].append(-float(np.sum(m * (x_half @ g))))
        h["elastic"].append(0.5 * sum(self.engine.elastic) if self.law_name == "penalty_coulomb" else np.nan)
        self._check_stable(t, ke, h["elastic"][-1], g, st)
        self._check_left(t)
        for name, ya, yb in self.named:
            hc = self.hc[name]
            row = np.flatnonzero(((st.id1 == ya) & (st.id2 == yb)) | ((st.id1 == yb) & (st.id2 == ya))) if len(st.fn) else []
            if len(row) == 0:
                for k, v in (("fn", 0.0), ("ft", np.zeros(3)), ("normal", np.full(3, np.nan)),
                             ("point", np.full(3, np.nan)),
                             ("slipping", False), ("area", 0.0), ("volume", 0.0)):
                    hc[k].append(v)
                continue
            r = int(row[0])
            sign = 1.0 if st.id1[r] == ya else -1.0  # orient normal and force from a to b
            n = sign * st.normal[r]
            f = sign * fb[r]
            fn = float(f @ n)
            hc["fn"].append(fn)
            hc["ft"].append(f - fn * n)
            hc["normal"].append(n)
            hc["point"].append(st.point[r].copy())
            hc["slipping"].append(bool(st.slipping[r]))
            hc["area"].append(float(st.area[r]))
            hc["volume"].append(float(st.volume[r]))
        self._check_collapse(t, R)

    def _check_depth(self):
        """Every step (a tunnelling block can pass through in less than a sample)."""
        st = self.engine.state
        if self.failure is None and len(st.fn):
            with np.errstate(divide="ignore", invalid="ignore"):
                deep = st.volume > stability.TUNNEL_FRACTION * st.area * np.minimum(self.size[st.id1], self.size[st.id2])
            if deep.any():
                names = [f"{self.bid[int(a)]}-{self.bid[int(b)]}" for a, b in zip(st.id1, st.id2)]
                self._fail(stability.tunnelling(st.volume, st.area, self.size[st.id1], self.size[st.id2], names))

    def _fail(self, msg):
        self.failure = msg
        print(f"[{self.spec['name']}] error: {msg}", flush=True)
        self.O.pause()

    def _check_stable(self, t, ke, elastic, g, st):
        """Stop the run (no histories, exit 3, failure.txt) at the first sample whose numbers
        are not physics: non-finite state, energy grown past the loads' work, tunnelling."""
        if self.failure is not None:
            return
        d = self.dyn
        msg = stability.non_finite(t, positions=self.pos[d], velocities=self.vel[d], angular_velocities=self.angvel[d],
                                   orientations=self.quat[d], kinetic_energy=ke)
        if msg is None:
            forces = [(int(np.flatnonzero(d == y)[0]), np.array(tuple(f))) for y, f, a, b in self.forces
                      if a <= t < b and y in d]
            p = stability.load_power(self.mass[d], self.vel[d], g, forces)
            msg = self.energy.update(t, ke, 0.0 if np.isnan(elastic) else elastic, p)
        if msg is None and len(d):
            if self.e0 is None:
                self.e0 = ke + (0.0 if np.isnan(elastic) else elastic)
            impulses = [(float(np.linalg.norm(tuple(f))) * max(0.0, min(t, b) - a), self.mass[y])
                        for y, f, a, b in self.forces if y in d]
            budget = stability.speed_budget(float(np.sum(self.mass[d])), self.e0, self.g_integral, impulses,
                                            self.jump_dvs)
            msg = stability.speed_check(t, self.mass[d], self.vel[d], ke, budget, self.w_free,
                                        [int(self.bid[int(i)]) for i in d])
        if msg is None and len(st.fn):
            names = [f"{self.bid[int(a)]}-{self.bid[int(b)]}" for a, b in zip(st.id1, st.id2)]
            msg = stability.tunnelling(st.volume, st.area, self.size[st.id1], self.size[st.id2], names)
        if msg is not None:
            self._fail(msg)

    def _check_left(self, t):
        """Record each free block when it first leaves the model (stability.ModelRegion:
        fallen below the supports' underside, or thrown beyond the supports' size plus the
        fall height); once every free block has, stop the run at this sample: what follows
        is the motion of nothing the model holds (run_info.json ``left_model``)."""
        if self.failure is not None or not len(self.dyn):
            return
        out = self.region.outside(self.pos[self.dyn])
        for i in self.dyn[out]:
            i = int(i)
            if i in self.left:
                continue
            p = self.pos[i]
            self.left[i] = {"block": int(self.bid[i]), "time_s": float(t), "where": self.region.where(p),
                            "position_m": p.tolist(), "speed_m_s": float(np.linalg.norm(self.vel[i]))}
            print(f"[{self.spec['name']}] block {self.bid[i]} left the model at t = {t:.3f} s "
                  f"({self.left[i]['where']}): its motion from there has no meaning (summary: unbounded, "
                  "no residual)", flush=True)
        if self.all_left_s is None and len(self.left) == len(self.dyn):
            self.all_left_s = float(t)
            print(f"[{self.spec['name']}] every free block has left the model: stopping at t = {t:.3f} s",
                  flush=True)
            if self.stop_at is None or self.stop_at > t:
                self.stop_at = t

    def _check_settled(self, t, ke_b):
        """A last rest stage with ``until_kinetic_below(_per_weight)``: stop the run once the
        kinetic energy of the free blocks (J, at the recorded samples; blocks fallen off the
        platform or otherwise out of the model left out) has stayed below the threshold for
        ``settle_window`` s;
        run_info.json says whether and when."""
        cfg = self.settle
        if cfg is None or cfg["reached"] or t < self.prog.stages[cfg["stage"] - 1].start:
            return
        # fallen off the platform, or left the model in any other way (stability.ModelRegion)
        fallen = (self.pos[self.dyn, 2] < self.z_floor) | self.region.outside(self.pos[self.dyn])
        ke = float(ke_b[~fallen].sum())
        cfg["final_kinetic_J"] = ke
        cfg["fallen_excluded"] = [int(self.bid[int(i)]) for i in self.dyn[fallen]]
        if ke >= cfg["threshold_J"]:
            self.below_since = None
            return
        if self.below_since is None:
            self.below_since = t
        if t - self.below_since >= cfg["window_s"] - 1e-12:
            cfg.update(reached=True, time_s=float(t), below_since_s=float(self.below_since))
            print(f"[{self.spec['name']}] settled: kinetic energy below {cfg['threshold_J']:.3g} J since "
                  f"t = {self.below_since:.3f} s; stopping at {t:.3f} s", flush=True)
            if self.stop_at is None or self.stop_at > t:
                self.stop_at = t

    def _check_collapse(self, t, R):
        """Tilt stages with ``until_collapse``. Collapse is detected when the vertical
        reaction of the moving blocks drops by ``reaction_drop`` of their weight (the
        paper's Figure 13) or a block moves more than its collapse threshold; the run
        stops ``after_collapse`` s later. The collapse angle (the onset of the motion that
        led to the detection) is found afterwards from the histories:
        drystone/collapse.py, called by drystone/postprocess/summary.py."""
        st = self.prog.stages[self.prog.stage_index(t)]
        if self.collapse is not None or st.type != "tilt" or not st.params.get("until_collapse"):
            return
        up = self.prog.true_vertical(t)
        rv = -float(R @ up)
        disp = np.linalg.norm(self.pos[self.dyn] - self.pos0[self.dyn], axis=1)
        thr = np.array([self.spec["collapse_threshold"][str(self.bid[int(i)])] for i in self.dyn])
        moved = disp > thr
        drop = rv < (1.0 - st.params["reaction_drop"]) * self.w_free
        if drop or moved.any():
            order = np.argsort(-(disp / thr))
            first = [int(self.bid[int(self.dyn[j])]) for j in order[:5] if disp[j] > 0.5 * thr[j]]
            self.collapse = {"angle_deg": self.prog.tilt_deg(t), "time_s": t,  # dated back by the summary
                             "detected_angle_deg": self.prog.tilt_deg(t), "detected_time_s": t,
                             "criterion": "reaction_drop" if drop else "displacement",
                             "vertical_reaction_N": rv, "first_blocks": first}
            print(f"[{self.spec['name']}] collapse detected at {self.collapse['detected_angle_deg']:.2f} deg "
                  f"(t = {t:.2f} s, {self.collapse['criterion']}), blocks {first}", flush=True)
            self.stop_at = t + st.params["after_collapse"]

    # -- run ----------------------------------------------------------------------
    def run(self):
        O = self.O
        builtins._drystone_step = self.step
        wall0 = time.time()
        if self.compiled:
            self._run_compiled()
            self._sync_yade()
        else:
            O.run(self.steps_total, True)
            self.iter, self.t = O.iter, O.time
        wall = time.time() - wall0
        if self.failure is None:
            if not self.compiled:  # the state after the last integration (the arrays are current)
                self._read_states(np.concatenate([self.dyn, np.array(self.moving_static, int)]))
            self._record(self.t)
        if self.failure is not None:  # no histories: nothing that looks like a result
            (self.out / "failure.txt").write_text(self.failure + "\n")
            sys.stdout.flush()
            os._exit(3)
        self.save(wall)

    def save(self, wall):
        arrays = {k: np.asarray(v) for k, v in self.h.items()}
        arrays["format"], arrays["version"] = np.array(HISTORIES_FORMAT), np.array(HISTORIES_VERSION)
        arrays["block_ids"] = np.array([self.bid[int(i)] for i in self.dyn])
        arrays["mass"] = self.mass[self.dyn]
        arrays["pos0"] = self.pos0[self.dyn]
        arrays["quat0"] = self.quat0[self.dyn]
        arrays["cp_names"] = np.array([c[0] for c in self.cp], dtype="U32")
        arrays["cp0"] = np.array([c[2] for c in self.cp]).reshape(-1, 3)
        for name, hc in self.hc.items():
            for k, v in hc.items():
                arrays[f"contact:{name}:{k}"] = np.asarray(v)
        tmp = self.out / "histories.tmp.npz"
        np.savez_compressed(tmp, **arrays)
        os.replace(tmp, self.out / "histories.npz")
        info = {"steps": int(self.iter), "simulated_time_s": float(self.t), "wall_time_s": wall,
                "dt_s": float(self.O.dt), "threads": int(yade.Omega().numThreads),
                "max_contacts": int(self.max_contacts), "final_contacts": int(self.h["n_contacts"][-1]),
                "stopped_early": bool(self.done), "collapse": self.collapse,
                "velocity_jumps": self.jumps, "settle": self.settle,
                "left_model": sorted(self.left.values(), key=lambda r: (r["time_s"], r["block"])),
                "all_left_model_s": self.all_left_s, "model_region": self.region.as_dict(),
                "max_contact_omega_dt": float(self.engine.max_omega_dt),
                "yade_version": yade.config.version if hasattr(yade, "config") else "unknown",
                "engine": self.engine_name,
                "us_per_step": 1e6 * wall / max(1, self.iter),
                "python_us_per_step": 1e6 * self.python_time / max(1, self.iter),
                "kernel_us_per_step": 1e6 * self.kernel_time / max(1, self.iter)}
        tmp = self.out / "run_info.tmp.json"
        tmp.write_text(json.dumps(info, indent=1))
        os.replace(tmp, self.out / "run_info.json")
        print(f"[{self.spec['name']}] done: {info['steps']} steps, {info['simulated_time_s']:.3f} s simulated, "
              f"{wall:.1f} s wall ({info['us_per_step']:.0f} us/step)", flush=True)


def main(argv):
    if len(argv) not in (1, 2):
        raise SystemExit("usage: yade -n -x drystone/yade_scripts/run_case.py SPEC.json [compiled|python]")
    spec = json.loads(Path(argv[0]).read_text())
    Driver(spec, Path(argv[0]).resolve().parent, *argv[1:]).run()


if __name__ == "__main__":  # yade -x runs this file as __main__; importing it runs nothing
    main(sys.argv[1:])
