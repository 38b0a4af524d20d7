"""Checks that stop a run whose numbers are no longer physics (plain Python, used by the
YADE driver at every recorded sample; SI units).

* ``non_finite``: any NaN or infinity in the state or the energies.
* ``EnergyWatch``: the mechanical energy the model stores, E = kinetic + elastic (J), can
  grow only by the work of the loads (gravity and the base's inertial body force m g_eff,
  applied forces) plus what velocity jumps inject; contacts and damping only dissipate.
  The work is bounded from above by W = integral of sum |F_i . v_i| dt (trapezoid over the
  recorded samples). A run is unstable when E - E_0 > 2 W + injected + E_tol: the factor 2
  and E_tol (the weight of the free blocks times 1 mm) absorb the sampling error of W
  between samples; an explicit integrator past its stable step grows E exponentially, by
  orders of magnitude, far past this bound.
* ``tunnelling``: a contact whose penetration depth (overlap volume / contact area) exceeds
  half the smallest dimension of the smaller block: the penalty spring cannot hold the
  load (a force too large for K_n, or a step too large), and the blocks would pass through
  each other.
* ``speed_limits``: velocities beyond what the loads can give (a bound independent of the
  velocities themselves, which the work bound of ``EnergyWatch`` is not: a state that blows
  up makes its own work bound grow with it). With E = kinetic + elastic energy of the free
  blocks, M their mass, contacts that only dissipate and dE/dt <= sum m_i |g_eff| |v_i| <=
  |g_eff| sqrt(M) sqrt(2 E) (Cauchy-Schwarz), sqrt(E) grows at most at the rate
  |g_eff| sqrt(M/2); an applied force F on a block of mass m adds at most |F| / sqrt(2 m), a
  velocity jump dv of every free block (Minkowski) sqrt(M/2) |dv|. So
  sqrt(E(t)) <= sqrt(E_0) + sqrt(M/2) integral |g_eff| dt + sum integral |F| dt / sqrt(2 m)
  + sum sqrt(M/2) |dv| (the budget, sqrt(J)), and block i's speed <= sqrt(2 / m_i) x budget:
  for one block accelerated from rest by a constant a, exactly a t. A run is unstable when
  sqrt(kinetic energy) > SPEED_FACTOR x budget + sqrt(E_tol), E_tol as for ``EnergyWatch``.
* ``ModelRegion``: where the motion of a free block has a physical meaning. The model is
  the supports (platform and fixed blocks) in the platform frame; nothing holds a block
  beyond them, and the model has no ground. The region is the bounding box of the supports
  and of the free blocks at t = 0, enlarged horizontally and upwards by the supports'
  horizontal size L (the larger of their x and y extents) plus the fall height H (the top of
  the free blocks minus the supports' underside), down to the underside itself. A free
  block whose centroid is outside has left the model (for good: nothing can bring it back):
  below the underside it fell off the supports, beyond the margin it was thrown away (a
  block toppling or jumping off an edge is below the underside long before it is L + H
  away), so its motion, in a frame that follows the platform's own motion, has no
  meaning: the YADE driver takes it out of the scene there (monitors.LeftModel: no contact
  search, integration nor energy from then on; it stays where it left), the summary marks
  it unbounded and gives no residual for it, and the driver stops the run once every free
  block has left.
"""
from __future__ import annotations

import math

import numpy as np

#: energy tolerance per newton of free weight (m): E_tol = W_free x this
E_TOL_M = 1e-3
#: work bound factor (see module docstring)
WORK_FACTOR = 2.0
#: a contact deeper than this fraction of the smaller block's smallest dimension tunnels
TUNNEL_FRACTION = 0.5
#: factor on the speed budget (module docstring, ``speed_limits``): the budget is a strict
#: bound for the continuous motion with dissipative contacts; the factor 2 absorbs the
#: leapfrog's bounded energy error in contacts (of order (omega dt)^2 of the contact energy at
#: the automatic step) and a penalty law that is not exactly conservative (K_n V applied at
#: the overlap's centroid, its area varying); a blow-up grows exponentially, the budget linearly
SPEED_FACTOR = 2.0


