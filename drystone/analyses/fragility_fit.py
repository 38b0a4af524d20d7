"""Lognormal fragility functions by binomial maximum likelihood (pure numpy/scipy, no YADE).

A fragility function gives the probability that a damage state (DS) is reached or
exceeded at an intensity measure IM = x (here PGA in g):

    P(DS | IM = x) = Phi(ln(x / theta) / beta)

with median theta (g) and logarithmic dispersion beta. From a multiple-stripe analysis
(n_j runs at IM x_j, z_j of which reach the DS) the parameters are estimated by
maximising the binomial likelihood over the stripes (Baker 2015, "Efficient analytical
fragility function fitting using dynamic structural analysis", Earthquake Spectra 31(1),
579-599, Eq. 11):

    L(theta, beta) = prod_j C(n_j, z_j) p_j^z_j (1 - p_j)^(n_j - z_j),  p_j = Phi(ln(x_j/theta)/beta)

Stripes with 0 % or 100 % exceedance enter the likelihood like any other (unlike a
regression on the observed fractions, which cannot take probit(0) or probit(1)).

Written as a probit regression, p_j = Phi(a + b ln x_j) with b = 1/beta and
a = -ln(theta)/beta, the log-likelihood is concave in (a, b), so a maximum, when it
exists, is unique and the optimiser (scipy.optimize.minimize, exact gradient and
Hessian) finds it from any start. It exists (finite theta and beta > 0) if and only if the
runs that reach the DS and those that do not overlap in IM: the smallest IM at which some
run reached the DS is below the largest IM at which some run did not. Otherwise
``fit`` raises ``FitError`` saying why (no exceedance at all, every run exceeding, or a
jump from 0 % to 100 % between or at one stripe: the likelihood then keeps growing as
beta -> 0 and only a bracket of theta can be given). Fewer than 2 stripes cannot identify
two parameters and are refused as well.

Confidence: ``bootstrap`` resamples the runs within each stripe (with replacement, n_j
of them, seeded), refits, and gives percentile intervals of theta and beta and pointwise
bands of the curve; replicates whose resample has no finite maximum are counted
(``failed``) and left out. ``standard_errors`` gives the asymptotic (Fisher information)
standard errors of ln(theta) and beta.

From an incremental dynamic analysis (IDA: each record scaled up until the wall collapses,
drystone/analyses/collapse.py) each record gives its own intensity at collapse, known only
to lie in a bracket (lo, hi] (interval-censored), or to exceed the highest intensity run
when the wall never collapsed (right-censored at c). ``fit_ida`` maximises

    L(theta, beta) = prod_i [Phi(ln(hi_i/theta)/beta) - Phi(ln(lo_i/theta)/beta)]
                     x prod_k [1 - Phi(ln(c_k/theta)/beta)]

(lo = 0 allowed: Phi(-inf) = 0), and ``bootstrap_ida`` resamples the records (with
replacement, seeded) and refits. The maximum is finite only if the brackets do not all
share (or touch at) a point below every censoring intensity (otherwise L is largest as
beta -> 0: ``why_no_ida_fit``).
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np
from scipy import optimize, stats
from scipy.special import log_ndtr, ndtr

_LOG_SQRT_2PI = 0.5 * math.log(2 * math.pi)


class FitError(ValueError):
    """No lognormal fragility can be fitted to these data (the message says why)."""


@dataclass
class Fit:
    """Maximum-likelihood lognormal fragility: median ``theta`` (IM units) and dispersion ``beta``."""

    theta: float
    beta: float
    loglik: float
    n_stripes: int
    n_runs: int
    n_exceed: int
    se_ln_theta: float | None = None
    se_beta: float | None = None
    iterations: int = 0
    stripes: list = field(default_factory=list)  # [im, n, z] per stripe

    def probability(self, x) -> np.ndarray:
        return probability(x, self.theta, self.beta)

    def as_dict(self) -> dict:
        return asdict(self)


def probability(x, theta: float, beta: float) -> np.ndarray:
    """P(DS | IM = x) = Phi(ln(x / theta) / beta)."""
    x = np.asarray(x, float)
    with np.errstate(divide="ignore"):
        return ndtr(np.log(x / theta) / beta)


def stripes_from_runs(im, exceeded) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Group runs (IM of each run, exceeded 0/1 or bool) into stripes: (x_j, n_j, z_j),
    x_j ascending. Runs whose IM agree to 1e-9 relative form one stripe."""
    im = np.asarray(im, float)
    ex = np.asarray(exceeded).astype(bool)
    if im.shape != ex.shape or im.ndim != 1:
        raise ValueError(f"im and exceeded must be 1-D arrays of one length, got {im.shape} and {ex.shape}")
    keys = np.round(np.log(im) * 1e9) if np.all(im > 0) else im
    xs, n, z = [], [], []
    for k in np.unique(keys):
        sel = keys == k
        xs.append(float(im[sel][0]))
        n.append(int(sel.sum()))
        z.append(int(ex[sel].sum()))
    order = np.argsort(xs)
    return np.asarray(xs)[order], np.asarray(n)[order], np.asarray(z)[order]


