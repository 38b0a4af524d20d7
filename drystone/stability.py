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
"""
from __future__ import annotations

import numpy as np

#: energy tolerance per newton of free weight (m): E_tol = W_free x this
E_TOL_M = 1e-3
#: work bound factor (see module docstring)
WORK_FACTOR = 2.0
#: a contact deeper than this fraction of the smaller block's smallest dimension tunnels
TUNNEL_FRACTION = 0.5


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


def replay(root) -> list[tuple[float, str]]:
    """``energy_bound_ratio`` of every finished run under ``root`` (folders with
    histories.npz, spec.json and run_info.json), ascending: how close each came to being
    stopped. ``python -m drystone.stability [ROOT]`` prints them (default results/)."""
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