def non_finite(t: float, **arrays) -> str | None:
    """Message naming the quantities with NaN or infinite entries at time ``t`` (s), or None."""
    bad = [k for k, a in arrays.items() if not np.all(np.isfinite(np.asarray(a, float)))]
    return f"non-finite {', '.join(bad)} at t = {t:.6g} s" if bad else None


class EnergyWatch:
    """Energy balance check over recorded samples (module docstring)."""

    def __init__(self, free_weight_N: float):
        self.e_tol = E_TOL_M * float(free_weight_N)
        self.e0 = None
        self.work = 0.0  # bound on the loads' work so far, J
        self.injected = 0.0  # kinetic energy given by velocity jumps, J
        self._last = None  # (t, |power|) of the previous sample

    def inject(self, energy_J: float) -> None:
        """Energy put in by an imposed velocity jump (J, may be negative)."""
        self.injected += max(0.0, float(energy_J))

    def update(self, t: float, kinetic_J: float, elastic_J: float, power_abs_W: float) -> str | None:
        """Add one sample; returns a message if the energy grew beyond the bound, else None."""
        e = float(kinetic_J) + float(elastic_J)
        if self._last is not None:
            t0, p0 = self._last
            self.work += 0.5 * (p0 + power_abs_W) * max(0.0, t - t0)
        self._last = (t, float(power_abs_W))
        if self.e0 is None:
            self.e0 = e
            return None
        grown = e - self.e0
        bound = WORK_FACTOR * self.work + self.injected + self.e_tol
        if grown > bound:
            return (f"the energy stored in the model grew by {grown:.4g} J by t = {t:.6g} s while the loads did at "
                    f"most {self.work:.4g} J of work (bound {bound:.4g} J): the integration is unstable (time step "
                    f"too large for the contact stiffness, or forces too large for it)")
        return None


def load_power(mass, vel, g_eff, forces=()) -> float:
    """Upper bound of the loads' power (W): sum over free blocks of |m v . g_eff| plus
    |F . v| of applied forces ``(index into vel, force)``."""
    p = float(np.sum(np.abs(np.asarray(mass) * (np.asarray(vel) @ np.asarray(g_eff)))))
    for i, f in forces:
        p += abs(float(np.dot(vel[i], f)))
    return p


def tunnelling(volume, area, size_a, size_b, names) -> str | None:
    """Message for the deepest contact whose depth volume/area (m) exceeds TUNNEL_FRACTION
    of the smaller of its blocks' smallest dimensions ``size_a``, ``size_b`` (m), or None.
    ``names``: a label per contact."""
    volume, area = np.asarray(volume, float), np.asarray(area, float)
    if not len(volume):
        return None
    with np.errstate(divide="ignore", invalid="ignore"):
        depth = np.where(area > 0, volume / area, 0.0)
    limit = TUNNEL_FRACTION * np.minimum(size_a, size_b)
    over = np.flatnonzero(np.nan_to_num(depth) > limit)
    if not len(over):
        return None
    k = over[np.argmax(depth[over] / limit[over])]
    return (f"contact {names[k]} penetrates {depth[k]:.4g} m, more than {TUNNEL_FRACTION:g} x the smaller block's "
            f"smallest dimension ({limit[k] / TUNNEL_FRACTION:.4g} m): the penalty contact cannot hold the load "
            f"and the blocks pass through each other (a force too large for K_n, or a time step too large)")


