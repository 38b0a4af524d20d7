"""Earth pressure on the stones (drystone/mechanics/earth_pressure.py): the coefficients against
textbook values and an independent trial-wedge search, the refusals, the integration over stone
faces against the closed forms of a plane wall, and the single retaining block's hand
calculations."""
import math

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

import tolerances as tol
from drystone.geometry import polygonal_wall
from drystone.mechanics import earth_pressure as ep_mod
from drystone.mechanics.earth_pressure import EarthPressure, coulomb_ka, mononobe_okabe_kae

R = math.radians
GAMMA = 18000.0  # N/m^3


# -- coefficients --------------------------------------------------------------------------
@pytest.mark.parametrize("phi", [20.0, 30.0, 36.5, 45.0])
def test_rankine_special_case(phi):
    """delta = beta = alpha = 0: K_A = tan^2(45 deg - phi/2), Rankine's, to round-off."""
    assert coulomb_ka(R(phi)) == pytest.approx(math.tan(R(45.0 - phi / 2)) ** 2, rel=tol.EXACT_REL)


def test_coulomb_smith_worked_example():
    """Smith, *Elements of Soil Mechanics* (Smith & Smith, Wiley-Blackwell), worked example
    "Coulomb K_a" (Example 7.8 of the 9th edition, 6.7 of earlier ones): phi = 20 deg,
    delta = 10 deg, beta = 0, vertical back (psi = 90 deg from the horizontal): K_a = 0.4467,
    printed to 4 decimals."""
    assert coulomb_ka(R(20), R(10)) == pytest.approx(0.4467, abs=tol.PRINTED_4_DECIMALS)


def test_mononobe_okabe_calculator_example():
    """A published worked example of Mononobe-Okabe (reuven.tools "Mononobe-Okabe Seismic
    Earth Pressure", a third-party calculator page, not a textbook: the independent check is
    the trial-wedge test below): vertical wall, level backfill, phi = 35 deg, delta = 17.5 deg,
    k_h = 0.2, k_v = 0: K_AE = 0.3797 and K_A = 0.2461 (4 decimals); P_AE = 123.04 kN/m for
    gamma = 18 kN/m^3, H = 6 m (2 decimals of kN/m)."""
    kae = mononobe_okabe_kae(R(35), R(17.5), 0.0, 0.0, 0.2, 0.0)
    assert kae == pytest.approx(0.3797, abs=tol.PRINTED_4_DECIMALS)
    assert coulomb_ka(R(35), R(17.5)) == pytest.approx(0.2461, abs=tol.PRINTED_4_DECIMALS)
    assert 0.5 * kae * 18.0 * 6.0 ** 2 == pytest.approx(123.04, abs=tol.PRINTED_2_DECIMALS)


def _trial_wedge_k(phi, delta, beta, alpha, k_h=0.0, k_v=0.0):
    """Coulomb's construction done numerically: the largest thrust over plane failure surfaces
    through the heel, from the force equilibrium of the wedge (weight with the pseudo-static
    inertia W (-k_h, -(1 - k_v)), the wall's reaction at delta from the face normal, friction
    up the face; the soil's reaction at phi from the plane's normal, friction up the plane),
    as K = 2 P / (gamma H^2 (1 - k_v)). Independent of the closed form. Coordinates (s, z), s
    horizontal into the soil, heel at 0, H = 1, gamma = 1."""
    top = np.array([-math.tan(alpha), 1.0])  # the face's top: the face leans over the soil for alpha > 0
    d_p = math.cos(delta) * np.array([math.cos(alpha), math.sin(alpha)]) \
        + math.sin(delta) * np.array([-math.sin(alpha), math.cos(alpha)])

    def thrust(rho):
        ell = (top[1] - top[0] * math.tan(beta)) / (math.sin(rho) - math.cos(rho) * math.tan(beta))
        c = ell * np.array([math.cos(rho), math.sin(rho)])
        w = 0.5 * abs(top[0] * c[1] - top[1] * c[0])
        body = w * np.array([-k_h, -(1.0 - k_v)])
        n_p = np.array([-math.sin(rho), math.cos(rho)])
        if n_p @ top < 0:
            n_p = -n_p
        d_r = math.cos(phi) * n_p + math.sin(phi) * np.array([math.cos(rho), math.sin(rho)])
        p, _ = np.linalg.solve(np.column_stack([d_p, d_r]), -body)
        return p

    lo, hi = beta + 1e-9, math.pi / 2 + alpha - 1e-9
    grid = np.linspace(lo, hi, 2001)
    vals = [thrust(r) for r in grid]
    i = int(np.argmax(vals))
    res = minimize_scalar(lambda r: -thrust(r), bracket=(grid[max(i - 1, 0)], grid[i], grid[min(i + 1, 2000)]),
                          tol=1e-12)
    return 2.0 * -res.fun / (1.0 - k_v)


