"""The 1D multiple-rigid-body friction/impact model of Ogawa et al. (Eqs. 1-5), plain numpy.

Blocks move horizontally only; ``u`` is each block's displacement relative to the base (m),
under the base acceleration a_g(t) (m/s^2): m_i u_i'' = -m_i a_g - sum of friction forces
(Eq. 1). Friction acts between stacked blocks (interface k: an upper block on a lower
block or on the base) with the Coulomb limit F_k = mu_k N_k, N_k the weight carried
(Eq. 3); neighbours side by side collide elastically (restitution e, 1 in the paper).

Integration: Newmark with beta = 0, gamma = 1/2, as Eq. 5:
    u_{n+1} = u_n + h v_n + h^2/2 a_n,   v_{n+1} = v_n + h/2 (a_n + a_{n+1}),
with the friction forces of step n+1 found implicitly (the paper's "iterative scheme"):
every interface force f_k lies in [-F_k, F_k], equals -F_k sign(w_k) if the interface slides
(relative velocity w_k != 0 at n+1) and is whatever keeps w_k = 0 otherwise. This
velocity-level complementarity problem is solved by projected Gauss-Seidel over the
interfaces (each update is the force that zeroes w_k, clipped to the limit; loops such as
base-1-4-2-base converge to one admissible distribution). So a sticking interface has
exactly zero relative velocity and never chatters around it: stick is a state of the
solution, not a sign change of the velocity. The paper's rule "friction acts only when
the input force exceeds static friction" is this stick condition.

Impacts: gaps between horizontal neighbours start at 0; after the velocity update, any
pair that overlaps (gap <= 0) and approaches exchanges momentum by Newton's law with
restitution e (sequential sweeps until no pair approaches), and the overlap is removed
by a mass-weighted position correction. Momentum is conserved exactly, and for e = 1 the
kinetic energy of an isolated impact too.

Units SI. Masses enter only through ratios: friction, gravity and inertia all scale with
the density, so a pure-friction result is density-free.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from drystone.units import GRAVITY as G  # m/s^2


@dataclass
class Model:
    """A 1D block system. ``mass`` (n,) kg; ``interfaces`` list of (upper, lower, limit_N)
    with block indices 0..n-1 and lower = -1 for the base; ``neighbours`` list of (left,
    right) block indices in contact side by side; ``restitution`` e."""

    mass: np.ndarray
    interfaces: list[tuple[int, int, float]]
    neighbours: list[tuple[int, int]] = field(default_factory=list)
    restitution: float = 1.0
    names: list[str] = field(default_factory=list)

    def __post_init__(self):
        self.mass = np.asarray(self.mass, float)
        self.masses = self.mass.tolist()  # plain floats for the scalar loops


@dataclass
class Result:
    t: np.ndarray  # s
    u: np.ndarray  # (nt, n) m, relative to the base
    v: np.ndarray  # (nt, n) m/s
    sticking: np.ndarray  # (nt, n_interfaces) bool

    @property
    def residual(self) -> np.ndarray:
        return self.u[-1]


def friction_forces(model: Model, v_star: np.ndarray, half_h: float, iters: int = 200,
                    tol: float = 1e-12, f0=None) -> tuple[np.ndarray, np.ndarray]:
    """Interface forces f (N, on the upper block; the lower one gets -f) such that the
    velocities v = v_star + half_h f_net / m satisfy Coulomb's law (module docstring).
    ``f0``: a starting guess (the previous step's forces). Returns (f, sticking)."""
    m = model.masses
    n_if = len(model.interfaces)
    f = [0.0] * n_if if f0 is None else list(f0)
    v = [float(x) for x in v_star]
    for k, (i, j, _) in enumerate(model.interfaces):  # the velocities the guess implies
        v[i] += half_h * f[k] / m[i]
        if j >= 0:
            v[j] -= half_h * f[k] / m[j]
    for _ in range(iters):
        change = 0.0
        for k, (i, j, lim) in enumerate(model.interfaces):
            wi = v[i] - (v[j] if j >= 0 else 0.0)
            c = half_h * (1.0 / m[i] + (1.0 / m[j] if j >= 0 else 0.0))
            new = min(max(f[k] - wi / c, -lim), lim)
            d = new - f[k]
            if d != 0.0:
                v[i] += half_h * d / m[i]
                if j >= 0:
                    v[j] -= half_h * d / m[j]
                f[k] = new
                change = max(change, abs(d) / max(lim, 1e-300))
        if change < tol:
            break
    sticking = [abs(f[k]) < lim * (1 - 1e-9) for k, (_, _, lim) in enumerate(model.interfaces)]
    return f, sticking


def _impacts(model: Model, u: list, v: list, sweeps: int = 50) -> None:
    """Resolve impacts and overlaps between neighbours in place (module docstring)."""
    m, e = model.masses, model.restitution
    for _ in range(sweeps):
        hit = False
        for i, j in model.neighbours:
            if u[j] - u[i] <= 0.0 and v[j] - v[i] < -1e-15:
                p = (1 + e) * (v[i] - v[j]) / (1 / m[i] + 1 / m[j])  # impulse on j
                v[i] -= p / m[i]
                v[j] += p / m[j]
                hit = True
        if not hit:
            break
    for i, j in model.neighbours:  # remove overlaps, mass-weighted
        gap = u[j] - u[i]
        if gap < 0:
            wi, wj = 1 / m[i], 1 / m[j]
            u[i] += gap * wi / (wi + wj)
            u[j] -= gap * wj / (wi + wj)


def _net(model: Model, f) -> list:
    """Net friction force on each block (N) from the interface forces."""
    out = [0.0] * len(model.mass)
    for k, (i, j, _) in enumerate(model.interfaces):
        out[i] += f[k]
        if j >= 0:
            out[j] -= f[k]
    return out


def simulate(model: Model, acc: np.ndarray, dt: float, substeps: int = 1, u0=None, v0=None,
             record_every: int = 1) -> Result:
    """Integrate under base acceleration samples ``acc`` (m/s^2, step ``dt`` s), linearly
    interpolated on ``substeps`` sub-steps per sample. Starts from u0, v0 (default rest).
    (Plain Python floats in the loop: five unknowns are faster so than as numpy arrays.)"""
    n = len(model.mass)
    m = model.mass.tolist()
    h = dt / substeps
    u = [0.0] * n if u0 is None else [float(x) for x in u0]
    v = [0.0] * n if v0 is None else [float(x) for x in v0]
    acc = np.asarray(acc, float)
    ag = np.interp(np.arange((len(acc) - 1) * substeps + 1) * h, np.arange(len(acc)) * dt, acc).tolist()
    f, stick = friction_forces(model, [x - 0.5 * h * ag[0] for x in v], 0.5 * h)
    fn = _net(model, f)
    a = [-ag[0] + fn[i] / m[i] for i in range(n)]
    ts, us, vs, ss = [0.0], [list(u)], [list(v)], [stick]
    hh = 0.5 * h * h
    for s in range(1, len(ag)):
        u = [u[i] + h * v[i] + hh * a[i] for i in range(n)]
        v_star = [v[i] + 0.5 * h * (a[i] - ag[s]) for i in range(n)]
        f, stick = friction_forces(model, v_star, 0.5 * h, f0=f)
        fn = _net(model, f)
        a_new = [-ag[s] + fn[i] / m[i] for i in range(n)]
        v = [v[i] + 0.5 * h * (a[i] + a_new[i]) for i in range(n)]
        _impacts(model, u, v)
        a = a_new
        if s % record_every == 0 or s == len(ag) - 1:
            ts.append(s * h)
            us.append(list(u))
            vs.append(list(v))
            ss.append(stick)
    return Result(np.array(ts), np.array(us), np.array(vs), np.array(ss))


# -- the paper's five-block model --------------------------------------------------
#: block sizes (m): a = b = 0.1 (blocks 1, 2, 4), c = e = 0.05 (blocks 3, 5), thickness
#: t = 0.05, heights h1 = h2 = 0.1 (paper §3, Figure 4, Eqs. 2-3)
A = B = 0.100
C = E = 0.050
T = 0.050
H1 = H2 = 0.100
DENSITY = 2600.0  # kg/m^3, assumed (the paper gives none; results do not depend on it)
MU_KEYS = ("mu10", "mu20", "mu31", "mu41", "mu42", "mu52")


def five_blocks(mu: dict, density: float = DENSITY, restitution: float = 1.0, g: float = G) -> Model:
    """Ogawa et al.'s model (Eqs. 2-3): blocks 1, 2 on the base; 3 on 1, 4 on 1 and 2, 5 on
    2. Index k = block k+1. Friction limits as Eq. 3, with gamma = density g."""
    gam = density * g
    mass = density * T * np.array([A * H1, B * H1, C * H2, (A - C + B - E) * H2, E * H2])
    lim = {
        "mu10": A * T * (H1 + H2) * gam, "mu20": B * T * (H1 + H2) * gam,
        "mu31": C * T * H2 * gam, "mu41": (A - C) * T * H2 * gam,
        "mu42": (B - E) * T * H2 * gam, "mu52": E * T * H2 * gam,
    }
    pairs = {"mu10": (0, -1), "mu20": (1, -1), "mu31": (2, 0), "mu41": (3, 0), "mu42": (3, 1), "mu52": (4, 1)}
    interfaces = [(pairs[k][0], pairs[k][1], float(mu[k]) * lim[k]) for k in MU_KEYS]
    return Model(mass, interfaces, neighbours=[(0, 1), (2, 3), (3, 4)], restitution=restitution,
                 names=["1", "2", "3", "4", "5"])


def repeated(model: Model, acc: np.ndarray, dt: float, runs: int = 5, substeps: int = 4,
             rest: float = 1.0) -> list[np.ndarray]:
    """Apply the record ``runs`` times in succession without resetting the blocks (with
    ``rest`` s of zero input after each run to let them stop). Returns the residual
    displacement of each block (m) after each run."""
    pad = np.concatenate([np.asarray(acc, float), np.zeros(int(round(rest / dt)))])
    u = v = None
    out = []
    for _ in range(runs):
        r = simulate(model, pad, dt, substeps=substeps, u0=u, v0=v, record_every=10 ** 9)
        u, v = r.u[-1], r.v[-1]
        out.append(u.copy())
    return out