def speed_budget(total_mass_kg: float, e0_J: float, g_integral_m_s: float, impulses=(), jumps=()) -> float:
    """The bound of sqrt(kinetic + elastic energy) (sqrt(J)) the loads allow (module
    docstring): ``total_mass_kg`` of the free blocks, ``e0_J`` their energy at the start,
    ``g_integral_m_s`` = integral of |g_eff| dt so far (m/s), ``impulses``: (integral |F| dt
    (N s), mass of the block it acts on (kg)) per applied force, ``jumps``: the velocity
    jumps given to every free block so far (3-vectors, m/s)."""
    half = math.sqrt(0.5 * float(total_mass_kg))
    b = math.sqrt(max(0.0, float(e0_J))) + half * float(g_integral_m_s)
    b += sum(float(i) / math.sqrt(2.0 * float(m)) for i, m in impulses)
    b += sum(half * float(np.linalg.norm(dv)) for dv in jumps)
    return b


def speed_limits(mass, budget: float, free_weight_N: float) -> np.ndarray:
    """Largest speed (m/s) each free block of ``mass`` (kg) may reach before the run counts
    as unstable: sqrt(2 / m_i) x (SPEED_FACTOR x ``budget`` + sqrt(E_tol)), E_tol =
    E_TOL_M x ``free_weight_N`` (the tolerance of ``EnergyWatch``: 0.14 m/s for one block)."""
    return np.sqrt(2.0 / np.asarray(mass, float)) * (SPEED_FACTOR * budget + math.sqrt(E_TOL_M * free_weight_N))


def speed_check(t: float, mass, vel, kinetic_J: float, budget: float, free_weight_N: float, names) -> str | None:
    """Message when the kinetic energy of the free blocks (J, rotations included) exceeds
    what the loads can give (``speed_limits``: sqrt(kinetic) > SPEED_FACTOR x ``budget`` +
    sqrt(E_tol)), naming the block fastest against its limit; else None. ``vel`` (n, 3) m/s,
    ``names``: the blocks' ids."""
    e_tol = E_TOL_M * float(free_weight_N)
    if math.sqrt(max(0.0, float(kinetic_J))) <= SPEED_FACTOR * budget + math.sqrt(e_tol):
        return None
    speed = np.linalg.norm(np.asarray(vel, float).reshape(-1, 3), axis=1)
    lim = speed_limits(mass, budget, free_weight_N)
    k = int(np.argmax(speed / lim)) if len(speed) else 0
    who = f"block {names[k]} moves at {speed[k]:.4g} m/s (its limit {lim[k]:.4g} m/s)" if len(speed) else "the blocks"
    return (f"velocities beyond what the loads can give at t = {t:.6g} s: {who}; kinetic energy {kinetic_J:.4g} J "
            f"against at most {(SPEED_FACTOR * budget + math.sqrt(e_tol)) ** 2:.4g} J from gravity, the base's "
            f"motion, applied forces and velocity jumps (speed bound, drystone/mechanics/stability.py): the integration is "
            f"unstable (time step too large for the contact stiffness, or forces too large for it)")


#: the rule of ``ModelRegion`` in one sentence (summary.json's run.left_model.rule)
REGION_RULE = ("a free block has left the model when its centroid is below the supports' underside, or farther "
               "horizontally from the bounding box of the supports and free blocks at t = 0 (or above its top) than "
               "the supports' horizontal size plus the fall height (top of the free blocks minus the supports' "
               "underside): nothing holds it any more, and its motion in the platform frame has no physical meaning "
               "(drystone/mechanics/stability.py ModelRegion)")


