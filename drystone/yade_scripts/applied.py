"""What a step engine applies besides the contacts (inside YADE only): the case's applied
forces (``run.forces``: a constant force on a block between two times) and its [[loads]]
(drystone/model/loads.py, ``run.loads``: coefficients at the step's time times fixed
vectors, a force on each loaded body and a moment about its centroid), and the directions
each body may move in. The step engines (engines.py) call these at every step; ``run``
is the driver (run_case.py). Units SI.
"""
from __future__ import annotations

import numpy as np
import yade

from drystone.mechanics import integration


def loads_at(run, t: float, g: np.ndarray) -> np.ndarray | None:
    """The loads' coefficients (J,) of the step at t (body acceleration g), None without
    loads. Where a load is undefined the driver stops the run (``load_limit``) and the
    step keeps the previous step's coefficients."""
    loads = run.loads
    if loads is None:
        return None
    c, bad, why = loads.coefficients(np.array([t]), np.asarray(g, float)[None])
    if bad is not None:
        run.load_limit(t, why)
        c = loads.last[None]
    loads.taken(c, run.O.dt)
    return c[0]


def give_yade(run, t: float, g: np.ndarray):
    """Give YADE this step's applied forces and loads; returns the loads' (force, moment)
    (nb, 3) or None without loads."""
    for y, f, start, end in run.forces:
        if start <= t < end:
            run.O.forces.addF(y, f)
    c = loads_at(run, t, g)
    if c is None:
        return None
    F, T = run.loads.wrench(c)
    for i in run.loads.loaded.tolist():
        run.O.forces.addF(i, yade.Vector3(*F[i]))
        run.O.forces.addT(i, yade.Vector3(*T[i]))
    return F, T


def external(run, t: float) -> np.ndarray:
    """The applied forces (nb, 3) N at t, on the bodies they act on."""
    F_ext = np.zeros_like(run.pos)
    for y, f, start, end in run.forces:
        if start <= t < end:
            F_ext[y] += tuple(f)
    return F_ext


def free_directions(run) -> tuple[np.ndarray, np.ndarray]:
    """(translations, rotations) (nb, 3): 1.0 on the directions each body may use."""
    free = [integration.free_directions(run.states[i].blockedDOFs or "", bool(np.isfinite(run.mass[i])))
            for i in range(len(run.mass))]
    return np.array([f[0] for f in free]).reshape(-1, 3), np.array([f[1] for f in free]).reshape(-1, 3)