@pytest.mark.parametrize("phi,delta,beta,alpha,k_h,k_v", [
    (30, 0, 0, 0, 0.0, 0.0), (30, 20, 0, 0, 0.0, 0.0), (34, 22, 10, 0, 0.0, 0.0), (36, 24, 15, 10, 0.0, 0.0),
    (36, 24, 15, -12, 0.0, 0.0), (30, 20, 0, 0, 0.3, 0.0), (35, 17.5, 0, 0, 0.2, 0.0), (38, 19, 10, -8, 0.25, 0.1),
    (40, 26, 5, 12, 0.35, -0.15), (30, 15, 10, 0, 0.35, 0.0)])
def test_coefficients_against_trial_wedge(phi, delta, beta, alpha, k_h, k_v):
    """Coulomb's K_A and Mononobe-Okabe's K_AE equal the trial-wedge maximum (batters of both
    signs, sloping backfills, upward and downward k_v; the last set is 0.71 deg from the limit
    phi - beta - theta = 0)."""
    args = (R(phi), R(delta), R(beta), R(alpha))
    k = mononobe_okabe_kae(*args, k_h, k_v)
    assert k == pytest.approx(_trial_wedge_k(*args, k_h, k_v), rel=tol.WEDGE_SEARCH_REL)


def test_k_h_zero_gives_k_a():
    """K_AE at k_h = 0 is K_A for any k_v (theta = 0: the vertical inertia only scales the
    weight, through the factor (1 - k_v) outside K_AE)."""
    args = (R(33), R(20), R(8), R(-5))
    for kv in (0.0, 0.2, -0.2):
        assert mononobe_okabe_kae(*args, 0.0, kv) == pytest.approx(coulomb_ka(*args), rel=tol.EXACT_REL)


def test_mononobe_okabe_vectorised():
    """An array of k_h gives the scalars element by element."""
    kh = np.array([0.0, 0.05, 0.2, 0.3])
    k = mononobe_okabe_kae(R(35), R(20), 0.0, 0.0, kh)
    assert k.shape == (4,)
    for i, x in enumerate(kh):
        assert k[i] == mononobe_okabe_kae(R(35), R(20), 0.0, 0.0, float(x))


def test_refuses_mononobe_okabe_without_solution():
    """phi - beta - theta < 0: refused, naming phi, beta, k_h, k_v, theta and the largest k_h."""
    # phi 30, beta 20, k_h 0.3: theta = 16.7 deg > 10 deg
    with pytest.raises(ValueError) as err:
        mononobe_okabe_kae(R(30), R(15), R(20), 0.0, 0.3, 0.0)
    msg = str(err.value)
    for part in ("Mononobe-Okabe has no solution", "phi - beta - theta", "phi = 30 deg", "beta = 20 deg",
                 "k_h = 0.3", "k_v = 0", "largest k_h", f"{math.tan(R(10)):.6g}"):
        assert part in msg, (part, msg)
    # a time series: the first offending sample is named
    with pytest.raises(ValueError, match="k_h = 0.6, .*at sample 2"):
        mononobe_okabe_kae(R(30), 0.0, 0.0, 0.0, np.array([0.1, 0.2, 0.6, 0.7]))
    assert ep_mod.max_k_h(R(30), R(20)) == pytest.approx(math.tan(R(10)))