class ModelRegion:
    """The region where a free block's motion has a physical meaning (module docstring):
    a block has left the model when its centroid is outside [``lo``, ``hi``] (m, platform
    frame)."""

    def __init__(self, lo, hi, margin: float, size: float, fall: float):
        self.lo, self.hi = np.asarray(lo, float), np.asarray(hi, float)
        self.margin, self.size, self.fall = float(margin), float(size), float(fall)

    @classmethod
    def from_blocks(cls, blocks) -> ModelRegion:
        """From the blocks at t = 0 (dicts with ``role``: platform, fixed or free, and
        ``vertices``, m). Without free blocks or supports the region is unbounded."""
        sup = [np.asarray(b["vertices"], float) for b in blocks if b["role"] != "free"]
        free = [np.asarray(b["vertices"], float) for b in blocks if b["role"] == "free"]
        if not sup or not free:
            return cls(np.full(3, -np.inf), np.full(3, np.inf), np.inf, np.inf, np.inf)
        sup, free = np.concatenate(sup), np.concatenate(free)
        s_lo, s_hi = sup.min(axis=0), sup.max(axis=0)
        lo, hi = np.minimum(s_lo, free.min(axis=0)), np.maximum(s_hi, free.max(axis=0))
        size = float(np.max(s_hi[:2] - s_lo[:2]))  # the supports' horizontal size L
        fall = float(free[:, 2].max() - s_lo[2])  # the fall height H
        margin = size + fall
        return cls(np.array([lo[0] - margin, lo[1] - margin, lo[2]]),
                   np.array([hi[0] + margin, hi[1] + margin, hi[2] + margin]), margin, size, fall)

    def outside(self, pos) -> np.ndarray:
        """Per centroid ((n, 3) m): True where it is outside the region."""
        p = np.asarray(pos, float).reshape(-1, 3)
        return np.any((p < self.lo) | (p > self.hi), axis=1)

    def where(self, p) -> str:
        """Which face of the region centroid ``p`` (m) is past, in words."""
        p = np.asarray(p, float)
        if p[2] < self.lo[2]:
            return f"below the supports' underside (z < {self.lo[2]:.4g} m)"
        for i, ax in enumerate("xyz"):
            if p[i] > self.hi[i]:
                return f"beyond {ax} = {self.hi[i]:.4g} m"
            if p[i] < self.lo[i]:
                return f"beyond {ax} = {self.lo[i]:.4g} m"
        return "inside"

    def as_dict(self) -> dict | None:
        """Bounds, margin, L and H (m) for run_info and summary.json; None when unbounded."""
        if not np.isfinite(self.margin):
            return None
        return {"lo_m": self.lo.tolist(), "hi_m": self.hi.tolist(), "margin_m": self.margin,
                "supports_horizontal_size_m": self.size, "fall_height_m": self.fall}

    def first_exits(self, t, pos) -> list[int | None]:
        """Per block, the first sample index at which its centroid is outside (``pos``
        (n_samples, n_blocks, 3) m), or None if it never is."""
        pos = np.asarray(pos, float)
        out = self.outside(pos.reshape(-1, 3)).reshape(pos.shape[:2])
        return [int(np.argmax(out[:, j])) if out[:, j].any() else None for j in range(pos.shape[1])]


def energy_bound_ratio(t, mass, vel, g_eff, kinetic, elastic, gravity, jumps=()) -> float:
    """Largest (E - E_0) / bound over a finished run's recorded samples (the check of
    ``EnergyWatch`` replayed; a run is stopped when it exceeds 1). Arrays as in
    histories.npz (t s, mass kg, vel (n, b, 3) m/s, g_eff (n, 3) m/s^2, kinetic and elastic
    J); ``jumps``: (time s, relative velocity (3,) m/s) of the run's velocity jumps."""
    t, mass = np.asarray(t, float), np.asarray(mass, float)
    p = np.abs(np.einsum("b,kbi,ki->kb", mass, np.asarray(vel, float), np.asarray(g_eff, float))).sum(1)
    work = np.concatenate([[0.0], np.cumsum(0.5 * (p[1:] + p[:-1]) * np.diff(t))])
    injected = np.zeros_like(t)
    for tj, dv in jumps:
        injected += (t >= tj - 1e-12) * 0.5 * mass.sum() * float(np.sum(np.asarray(dv) ** 2))
    e = np.asarray(kinetic, float) + np.nan_to_num(np.asarray(elastic, float))
    bound = WORK_FACTOR * work + injected + E_TOL_M * mass.sum() * gravity
    return float(((e - e[0]) / bound)[1:].max()) if len(t) > 1 else 0.0