def _check(x, n, z) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    x, n, z = (np.asarray(v, float).ravel() for v in (x, n, z))
    if not (len(x) == len(n) == len(z)):
        raise ValueError(f"x, n, z must have one length, got {len(x)}, {len(n)}, {len(z)}")
    if not np.all(np.isfinite(x)) or np.any(x <= 0):
        raise ValueError(f"the intensity measure of every stripe must be a positive number, got {x.tolist()}")
    if np.any(n < 0) or np.any(z < 0) or np.any(z > n) or np.any(n != np.round(n)) or np.any(z != np.round(z)):
        raise ValueError(f"n (runs) and z (exceedances) must be integers with 0 <= z <= n, got n={n.tolist()}, "
                         f"z={z.tolist()}")
    keep = n > 0
    return x[keep], n[keep], z[keep]


def why_no_fit(x, n, z) -> str | None:
    """The reason no finite maximum-likelihood fit exists, or None when it exists."""
    x, n, z = _check(x, n, z)
    ux = np.unique(x)
    if len(ux) < 2:
        return (f"{len(ux)} stripe(s) with runs: a median and a dispersion cannot both be identified from fewer than "
                "2 intensity levels")
    if z.sum() == 0:
        return (f"no run reached the damage state (0 of {int(n.sum())} runs, stripes {_fmt(ux)}): the median is only "
                f"known to lie above about {ux.max():g} and the data say nothing about the dispersion")
    if z.sum() == n.sum():
        return (f"every run reached the damage state ({int(n.sum())} of {int(n.sum())}, stripes {_fmt(ux)}): the "
                f"median is only known to lie below about {ux.min():g}")
    lo_exceed = x[z > 0].min()      # smallest IM at which some run exceeded
    hi_survive = x[z < n].max()     # largest IM at which some run did not
    if lo_exceed > hi_survive:
        return (f"the observed fraction jumps from 0 % (at {hi_survive:g} and below) to 100 % (at {lo_exceed:g} and "
                f"above) between two stripes (complete separation): the likelihood grows without bound as beta -> 0; "
                f"the median lies between {hi_survive:g} and {lo_exceed:g} and the dispersion is not resolved by "
                "these stripes (add runs or stripes in between)")
    if lo_exceed == hi_survive:
        below, above = (ux < lo_exceed).any(), (ux > lo_exceed).any()
        return (f"the runs that reached the damage state and those that did not share only the stripe at "
                f"{lo_exceed:g}" + (f" (none reached it below {lo_exceed:g}" if below else " (no stripe below it")
                + (f", all did above it)" if above else ", no stripe above it)")
                + f" (quasi-complete separation): the likelihood grows without bound as beta -> 0 with the median at "
                f"{lo_exceed:g}; the dispersion is not resolved by these stripes (add runs or stripes)")
    return None


def _fmt(v) -> str:
    return ", ".join(f"{a:g}" for a in v)


def _negll(params, lx, n, z):
    a, b = params
    u = a + b * lx
    return -float(np.sum(z * log_ndtr(u) + (n - z) * log_ndtr(-u)))


def _mills(u):
    """phi(u)/Phi(u) and phi(u)/(1 - Phi(u)), stable for large |u|."""
    lphi = -0.5 * u * u - _LOG_SQRT_2PI
    return np.exp(lphi - log_ndtr(u)), np.exp(lphi - log_ndtr(-u))


def _grad(params, lx, n, z):
    a, b = params
    u = a + b * lx
    r1, r0 = _mills(u)
    s = z * r1 - (n - z) * r0           # d loglik / d u_j
    return -np.array([s.sum(), (s * lx).sum()])


