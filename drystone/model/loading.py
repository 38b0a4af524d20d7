"""The load programme: what the stages of a case impose at time t (no YADE import).

Everything is formulated in the platform frame (the frame moving with the rigid
platform, which therefore never moves in the simulation):

* gravity is ramped linearly over ``ramp`` s and then held;
* a platform tilt by theta (deg) towards the horizontal unit vector ``d`` turns gravity
  into g_eff = g (sin(theta) d - cos(theta) z): the exact body force in the tilted frame
  except the fictitious forces of the rotation itself (centrifugal omega^2 r and Euler
  r d(omega)/dt, below 1e-5 g at the paper's 1 deg/s on a 0.4 m wall);
* a base acceleration a_b(t) along ``e`` adds the inertial body force -a_b e (exact for a
  rigid, translating base): no displacement needs to be integrated from the record, so no
  baseline drift enters, and block displacements are directly relative to the platform;
* a sine excitation with ``start = "displacement"`` (the Sacsayhuaman paper's Eq. 9 as a
  base displacement) also carries the base's velocity jump at its start: every free block
  gets the relative velocity ``initial_relative_velocity`` = -(A / w) e when the stage
  begins (``velocity_jump``; derivation in ``drystone.model.stages.initial_relative_velocity``);
* a settlement moves one non-moving block down at constant speed;
* a last rest stage may end early once the kinetic energy has settled (``settle``).

What each stage type imposes is declared with it (drystone/model/stages.py); ``LoadProgramme``
composes the stages' contributions at t: the body-force field and the imposed velocities.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from drystone import libm
from drystone.model.spec import upgrade_stage
from drystone.model.stages import REGISTRY, StageType
from drystone.units import GRAVITY

Z = np.array([0.0, 0.0, 1.0])


@dataclass
class Stage:
    """One resolved stage: ``type`` a key of drystone.model.stages.REGISTRY (gravity, settlement,
    tilt, excitation, rest); absolute start and end times (s); ``params`` (copied: a
    programme may add to them, e.g. an excitation's samples)."""

    type: str
    start: float
    end: float
    params: dict = field(default_factory=dict)

    def __post_init__(self):
        if self.type not in REGISTRY:
            raise ValueError(f"unknown stage type {self.type!r}; known: {sorted(REGISTRY)}")
        self.params = dict(self.params)

    @property
    def behaviour(self) -> StageType:
        """What the stage's type imposes (drystone/model/stages.py)."""
        return REGISTRY[self.type]


class LoadProgramme:
    """Piecewise load history built from resolved stages.

    ``gravity`` m/s^2; stages must be contiguous and in order. Excitations carry
    ``acc`` (samples, m/s^2), ``dt`` (s) and ``direction`` (unit 3-vector); tilts carry
    ``rate_deg_s``, ``towards`` (unit horizontal 3-vector).
    """

    def __init__(self, stages: list[Stage], gravity: float = GRAVITY):
        self.stages = stages
        self.gravity = float(gravity)
        self.end = stages[-1].end if stages else 0.0
        self._towards = np.array([0.0, 1.0, 0.0])
        for s in stages:
            d = s.behaviour.towards(s)
            if d is not None:  # the first tilt stage's direction
                self._towards = d
                break

    @classmethod
    def from_spec(cls, spec, folder=None) -> LoadProgramme:
        """The programme of a spec (a drystone.model.spec.Spec, or a spec.json dict of any
        version); with ``folder`` (the run's), the files the stages need (excitation
        samples) are loaded from it."""
        stages = []
        for st in spec["stages"]:
            st = upgrade_stage(st)
            stages.append(Stage(st["type"], st["start"], st["end"], st["params"]))
        prog = cls(stages, spec["gravity"])
        if folder is not None:
            for s in prog.stages:
                s.behaviour.load_samples(s, folder)
        return prog

    def stage_index(self, t: float) -> int:
        for k, s in enumerate(self.stages):
            if t < s.end:
                return k
        return len(self.stages) - 1

    # The body-force field at many times in one call (``*_at``: ``ts`` a 1-D array, s) and
    # at one (the scalar methods, which call them): the same numbers bit for bit, so a
    # compiled loop given a sample's worth of steps at once runs as one step at a time.
    def gravity_scale_at(self, ts: np.ndarray) -> np.ndarray:
        """Fraction of gravity applied at each time (0..1): the first gravity stage's ramp."""
        for s in self.stages:
            scale = s.behaviour.gravity_scale(s, ts)
            if scale is not None:
                return scale
        return np.ones(len(ts))  # no gravity stage: gravity on from the start

    def tilt_deg_at(self, ts: np.ndarray) -> np.ndarray:
        """Platform tilt at each time (deg), accumulated over tilt stages."""
        theta = np.zeros(len(ts))
        for s in self.stages:
            theta = theta + s.behaviour.tilt_increment(s, ts)
        return theta

    def base_acceleration_at(self, ts: np.ndarray) -> np.ndarray:
        """Base acceleration vectors (m/s^2, (n, 3)) at the times: linear interpolation of
        the samples of the stage that shakes the base then (the first, if several)."""
        out = np.zeros((len(ts), 3))
        free = np.ones(len(ts), bool)  # times no stage has claimed yet
        for s in self.stages:
            got = s.behaviour.base_acceleration(s, ts)
            if got is not None:
                on, a = got
                claim = free[on]
                out[np.flatnonzero(on)[claim]] = a[claim]
                free &= ~on
        return out

    def body_acceleration_at(self, ts: np.ndarray) -> np.ndarray:
        """Effective body-force field per unit mass in the platform frame (m/s^2, (n, 3)) at
        the times: gravity turned by the tilt, minus the base acceleration. sin and cos are
        the C library's (``drystone.libm``: numpy's AVX-512 variants differ in the last bits)."""
        ts = np.asarray(ts, float)
        th = self.tilt_deg_at(ts) * (math.pi / 180.0)  # as math.radians
        s, c = libm.sin(th)[:, None], libm.cos(th)[:, None]
        g = (self.gravity * self.gravity_scale_at(ts))[:, None] * (s * self._towards - c * Z)
        return g - self.base_acceleration_at(ts)

    def gravity_scale(self, t: float) -> float:
        """Fraction of gravity applied at t (0..1)."""
        return float(self.gravity_scale_at(np.array([t]))[0])

    def tilt_deg(self, t: float) -> float:
        """Platform tilt at t (deg)."""
        return float(self.tilt_deg_at(np.array([t]))[0])

    def base_acceleration(self, t: float) -> np.ndarray:
        """Base acceleration vector (m/s^2) at t."""
        return self.base_acceleration_at(np.array([t]))[0]

    def body_acceleration(self, t: float) -> np.ndarray:
        """Effective body-force field per unit mass in the platform frame (m/s^2) at t."""
        return self.body_acceleration_at(np.array([t]))[0]

    def velocity_jump(self, k: int) -> np.ndarray:
        """Relative velocity (m/s, platform frame) added to every free block when stage k
        begins: -v_base(0) for a sine excitation started as a displacement, else zero."""
        s = self.stages[k]
        return s.behaviour.velocity_jump(s)

    def settle(self, k: int, weight: float) -> dict | None:
        """Early end of rest stage k: {"threshold_J", "window_s"} when it has an
        ``until_kinetic_below`` (J) or ``until_kinetic_below_per_weight`` (m, times
        ``weight``, the free blocks' weight in N), else None."""
        s = self.stages[k]
        return s.behaviour.settle(s, weight)

    def monitor(self, k: int, run):
        """The monitor stage k adds from its start (``StageType.monitor``), or None."""
        s = self.stages[k]
        return s.behaviour.monitor(s, k, run)

    def imposed_velocities(self, t: float) -> dict[int, np.ndarray]:
        """Velocities (m/s) imposed on non-moving blocks at t, by block id."""
        out = {}
        for s in self.stages:
            out.update(s.behaviour.imposed_velocities(s, t))
        return out

    def moving_blocks(self) -> list[int]:
        """Ids of the non-moving blocks whose velocity a stage imposes (settlements)."""
        return [b for s in self.stages for b in s.behaviour.moving_blocks(s)]

    def true_vertical(self, t: float) -> np.ndarray:
        """Unit vector of the true (world) vertical, up, seen in the platform frame."""
        th = math.radians(self.tilt_deg(t))
        return math.cos(th) * Z - math.sin(th) * self._towards

    def to_world(self, t: float, x: np.ndarray) -> np.ndarray:
        """Platform-frame positions (n, 3) to world coordinates for display: rotation by
        the tilt about the horizontal axis z x towards through the origin."""
        th = math.radians(self.tilt_deg(t))
        axis = np.cross(Z, self._towards)
        axis = axis / np.linalg.norm(axis)
        # rotate by +theta about z x towards: the top moves towards 'towards'
        k = axis
        x = np.atleast_2d(x)
        c, s_ = math.cos(th), math.sin(th)
        return x * c + np.cross(k, x) * s_ + np.outer(x @ k, k) * (1 - c)