@pytest.mark.parametrize("kwargs,words", [
    (dict(phi=0.0), "phi = 0 deg"), (dict(phi=R(30), delta=R(35)), "delta = 35 deg"),
    (dict(phi=R(30), delta=-0.1), "wall friction delta"), (dict(phi=R(30), beta=R(40)), "phi - beta"),
    (dict(phi=R(30), k_v=1.0), "k_v = 1"), (dict(phi=R(30), alpha=R(95)), "alpha = 95 deg"),
    (dict(phi=R(30), beta=R(-80), alpha=R(20)), "folds over"),
])
def test_refuses_invalid_sets(kwargs, words):
    with pytest.raises(ValueError, match=words):
        ep_mod.check(**kwargs)


def test_earth_pressure_refusals():
    """The soil and plane description refuses what it cannot model, naming the key."""
    base = dict(gamma=GAMMA, phi=R(30), z_top=1.0, z_base=0.0)
    for bad, words in ((dict(z_top=0.0), "z_top"), (dict(into_soil="y"), "into_soil"),
                       (dict(increment="cubic"), "increment"), (dict(gamma=-1.0), "gamma"),
                       (dict(water_level=1.5), "water_level"), (dict(water_level=0.5, gamma_sat=9000.0), "gamma_sat"),
                       (dict(surcharge=-1.0), "surcharge")):
        with pytest.raises(ValueError, match=words):
            EarthPressure(**{**base, **bad})


# -- geometry helpers ----------------------------------------------------------------------------
def test_polygon_moments_of_a_rectangle():
    """A 2 x 3 rectangle in the plane y = 0.5, corner at (1, 0.5, 2): area 6, first moments
    6 x centre, second moments of a rectangle (int x^2 = A (cx^2 + a^2 / 12))."""
    p = np.array([[1, 0.5, 2], [3, 0.5, 2], [3, 0.5, 5], [1, 0.5, 5]], dtype=float)
    a, s1, s2 = ep_mod.polygon_moments(p)
    c = np.array([2.0, 0.5, 3.5])
    assert a == pytest.approx(6.0, rel=tol.EXACT_REL)
    assert s1 == pytest.approx(6.0 * c, rel=tol.EXACT_REL)
    expected = 6.0 * np.outer(c, c) + 6.0 * np.diag([2.0 ** 2 / 12, 0.0, 3.0 ** 2 / 12])
    assert s2 == pytest.approx(expected, rel=tol.EXACT_REL, abs=tol.EXACT_ABS)


def test_clip_z():
    """A square clipped at mid height keeps half of it, on the side asked for."""
    p = np.array([[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1]], dtype=float)
    below = ep_mod.clip_z(p, 0.25, True)
    above = ep_mod.clip_z(p, 0.25, False)
    assert ep_mod.polygon_moments(below)[0] == pytest.approx(0.25)
    assert ep_mod.polygon_moments(above)[0] == pytest.approx(0.75)
    assert below[:, 2].max() == pytest.approx(0.25) and above[:, 2].min() == pytest.approx(0.25)
    assert len(ep_mod.clip_z(p, -1.0, True)) == 0


# -- plane walls ---------------------------------------------------------------------------------
def _box(x0, x1, y0, y1, z0, z1):
    return [[x, y, z] for x in (x0, x1) for y in (y0, y1) for z in (z0, z1)]


def _courses(length, thickness, height, n, y_back=0.0):
    """A wall of n equal courses of box stones, back face at y = y_back, soil at y > y_back."""
    h = height / n
    return {k: [_box(0.0, length, y_back - thickness, y_back, k * h, (k + 1) * h)] for k in range(n)}


