"""Run one resolved case inside YADE:  yade -n -x drystone/yade_scripts/run_case.py SPEC.json [ENGINE]

SPEC.json is written by ``python -m drystone run CASE.toml`` (drystone/runner.py), which
validates the case and the geometry first; this script only simulates and writes
``histories.npz`` and ``run_info.json`` into the output folder (under temporary names,
renamed when complete). Units SI; the simulation runs in the platform frame
(drystone/model/loading.py).

The driver composes a run as YADE composes ``O.engines``: the scene (scene.py), one step
engine (engines.py: ``compiled``, ``python`` or ``yade``, chosen by the case's contact law
and ENGINE, drystone/mechanics/laws.py), the recorder (recorder.py) and the monitors run at every
recorded sample (drystone/mechanics/monitors.py: stability, blocks leaving the model, and those the
stages add: a tilt's collapse, a last rest's settling).
"""
from __future__ import annotations

import json
import os
import resource
import sys
import time
from pathlib import Path

import numpy as np
import yade
from yade import log

# drystone is installed in the interpreter YADE runs (make setup: pip install -e .)
from drystone.mechanics import laws, monitors, rotations, stability  # noqa: E402
from drystone.model.loading import LoadProgramme  # noqa: E402
from drystone.model.loads import AppliedLoads  # noqa: E402
from drystone.simulate import ENGINES as REQUESTS  # noqa: E402 (what ENGINE may ask for)
from drystone.model.spec import Spec, load_spec  # noqa: E402
from drystone.yade_scripts import scene as sc  # noqa: E402
from drystone.yade_scripts.engines import ENGINES  # noqa: E402
from drystone.yade_scripts.quiet_steps import FieldAhead  # noqa: E402
from drystone.yade_scripts.recorder import Recorder  # noqa: E402

# YADE's polyhedra intersection warns "Unhandled switch case" on exactly touching faces,
# every step; it is harmless (the contact is then treated as no overlap).
log.setLevel("Polyhedra_support.cpp", log.ERROR)


