"""The earth pressure as a load type of the case files ([[loads]] type = "earth_pressure",
drystone/model/loads.py) and its application by the engines (docs/earth-pressure.md).

Without YADE: (a) the resolved loads of a plane vertical wall of stacked boxes (water table,
surcharge, wall friction) sum to the closed form's thrust at its height; the coefficients
follow the programme (gravity alone: K_A exactly; the gravity ramp scales them; a tilt
theta is Mononobe-Okabe's seismic angle theta); (e) refusals before any run: a record
scaled beyond the Mononobe-Okabe limit (naming phi, beta, k_h and the time), an unknown key
or type, a back plane that touches no stone.

With YADE: (a) a block retaining soil at rest carries the load into its base (the reaction
equals P_A, the recorded load's height H/3); (b) sliding and toppling 5 % on either side of
the hand calculation (``block_limits``); (c) under a base sine the applied force and its
height follow K_AE(k_h(t)) with the seismic increment at 0.6 H; (d) the energy balance
closes with the load's work (a sliding block, where the load's work is also checked against
its force times the slide; the shaken block in the compiled and python engines, which
agree); a tilt that reaches
the soil's limit before the wall collapses is a run failure.
"""
import copy
import math
import subprocess
import sys

import numpy as np
import pytest

import tolerances as tol
from conftest import requires_yade, run_case
from drystone.mechanics import earth_pressure as ep
from drystone.model import case as casemod
from drystone.model import loads as ld
from drystone.model.loading import LoadProgramme, Stage
from drystone.model.resolve import resolve
from drystone.model.stages import TOWARDS
from drystone.runner import RunError
from drystone.units import GRAVITY as G
from test_energy import balance, omega_max

GAMMA, PHI = 18000.0, 30.0  # N/m^3, deg
RHO = 2300.0  # kg/m^3 (boxes_on_platform's default)


def block_case(width=0.8, height=1.0, length=1.0, mu=0.6, damping=0.2, rest=0.3, **soil):
    """A box ``width`` (m, along +y, into the soil) x ``height`` x ``length`` on the platform,
    its back face at y = width / 2, dry soil to its top (``soil``: more [[loads]] keys)."""
    load = {"type": "earth_pressure", "phi_deg": PHI, "gamma": GAMMA, "into_soil": "+y", "back": width / 2,
            "z_top": height, **soil}
    return {"case": {"name": "block", "geometry": {
                "generator": "boxes_on_platform", "mu": mu, "damping": damping, "platform_size": [3.0, 3.0],
                "boxes": [{"id": 1, "center_xy": [0.0, 0.0], "size": [length, width, height]}]}},
            "loads": [load],
            "stages": [{"type": "gravity", "duration": 0.3, "ramp": 0.15}, {"type": "rest", "duration": rest}],
            "output": {"interval": 0.01}}


def soil_of(load: dict) -> ep.EarthPressure:
    """The soil of a resolved load ({type, params})."""
    return ld.soil_from_params(load["params"])


def resolved(case: dict, tmp_path):
    c = casemod.validate(copy.deepcopy(case), "case.toml", tmp_path)
    return resolve(c, "case.toml", tmp_path).to_dict()


# -- without YADE ------------------------------------------------------------------------