def _hess(params, lx, n, z):
    a, b = params
    u = a + b * lx
    r1, r0 = _mills(u)
    # d2 loglik / du2 = -z r1 (u + r1) - (n - z) r0 (r0 - u)  (<= 0: concave)
    w = z * r1 * (u + r1) + (n - z) * r0 * (r0 - u)
    return np.array([[w.sum(), (w * lx).sum()], [(w * lx).sum(), (w * lx * lx).sum()]])


def _start(lx, n, z) -> np.ndarray:
    """A starting point: least squares of probit((z + 0.5)/(n + 1)) on ln x, weighted by n."""
    q = stats.norm.ppf((z + 0.5) / (n + 1.0))
    A = np.column_stack([np.ones_like(lx), lx]) * np.sqrt(n)[:, None]
    a, b = np.linalg.lstsq(A, q * np.sqrt(n), rcond=None)[0]
    if not np.isfinite(b) or b <= 0:
        b = 1.0 / 0.5
        a = -b * float(np.average(lx, weights=n))
    return np.array([a, b])


def fisher_information(x, n, theta: float, beta: float) -> np.ndarray:
    """Expected Fisher information of (a, b) = (-ln(theta)/beta, 1/beta) for stripes at x with
    n runs each: sum_j n_j phi(u_j)^2 / (p_j (1 - p_j)) [1, ln x_j]^T [1, ln x_j]."""
    lx = np.log(np.asarray(x, float))
    n = np.asarray(n, float)
    u = (lx - math.log(theta)) / beta
    # p (1 - p) as Phi(u) Phi(-u): 1 - Phi(u) rounds to 0 beyond u ~ 8.3 (a run far above the
    # median, one run per IM value), which made the weight phi^2 / 1e-300 ~ 1e250
    w = n * stats.norm.pdf(u) ** 2 / np.maximum(ndtr(u) * ndtr(-u), 1e-300)
    return np.array([[w.sum(), (w * lx).sum()], [(w * lx).sum(), (w * lx * lx).sum()]])


def standard_errors(x, n, theta: float, beta: float) -> tuple[float, float]:
    """Asymptotic standard errors (SE of ln theta, SE of beta) of the maximum-likelihood
    estimates for n_j runs at each x_j, by the delta method from the Fisher information
    of (a, b): ln theta = -a/b, beta = 1/b."""
    cov = np.linalg.inv(fisher_information(x, n, theta, beta))
    b = 1.0 / beta
    a = -math.log(theta) * b
    j_lnt = np.array([-1.0 / b, a / b ** 2])    # d(-a/b)/d(a, b)
    j_beta = np.array([0.0, -1.0 / b ** 2])     # d(1/b)/d(a, b)
    return float(math.sqrt(j_lnt @ cov @ j_lnt)), float(math.sqrt(j_beta @ cov @ j_beta))


def fit(x, n, z) -> Fit:
    """Maximum-likelihood lognormal fragility for stripes at IM ``x`` (> 0) with ``n`` runs
    and ``z`` exceedances each. Raises FitError when no finite maximum exists (see
    ``why_no_fit``), ValueError on malformed input."""
    x, n, z = _check(x, n, z)
    reason = why_no_fit(x, n, z)
    if reason:
        raise FitError(reason)
    lx = np.log(x)
    res = optimize.minimize(_negll, _start(lx, n, z), args=(lx, n, z), jac=_grad, hess=_hess,
                            method="trust-exact", options={"gtol": 1e-10, "maxiter": 500})
    a, b = res.x
    g = np.abs(_grad(res.x, lx, n, z)).max()
    if not np.all(np.isfinite(res.x)) or g > 1e-6 * max(1.0, float(n.sum())):
        raise FitError(f"the optimiser did not converge ({res.message}; gradient {g:.2g})")
    if b <= 0:  # cannot happen for overlapping data with probability increasing in x, but say so if it does
        raise FitError(f"the fitted probability decreases with the intensity measure (slope {b:.3g}): the data do "
                       "not describe a fragility")
    if abs(a / b) > math.log(np.finfo(float).max):  # a nearly flat fit (a bootstrap resample): no finite median
        raise FitError(f"the fitted median exp({-a / b:.3g}) is beyond any number (slope {b:.3g}): the data do not "
                       "resolve it")
    theta, beta = math.exp(-a / b), 1.0 / b
    try:
        se_t, se_b = standard_errors(x, n, theta, beta)
    except np.linalg.LinAlgError:
        se_t = se_b = None
    return Fit(theta=theta, beta=beta, loglik=-float(res.fun) + _log_binom(n, z), n_stripes=len(np.unique(x)),
               n_runs=int(n.sum()), n_exceed=int(z.sum()), se_ln_theta=se_t, se_beta=se_b, iterations=int(res.nit),
               stripes=[[float(a_), int(b_), int(c_)] for a_, b_, c_ in zip(x, n, z)])