def _totals(stones, ep, k_h=0.0, k_v=0.0, about=(0.0, 0.0, 0.0)):
    """The wall's total force (N) and moment about ``about`` (N m) from the stones' loads."""
    w = ep_mod.wall_loads(stones, ep)
    f, m = w.at(k_h, k_v)
    f, m = f[0], m[0]
    moment = m.sum(axis=0) + np.cross(w.centroids - np.asarray(about), f).sum(axis=0)
    return f.sum(axis=0), moment


def _height_of(force, moment):
    """Elevation of a horizontal force -F_y at x = ... acting on the plane y = 0: M_x = -F_y z
    about the origin on the base, so z = M_x / (-F_y) (N m / N)."""
    return moment[0] / -force[1]


H, L = 2.0, 1.5  # m: wall height, length


def test_dry_wall_resultant_and_height():
    """Dry backfill, smooth vertical wall: the stones' forces sum to P_A = 1/2 K_A gamma H^2 per
    metre (times L) at H/3; with wall friction delta the thrust turns down by delta (F_z =
    -tan(delta) F_h) and the horizontal part is P_A cos(delta) at H / 3."""
    for delta in (0.0, R(20)):
        ep = EarthPressure(gamma=GAMMA, phi=R(32), z_top=H, z_base=0.0, delta=delta)
        p_a = 0.5 * ep.ka * GAMMA * H ** 2 * L
        force, moment = _totals(_courses(L, 0.5, H, 5), ep)
        assert -force[1] == pytest.approx(p_a * math.cos(delta), rel=tol.EXACT_REL)
        assert -force[2] == pytest.approx(p_a * math.sin(delta), rel=tol.EXACT_REL, abs=tol.EXACT_ABS * p_a)
        assert force[0] == pytest.approx(0.0, abs=tol.EXACT_ABS * p_a)
        assert _height_of(force, moment) == pytest.approx(H / 3, rel=tol.EXACT_REL)


def test_surcharge_and_water_closed_forms():
    """Surcharge q and a water table at depth z_w below the top: per metre of wall, smooth
    vertical back, level backfill,
        P = K q H + 1/2 K gamma z_w^2 + K gamma z_w h_w + 1/2 K gamma' h_w^2 + 1/2 gamma_w h_w^2
    (h_w = H - z_w, gamma' = gamma_sat - gamma_w), each term at the centroid of its rectangle
    or triangle: H/2, h_w + z_w/3, h_w/2, h_w/3, h_w/3 above the base."""
    q, zw_depth, gsat = 10e3, 0.8, 20e3
    ep = EarthPressure(gamma=GAMMA, phi=R(30), z_top=H, z_base=0.0, surcharge=q, water_level=H - zw_depth,
                       gamma_sat=gsat)
    k, hw, gw = ep.ka, H - zw_depth, ep.gamma_w
    terms = [(k * q * H, H / 2), (0.5 * k * GAMMA * zw_depth ** 2, hw + zw_depth / 3), (k * GAMMA * zw_depth * hw, hw / 2),
             (0.5 * k * (gsat - gw) * hw ** 2, hw / 3), (0.5 * gw * hw ** 2, hw / 3)]
    p = sum(t for t, _ in terms)
    z = sum(t * y for t, y in terms) / p
    # courses that do not fall on the water table: the faces are clipped there
    force, moment = _totals(_courses(L, 0.4, H, 3), ep)
    assert -force[1] == pytest.approx(p * L, rel=tol.EXACT_REL)
    assert _height_of(force, moment) == pytest.approx(z, rel=tol.EXACT_REL)
    closed = ep_mod.plane_wall_resultant(ep)
    assert closed.horizontal == pytest.approx(p, rel=tol.EXACT_REL)
    assert closed.height == pytest.approx(z, rel=tol.EXACT_REL)