def test_resolved_loads_of_a_plane_wall_equal_the_closed_form(tmp_path):
    """Three courses of two 0.5 x 0.6 x 0.4 m boxes (1 m long, 1.2 m high, back at y = 0.3 m),
    soil to z = 1.1 m, delta = 20 deg, water at 0.5 m, surcharge 5 kPa: the stones' forces sum
    to P L along the face at delta (horizontal and vertical) and their moments put the
    horizontal thrust at the closed form's height (``plane_wall_resultant``)."""
    boxes = [{"id": 1 + 2 * k + j, "center_xy": [-0.25 + 0.5 * j, 0.0], "size": [0.5, 0.6, 0.4], "z0": 0.4 * k}
             for k in range(3) for j in range(2)]
    case = {"case": {"geometry": {"generator": "boxes_on_platform", "boxes": boxes}},
            "loads": [{"type": "earth_pressure", "phi_deg": 32.0, "delta_deg": 20.0, "gamma": GAMMA,
                       "gamma_sat": 20000.0, "back": 0.3, "z_top": 1.1, "water_level": 0.5, "surcharge": 5000.0}],
            "stages": [{"type": "gravity", "duration": 0.1}]}
    load = resolved(case, tmp_path)["loads"][0]
    soil = soil_of(load)
    assert soil.z_base == 0.0  # the default: the lowest back face
    load = load["params"]
    f = np.asarray(load["force_N"])  # (stones, field, 3)
    m = np.asarray(load["moment_Nm"])
    c = np.asarray(load["centroid_m"])
    assert sorted(load["blocks"]) == [1, 2, 3, 4, 5, 6]
    coef = np.array([soil.ka, 0.0, 1.0])  # gravity alone: static and water
    F = np.einsum("j,sjk->sk", coef, f)
    M = np.einsum("j,sjk->sk", coef, m) + np.cross(c, F)  # about the origin
    closed = ep.plane_wall_resultant(soil)
    L = 1.0
    assert -F[:, 1].sum() == pytest.approx(closed.horizontal * L, rel=tol.EXACT_REL)
    assert -F[:, 2].sum() == pytest.approx(closed.vertical * L, rel=tol.EXACT_REL)
    assert F[:, 0].sum() == pytest.approx(0.0, abs=tol.EXACT_REL * closed.horizontal)
    # M_x = sum (y F_z - z F_y): the vertical part acts on the plane y = back
    z_h = (M[:, 0].sum() - 0.3 * F[:, 2].sum()) / -F[:, 1].sum()
    assert z_h == pytest.approx(closed.height, rel=tol.EXACT_REL)


def _programme(stages, gravity=G):
    return LoadProgramme([Stage(*s) for s in stages], gravity)


def test_coefficients_follow_gravity_ramp_and_tilt():
    """Gravity alone: (K_A, 0, 1) exactly; half-way up the ramp: half of it; a platform tilted
    by theta towards the wall: k_h = sin theta, 1 - k_v = cos theta, so the wedge's seismic
    angle is theta and the thrust (1 - k_v) K_AE(theta); tilted away: k_h = 0."""
    params = {"soil": {"gamma": GAMMA, "phi": math.radians(PHI), "z_top": 1.0, "z_base": 0.0, "into_soil": "+y",
                       "back": 0.4}, "vertical": False, "start": 0.0, "end": None}
    soil = ld.soil_from_params(params)
    lt = ld.REGISTRY["earth_pressure"]
    prog = _programme([("gravity", 0.0, 1.0, {"ramp": 0.5}), ("rest", 1.0, 2.0, {})])
    c, bad, _ = lt.coefficients(params, ld.Field.of(prog, np.array([0.0, 0.25, 1.5])))
    assert bad is None
    assert c[2].tolist() == [soil.ka, 0.0, 1.0]
    assert c[1] == pytest.approx([0.5 * soil.ka, 0.0, 0.5], rel=tol.FEW_ULP_REL)
    assert c[0].tolist() == [0.0, 0.0, 0.0]
    theta = math.radians(12.0)
    for towards, k_h in (("-y", math.sin(theta)), ("+y", 0.0)):
        prog = _programme([("tilt", 0.0, 1.0, {"rate_deg_s": 12.0, "towards": TOWARDS[towards]})])
        c, bad, _ = lt.coefficients(params, ld.Field.of(prog, np.array([1.0])))
        kv = 1 - math.cos(theta)
        assert ep.seismic_angle(math.sin(theta), kv) == pytest.approx(theta, rel=tol.FEW_ULP_REL)
        assert c[0, 0] + c[0, 1] == pytest.approx((1 - kv) * soil.kae(k_h, kv), rel=tol.EXACT_REL)