def _log_binom(n, z) -> float:
    from scipy.special import gammaln

    return float(np.sum(gammaln(n + 1) - gammaln(z + 1) - gammaln(n - z + 1)))


def fit_runs(im, exceeded) -> Fit:
    """``fit`` on runs given one by one (IM of each run, exceeded or not)."""
    return fit(*stripes_from_runs(im, exceeded))


def bootstrap(x, n, z, n_boot: int = 1000, seed: int = 0, grid=None, level: float = 0.95) -> dict:
    """Non-parametric bootstrap: each replicate resamples the n_j runs of every stripe with
    replacement (so its exceedance count is Binomial(n_j, z_j/n_j)), refits, and the
    ``level`` percentile intervals of theta and beta and pointwise bands of P(DS | x) on
    ``grid`` are returned. Replicates with no finite maximum (a resample that is
    separated) are counted in ``failed`` and left out; the fraction is reported so that a
    band built from few replicates is not mistaken for a tight one."""
    x, n, z = _check(x, n, z)
    rng = np.random.default_rng(seed)
    grid = np.geomspace(x.min() / 2, x.max() * 1.5, 200) if grid is None else np.asarray(grid, float)
    thetas, betas, curves = [], [], []
    failed = 0
    p = z / n
    for _ in range(n_boot):
        zb = rng.binomial(n.astype(int), p)
        try:
            f = fit(x, n, zb)
        except FitError:
            failed += 1
            continue
        thetas.append(f.theta)
        betas.append(f.beta)
        curves.append(probability(grid, f.theta, f.beta))
    lo, hi = 50 * (1 - level), 50 * (1 + level)
    out = {"n_boot": n_boot, "seed": seed, "level": level, "failed": failed, "grid": grid.tolist()}
    if not thetas:
        out.update(theta_ci=None, beta_ci=None, band_lo=None, band_hi=None)
        return out
    curves = np.array(curves)
    out.update(theta_ci=[float(np.percentile(thetas, lo)), float(np.percentile(thetas, hi))],
               beta_ci=[float(np.percentile(betas, lo)), float(np.percentile(betas, hi))],
               band_lo=np.percentile(curves, lo, axis=0).tolist(), band_hi=np.percentile(curves, hi, axis=0).tolist())
    return out


def bootstrap_runs(im, exceeded, n_boot: int = 1000, seed: int = 0, level: float = 0.95) -> dict:
    """Case-resampling bootstrap for runs that each have their own IM (PGV, Sa(T1) of a
    scaled record: one run per "stripe", where ``bootstrap``'s within-stripe resampling
    would leave every replicate equal to the data): each replicate draws len(im) runs with
    replacement from all runs, refits (``fit_runs``), and the ``level`` percentile
    intervals of theta and beta are returned, with the count of replicates that had no
    finite maximum (``failed``, left out)."""
    im = np.asarray(im, float)
    ex = np.asarray(exceeded).astype(bool)
    if im.shape != ex.shape or im.ndim != 1:
        raise ValueError(f"im and exceeded must be 1-D arrays of one length, got {im.shape} and {ex.shape}")
    rng = np.random.default_rng(seed)
    thetas, betas, failed = [], [], 0
    for _ in range(n_boot):
        k = rng.integers(0, len(im), len(im))
        try:
            f = fit_runs(im[k], ex[k])
        except FitError:
            failed += 1
            continue
        thetas.append(f.theta)
        betas.append(f.beta)
    return _intervals(thetas, betas, level, {"n_boot": n_boot, "seed": seed, "level": level, "failed": failed,
                                             "method": "runs resampled"})


# --- incremental dynamic analysis: one interval- or right-censored intensity per record -----------------------
@dataclass
class IdaFit:
    """Maximum-likelihood lognormal fragility from IDA brackets: median ``theta``, dispersion ``beta``."""

    theta: float
    beta: float
    loglik: float
    n_records: int
    n_collapsed: int
    n_censored: int
    iterations: int = 0

    def probability(self, x) -> np.ndarray:
        return probability(x, self.theta, self.beta)

    def as_dict(self) -> dict:
        return asdict(self)