@pytest.mark.parametrize("increment,eta", [("seed_whitman", 0.6), ("inverted_triangle", 2 / 3), ("static", 1 / 3)])
def test_seismic_resultant_and_height(increment, eta):
    """Dry, level, smooth vertical wall under k_h = 0.2, k_v = 0.1: the total is
    P_AE = 1/2 K_AE gamma H^2 (1 - k_v); the static part (1 - k_v) P_A acts at H/3 and the
    increment (1 - k_v)(K_AE - K_A) 1/2 gamma H^2 at 0.6 H (Seed & Whitman), 2/3 H or H/3."""
    kh, kv = 0.2, 0.1
    ep = EarthPressure(gamma=GAMMA, phi=R(34), z_top=H, z_base=0.0, increment=increment)
    ka, kae = ep.ka, ep.kae(kh, kv)
    p_ae = 0.5 * kae * GAMMA * H ** 2 * (1 - kv)
    static = 0.5 * ka * GAMMA * H ** 2 * (1 - kv)
    z = (static * H / 3 + (p_ae - static) * eta * H) / p_ae
    force, moment = _totals(_courses(L, 0.5, H, 4), ep, kh, kv)
    assert -force[1] == pytest.approx(p_ae * L, rel=tol.EXACT_REL)
    assert _height_of(force, moment) == pytest.approx(z, rel=tol.EXACT_REL)
    closed = ep_mod.plane_wall_resultant(ep, kh, kv)
    assert closed.horizontal == pytest.approx(p_ae, rel=tol.EXACT_REL)
    assert closed.height == pytest.approx(z, rel=tol.EXACT_REL)


def test_pressure_profile_seed_whitman():
    """The increment's pressure is linear from 1.6 dP/H at the top to 0.4 dP/H at the base."""
    ep = EarthPressure(gamma=GAMMA, phi=R(34), z_top=H, z_base=0.0)
    dk = ep.kae(0.2) - ep.ka
    dp = dk * 0.5 * GAMMA * H ** 2
    e0, _ = ep.pressure([0.0, H], 0.0)
    e1, _ = ep.pressure([0.0, H], 0.2)
    assert e1 - e0 == pytest.approx([0.4 * dp / H, 1.6 * dp / H], rel=tol.EXACT_REL)


def _fancy_soil(**kw):
    return EarthPressure(**{**dict(gamma=GAMMA, phi=R(36), z_top=1.0, z_base=0.0, into_soil="+y", back=0.2,
                                   delta=R(24), surcharge=5e3, water_level=0.35, gamma_sat=20.5e3), **kw})


@pytest.mark.parametrize("seed,reentrant", [(1, 0.0), (2, 0.6)])
def test_polygonal_stones_give_the_same_total(seed, reentrant):
    """Splitting the wall into polygonal stones (some of two convex parts) instead of courses
    changes neither the total force nor the total moment: the integrals are exact. Wall 2 m x
    1 m x 0.4 m (back at y = 0.2), friction, surcharge, water table and k_h; moments about a
    point off the wall."""
    d = polygonal_wall.make(length=2.0, height=1.0, thickness=0.4, seed=seed, reentrant=reentrant)
    stones = {b["id"]: b.get("parts") or [b["vertices"]] for b in d["blocks"]}
    assert any(len(p) > 1 for p in stones.values()) == (reentrant > 0)
    boxes = {k: [_box(0.0, 2.0, -0.2, 0.2, z0, z0 + 0.25)] for k, z0 in enumerate((0.0, 0.25, 0.5, 0.75))}
    about = (0.3, -1.0, 0.7)
    for kh in (0.0, 0.25):
        ep = _fancy_soil()
        f_poly, m_poly = _totals(stones, ep, kh, about=about)
        f_box, m_box = _totals(boxes, ep, kh, about=about)
        scale = np.abs(f_box).max()
        assert f_poly == pytest.approx(f_box, rel=tol.EXACT_REL, abs=tol.EXACT_ABS * scale)
        assert m_poly == pytest.approx(m_box, rel=tol.EXACT_REL, abs=tol.EXACT_ABS * scale)
        closed = ep_mod.plane_wall_resultant(ep, kh)
        assert -f_box[1] == pytest.approx(2.0 * closed.horizontal, rel=tol.EXACT_REL)
        assert -f_box[2] == pytest.approx(2.0 * closed.vertical, rel=tol.EXACT_REL)


