"""Rigid-block limit analysis by linear programming (scipy's HiGHS; no YADE).

The collapse multiplier lambda of a horizontal body force lambda x (self-weight) along a
unit direction d: the largest lambda for which interface forces exist that are

* in equilibrium with every free body's weight m g and load lambda m |g| d (both at its
  centroid): 3 force and 3 moment equations (about the centroid) per body, a DOF the
  body's ``blocked`` letters fix (x y z X Y Z, global axes) left out (its reaction free);
* compressive (no tension) and frictional: at each corner x_v of each contact polygon
  (normal n from body a to body b), the force on b is a non-negative combination of the
  m = ``FACETS`` edge rays of a friction pyramid, f_v = sum_k c_vk (n + mu t_k), c_vk >= 0,
  t_k = cos(2 pi k / m) e1 + sin(2 pi k / m) e2 (e1 the load direction's projection on the
  interface plane): its normal part N_v = sum_k c_vk >= 0 and its tangential part lies in
  the m-gon inscribed in the circle of radius mu N_v with a corner on e1 (associative
  friction; no inequality row is needed). The m-gon is inside Coulomb's cone: the shear
  along e1 is exact, in between directions low by at most 1 - cos(pi / m), 7.6 % at m = 8;
* the force on a is -f_v.

Forces at the polygon's corners represent any distribution of normal and shear stress
over a flat convex interface whose resultant lies inside it (the standard formulation of
Livesley 1978, Ferris & Tin-Loi 2001, Portioli et al. 2014). Maximise lambda over
(c, lambda), lambda free in sign, by ``scipy.optimize.linprog`` with HiGHS (``METHOD``), sparse
matrices, the rows scaled to the heaviest stone's weight and each stone's size: lambda < 0 at the optimum means the wall cannot carry
its own weight without a push the other way; an infeasible problem that no lambda can
balance (a stone touching nothing, an overhang). Both are reported as such
(``Result.status``), not as multipliers.

Mechanism: the dual variables of the equilibrium equations (HiGHS's marginals) are the
virtual velocities of the bodies, the centroid's velocity (force rows) and the angular
velocity (moment rows), normalised so that the largest corner speed of a moving body is 1.
By LP duality the collapse mechanism is kinematically admissible for the flow rule of
the faceted cone (opening and sliding at each corner in the cone's normal directions) and
lambda = -(power of the weights) / (power of the unit load) on it. Moving bodies: corner
speed above ``MOVING`` (relative to the largest); per interface, the relative velocity at
its corners gives rotation (opening varying over the polygon: rocking about a hinge line,
the corners not opening) and sliding (tangential velocity at the hinge).

Non-associative Coulomb friction (``solve_coulomb``): associative flow makes sliding dilate
(opening mu x slip), which the joints of a real wall do not, so the associative lambda is
an upper estimate where sliding governs. After the iterative scheme of Gilbert, Casapulla &
Ahmed (2006, Computers & Structures 84, 873-887): repeatedly solve the problem with each
interface's friction capped by the previous normal forces: per interface, the shear of its
corners sum_v mu N_v^rays <= mu N_prev (its total normal force of the previous iterate),
besides each corner's own pyramid (shear <= mu x its own normal force: the columns are the
pyramid's rays plus a pure normal force per corner, so every iterate satisfies Coulomb with
its own normal forces by construction). Where the cap governs, the mechanism slips without
opening (non-associative); at a fixed point (N = N_prev per interface) the forces are
Coulomb-admissible and the mechanism slips only where the shear is at mu N. The start is
the wall at rest (lambda = 0) carrying its weight with the least total normal force, and
each iterate's forces are, among the LP's optimal ones, those of least total normal force
at its lambda (a second LP): a normal force nothing asks for, a squeeze across a joint
that the mechanism does not load, would otherwise become friction capacity and ratchet
lambda up towards the associative value. No under-relaxation (``RELAX`` = 1). Converged:
the estimated change still to come (``_remaining``: the last step, or the tail of the
geometric series its last two steps make) below ``LAMBDA_TOL`` relative. Not converged in
``MAX_ITER`` LPs: ``not_converged`` with the last iterate (Coulomb-admissible). The value is
never above the associative one (the capped set is inside the associative pyramids; an
excess of solver tolerance is cut). The scheme finds a solution of the non-associative
problem, not provably the lowest (docs/limit-analysis.md).

Units: SI (kg, m, N); velocities are dimensionless (normalised).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from scipy import sparse
from scipy.optimize import linprog

from drystone.mechanics.interfaces import Interface

#: tangential directions of the friction pyramid at each corner (an inscribed regular m-gon)
FACETS = 8
#: a body moves when its largest corner speed exceeds this fraction of the largest one
MOVING = 1e-3
#: an interface opens / slides where the relative speed exceeds this fraction of the largest
ACTIVE = 1e-3
#: non-associative iteration: estimated change of lambda still to come (relative) below which
#: it has converged; the Coulomb check per interface (shear above mu N, of the largest mu N;
#: zero by construction, checked); under-relaxation of the normal forces; most iterations
LAMBDA_TOL = 1e-4
FORCE_TOL = 1e-3
RELAX = 1.0
#: each non-associative iterate's forces: the least total normal force at lambda (1 -
#: LEAN_BACKOFF), lambda the iterate's (its optimum is feasible only to the LP's tolerance,
#: 1e-8), by a second LP with HiGHS's IPX after presolve (LEAN_OPTIONS: HiPO fails on these
#: LPs, "Solve error"). A small penalty on the normal forces in the first LP instead (one LP
#: per iteration) did not keep the split columns' vertical joint free of normal force
LEAN_BACKOFF = 1e-7
LEAN_OPTIONS = {"solver": "ipx", "presolve": "on"}
MAX_ITER = 60
_LETTERS = "xyzXYZ"
#: coefficients of the equilibrium rows (forces over the heaviest weight, moments over the
#: body's size: order 1) below this are round-off of exact zeros and left out (HiGHS drops
#: those under 1e-9 itself)
ZERO = 1e-12
#: HiGHS's interior-point method with crossover (a vertex solution and its duals): on these
#: problems, degenerate (many corners with the same lever), 5-10 times faster than its
#: dual simplex (``make bench``, section limit)
METHOD = "highs-ipm"
#: where highspy and highspy-extras are installed (requirements.txt), HiGHS 1.15's direct
#: interior point HiPO instead: no crossover (the duals of the interior solution: a collapse
#: mechanism, possibly a combination of equivalent ones), one thread, its Newton systems as
#: normal equations (one row per body DOF: 6 per stone) ordered by AMD, no presolve. The
#: 1000-stone wall's LP (``make bench``, section limit; CPU s, one process): 16.5 with HiPO's
#: default (augmented system, 96 600 unknowns, 5 s of ordering), 11.9 as normal equations after
#: presolve (its reductions spoil the ordering: 3.4 M non-zeros in the factor), 4.4 as here
#: (1.5 M; METIS 5.1, RCM 15); 22 interior-point iterations each way; more than 3 min with
#: scipy's HiGHS 1.2. The same LP, so the same lambda (to the solver's tolerance, 1e-8)
HIPO_OPTIONS = {"solver": "hipo", "run_crossover": "off", "threads": 1, "presolve": "off",
                "hipo_system": "normaleq", "hipo_ordering": "amd"}
#: where HiPO so set up ends neither optimal, infeasible nor unbounded (HiGHS's "Solve error"
#: or "Unknown": without presolve it cannot tell a stone touching nothing from a failure; the
#: normal equations of the non-associative iteration's capped LPs can break down), the same
#: LP once more with each of these changes in turn: presolve on, HiPO's augmented system,
#: HiGHS's other interior point (IPX, no crossover)
HIPO_FALLBACKS = ({"presolve": "on"}, {"hipo_system": "augmented", "hipo_ordering": "choose"},
                  {"solver": "ipx"})


@dataclass
class Bodies:
    """The bodies: ``ids`` (block ids), ``mass`` kg, ``centroid`` (n, 3) m, ``fixed`` bool
    (platform and fixed stones: no equilibrium equations), ``blocked`` DOF letters per body
    ("" none), ``size`` (n,) m each body's largest extent (scales the moment rows)."""
    ids: list
    mass: np.ndarray
    centroid: np.ndarray
    fixed: np.ndarray
    blocked: list = field(default_factory=list)
    size: np.ndarray | None = None

    def __post_init__(self):
        n = len(self.ids)
        self.mass = np.asarray(self.mass, float)
        self.centroid = np.asarray(self.centroid, float).reshape(n, 3)
        self.fixed = np.asarray(self.fixed, bool)
        self.blocked = list(self.blocked) or [""] * n
        self.size = np.ones(n) if self.size is None else np.asarray(self.size, float)