def _ida_check(brackets, censored) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    b = np.asarray(brackets, float).reshape(-1, 2)
    c = np.asarray(censored, float).ravel()
    lo, hi = b[:, 0], b[:, 1]
    if not (np.all(np.isfinite(b)) and np.all(lo >= 0) and np.all(hi > lo)):
        raise ValueError(f"every bracket must be (lo, hi] with 0 <= lo < hi, got {b.tolist()}")
    if not (np.all(np.isfinite(c)) and np.all(c > 0)):
        raise ValueError(f"every censoring intensity must be a positive number, got {c.tolist()}")
    return lo, hi, c


def why_no_ida_fit(brackets, censored=()) -> str | None:
    """The reason no finite maximum-likelihood IDA fit exists, or None when it exists."""
    lo, hi, c = _ida_check(brackets, censored)
    if len(lo) == 0:
        return (f"no record collapsed the wall ({len(c)} censored, the highest intensity run "
                f"{c.max() if len(c) else 0:g}): the median is only known to lie above {c.min() if len(c) else 0:g}")
    top = lo.max()
    if top <= hi.min() and (len(c) == 0 or top < c.min()):
        return (f"the {len(lo)} bracket(s) all hold or touch the intensity {top:g}, below every censoring intensity: "
                "the likelihood is largest as beta -> 0 (the records do not resolve a dispersion; add records or "
                "narrow the brackets)")
    return None


def _log_diff_ndtr(a, b):
    """log(Phi(b) - Phi(a)) for a < b, stable in both tails (a may be -inf)."""
    flip = a > 0  # upper tail: Phi(b) - Phi(a) = Phi(-a) - Phi(-b)
    hi = np.where(flip, -a, b)
    lo = np.where(flip, -b, a)
    lh, ll = log_ndtr(hi), log_ndtr(lo)
    with np.errstate(divide="ignore"):
        return lh + np.log1p(-np.exp(ll - lh))


def ida_loglik(theta: float, beta: float, brackets, censored=()) -> float:
    """The log-likelihood above."""
    lo, hi, c = _ida_check(brackets, censored)
    return -_ida_negll(np.array([math.log(theta), math.log(beta)]), *_ida_logs(lo, hi, c))[0]


def _ida_logs(lo, hi, c) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """ln lo (-inf where lo = 0), ln hi, ln c: ``_ida_negll``'s data, taken once per fit."""
    with np.errstate(divide="ignore"):
        return np.log(lo), np.log(hi), np.log(c)


def _ida_terms(m, s, log_lo, log_hi, log_c):
    """Each record's log-likelihood term and its derivatives in (m, s) = (ln theta, ln beta),
    from the data's logarithms (``_ida_logs``); ``m`` and ``s`` broadcast against the records
    (scalars, or (R, 1) for R data sets at once). Returns (ld, d ld/dm, d ld/ds) of the brackets
    and (lq, d lq/dm, d lq/ds) of the censored records."""
    beta = np.exp(s)
    a = (log_lo - m) / beta
    b = (log_hi - m) / beta
    ld = _log_diff_ndtr(a, b)
    lpa = np.where(np.isfinite(a), -0.5 * a * a - _LOG_SQRT_2PI, -np.inf)
    lpb = -0.5 * b * b - _LOG_SQRT_2PI
    ra, rb = np.exp(lpa - ld), np.exp(lpb - ld)            # phi(a)/D, phi(b)/D
    a0 = np.where(np.isfinite(a), a, 0.0)
    u = (log_c - m) / beta
    lq = log_ndtr(-u)
    rc = np.exp(-0.5 * u * u - _LOG_SQRT_2PI - lq)          # phi(u)/Q
    # d ln D / dm = -(phi(b) - phi(a))/(beta D); d ln D / ds = -(b phi(b) - a phi(a))/D
    return (ld, -(rb - ra) / beta, -(b * rb - a0 * ra)), (lq, rc / beta, u * rc)


def _ida_negll(params, log_lo, log_hi, log_c):
    """-log L and its gradient in (m, s) = (ln theta, ln beta), from the data's logarithms
    (``_ida_logs``)."""
    m, s = params
    (ld, dm, ds), (lq, cm, cs) = _ida_terms(m, s, log_lo, log_hi, log_c)
    ll = float(ld.sum() + lq.sum())
    return -ll, -np.array([float(dm.sum() + cm.sum()), float(ds.sum() + cs.sum())])