def _refused(tmp_path, text: str) -> str:
    """Run ``text`` as a case file through the command line: refused (exit 2, one line, no
    traceback, nothing written); its message."""
    (tmp_path / "c.toml").write_text(text)
    r = subprocess.run([sys.executable, "-m", "drystone", "run", "c.toml", "--out", "out"], cwd=tmp_path,
                       capture_output=True, text=True)
    assert r.returncode == 2, r.stderr
    assert r.stderr.strip().count("\n") == 0 and "Traceback" not in r.stderr
    assert not (tmp_path / "out").exists()
    return r.stderr


GEOMETRY = ('[case]\ngeometry = { generator = "boxes_on_platform", boxes = [{ id = 1, center_xy = [0.0, 0.0], '
            'size = [1.0, 0.8, 1.0] }] }\n')


def test_refused_before_the_run(tmp_path):
    """A sine whose peak k_h = 0.8 g / g exceeds tan(phi - beta) = tan(30 deg) = 0.577 is
    refused before the run, naming phi, beta, k_h and the time of the first such instant
    (sin(2 pi 2 t) = 0.577 / 0.8 + ...); an unknown key is refused naming it."""
    load = '[[loads]]\ntype = "earth_pressure"\nphi_deg = 30.0\ngamma = 18000.0\nback = 0.4\nz_top = 1.0\n'
    shake = ('[[stages]]\ntype = "gravity"\nduration = 0.1\n[[stages]]\ntype = "excitation"\nmotion = "sine"\n'
             'frequency_hz = 2.0\namplitude = 7.848\nduration = 0.5\ndirection = "y"\n')
    msg = _refused(tmp_path, GEOMETRY + load + shake)
    assert "Mononobe-Okabe has no solution" in msg
    assert "phi = 30 deg" in msg and "beta = 0 deg" in msg and "k_h = " in msg and "at t = " in msg
    t = float(msg.split("at t = ")[1].split(" s")[0])
    a = 7.848 * abs(math.sin(2 * math.pi * 2.0 * (t - 0.1)))
    assert a / G >= math.tan(math.radians(30.0)) - 1e-3  # the instant named is past the limit
    msg = _refused(tmp_path, GEOMETRY + load + "phi = 30.0\n" + shake)
    assert "[[loads]] #1" in msg and "unknown key(s) ['phi']" in msg


def test_refused_cases_name_the_problem(tmp_path):
    """A back plane 5 cm behind the block's back face; an unknown type; a backfill steeper
    than phi (no static wedge)."""
    base = {"case": {"geometry": {"generator": "boxes_on_platform", "boxes": [
        {"id": 1, "center_xy": [0.0, 0.0], "size": [1.0, 0.8, 1.0]}]}},
        "stages": [{"type": "gravity", "duration": 0.1}]}
    load = {"type": "earth_pressure", "phi_deg": 30.0, "gamma": GAMMA, "back": 0.45, "z_top": 1.0}
    with pytest.raises(casemod.CaseError, match=r"no free stone has a face on the back plane .*back = 0.45 m"):
        resolved({**base, "loads": [load]}, tmp_path)
    with pytest.raises(casemod.CaseError, match="unknown load type 'soil'"):
        casemod.validate({**base, "loads": [{"type": "soil"}]}, "c.toml", tmp_path)
    with pytest.raises(casemod.CaseError, match=r"phi - beta = .* < 0"):
        casemod.validate({**base, "loads": [dict(load, beta_deg=35.0)]}, "c.toml", tmp_path)


# -- with YADE -----------------------------------------------------------------------------

def _moved(h) -> float:
    """Largest displacement of the block's centroid from its start (m)."""
    return float(np.linalg.norm(h["pos"][:, 0] - h["pos"][0, 0], axis=1).max())