@dataclass
class Result:
    """``status``: "collapse" (a multiplier), "cannot_stand" (lambda < 0: the wall cannot
    carry its own weight), "infeasible" (no admissible forces at any lambda), "unbounded"
    (no collapse at any lambda: nothing can move), "not_converged" (non-associative
    iteration), "failed" (the solver's message in ``message``). ``multiplier`` only for
    "collapse" and "not_converged" (the last iterate); ``velocity`` (n, 6) per body:
    centroid velocity and angular velocity, normalised; ``normal`` N_v per corner (N)."""
    status: str
    multiplier: float | None
    message: str = ""
    velocity: np.ndarray | None = None
    normal: np.ndarray | None = None
    iterations: int = 1
    history: list = field(default_factory=list)
    solve_s: float = 0.0
    shear: np.ndarray | None = None
    coulomb_residual: float | None = None
    converged: bool | None = None


@dataclass
class Problem:
    """The assembled LP (``assemble``): the equilibrium rows (one per free body DOF, forces
    in units of ``force_scale``, moment rows divided by the body's size: ``row_scale``) of
    the corner force columns: with ``cone``, per corner the ``facets`` edge rays
    n + mu t_k of its friction pyramid (associative: every force in the pyramid is a
    non-negative combination of them, no further row); else the same rays followed by a
    pure normal force (along n) per corner, for the non-associative iteration's caps (the
    rays' sum times mu is the corner's shear, at most mu x its normal force)."""
    A: sparse.csr_matrix
    b: np.ndarray
    live: np.ndarray
    rows: np.ndarray  # (body, dof) of each equality row
    corner_iface: np.ndarray  # interface of each corner
    corner_x: np.ndarray  # (nc, 3) corner positions
    mu: np.ndarray  # per corner
    ncorner: int
    facets: int
    cone: bool
    force_scale: float
    row_scale: np.ndarray