def speed_bound_ratio(t, mass, g_eff, kinetic, elastic, gravity, jumps=()) -> float:
    """Largest sqrt(kinetic) / (SPEED_FACTOR x budget + sqrt(E_tol)) over a finished run's
    recorded samples (the speed check replayed, ``speed_budget`` with the integral of
    |g_eff| by the trapezoid over the samples instead of the driver's sum over steps; a run
    is stopped when it exceeds 1). Arrays as in histories.npz; ``jumps`` as in
    ``energy_bound_ratio``; applied forces are left out."""
    t, mass = np.asarray(t, float), np.asarray(mass, float)
    if len(t) < 2:
        return 0.0
    g = np.linalg.norm(np.asarray(g_eff, float).reshape(len(t), 3), axis=1)
    gint = np.concatenate([[0.0], np.cumsum(0.5 * (g[1:] + g[:-1]) * np.diff(t))])
    e0 = float(kinetic[0]) + float(np.nan_to_num(elastic[0]))
    e_tol = E_TOL_M * mass.sum() * gravity
    ratio = 0.0
    for k in range(1, len(t)):
        done = [np.asarray(dv, float) for tj, dv in jumps if tj <= t[k] + 1e-12]
        b = speed_budget(mass.sum(), e0, gint[k], (), done)
        ratio = max(ratio, math.sqrt(max(0.0, float(kinetic[k]))) / (SPEED_FACTOR * b + math.sqrt(e_tol)))
    return ratio


def replay(root) -> list[tuple[float, str]]:
    """``energy_bound_ratio`` of every finished run under ``root`` (folders with
    histories.npz, spec.json and run_info.json), ascending: how close each came to being
    stopped. ``python -m drystone.mechanics.stability [ROOT]`` prints them (default results/)."""
    import glob
    import json
    from pathlib import Path

    rows = []
    for f in sorted(glob.glob(str(Path(root) / "**" / "histories.npz"), recursive=True)):
        d = Path(f).parent
        try:
            with np.load(f) as h:
                info = json.loads((d / "run_info.json").read_text())
                spec = json.loads((d / "spec.json").read_text())
                jumps = [(j["time_s"], j["relative_velocity_m_s"]) for j in info.get("velocity_jumps") or []]
                r = energy_bound_ratio(h["t"], h["mass"], h["vel"], h["g_eff"], h["kinetic"], h["elastic"],
                                       spec["gravity"], jumps)
        except (OSError, KeyError, ValueError):
            continue
        rows.append((r, str(d)))
    return sorted(rows)


if __name__ == "__main__":
    import sys

    from drystone import paths

    rows = replay(sys.argv[1] if len(sys.argv) > 1 else paths.RESULTS)
    for r, d in rows:
        print(f"{r:6.3f}  {d}")
    print(f"{len(rows)} runs; a run is stopped when its ratio exceeds 1")


def box_joint_omega_max(size, kn: float, kt: float, density: float) -> float:
    """Highest mode (rad/s) of a box (b, d, h, m) standing on a rigid base on its joint's
    springs: the 6 x 6 patch stiffness (K_n, K_t in N/m^3 over the b x d base) on the box's
    mass and inertia seen at the joint (drystone/mechanics/contact.py ``damping_matrix``).
    The leapfrog energy bound's omega_max (tests/tolerances.py BALANCE_SHADOW)."""
    from drystone.mechanics import contact as law

    b, d, h = size
    m = density * b * d * h
    ic = np.diag([m * (d * d + h * h), m * (b * b + h * h), m * (b * b + d * d)]) / 12
    W = law.mobility(np.zeros((1, 3)), np.array([[0.0, 0.0, -h / 2]]), np.zeros(1), np.array([1 / m]),
                     np.zeros((1, 3, 3)), np.linalg.inv(ic)[None])
    K = law.patch_stiffness(np.array([[0.0, 0.0, 1.0]]), np.array([b * d]),
                            np.diag([b ** 3 * d / 12, d ** 3 * b / 12, 0.0])[None], np.array([kn]), np.array([kt]),
                            np.array([True]))
    return float(law.damping_matrix(K, W, np.array([1.0]))[1][0])