def test_only_back_faces_are_loaded():
    """The platform (its side faces are off the plane) and stones set back from the plane get
    nothing; a stone standing above z_top gets nothing; the moment of a stone is about its own
    centroid."""
    ep = _fancy_soil()
    stones = {"platform": [_box(-1, 3, -0.6, 0.6, -0.1, 0.0)], "set_back": [_box(0, 1, -0.2, 0.15, 0, 0.5)],
              "above": [_box(0, 1, -0.2, 0.2, 1.0, 1.3)], "loaded": [_box(1, 2, -0.2, 0.2, 0, 0.5)]}
    w = ep_mod.wall_loads(stones, ep)
    f, m = w.at(0.1)
    assert np.all(f[0, :3] == 0.0) and np.all(m[0, :3] == 0.0)
    assert f[0, 3, 1] < 0
    assert w.centroids[3] == pytest.approx([1.5, 0.0, 0.25])


def test_battered_wall():
    """A back face with a batter alpha (both signs) built of stacked stones whose back faces lie
    on the inclined plane: the horizontal and vertical totals are P cos(delta + alpha) and
    P sin(delta + alpha), P = 1/2 K_A(alpha) gamma H^2 (+ the surcharge term K q H cos(alpha) /
    cos(alpha - beta), Das), the water's int u dz and tan(alpha) int u dz."""
    for alpha in (R(10), R(-12)):
        ep = EarthPressure(gamma=GAMMA, phi=R(34), z_top=H, z_base=0.0, delta=R(20), beta=R(10), alpha=alpha,
                           surcharge=4e3)
        t = math.tan(alpha)
        stones = {}
        for k in range(4):
            z0, z1 = k * H / 4, (k + 1) * H / 4
            # the back face at y = -z tan(alpha) (it leans over the soil for alpha > 0)
            stones[k] = [[[x, -z * t - 0.5, z] for x in (0.0, L) for z in (z0, z1)]
                         + [[x, -z * t, z] for x in (0.0, L) for z in (z0, z1)]]
        force, _ = _totals(stones, ep)
        p = 0.5 * ep.ka * GAMMA * H ** 2 + ep.ka * 4e3 * H * math.cos(alpha) / math.cos(alpha - R(10))
        assert -force[1] == pytest.approx(L * p * math.cos(R(20) + alpha), rel=tol.EXACT_REL)
        assert -force[2] == pytest.approx(L * p * math.sin(R(20) + alpha), rel=tol.EXACT_REL)
    ep = EarthPressure(gamma=GAMMA, phi=R(34), z_top=H, z_base=0.0, alpha=R(10), water_level=1.0, gamma_sat=2e4)
    closed = ep_mod.plane_wall_resultant(ep)
    u = 0.5 * ep.gamma_w * 1.0 ** 2
    k = ep.ka
    earth = 0.5 * k * GAMMA * 1.0 + k * GAMMA * 1.0 * 1.0 + 0.5 * k * (2e4 - ep.gamma_w) * 1.0
    assert closed.horizontal == pytest.approx(earth * math.cos(R(10)) + u, rel=tol.EXACT_REL)
    assert closed.vertical == pytest.approx(earth * math.sin(R(10)) + u * math.tan(R(10)), rel=tol.EXACT_REL)