@requires_yade
@pytest.mark.yade
def test_block_at_rest_carries_the_active_thrust(outdir):
    """The example case (a 0.8 x 1 x 1 m block, phi = 30 deg, H = 1 m): at rest the platform
    carries P_A = 1/2 K_A gamma H^2 L = 3000 N horizontally and W; the recorded load's
    resultant acts at H / 3."""
    s, h, spec = run_case(block_case(), outdir)
    soil = soil_of(spec["loads"][0])
    pa = ep.plane_wall_resultant(soil).horizontal * 1.0
    assert pa == pytest.approx(3000.0, rel=tol.EXACT_REL)
    assert h["load_force"][-1] == pytest.approx([0.0, -pa, 0.0], abs=tol.EXACT_REL * pa)
    assert h["load_moment"][-1, 0] / -h["load_force"][-1, 1] == pytest.approx(1.0 / 3.0, rel=tol.EXACT_REL)
    assert h["reaction"][-1, 1] == pytest.approx(-pa, rel=tol.RESTING_REACTION_REL)
    w = RHO * 0.8 * G
    assert h["reaction"][-1, 2] == pytest.approx(-w, rel=tol.RESTING_REACTION_REL)
    assert _moved(h) < tol.PUSH_STAYED_M


def _slide_work(h, spec):
    """(d) The sliding block's energy balance closes (within leapfrog's bound) and, over the
    rest stage (constant loads), the loads' work is that of gravity and the earth pressure's
    constant wrench over the centred displacement: W = (m g + F) . dx + M . dtheta, x and
    theta at the half steps the recorder holds (x - v dt / 2; small rotations: theta = 2 q).
    The earth pressure does ~100 J of it, against a bound of 1 J."""
    b = balance(h)
    bound = tol.BALANCE_SHADOW * (omega_max((1.0, 0.8, 1.0)) * spec["dt"]) ** 2 * float(h["kinetic"].max())
    assert np.abs(b).max() <= bound
    dt = spec["dt"]
    k0 = int(np.searchsorted(h["t"], 0.3 + 1e-9))  # the rest stage (gravity held, load constant)
    x = h["pos"][:, 0] - 0.5 * dt * h["vel"][:, 0]
    th = 2.0 * h["quat"][:, 0, :3] - 0.5 * dt * h["angvel"][:, 0]
    m = float(h["mass"][0])
    F, M = h["load_force"][-1], h["load_moment"][-1] - np.cross(h["pos0"][0], h["load_force"][-1])
    earth = F @ (x[-1] - x[k0]) + M @ (th[-1] - th[k0])
    gravity = m * h["g_eff"][-1] @ (x[-1] - x[k0])
    assert earth > 100 * bound
    assert h["work_loads"][-1] - h["work_loads"][k0] == pytest.approx(gravity + earth, rel=tol.SLIDE_WORK_REL)


@requires_yade
@pytest.mark.yade
def test_sliding_and_toppling_around_the_hand_calculation(outdir):
    """mu 5 % above ``block_limits``' sliding limit (0.1662): the block stays (elastic
    deflection); 5 % below: it slides. A slender block (0.298 m for 1 m of soil) 5 % wider
    than the toppling limit (restoring = overturning moment about the toe) stays, 5 % narrower
    topples (mu = 0.9: no sliding). The toppling runs take K_n = 2e10 N/m^3: near the limit
    the joint's resultant is 1.5 cm from the toe, carried by a 2 cm strip of the penalty
    joint, which sinks 2 W / (K_n c L) there: at the default 2e8 N/m^3 that is a rotation of
    8 deg, whose lean of the centroid (0.07 m) is more than the 5 % margin (7 mm); at 2e10
    N/m^3, 0.08 deg and 0.7 mm."""
    soil = ep.EarthPressure(gamma=GAMMA, phi=math.radians(PHI), z_top=1.0, z_base=0.0, back=0.4)
    mu = ep.block_limits(0.8, 1.0, 1.0, RHO, soil).mu_slide
    for factor, moves in ((1.05, False), (0.95, True)):
        _, h, spec = run_case(block_case(mu=mu * factor, damping=0.0, rest=0.7), outdir, f"slide_{factor}")
        assert (_moved(h) > tol.PUSH_MOVED_M) if moves else (_moved(h) < tol.PUSH_STAYED_M), (factor, _moved(h))
    _slide_work(h, spec)
    from scipy.optimize import brentq

    def margin(b):
        lim = ep.block_limits(b, 1.0, 1.0, RHO, soil)
        return lim.restoring - lim.overturning

    b0 = brentq(margin, 0.1, 0.8, xtol=1e-12)
    for factor, topples in ((1.05, False), (0.95, True)):
        b = b0 * factor
        case = block_case(width=b, mu=0.9, damping=0.0, rest=1.0)
        case["case"]["geometry"].update(kn=2e10, kt=1e10)
        _, h, _ = run_case(case, outdir, f"topple_{factor}")
        assert (_moved(h) > tol.PUSH_MOVED_M) if topples else (_moved(h) < tol.PUSH_STAYED_M), (factor, _moved(h))