class Driver:
    """One run: the scene, its state arrays (bodies in YADE's order; SI), the load
    programme, the engine, the recorder and the monitors (drystone/mechanics/monitors.py)."""

    def __init__(self, spec: Spec, out: Path | None = None, engine: str = "compiled"):
        if engine not in REQUESTS:
            raise SystemExit(f"unknown engine {engine!r}; allowed: {', '.join(REQUESTS)}")
        self.spec, self.spec_name, self.O = spec, spec.name, yade.Omega()
        self.out = Path(out if out is not None else spec.out_dir)  # the folder of spec.json
        engine_class = ENGINES[laws.get(spec.law).engine(engine, spec.detection)]
        tables = sc.build(spec, integrate=engine_class.yade_integrates)
        self.newton, self.yid, self.bid = tables["newton"], tables["yid"], tables["bid"]
        self.members = tables["members"]  # a clump's YADE id -> its members' ids
        self.dyn = np.array(tables["dynamic"], int)
        O, nb = self.O, len(self.O.bodies)
        self.states = [O.bodies[i].state for i in range(nb)]
        # a clump's members move with it: never integrated themselves (mass inf here). A moving
        # stone keeps its mass even with every dof blocked (blocked_dofs "xyzXYZ"), which YADE
        # reports as dynamic = False: it is a free stone that cannot move, not a fixed one
        moving = set(tables["dynamic"])
        self.mass = np.array([O.bodies[i].state.mass if i in moving else np.inf for i in range(nb)])
        self.inertia = np.array([tuple(O.bodies[i].state.inertia) for i in range(nb)])
        self.blocks = {b["id"]: b for b in spec.blocks}
        self.pos = np.array([tuple(O.bodies[i].state.pos) for i in range(nb)])
        self.pos0 = self.pos.copy()
        self.vel, self.angvel = np.zeros((nb, 3)), np.zeros((nb, 3))
        self.quat = np.array([tuple(O.bodies[i].state.ori) for i in range(nb)])
        self.quat0 = self.quat.copy()
        self.rot = rotations.to_matrix(self.quat)
        # the convex shapes the contact laws see (sc.shapes): owner, local_v, shape_size; size per body
        self.owner, self.local_v, self.shape_size, self.size = sc.shapes(O, self.blocks, self.bid, tables["members"],
                                                                         self.pos, self.rot)
        self.prog = LoadProgramme.from_spec(spec, self.out)  # excitation samples from the run folder
        self.moving_static = [self.yid[b] for b in self.prog.moving_blocks()]
        self.moving = np.concatenate([self.dyn, np.array(self.moving_static, int)])  # the bodies read back
        self.forces = [(self.yid[f["block"]], yade.Vector3(*f["force"]), f["start"],
                        f["end"] if f["end"] is not None else np.inf) for f in spec.forces]
        # the case's [[loads]] over the bodies (a stone's clump body for a multi-part one), or None
        self.loads = AppliedLoads.from_spec(spec, self.prog, self.yid, nb)
        self.load_limit_s = None  # when a load reached its limit after the collapse (run_info.json)
        self.engine = engine_class(self)
        self.rec_every = max(1, int(round(spec.output["interval"] / spec.dt)))
        self.steps_total = int(np.ceil(self.prog.end / spec.dt - 1e-9))
        self.recorder = Recorder(self)
        self.w_free = float(np.sum(self.mass[self.dyn])) * spec.gravity
        self.collapse_threshold = spec.collapse_threshold
        # a stone whose centroid is below the platform's underside has fallen off the model
        self.z_floor = min((min(v[2] for v in b["vertices"]) for b in spec.blocks if b["role"] == "platform"),
                           default=-np.inf)
        self.region = stability.ModelRegion.from_blocks(spec.blocks)
        # free blocks taken out of the scene when they left the model (``retire``), and the kinetic
        # energy they carried out of it then (J, cumulative: histories.npz ``removed_kinetic``)
        self.removed = np.zeros(nb, bool)
        self.removed_kinetic = 0.0
        self.stability = monitors.Stability(self.w_free, self.size)
        self.monitors = [self.stability, monitors.LeftModel(self.region)]
        if spec.output.get("stop_when_fallen"):
            heights = np.array([float(np.ptp(np.asarray(self.blocks[self.bid.get(i)]["vertices"], float)[:, 2]))
                                if self.bid.get(i) in self.blocks else np.inf for i in range(nb)])
            grav = [st.end for st in self.prog.stages if st.type == "gravity"]
            self.monitors.append(monitors.Fallen(heights, grav[-1] if grav else 0.0))
        self.stage, self.stop_at, self.done, self.failure, self.collapse = -1, None, False, None, None
        self.jumps, self.jump_dvs = [], []  # velocity jumps at stage starts (run_info.json; the speed bound)
        self.g_integral = 0.0  # integral of |g_eff| dt over the steps taken, m/s (stability.speed_budget)
        self.iter, self.t = 0, 0.0  # the step being taken: YADE's iteration and time
        self.field = FieldAhead(self.prog)  # the body-force field of the steps one at a time
        self.python_time = self.kernel_time = 0.0  # s in the per-step Python, of which in compiled kernels
        self.progress = monitors.Progress()

    def step(self):
        """One step that needs Python: the load, a stage's start, the forces, a recorded
        sample with its monitors, the motion (engines.py calls it)."""
        t_py = time.perf_counter()
        e = self.engine
        e.clock()
        t = self.t
        g = self.field.at(t, self.O.dt) if e.yade_integrates else self.prog.body_acceleration(t)
        self.g_integral += float(np.linalg.norm(g)) * self.O.dt  # the speed bound (stability.speed_budget)
        k = self.prog.stage_index(t)
        if k != self.stage:
            enter_stage(self, k)
        e.forces(t, g)
        if self.iter % self.rec_every == 0:
            e.before_sample()
            self._sample(t, g)
        e.finish_step(g)
        self.progress.on_step(self, t, k)
        if self.stop_at is not None and t >= self.stop_at:
            self.done = True
            e.stop()
        if e.yade_integrates:
            self.python_time += time.perf_counter() - t_py

    def _sample(self, t, g=None):
        s = self.recorder.sample(t, g)
        for m in self.monitors:  # kept in their order (enter_stage)
            m.on_sample(self, s)

    def retire(self, i: int, kinetic_J: float) -> None:
        """Take free body ``i`` out of the scene: it left the model (monitors.LeftModel) at
        this sample, whose kinetic energy of it, ``kinetic_J``, leaves the energy balance with
        it (``removed_kinetic``). From the next step on it is neither integrated (it stays
        where it left) nor in any contact search, and carries no kinetic energy nor work."""
        self.removed[i] = True
        self.removed_kinetic += float(kinetic_J)
        self.engine.retire(i)

    def load_limit(self, t, why):
        """A load is undefined at t (the retained soil's Mononobe-Okabe limit, ``why``): before
        a collapse the run fails (no result that looks complete); after one it ends with
        this step (which keeps the loads of the step before)."""
        if self.collapse is None:
            self.fail(f"t = {t:.6g} s (tilt {self.prog.tilt_deg(t):.4g} deg): [[loads]]: {why}; the retained soil "
                      "reached its limit before the wall collapsed: no result")
        elif self.load_limit_s is None:
            self.load_limit_s = float(t)
            print(f"[{self.spec_name}] t = {t:.6g} s: the retained soil reached its limit after the collapse; "
                  "the run ends here", flush=True)
            if self.stop_at is None or self.stop_at > t:
                self.stop_at = t

    def fail(self, msg):
        """Stop the run on a failed check: no histories, failure.txt, exit 3."""
        self.failure = msg
        print(f"[{self.spec_name}] error: {msg}", flush=True)
        self.O.pause()

    def run(self):
        wall0 = time.time()
        self.engine.loop()
        self.engine.finish()
        wall = time.time() - wall0
        if self.failure is None:
            self._sample(self.t)  # the state after the last step
        if self.failure is not None:  # no histories: nothing that looks like a result
            (self.out / "failure.txt").write_text(self.failure + "\n")
            sys.stdout.flush()
            os._exit(3)
        self.recorder.save(self.out)
        write_run_info(self, wall)