def test_time_series_is_linear_in_k():
    """WallLoads.at over a series equals the stones' loads evaluated sample by sample through the
    closed form's decomposition, and refuses a sample past Mononobe-Okabe's limit, naming it."""
    ep = _fancy_soil()
    d = polygonal_wall.make(length=2.0, height=1.0, thickness=0.4, seed=3)
    stones = {b["id"]: b.get("parts") or [b["vertices"]] for b in d["blocks"]}
    w = ep_mod.wall_loads(stones, ep)
    kh = np.array([0.0, 0.1, 0.3, 0.05])
    f, m = w.at(kh)
    assert f.shape == (4, len(stones), 3) and m.shape == f.shape
    for i, x in enumerate(kh):
        closed = ep_mod.plane_wall_resultant(ep, x)
        assert -f[i].sum(axis=0)[1] == pytest.approx(2.0 * closed.horizontal, rel=tol.EXACT_REL)
        fi, mi = w.at(float(x))
        assert np.array_equal(fi[0], f[i]) and np.array_equal(mi[0], m[i])
    with pytest.raises(ValueError, match="at sample 1"):
        w.at([0.1, 2.0])


def test_k_h_from_acceleration():
    """k_h is the acceleration towards the soil over g, never negative; k_v = -a_z / g."""
    acc = np.array([[0.0, 2.0, -1.0], [0.0, -3.0, 0.5], [5.0, 0.0, 0.0]])
    kh, kv = ep_mod.k_h_from_acceleration(acc, "+y", g=10.0, vertical=True)
    assert kh == pytest.approx([0.2, 0.0, 0.0]) and kv == pytest.approx([0.1, -0.05, 0.0])
    kh, kv = ep_mod.k_h_from_acceleration(acc, "-y", g=10.0)
    assert kh == pytest.approx([0.0, 0.3, 0.0]) and np.all(kv == 0)


# -- a single retaining block ---------------------------------------------------------------------
B, HB, LB, RHO, G = 0.8, 1.0, 1.0, 2300.0, 9.81  # m, m, m, kg/m^3, m/s^2


def test_block_limits_by_hand():
    """Box 0.8 m x 1 m x 1 m of 2300 kg/m^3, soil to its top, phi = 30 deg, gamma = 18 kN/m^3.
    Smooth back: K_A = 1/3, P = 1/2 (1/3) 18000 1^2 = 3000 N at 1/3 m; W = 2300 9.81 0.8 =
    18050.4 N; sliding starts at mu = 3000 / 18050.4 = 0.166201; about the toe 3000 / 3 =
    1000 N m overturns and 18050.4 x 0.4 = 7220.16 N m restores.
    delta = 20 deg: P = 1/2 K_A 18000 (K_A = 0.297258 from the closed form), P_h = P cos 20,
    P_v = P sin 20 at the back (lever 0.8 m); with k_h = 0.1 the block's inertia 0.1 W acts
    at 0.5 m."""
    soil = EarthPressure(gamma=GAMMA, phi=R(30), z_top=HB, z_base=0.0)
    b = ep_mod.block_limits(B, HB, LB, RHO, soil, g=G)
    assert b.weight == pytest.approx(18050.4, rel=tol.EXACT_REL)
    assert b.thrust_h == pytest.approx(3000.0, rel=tol.EXACT_REL)
    assert b.thrust_height == pytest.approx(1 / 3, rel=tol.EXACT_REL)
    assert b.mu_slide == pytest.approx(3000.0 / 18050.4, rel=tol.EXACT_REL)
    assert b.overturning == pytest.approx(1000.0, rel=tol.EXACT_REL)
    assert b.restoring == pytest.approx(7220.16, rel=tol.EXACT_REL)
    assert b.overturning_ratio == pytest.approx(7.22016, rel=tol.EXACT_REL)

    soil = EarthPressure(gamma=GAMMA, phi=R(30), z_top=HB, z_base=0.0, delta=R(20))
    kh = 0.1
    b = ep_mod.block_limits(B, HB, LB, RHO, soil, k_h=kh, g=G)
    p = 0.5 * soil.kae(kh) * GAMMA
    static, inc = 0.5 * soil.ka * GAMMA, p - 0.5 * soil.ka * GAMMA
    ph, pv, w = p * math.cos(R(20)), p * math.sin(R(20)), 18050.4
    z = (static / 3 + inc * 0.6) / p
    assert b.thrust_h == pytest.approx(ph, rel=tol.EXACT_REL)
    assert b.thrust_v == pytest.approx(pv, rel=tol.EXACT_REL)
    assert b.mu_slide == pytest.approx((ph + kh * w) / (w + pv), rel=tol.EXACT_REL)
    assert b.overturning == pytest.approx(ph * z + kh * w * 0.5, rel=tol.EXACT_REL)
    assert b.restoring == pytest.approx(w * 0.4 + pv * 0.8, rel=tol.EXACT_REL)


