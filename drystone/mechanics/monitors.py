"""Monitors: the jobs a run does at every recorded sample, whatever engine steps it (the
YADE driver, drystone/yade_scripts/run_case.py, runs them sorted by their ``order``). Each may stop
the run at a time (``run.stop_at``), stop it with a named failure (``run.fail``: no
histories, exit 3) and report what it found in run_info.json (``info``). Two are always
on (``Stability``: drystone/mechanics/stability.py's checks; ``LeftModel``: blocks that left the
model); the stage types add their own when their stage starts (``StageType.monitor`` in
drystone/model/stages.py: a tilt stage's ``Collapse``, a last rest stage's ``Settle``). ``Progress``
runs at every step instead.

No YADE import. ``run`` is the driver as the monitors see it: ``spec_name``, ``prog``
(drystone.model.loading.LoadProgramme), the arrays ``pos``, ``vel`` (bodies, m, m/s) and
``dyn`` (the free bodies' indices), ``pos0``, ``mass`` (kg, inf for non-moving), ``bid``
(index -> block id), ``w_free`` (the free blocks' weight, N), ``forces`` (applied forces:
(index, force, start, end)), ``loads`` (drystone.model.loads.AppliedLoads or None), ``g_integral`` (integral of |g_eff| dt so far, m/s),
``jump_dvs``, ``collapse_threshold`` (block id -> m), ``stop_at`` and ``failure``.
SI units.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from drystone.mechanics import stability


@dataclass
class Sample:
    """What the recorder measured at one sample: time t (s), body acceleration g (3,)
    m/s^2, kinetic energy ke (J) and per free block ke_b, elastic energy (J, NaN where the
    law stores none), the contacts (drystone.mechanics.contact_step.ContactState) and the reaction R
    (3,) of the moving blocks on the non-moving ones (N)."""

    t: float
    g: np.ndarray
    ke: float
    ke_b: np.ndarray
    elastic: float
    contacts: object
    reaction: np.ndarray


class Monitor:
    """A job at every recorded sample; ``order`` sorts the monitors of a run."""

    order = 0

    def on_sample(self, run, s: Sample) -> None:
        raise NotImplementedError

    def info(self) -> dict:
        """Entries for run_info.json."""
        return {}


class Settle(Monitor):
    """A last rest stage with ``until_kinetic_below(_per_weight)``: stop the run once the
    kinetic energy of the free blocks (J, at the recorded samples; blocks fallen off the
    platform or otherwise out of the model left out) has stayed below the threshold for
    the settle window; run_info.json ``settle`` says whether and when."""

    order = 0

    def __init__(self, k: int, cfg: dict, start: float, end: float, z_floor: float,
                 region: stability.ModelRegion):
        self.start, self.z_floor, self.region = start, z_floor, region
        self.cfg = dict(cfg, stage=k + 1, reached=False, time_s=None, max_end_s=end, final_kinetic_J=None)
        self.below_since = None

    def on_sample(self, run, s):
        cfg, t = self.cfg, s.t
        if cfg["reached"] or t < self.start:
            return
        # fallen off the platform, or left the model in any other way (stability.ModelRegion)
        fallen = (run.pos[run.dyn, 2] < self.z_floor) | self.region.outside(run.pos[run.dyn])
        ke = float(s.ke_b[~fallen].sum())
        cfg["final_kinetic_J"] = ke
        cfg["fallen_excluded"] = [int(run.bid[int(i)]) for i in run.dyn[fallen]]
        if ke >= cfg["threshold_J"]:
            self.below_since = None
            return
        if self.below_since is None:
            self.below_since = t
        if t - self.below_since >= cfg["window_s"] - 1e-12:
            cfg.update(reached=True, time_s=float(t), below_since_s=float(self.below_since))
            print(f"[{run.spec_name}] settled: kinetic energy below {cfg['threshold_J']:.3g} J since "
                  f"t = {self.below_since:.3f} s; stopping at {t:.3f} s", flush=True)
            if run.stop_at is None or run.stop_at > t:
                run.stop_at = t

    def info(self):
        return {"settle": self.cfg}


class Stability(Monitor):
    """Stop the run (no histories, exit 3, failure.txt) at the first sample whose numbers
    are not physics (drystone/mechanics/stability.py): non-finite state, energy grown past the loads'
    work, speeds beyond what the loads can give, tunnelling."""

    order = 1

    def __init__(self, w_free: float, size: np.ndarray):
        self.energy = stability.EnergyWatch(w_free)
        self.size = size  # each body's smallest dimension (m)
        self.e0 = None

    def on_sample(self, run, s):
        if run.failure is not None:
            return
        d, t, ke, elastic, st = run.dyn, s.t, s.ke, s.elastic, s.contacts
        msg = stability.non_finite(t, positions=run.pos[d], velocities=run.vel[d], angular_velocities=run.angvel[d],
                                   orientations=run.quat[d], kinetic_energy=ke)
        if msg is None:
            forces = [(int(np.flatnonzero(d == y)[0]), np.array(tuple(f))) for y, f, a, b in run.forces
                      if a <= t < b and y in d]
            p = stability.load_power(run.mass[d], run.vel[d], s.g, forces)
            loads = getattr(run, "loads", None)
            if loads is not None:
                p += loads.power(run.vel, run.angvel)
            msg = self.energy.update(t, ke, 0.0 if np.isnan(elastic) else elastic, p)
        if msg is None and len(d):
            if self.e0 is None:
                self.e0 = ke + (0.0 if np.isnan(elastic) else elastic)
            impulses = [(float(np.linalg.norm(tuple(f))) * max(0.0, min(t, b) - a), run.mass[y])
                        for y, f, a, b in run.forces if y in d]
            if getattr(run, "loads", None) is not None:
                impulses += run.loads.impulses(run.mass, run.inertia)
            budget = stability.speed_budget(float(np.sum(run.mass[d])), self.e0, run.g_integral, impulses,
                                            run.jump_dvs)
            msg = stability.speed_check(t, run.mass[d], run.vel[d], ke, budget, run.w_free,
                                        Labels(lambda k: int(run.bid[int(d[k])])))
        if msg is None and len(st.fn):
            msg = tunnelling(run, st, self.size)
        if msg is not None:
            run.fail(msg)


def tunnelling(run, st, size) -> str | None:
    """stability.tunnelling on the contacts ``st`` (blocks named by id)."""
    names = Labels(lambda k: f"{run.bid[int(st.id1[k])]}-{run.bid[int(st.id2[k])]}")
    return stability.tunnelling(st.volume, st.area, size[st.id1], size[st.id2], names)


class Labels:
    """The labels of a check's rows (``labels[k]``), made only when a message names one: the
    checks pass at nearly every sample, and a list of every block's or contact's name cost
    more than the checks."""

    def __init__(self, label_of):
        self.label_of = label_of

    def __getitem__(self, k):
        return self.label_of(int(k))


class LeftModel(Monitor):
    """Record each free block when it first leaves the model (stability.ModelRegion: fallen
    below the supports' underside, or thrown beyond the supports' size plus the fall
    height) and take it out of the scene there (the driver's ``retire``: no contact search,
    no integration, no energy from then on; it stays where it left); once every free block
    has, stop the run at this sample: what follows is the motion of nothing the model holds
    (run_info.json ``left_model``)."""

    order = 2

    def __init__(self, region: stability.ModelRegion):
        self.region = region
        self.left = {}  # body index -> {"block", "time_s", "where", "position_m", "speed_m_s"}
        self.all_left_s = None

    def on_sample(self, run, s):
        if run.failure is not None or not len(run.dyn):
            return
        t = s.t
        out = self.region.outside(run.pos[run.dyn])
        for i in run.dyn[out]:
            i = int(i)
            if i in self.left:
                continue
            p = run.pos[i]
            self.left[i] = {"block": int(run.bid[i]), "time_s": float(t), "where": self.region.where(p),
                            "position_m": p.tolist(), "speed_m_s": float(np.linalg.norm(run.vel[i]))}
            print(f"[{run.spec_name}] block {run.bid[i]} left the model at t = {t:.3f} s "
                  f"({self.left[i]['where']}): taken out of the scene there (summary: unbounded, "
                  "no residual)", flush=True)
            retire = getattr(run, "retire", None)
            if retire is not None:  # no contact search, integration nor energy from here on
                retire(i, float(s.ke_b[int(np.flatnonzero(run.dyn == i)[0])]))
        if self.all_left_s is None and len(self.left) == len(run.dyn):
            self.all_left_s = float(t)
            print(f"[{run.spec_name}] every free block has left the model: stopping at t = {t:.3f} s",
                  flush=True)
            if run.stop_at is None or run.stop_at > t:
                run.stop_at = t

    def info(self):
        return {"left_model": sorted(self.left.values(), key=lambda r: (r["time_s"], r["block"])),
                "all_left_model_s": self.all_left_s, "model_region": self.region.as_dict()}


class Fallen(Monitor):
    """``output.stop_when_fallen``: stop the run at the first sample at or after the end of
    the last gravity stage (``gravity_end_s``) at which a free stone is certain to have
    collapsed by the package's rule (drystone/mechanics/collapse.py ``stone``): it left the
    model (taken out of the scene), or it fell: its centroid is lower than at the end of
    gravity by more than half its height (``heights``, m, per body index), so it no longer
    stands on its seat and cannot regain it. The run's collapse is then decided whatever
    follows; what it leaves out is the rest of the motion (run_info.json
    ``stopped_when_fallen``)."""

    order = 4

    def __init__(self, heights, gravity_end_s: float):
        self.heights = np.asarray(heights, float)
        self.gravity_end_s = float(gravity_end_s)
        self.z0 = None
        self.stopped = None

    def on_sample(self, run, s):
        if run.failure is not None or self.stopped is not None or not len(run.dyn):
            return
        if s.t < self.gravity_end_s - 1e-9:
            return
        if self.z0 is None:  # the rule's reference: the first sample at the end of gravity
            self.z0 = run.pos[:, 2].copy()
        dyn = run.dyn
        gone = np.asarray(run.removed, bool)[dyn]
        fell = ~gone & (self.z0[dyn] - run.pos[dyn, 2] > 0.5 * self.heights[dyn])
        if not (gone.any() or fell.any()):
            return
        self.stopped = {"time_s": float(s.t), "fell": [int(run.bid[int(i)]) for i in dyn[fell]],
                        "left_model": [int(run.bid[int(i)]) for i in dyn[gone]]}
        print(f"[{run.spec_name}] t = {s.t:.3f} s: a stone collapsed for certain (fell {self.stopped['fell']}, left "
              f"the model {self.stopped['left_model']}): stopping (output.stop_when_fallen)", flush=True)
        if run.stop_at is None or run.stop_at > s.t:
            run.stop_at = float(s.t)

    def info(self):
        return {"stopped_when_fallen": self.stopped}


class Collapse(Monitor):
    """A tilt stage with ``until_collapse``. Collapse is detected when the vertical reaction
    of the moving blocks drops by ``reaction_drop`` of their weight (the paper's Figure 13)
    or a block moves more than its collapse threshold; the run stops ``after_collapse`` s
    later. The collapse angle (the onset of the motion that led to the detection) is found
    afterwards from the histories: drystone/mechanics/collapse.py, called by
    drystone/postprocess/summary.py. Run-wide: the first detection of any tilt stage."""

    order = 3

    def __init__(self, k: int, params: dict):
        self.k, self.params = k, params

    def on_sample(self, run, s):
        t, R = s.t, s.reaction
        if run.collapse is not None or run.prog.stage_index(t) != self.k:
            return
        up = run.prog.true_vertical(t)
        rv = -float(R @ up)
        disp = np.linalg.norm(run.pos[run.dyn] - run.pos0[run.dyn], axis=1)
        thr = np.array([run.collapse_threshold[str(run.bid[int(i)])] for i in run.dyn])
        moved = disp > thr
        drop = rv < (1.0 - self.params["reaction_drop"]) * run.w_free
        if drop or moved.any():
            order = np.argsort(-(disp / thr))
            first = [int(run.bid[int(run.dyn[j])]) for j in order[:5] if disp[j] > 0.5 * thr[j]]
            run.collapse = {"angle_deg": run.prog.tilt_deg(t), "time_s": t,  # dated back by the summary
                            "detected_angle_deg": run.prog.tilt_deg(t), "detected_time_s": t,
                            "criterion": "reaction_drop" if drop else "displacement",
                            "vertical_reaction_N": rv, "first_blocks": first}
            print(f"[{run.spec_name}] collapse detected at {run.collapse['detected_angle_deg']:.2f} deg "
                  f"(t = {t:.2f} s, {run.collapse['criterion']}), blocks {first}", flush=True)
            run.stop_at = t + self.params["after_collapse"]


class Progress:
    """Every step: a progress line every ``every_s`` s of wall time (simulated time, percent,
    stage, tilt, contacts, ETA; a sweep reads the last one from the run's log)."""

    #: a pause longer than this (s of wall time) between two Python steps is not simulation pace
    #: but numba compiling a kernel on its first call (1.5-2.5 min): the ETA clock restarts after it
    STALL_S = 10.0

    def __init__(self, every_s: float = 5.0):
        self.every_s = every_s
        self.t_wall0 = self.t_print = self.t_last = self.frac0 = None

    def eta(self, now: float, frac: float) -> float | None:
        """Seconds left at the pace since the clock started (s), None before any progress."""
        if self.t_wall0 is None or frac <= self.frac0 or now - self.t_wall0 < 1.0:  # no pace measured yet
            return None
        return (now - self.t_wall0) * (1 - frac) / (frac - self.frac0)

    def on_step(self, run, t: float, k: int) -> None:
        now = time.time()
        prog = run.prog
        frac = t / prog.end
        stalled = self.t_last is not None and now - self.t_last > self.STALL_S
        self.t_last = now
        if self.t_wall0 is None or stalled:  # the clock starts after the first step and after a compilation
            self.t_wall0 = now
            self.frac0 = frac
            self.t_print = self.t_print or now
            return
        if now - self.t_print > self.every_s:
            self.t_print = now
            eta = self.eta(now, frac)
            eta = "   ?" if eta is None else f"{eta:6.0f}"
            print(f"[{run.spec_name}] t = {t:7.3f} / {prog.end:.3f} s ({100 * frac:5.1f} %)  "
                  f"stage {k + 1}/{len(prog.stages)} {prog.stages[k].type}  tilt {prog.tilt_deg(t):6.2f} deg  "
                  f"contacts {len(run.engine.contacts().fn)}  ETA {eta} s", flush=True)