def enter_stage(run, k: int) -> None:
    """The start of stage ``k`` of ``run`` (the driver): imposed velocities, the base's velocity
    jump given to every free block (its energy), the stage's monitor."""
    run.stage = k
    st = run.prog.stages[k]
    print(f"[{run.spec_name}] stage {k + 1}/{len(run.prog.stages)}: {st.type} "
          f"{st.start:.3f}-{st.end:.3f} s", flush=True)
    for block, v in run.prog.imposed_velocities(run.t).items():
        run.engine.set_velocity(run.yid[block], v)
    dv = run.prog.velocity_jump(k)
    if np.any(dv):
        # Eq. 9 as a displacement: the base's velocity jump, as a relative velocity of every
        # free block (drystone.runner.initial_relative_velocity); blocked translations keep theirs
        for i in run.dyn:
            state = run.states[int(i)]
            free = np.array([c not in (state.blockedDOFs or "") for c in "xyz"], float)
            v0 = run.engine.velocity(int(i))
            run.engine.set_velocity(int(i), v0 + dv * free)
            gained = 0.5 * run.mass[i] * (np.sum((v0 + dv * free) ** 2) - np.sum(v0 ** 2))
            run.stability.energy.inject(gained)
            run.engine.add_work(gained)  # the base's impulse: work of the excitation (energy balance)
        run.jumps.append({"stage": k + 1, "time_s": float(run.t), "relative_velocity_m_s": dv.tolist()})
        run.jump_dvs.append(np.asarray(dv, float))
        print(f"[{run.spec_name}] stage {k + 1}: base velocity jump, free blocks get {dv.tolist()} m/s "
              "relative to the platform", flush=True)
    m = run.prog.monitor(k, run)
    if m is not None:
        run.monitors = sorted(run.monitors + [m], key=lambda x: x.order)


def peak_memory_mib() -> float:
    """The process's peak resident memory, MiB: Linux's ``VmHWM`` (which a worker serving many
    runs starts again at each, drystone/yade_scripts/worker.py), else ``ru_maxrss``."""
    try:
        with open("/proc/self/status") as f:
            return next(float(x.split()[1]) for x in f if x.startswith("VmHWM:")) / 1024.0  # kB
    except (OSError, StopIteration, ValueError, IndexError):
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # KiB on Linux


def write_run_info(run, wall) -> None:
    """run_info.json of a finished run (the driver ``run``; ``wall`` its wall time, s) into its folder."""
    info = {"steps": int(run.iter), "simulated_time_s": float(run.t), "wall_time_s": wall,
            "dt_s": float(run.O.dt), "threads": int(yade.Omega().numThreads),
            "max_contacts": int(run.recorder.max_contacts), "final_contacts": int(run.recorder.h["n_contacts"][-1]),
            "stopped_early": bool(run.done), "collapse": run.collapse, "velocity_jumps": run.jumps,
            "settle": None}
    if run.loads is not None:
        info["load_limit_s"] = run.load_limit_s
    for m in run.monitors:
        info.update(m.info())
    info.update({"max_contact_omega_dt": float(run.engine.max_omega_dt),
                 "yade_version": yade.config.version if hasattr(yade, "config") else "unknown",
                 "engine": run.engine.name, "us_per_step": 1e6 * wall / max(1, run.iter),
                 "python_us_per_step": 1e6 * run.python_time / max(1, run.iter),
                 "kernel_us_per_step": 1e6 * run.kernel_time / max(1, run.iter),
                 # the run's peak resident memory (MiB), in a worker too (peak_memory_mib)
                 "max_rss_mib": peak_memory_mib(),
                 # rebuilds of the compiled step's neighbour list (drystone/mechanics/neighbours.py)
                 "neighbour_list_builds": getattr(getattr(run.engine.step, "neighbours", None), "builds", None)})
    tmp = run.out / "run_info.tmp.json"
    tmp.write_text(json.dumps(info, indent=1))
    os.replace(tmp, run.out / "run_info.json")
    print(f"[{run.spec_name}] done: {info['steps']} steps, {info['simulated_time_s']:.3f} s simulated, "
          f"{wall:.1f} s wall ({info['us_per_step']:.0f} us/step)", flush=True)


def main(argv):
    if len(argv) not in (1, 2):
        raise SystemExit("usage: yade -n -x drystone/yade_scripts/run_case.py SPEC.json [compiled|python]")
    Driver(load_spec(argv[0]), Path(argv[0]).resolve().parent, *argv[1:]).run()


if __name__ == "__main__":  # yade -x runs this file as __main__; importing it runs nothing
    main(sys.argv[1:])