def _mid_points(lo, hi) -> np.ndarray:
    """The brackets' geometric mid-points (hi / 2 where lo = 0): where a fit starts from."""
    return np.where(lo > 0, np.sqrt(np.maximum(lo, 1e-300) * hi), hi / 2)


def _ida_start(lo, hi, c, wb, wc) -> np.ndarray:
    """The starting point (m, s) of each weighted data set (``_fit_ida_weighted``'s counts): the
    weighted mean and standard deviation (at least 0.1) of ln of the mid-points and of the
    censoring intensities (``fit_ida``'s, with weights)."""
    pts = np.log(np.concatenate([_mid_points(lo, hi), c]))
    w = np.concatenate([wb, wc], axis=1)
    mean = (w * pts).sum(1) / w.sum(1)
    std = np.sqrt((w * (pts - mean[:, None]) ** 2).sum(1) / w.sum(1))
    return np.column_stack([mean, np.log(np.maximum(std, 0.1))])


def _fit_ida_weighted(logs, wb, wc, x0, gtol: float = 1e-9, max_iter: int = 60) -> tuple[np.ndarray, np.ndarray]:
    """Maximise R weighted IDA likelihoods at once (``wb`` (R, n_b), ``wc`` (R, n_c): each data
    set's count of each bracket and censored record), by Newton's method from ``x0`` (R, 2):
    the Hessian from central differences of the analytic gradient (a positive definite one, else
    the gradient's direction), steps halved until the objective decreases. Returns the
    parameters (R, 2) in (ln theta, ln beta) and the largest gradient component of each."""
    def wsum(w, v):  # a record drawn 0 times adds nothing, even where its term is not finite
        return np.where(w > 0, w * v, 0.0).sum(1)

    def objective(x, rows):  # -log L and its gradient of data sets ``rows`` at x (len(rows), 2)
        b, c = wb[rows], wc[rows]
        with np.errstate(invalid="ignore", over="ignore"):
            (ld, dm, ds), (lq, cm, cs) = _ida_terms(x[:, :1], x[:, 1:], *logs)
            return (-(wsum(b, ld) + wsum(c, lq)),
                    -np.column_stack([wsum(b, dm) + wsum(c, cm), wsum(b, ds) + wsum(c, cs)]))

    x = np.array(x0, float)
    f, g = objective(x, slice(None))
    h = 1e-6
    for _ in range(max_iter):
        todo = np.flatnonzero(np.isfinite(f) & (np.abs(g).max(1) > gtol))
        if len(todo) == 0:
            break
        xt, ft, gt = x[todo], f[todo], g[todo]
        cols = [(objective(xt + h * e, todo)[1] - objective(xt - h * e, todo)[1]) / (2 * h) for e in np.eye(2)]
        H = np.stack(cols, axis=2)
        a, b, d = H[:, 0, 0], 0.5 * (H[:, 0, 1] + H[:, 1, 0]), H[:, 1, 1]
        det = a * d - b * b
        newton = (a > 0) & (det > 0)
        with np.errstate(divide="ignore", invalid="ignore"):
            step = np.where(newton[:, None], -np.column_stack([d * gt[:, 0] - b * gt[:, 1],
                                                               a * gt[:, 1] - b * gt[:, 0]]) / det[:, None], -gt)
        slope = (step * gt).sum(1)
        t = np.ones(len(todo))
        open_ = np.ones(len(todo), bool)
        for _ in range(40):  # halve each step until f decreases (Armijo; within f's round-off at the optimum)
            fn, gn = objective(xt + t[:, None] * step, todo)
            ok = np.isfinite(fn) & (fn <= ft + 1e-4 * t * slope + 4 * np.finfo(float).eps * np.abs(ft))
            take = open_ & ok
            x[todo[take]] = (xt + t[:, None] * step)[take]
            f[todo[take]], g[todo[take]] = fn[take], gn[take]
            open_ &= ~ok
            if not open_.any():
                break
            t = np.where(open_, 0.5 * t, t)
        if open_.all():  # no data set could move: round-off at their optimum
            break
    return x, np.abs(g).max(1)