@requires_yade
@pytest.mark.yade
def test_seismic_thrust_follows_the_base_acceleration_and_the_balance_closes(outdir):
    """A 2 Hz base sine of 1 m/s^2 along the wall's normal: at every sample the applied force
    is (1 - k_v) K_AE(k_h) 1/2 gamma H^2 L with k_h = max(0, a . e_h) / g from the recorded
    base acceleration, at the height (P_A H/3 + dP 0.6 H) / P_AE (``plane_wall_resultant``);
    the energy balance, with the load's work, stays within leapfrog's bound (a stronger
    shaking lifts the block's heel, where the normal spring's energy estimate leaves that
    bound for any eccentric push, an applied [[forces]] too: 2.1 J against 0.9 J measured
    for 3000 N at the centroid under 2 m/s^2); the python engine (YADE's integrator,
    O.forces.addF/addT) gives the same run."""
    case = block_case(mu=0.6, damping=0.0, rest=0.1)
    case["stages"].insert(1, {"type": "excitation", "motion": "sine", "frequency_hz": 2.0, "amplitude": 1.0,
                              "duration": 0.6, "direction": "y"})
    _, h, spec = run_case(case, outdir, "shake")
    soil = soil_of(spec["loads"][0])
    k_h, k_v = ep.k_h_from_acceleration(h["base_acc"], "+y")
    assert k_h.max() > 0.1 - 1e-3 and soil.kae(k_h.max()) > 1.15 * soil.ka
    after = h["t"] >= 0.3 - 1e-9  # gravity full
    for k in np.flatnonzero(after):
        closed = ep.plane_wall_resultant(soil, k_h[k], k_v[k])
        assert -h["load_force"][k, 1] == pytest.approx(closed.horizontal, rel=tol.EXACT_REL)
        assert h["load_moment"][k, 0] / -h["load_force"][k, 1] == pytest.approx(closed.height, rel=tol.EXACT_REL)
    b = balance(h)
    bound = tol.BALANCE_SHADOW * (omega_max((1.0, 0.8, 1.0)) * spec["dt"]) ** 2 * float(h["kinetic"].max())
    assert np.abs(b).max() <= bound
    from drystone import runner
    from drystone.postprocess import summary as summ

    runner.run_dict(case, outdir / "shake_py.toml", out_dir=outdir / "shake_py", quiet=True, engine="python")
    hp = summ.load_histories(outdir / "shake_py")
    np.testing.assert_allclose(hp["pos"], h["pos"], rtol=0, atol=tol.ENGINE_AGREEMENT_M)
    np.testing.assert_allclose(hp["work_loads"], h["work_loads"], rtol=0,
                               atol=tol.ENGINE_WORK_REL * np.abs(h["work_loads"]).max())


@requires_yade
@pytest.mark.yade
def test_tilt_reaching_the_soil_limit_before_collapse_fails(outdir):
    """A wide block (it would slide only at atan(0.9) = 42 deg) tilted towards the wall until
    collapse, soil phi = 20 deg: the soil's limit theta = phi comes first: the run stops with
    a failure naming it, no results."""
    case = block_case(mu=0.9, phi_deg=20.0)
    case["stages"][1] = {"type": "tilt", "rate_deg_s": 40.0, "until_collapse": True, "max_deg": 45.0,
                         "towards": "-y"}
    with pytest.raises(RunError, match=r"Mononobe-Okabe has no solution.*before the wall collapsed"):
        run_case(case, outdir, "tilt")
    assert not (outdir / "tilt").exists()