def test_block_limits_match_the_integrated_loads():
    """The stone's integrated force and moment (about its centroid, moved to the toe) give the
    same sliding coefficient and toe moments as the hand calculation, with water, surcharge,
    friction and k_h, k_v."""
    soil = EarthPressure(gamma=GAMMA, phi=R(35), z_top=0.9, z_base=0.0, delta=R(22), surcharge=3e3,
                         water_level=0.3, gamma_sat=2e4)
    kh, kv = 0.15, 0.05
    box = _box(0.0, LB, -B, 0.0, 0.0, HB)
    w = ep_mod.wall_loads({1: [box]}, soil)
    f, m = w.at(kh, kv)
    f, m = f[0, 0], m[0, 0]
    weight = RHO * G * B * HB * LB
    c = w.centroids[0]
    toe = np.array([0.0, -B, 0.0])
    inertia = np.array([0.0, -kh * weight, 0.0])
    gravity = np.array([0.0, 0.0, -(1 - kv) * weight])
    m_toe = m + np.cross(c - toe, f + inertia + gravity)  # about the toe (the x axis through it)
    b = ep_mod.block_limits(B, HB, LB, RHO, soil, kh, kv, g=G)
    assert (-f[1] + kh * weight) / ((1 - kv) * weight - f[2]) == pytest.approx(b.mu_slide, rel=tol.EXACT_REL)
    # toppling about the toe turns the block's top towards -y: a positive moment about +x
    assert m_toe[0] == pytest.approx(b.overturning - b.restoring, rel=tol.EXACT_REL)


def test_block_critical_k_h():
    """With a vanishing soil weight the block alone slides at k_h = mu and topples at
    k_h = width / height; with soil, each returned k_h is where the margin changes sign."""
    light = EarthPressure(gamma=1e-9, phi=R(40), z_top=HB, z_base=0.0)
    slide, topple = ep_mod.block_critical_k_h(B, HB, LB, RHO, light, mu=0.5, g=G)
    assert slide == pytest.approx(0.5, rel=tol.NUMERICAL_REL)
    assert topple == pytest.approx(B / HB, rel=tol.NUMERICAL_REL)
    soil = EarthPressure(gamma=GAMMA, phi=R(40), z_top=HB, z_base=0.0, delta=R(20))
    slide, topple = ep_mod.block_critical_k_h(0.4, HB, LB, RHO, soil, mu=0.6, g=G)
    assert 0 < slide < ep_mod.max_k_h(R(40)) and 0 < topple < ep_mod.max_k_h(R(40))
    assert ep_mod.block_limits(0.4, HB, LB, RHO, soil, slide, g=G).mu_slide == pytest.approx(0.6, rel=tol.NUMERICAL_REL)
    b = ep_mod.block_limits(0.4, HB, LB, RHO, soil, topple, g=G)
    assert b.overturning_ratio == pytest.approx(1.0, rel=tol.NUMERICAL_REL)
    assert ep_mod.block_critical_k_h(0.4, HB, LB, RHO, soil, mu=0.1, g=G)[0] == 0.0
    assert ep_mod.block_critical_k_h(2.0, HB, LB, RHO, soil, mu=5.0, g=G) == (math.inf, math.inf)