def fit_ida(brackets, censored=()) -> IdaFit:
    """Maximum-likelihood lognormal fragility from IDA: ``brackets`` [(lo, hi)] of the
    records that collapsed the wall (its intensity at collapse in (lo, hi]), ``censored``
    [c] of those that did not up to c. FitError when no finite maximum exists."""
    lo, hi, c = _ida_check(brackets, censored)
    reason = why_no_ida_fit(np.column_stack([lo, hi]), c)
    if reason:
        raise FitError(reason)
    pts = np.log(np.concatenate([_mid_points(lo, hi), c]))
    x0 = np.array([pts.mean(), math.log(max(float(np.std(pts)), 0.1))])
    res = optimize.minimize(_ida_negll, x0, args=_ida_logs(lo, hi, c), jac=True, method="BFGS",
                            options={"gtol": 1e-9})
    if not np.all(np.isfinite(res.x)) or np.abs(res.jac).max() > 1e-5 * max(1.0, len(lo) + len(c)):
        raise FitError(f"the optimiser did not converge ({res.message}; gradient {np.abs(res.jac).max():.2g})")
    return IdaFit(theta=math.exp(res.x[0]), beta=math.exp(res.x[1]), loglik=-float(res.fun), n_records=len(lo) + len(c),
                  n_collapsed=len(lo), n_censored=len(c), iterations=int(res.nit))


def bootstrap_ida(brackets, censored=(), n_boot: int = 1000, seed: int = 0, level: float = 0.95) -> dict:
    """Record-resampling bootstrap of ``fit_ida``: each replicate draws as many records as
    there are, with replacement, from the brackets and censored records together, refits,
    and the ``level`` percentile intervals of theta and beta are returned; replicates with no
    finite maximum are counted (``failed``) and left out. The replicates are fitted together
    (``_fit_ida_weighted``: each one's counts of the records), to the optimum ``fit_ida``
    reaches, with the same test of convergence."""
    lo, hi, c = _ida_check(brackets, censored)
    k_br, n = len(lo), len(lo) + len(c)
    rng = np.random.default_rng(seed)
    counts = np.array([np.bincount(rng.integers(0, n, n), minlength=n) for _ in range(n_boot)], float).reshape(-1, n)
    wb, wc = counts[:, :k_br], counts[:, k_br:]
    # no finite maximum (why_no_ida_fit): no bracket drawn, or the drawn ones share a point below every censored one
    top = np.where(wb > 0, lo, -np.inf).max(1, initial=-np.inf)
    fits = (wb.sum(1) > 0) & ~((top <= np.where(wb > 0, hi, np.inf).min(1, initial=np.inf))
                               & (top < np.where(wc > 0, c, np.inf).min(1, initial=np.inf)))
    x, gmax = _fit_ida_weighted(_ida_logs(lo, hi, c), wb[fits], wc[fits], _ida_start(lo, hi, c, wb[fits], wc[fits]))
    good = np.all(np.isfinite(x), axis=1) & (gmax <= 1e-5 * max(1.0, n))
    return _intervals(np.exp(x[good, 0]).tolist(), np.exp(x[good, 1]).tolist(), level,
                      {"n_boot": n_boot, "seed": seed, "level": level, "failed": int(n_boot - good.sum()),
                       "method": "records resampled"})


def brackets_of_runs(runs, exceeded) -> tuple[list, float | None]:
    """For one record's runs [(im, exceeded)]: the bracket (lo, hi] of the intensity at which a
    damage state is first reached (hi = the lowest intensity that reached it, lo = the highest
    below it that did not, 0 if none), or None and the highest intensity run (right-censored)
    when no run reached it. Returns (bracket or None, censored_at or None)."""
    pts = sorted((float(x), bool(e)) for x, e in zip(runs, exceeded))
    hit = [x for x, e in pts if e]
    if not hit:
        return None, (pts[-1][0] if pts else None)
    hi = min(hit)
    below = [x for x, e in pts if not e and x < hi]
    return [max(below) if below else 0.0, hi], None


def _intervals(thetas, betas, level: float, out: dict) -> dict:
    """``out`` with the bootstrap's percentile intervals of theta and beta at ``level``
    (None when no resample could be fitted)."""
    if not thetas:
        return dict(out, theta_ci=None, beta_ci=None)
    lo, hi = 50 * (1 - level), 50 * (1 + level)
    return dict(out, theta_ci=[float(np.percentile(thetas, lo)), float(np.percentile(thetas, hi))],
                beta_ci=[float(np.percentile(betas, lo)), float(np.percentile(betas, hi))])