def _basis(n: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per interface normal n (k, 3): e1 the load direction d's projection on the interface
    plane (normalised; where d is along n, a fixed axis's), e2 = n x e1."""
    n = np.asarray(n, float).reshape(-1, 3)
    e1 = d - (n @ d)[:, None] * n
    along = np.linalg.norm(e1, axis=1) < 1e-9
    if along.any():
        a = np.where((np.abs(n[along, 0]) < 0.9)[:, None], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
        e1[along] = a - (a * n[along]).sum(axis=1)[:, None] * n[along]
    e1 /= np.linalg.norm(e1, axis=1)[:, None]
    return e1, np.cross(n, e1)


def assemble(bodies: Bodies, ifaces: list[Interface], mu, direction, gravity=(0.0, 0.0, -9.81),
             facets: int = FACETS, cone: bool = True, outer: bool = False) -> Problem:
    """The LP's matrices for a load along ``direction`` (unit horizontal vector); ``mu``
    per interface (or one value); ``gravity`` m/s^2; ``cone``: the column layout (``Problem``).
    ``outer``: the pyramid circumscribed about Coulomb's cone instead of inscribed in it (its
    rays at mu / cos(pi / facets), turned by half a facet so that a face, not an edge, touches
    the cone along the load: sliding along the load stays exact), for ``cone_bracket``."""
    d = np.asarray(direction, float)
    d = d / np.linalg.norm(d)
    g = np.asarray(gravity, float)
    nb = len(bodies.ids)
    mu_i = np.broadcast_to(np.asarray(mu, float), (len(ifaces),))
    row_of = -np.ones((nb, 6), np.int64)
    rows = []
    for bi in np.flatnonzero(~bodies.fixed):
        for c in range(6):
            if _LETTERS[c] not in bodies.blocked[bi]:
                row_of[bi, c] = len(rows)
                rows.append((bi, c))
    rows = np.array(rows, np.int64).reshape(-1, 2)
    free_w = bodies.mass[~bodies.fixed] * np.linalg.norm(g)
    force_scale = float(free_w.max()) if len(free_w) else 1.0
    ang = 2 * np.pi * np.arange(facets) / facets
    if outer:
        ang = ang + np.pi / facets
        mu_i = mu_i / np.cos(np.pi / facets)
    cx, ci = _corners(ifaces)
    normals = np.array([f.normal for f in ifaces], float).reshape(-1, 3)
    e1, e2 = _basis(normals, d)
    cn = normals[ci]
    # (corner, facet, 3): the facet directions of the corner's interface
    cdirs = (np.cos(ang)[None, :, None] * e1[ci][:, None, :] + np.sin(ang)[None, :, None] * e2[ci][:, None, :])
    nc = len(cx)
    cmu = mu_i[ci]
    if cone:  # corner c's ray k is column c * facets + k
        u = (cn[:, None, :] + cmu[:, None, None] * cdirs).reshape(-1, 3)
        col_corner = np.repeat(np.arange(nc), facets)
    else:  # corner c's ray k is column c * facets + k, its pure normal force column nc * facets + c
        u = np.concatenate([(cn[:, None, :] + cmu[:, None, None] * cdirs).reshape(-1, 3), cn])
        col_corner = np.concatenate([np.repeat(np.arange(nc), facets), np.arange(nc)])
    x = cx[col_corner]
    ia = np.array([f.a for f in ifaces], np.int64)[ci[col_corner]]
    ib = np.array([f.b for f in ifaces], np.int64)[ci[col_corner]]
    r_i, c_i, v_i = [], [], []
    for body, sign in ((ib, 1.0), (ia, -1.0)):
        mom = np.cross(x - bodies.centroid[body], u)
        for c in range(6):
            r = row_of[body, c]
            ok = r >= 0
            val = u[:, c] if c < 3 else mom[:, c - 3] / bodies.size[body]
            r_i.append(r[ok])
            c_i.append(np.flatnonzero(ok))
            v_i.append(sign * val[ok])
    nr = len(rows)
    v_i, r_i, c_i = np.concatenate(v_i), np.concatenate(r_i), np.concatenate(c_i)
    nz = np.abs(v_i) > ZERO  # round-off of exact zeros (a ray's moment about an axis it meets)
    A = sparse.csr_matrix((v_i[nz], (r_i[nz], c_i[nz])), shape=(nr, len(u)))
    b = np.zeros(nr)
    live = np.zeros(nr)
    row_scale = np.where(rows[:, 1] < 3, 1.0, 1.0 / bodies.size[rows[:, 0]]) if nr else np.zeros(0)
    trans = rows[:, 1] < 3
    b[trans] = -bodies.mass[rows[trans, 0]] * g[rows[trans, 1]] / force_scale
    live[trans] = -bodies.mass[rows[trans, 0]] * np.linalg.norm(g) * d[rows[trans, 1]] / force_scale
    return Problem(A, b, live, rows, ci, cx, cmu, nc, facets, cone, force_scale, row_scale)


def _solve(p: Problem, capacity=None, slope: float = 0.0, rest: bool = False,
           at: float | None = None) -> tuple[Result, np.ndarray | None]:
    """One LP: maximise lambda. ``capacity`` (N, per interface) only with the capped layout:
    the shear of the interface's corners (mu x their rays) <= capacity + slope mu N (N the
    interface's normal force). ``rest``: the least total normal force at lambda = 0; ``at``:
    the same at lambda = at. Returns the
    result (normal force per corner, N; the tangential force sum per interface, N, in
    ``shear``) and the equilibrium rows' duals (or None)."""
    t0 = time.perf_counter()
    ncol = p.A.shape[1]
    # A f + (weights) + lambda (unit loads) = 0, i.e. A f - lambda live = b (assemble: b = -weights, live = -loads)
    A_eq = sparse.hstack([p.A, sparse.csr_matrix(-p.live.reshape(-1, 1))]).tocsr()
    A_ub = b_ub = None
    if not p.cone:  # per interface: shear = sum over its corners of mu x (the corner's rays) <= capacity
        # + slope mu N, N = its corners' rays + normals
        nc, m = p.ncorner, p.facets
        ni = int(p.corner_iface.max(initial=-1)) + 1
        rows = np.concatenate([np.repeat(p.corner_iface, m), p.corner_iface])
        cols = np.arange(nc * m + nc)
        vals = np.concatenate([np.repeat((1 - slope) * p.mu, m), -slope * p.mu])
        A_ub = sparse.csr_matrix((vals, (rows, cols)), shape=(ni, ncol + 1))
        b_ub = np.asarray(capacity, float) / p.force_scale
    c = np.zeros(ncol + 1)
    c[-1] = -1.0
    bounds = np.zeros((ncol + 1, 2))
    bounds[:, 1] = np.inf
    bounds[-1] = (-np.inf, np.inf)
    if rest or at is not None:  # at rest (lambda = 0), or at lambda = at, the least total normal
        # force: no self-stress
        c[:] = 0.0
        c[:ncol] = 1.0
        bounds[-1] = (at or 0.0, at or 0.0)
    if _highspy() is not None:
        status, message, x, y = _solve_hipo(c, A_eq, p.b, A_ub, b_ub, bounds,
                                            first=LEAN_OPTIONS if at is not None else None)
    else:
        res = linprog(c, A_ub=A_ub, b_ub=b_ub, A_eq=A_eq, b_eq=p.b, bounds=bounds, method=METHOD)
        status, message, x = res.status, res.message, res.x
        y = None if res.eqlin is None else np.asarray(res.eqlin.marginals)
    dt = time.perf_counter() - t0
    if status == 2:
        return Result("infeasible", None, message, solve_s=dt), None
    if status == 3:
        return Result("unbounded", None, message, solve_s=dt), None
    if status != 0:
        return Result("failed", None, message, solve_s=dt), None
    lam = float(x[-1])
    xs = x[:-1] * p.force_scale
    rays = xs[:p.ncorner * p.facets].reshape(p.ncorner, p.facets).sum(axis=1)
    normal = rays if p.cone else rays + xs[p.ncorner * p.facets:]
    r = Result("collapse" if lam >= 0 else "cannot_stand", lam, message, normal=normal, solve_s=dt)
    if not p.cone:
        r.shear = p.mu * rays
    return r, y


def _highspy():
    """highspy with HiGHS's direct interior point (HiPO: needs highspy-extras' BLAS and
    METIS), or None (then scipy's HiGHS 1.2, ``METHOD``)."""
    global _HIGHSPY
    if _HIGHSPY is None:
        try:
            import highspy
            import highspy_extras  # noqa: F401  (HiPO's BLAS, METIS, AMD)
            _HIGHSPY = highspy
        except ImportError:
            _HIGHSPY = False
    return _HIGHSPY or None


_HIGHSPY = None


def _solve_hipo(c, A_eq, b_eq, A_ub=None, b_ub=None, bounds=None, attempt: int = 0, first: dict | None = None):
    """min c x, A_eq x = b_eq, A_ub x <= b_ub, x >= 0 but the last (free), by HiGHS's HiPO
    (``HIPO_OPTIONS``: one thread, no crossover). Returns (status as scipy's linprog: 0
    optimal, 2 infeasible, 3 unbounded, 4 other), message, x, the equality rows' duals.
    ``bounds``: (n, 2) column bounds as linprog's (default: x >= 0 but the last, free)."""
    hs = _highspy()
    A = A_eq if A_ub is None else sparse.vstack([A_eq, A_ub])
    A = sparse.csc_matrix(A)
    A.eliminate_zeros()
    n_eq = A_eq.shape[0]
    lo = np.asarray(b_eq, float) if A_ub is None else np.r_[b_eq, np.full(A_ub.shape[0], -hs.kHighsInf)]
    up = np.asarray(b_eq, float) if A_ub is None else np.r_[b_eq, b_ub]
    n = A.shape[1]
    lp = hs.HighsLp()
    lp.num_col_, lp.num_row_ = n, A.shape[0]
    lp.col_cost_ = np.asarray(c, float)
    if bounds is None:
        bounds = np.zeros((n, 2))
        bounds[:, 1] = np.inf
        bounds[-1, 0] = -np.inf
    bounds = np.clip(np.asarray(bounds, float), -hs.kHighsInf, hs.kHighsInf)
    lp.col_lower_ = np.ascontiguousarray(bounds[:, 0])
    lp.col_upper_ = np.ascontiguousarray(bounds[:, 1])
    lp.row_lower_, lp.row_upper_ = lo, up
    lp.a_matrix_.format_ = hs.MatrixFormat.kColwise
    lp.a_matrix_.start_, lp.a_matrix_.index_, lp.a_matrix_.value_ = A.indptr, A.indices, A.data
    h = hs.Highs()
    h.setOptionValue("output_flag", False)
    for k, v in HIPO_OPTIONS.items():
        h.setOptionValue(k, v)
    for k, v in (HIPO_FALLBACKS[attempt - 1] if attempt else first or {}).items():
        h.setOptionValue(k, v)
    h.passModel(lp)
    h.run()
    st = h.getModelStatus()
    msg = h.modelStatusToString(st)
    if st == hs.HighsModelStatus.kOptimal:
        sol = h.getSolution()
        return 0, msg, np.asarray(sol.col_value), np.asarray(sol.row_dual)[:n_eq]
    if st == hs.HighsModelStatus.kInfeasible:
        return 2, msg, None, None
    if st in (hs.HighsModelStatus.kUnbounded, hs.HighsModelStatus.kUnboundedOrInfeasible):
        if st == hs.HighsModelStatus.kUnboundedOrInfeasible:  # tell them apart: feasibility at lambda = 0 cost
            s2, m2, _, _ = _solve_hipo(np.zeros(n), A_eq, b_eq, A_ub, b_ub, bounds)
            return (3 if s2 == 0 else 2), msg, None, None
        return 3, msg, None, None
    if attempt < len(HIPO_FALLBACKS):
        return _solve_hipo(c, A_eq, b_eq, A_ub, b_ub, bounds, attempt + 1)
    return 4, msg, None, None


def _velocities(p: Problem, y: np.ndarray, bodies: Bodies) -> np.ndarray:
    """Per body (n, 6): the dual of the equilibrium rows as centroid velocity and angular
    velocity (a moment row was divided by the body's size: ``row_scale``), signed so that
    the unit load's power is positive (module docstring); not normalised."""
    v = np.zeros((len(bodies.ids), 6))
    if len(y) == 0:
        return v
    u = y * p.row_scale
    if u @ p.live > 0:  # live = -(the unit loads): their power u . loads must be positive
        u = -u
    v[p.rows[:, 0], p.rows[:, 1]] = u
    return v


def point_velocity(v: np.ndarray, bodies: Bodies, body: int, x) -> np.ndarray:
    """Velocity of the point x (m) of a body under the virtual velocities v (n, 6)."""
    return v[body, :3] + np.cross(v[body, 3:], np.asarray(x, float) - bodies.centroid[body])


def solve(bodies: Bodies, ifaces: list[Interface], mu, direction, gravity=(0.0, 0.0, -9.81),
          facets: int = FACETS, outer: bool = False) -> Result:
    """Associative friction: the largest multiplier and its mechanism (module docstring);
    ``outer``: with the circumscribed pyramid (``assemble``)."""
    t0 = time.perf_counter()
    p = assemble(bodies, ifaces, mu, direction, gravity, facets, outer=outer)
    r, y = _solve(p)
    if y is not None:
        r.velocity = _normalise(_velocities(p, y, bodies), bodies, ifaces)
    r.history = [] if r.multiplier is None else [r.multiplier]
    r.solve_s = time.perf_counter() - t0
    return r


def solve_coulomb(bodies: Bodies, ifaces: list[Interface], mu, direction, gravity=(0.0, 0.0, -9.81),
                  facets: int = FACETS, relax: float = RELAX, max_iter: int = MAX_ITER,
                  lambda_tol: float = LAMBDA_TOL, force_tol: float = FORCE_TOL, slope: float = 0.0) -> Result:
    """Non-associative Coulomb friction by the iterative scheme of the module docstring."""
    t0 = time.perf_counter()
    r = solve(bodies, ifaces, mu, direction, gravity, facets)
    if r.status != "collapse":
        r.solve_s = time.perf_counter() - t0
        return r
    p = assemble(bodies, ifaces, mu, direction, gravity, facets, cone=False)
    mu_c = p.mu  # per corner
    mu_i = np.zeros(len(ifaces))
    mu_i[p.corner_iface] = mu_c
    per_iface = lambda x: np.bincount(p.corner_iface, x, minlength=len(ifaces))  # noqa: E731
    hist = [r.multiplier]
    # the start: the normal forces of the wall at rest carrying its weight with the least total
    # normal force (no self-stress locked across joints that nothing loads)
    r0, _ = _solve(assemble(bodies, ifaces, mu, direction, gravity, facets), rest=True)
    n_prev = per_iface(r0.normal if r0.normal is not None else r.normal)
    converged = False
    rest_c = remaining = float("nan")
    y = None
    for k in range(max_iter):
        # a corner's capacity below round-off of the largest is none (HiGHS: "excessively small row bounds")
        cap = (1 - slope) * mu_i * n_prev
        cap[cap < ZERO * max(float(cap.max(initial=0.0)), 1e-300)] = 0.0
        rk, yk = _solve(p, capacity=cap, slope=slope)
        if rk.multiplier is None:  # no admissible forces with the capped joints
            if k == 0:
                rk.iterations, rk.history, rk.solve_s = len(hist) + 1, hist, time.perf_counter() - t0
                return rk
            break  # keep the last good iterate
        r, y = rk, yk
        hist.append(r.multiplier)
        # among the LP's optimal forces (many: the problem is degenerate), those with the least
        # total normal force: a normal force that nothing asks for (a squeeze across a joint
        # that the mechanism does not load) would become friction capacity in the next LP and
        # ratchet lambda up towards the associative value
        lean, _ = _solve(p, capacity=cap, slope=slope, at=r.multiplier * (1 - LEAN_BACKOFF))
        if lean.normal is not None:
            r.normal, r.shear = lean.normal, lean.shear
        # Coulomb with the iterate's own normal forces, per interface (by construction; checked):
        # its corners' shear above mu x its normal force, of the largest mu N of an interface
        shear_i, n_i = per_iface(r.shear), per_iface(r.normal)
        mun_i = mu_i * n_i
        rest_c = float(np.max(shear_i - mun_i, initial=0.0)) / max(float(np.max(mun_i, initial=0.0)), 1e-300)
        r.coulomb_residual = rest_c
        n_prev = relax * n_i + (1 - relax) * n_prev
        remaining = _remaining(hist[1:])
        if remaining <= lambda_tol and rest_c <= force_tol:
            converged = True
            break
    a_lam = hist[0]
    if r.multiplier > a_lam:  # the capped joints' forces are inside the associative pyramids: an excess
        # is the solvers' tolerance (a few 1e-6 relative: LEAN, 1e-8 of each LP)
        r.multiplier = a_lam
    if not converged:
        r.status = "not_converged"
        r.message = (f"the non-associative iteration did not settle in {len(hist) - 1} LPs (estimated change "
                     f"still to come {remaining:.2g} of lambda; shear above mu N {rest_c:.2g} of the largest "
                     f"mu N); the value is the last iterate, whose forces satisfy Coulomb with their own normal forces")
    if y is not None:
        r.velocity = _normalise(_velocities(p, y, bodies), bodies, ifaces)
    r.iterations = len(hist)
    r.history = hist
    r.converged = converged
    r.solve_s = time.perf_counter() - t0
    return r


def _remaining(h: list) -> float:
    """How much (relative to the last value) the sequence h may still move: its last step,
    or, where the last steps shrink geometrically with ratio rho < 1 (the iteration's
    linear convergence), the tail of that series, |step| rho / (1 - rho), if larger; inf
    with fewer than two values."""
    if len(h) < 2:
        return float("inf")
    scale = max(abs(h[-1]), 1e-12)
    d1 = h[-1] - h[-2]
    out = abs(d1) / scale
    if len(h) >= 3:
        d0 = h[-2] - h[-1 - 2]
        if d0 != 0.0 and 0.0 < d1 / d0 < 1.0:
            rho = d1 / d0
            out = max(out, abs(d1) * rho / (1.0 - rho) / scale)
    return out


def _corners(ifaces: list[Interface]) -> tuple[np.ndarray, np.ndarray]:
    """All interfaces' corners (nc, 3) m and the interface of each."""
    if not ifaces:
        return np.zeros((0, 3)), np.zeros(0, np.int64)
    cx = np.concatenate([f.polygon for f in ifaces])
    ci = np.repeat(np.arange(len(ifaces)), [len(f.polygon) for f in ifaces])
    return cx, ci


def _normalise(v: np.ndarray, bodies: Bodies, ifaces: list[Interface]) -> np.ndarray:
    """Scale the velocities so that the largest speed at any interface corner is 1."""
    cx, ci = _corners(ifaces)
    top = 0.0
    for side in ("a", "b"):
        body = np.array([getattr(f, side) for f in ifaces], np.int64)[ci]
        free = ~bodies.fixed[body]
        body, x = body[free], cx[free]
        w = v[body, :3] + np.cross(v[body, 3:], x - bodies.centroid[body])
        top = max(top, float(np.linalg.norm(w, axis=1).max(initial=0.0)))
    return v / top if top > 0 else v


def mechanism(bodies: Bodies, ifaces: list[Interface], v: np.ndarray, moving_tol: float = MOVING,
              active_tol: float = ACTIVE) -> dict:
    """The collapse mechanism from the normalised virtual velocities v (n, 6): moving
    bodies (ids), each one's velocity, and per active interface its opening / sliding and
    hinge line (module docstring). Speeds are relative to the largest corner speed (1)."""
    nb = len(bodies.ids)
    speed = np.zeros(nb)
    for f in ifaces:
        for b in (f.a, f.b):
            w = v[b, :3] + np.cross(v[b, 3:], f.polygon - bodies.centroid[b])
            speed[b] = max(speed[b], float(np.linalg.norm(w, axis=1).max()))
    speed = np.maximum(speed, np.linalg.norm(v[:, :3], axis=1))
    moving = [int(b) for b in np.flatnonzero((speed > moving_tol) & ~bodies.fixed)]
    joints = []
    modes = set()
    body_modes = {b: set() for b in moving}
    for f in ifaces:
        if f.a not in body_modes and f.b not in body_modes:
            continue
        rel = (v[f.b, :3] + np.cross(v[f.b, 3:], f.polygon - bodies.centroid[f.b])) \
            - (v[f.a, :3] + np.cross(v[f.a, 3:], f.polygon - bodies.centroid[f.a]))
        if np.linalg.norm(rel, axis=1).max() <= active_tol:
            continue
        opening = rel @ f.normal
        slip = np.linalg.norm(rel - np.outer(opening, f.normal), axis=1)
        rotating = float(opening.max() - opening.min()) > active_tol
        hinge = opening <= opening.min() + active_tol
        sliding = float(slip[hinge].max()) > active_tol
        kind = "rocking+sliding" if rotating and sliding else "rocking" if rotating else \
            "sliding" if sliding else "separation"
        modes.add(kind)
        for b in (f.a, f.b):
            if b in body_modes:
                body_modes[b].add(kind)
        j = {"stones": [bodies.ids[f.a], bodies.ids[f.b]], "mode": kind,
             "max_opening": float(opening.max()), "max_slip": float(slip.max())}
        if rotating and not sliding and hinge.sum() >= 2:
            pts = f.polygon[hinge]
            far = np.argmax(np.linalg.norm(pts - pts[0], axis=1))
            j["hinge"] = [[float(c) for c in pts[0]], [float(c) for c in pts[far]]]
        joints.append(j)
    return {"moving_stones": [bodies.ids[b] for b in moving],
            "modes": sorted(modes),
            "stones": {str(bodies.ids[b]): {"speed": float(speed[b]),
                                            "velocity": [float(c) for c in v[b, :3]],
                                            "angular_velocity": [float(c) for c in v[b, 3:]],
                                            "modes": sorted(body_modes[b])} for b in moving},
            "interfaces": joints}
