"""The compiled engine's steps that need no Python (inside YADE's interpreter; no YADE
import): between two steps that go through the driver's ``step`` (a recorded sample, a
stage's start, an applied force switched, the run's stop) every step is a contact step
and a leapfrog step, taken in one compiled call (``CompiledStep.advance``) with the
body accelerations and the loads' coefficients of each step computed beforehand, bit for
bit those of the steps taken one by one. ``FieldAhead``: the same for the engines whose
every step goes through ``step`` (YADE integrates), the body-force field a block of steps ahead.
"""
from __future__ import annotations

import time

import numpy as np


def step_times(t: float, dt: float, n: int) -> np.ndarray:
    """The times (s) of n steps from t, dt added one step after another as YADE adds it."""
    return np.add.accumulate(np.concatenate([[t], np.full(n - 1, dt)]))


def quiet_steps(run, dt) -> np.ndarray:
    """Times (s) of the steps from ``run.iter`` on that need no Python: up to the next
    recorded sample, stage start or switch of an applied force, and to the step after
    which the run stops (``stop_at``), at most the run's end."""
    i = run.iter
    nxt = min((i // run.rec_every + 1) * run.rec_every if i % run.rec_every else i, run.steps_total)
    if nxt <= i:
        return np.zeros(0)
    ts = step_times(run.t, dt, nxt - i)
    ends = np.array([st.end for st in run.prog.stages])
    k = np.minimum(np.searchsorted(ends, ts, side="right"), len(ends) - 1)  # prog.stage_index
    cut = len(ts) if np.all(k == k[0]) else int(np.argmax(k != k[0]))
    for _, _, start, end in run.forces:
        on = (start <= ts) & (ts < end)
        if not np.all(on == on[0]):
            cut = min(cut, int(np.argmax(on != on[0])))
    if k[0] != run.stage:  # step() enters a stage
        cut = 0
    if run.stop_at is not None:
        past = np.flatnonzero(ts[:cut] >= run.stop_at)
        if len(past):
            cut = int(past[0]) + 1  # the run stops after that step
    return ts[:cut]


class FieldAhead:
    """``prog.body_acceleration(t)`` of a run's steps taken one at a time, computed ``BLOCK``
    steps ahead at the times YADE will reach (``step_times``):
    the per-step values bit for bit (``LoadProgramme.body_acceleration_at``), 2-4 us a step
    instead of 36-119 us (gravity, a tilt, a record). A step at another time than foreseen
    computes them again."""

    BLOCK = 128

    def __init__(self, prog):
        self.prog = prog
        self.ts, self.g, self.next = np.zeros(0), np.zeros((0, 3)), 0

    def at(self, t: float, dt: float) -> np.ndarray:
        """The field (m/s^2, (3,)) at step time t (s) of steps dt (s) apart."""
        if self.next >= len(self.ts) or self.ts[self.next] != t:
            self.ts = step_times(t, dt, self.BLOCK)
            self.g, self.next = self.prog.body_acceleration_at(self.ts), 0
        self.next += 1
        return self.g[self.next - 1].copy()


def advance_quietly(engine, dt) -> None:
    """The steps of ``quiet_steps`` in one compiled call of ``engine`` (a CompiledEngine;
    the depth check stops it, ``CompiledStep.advance``)."""
    run = engine.run
    ts = quiet_steps(run, dt)
    if len(ts) == 0:
        return
    g = run.prog.body_acceleration_at(ts)  # bit for bit the per-step values
    loads = coef = None
    if run.loads is not None:  # a coefficient row per step; a step where a load is undefined goes through step()
        coef, bad, _ = run.loads.coefficients(ts, g)
        if bad is not None:
            ts, g, coef = ts[:bad], g[:bad], coef[:bad]
            if len(ts) == 0:
                return
        loads = (coef, run.loads.force, run.loads.moment)
    F_ext = np.zeros_like(run.pos)
    for y, f, start, end in run.forces:
        if start <= ts[0] < end:
            F_ext[y] += tuple(f)
    t_k = time.perf_counter()
    done, F, T, integrated = engine.step.advance(run.pos, run.rot, run.vel, run.angvel, dt, g, F_ext,
                                               engine.motion() + (run.quat,), loads)
    run.kernel_time += time.perf_counter() - t_k
    if not integrated:  # stopped on the depth check before integrating step ts[done]
        engine.check_depth()
        if run.failure is not None:
            return
        engine.integrate(dt, g[done], F, T, F_ext, None if coef is None else coef[done])
        done += 1
    if coef is not None:
        run.loads.taken(coef[:done], dt)
    run.g_integral += float(np.sum(np.linalg.norm(g[:done], axis=1))) * dt  # the speed bound
    run.iter += done
    last = ts[done - 1]  # the time of the last step taken
    run.t = last + dt
    if run.stop_at is not None and last >= run.stop_at:
        run.done = True
    run.progress.on_step(run, run.t, run.stage)
