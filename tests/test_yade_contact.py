"""The penalty-Coulomb-damping law inside YADE, against closed forms (issue 2, §5).

Blocks: 0.4 x 0.4 x 0.04 m slabs (flat, so that the push, applied at the centroid, tilts
them by less than 1e-5 rad and the measured slip is the joint's), 2300 kg/m^3, on a rigid
platform with K_n = 2e8, K_t = 1e8 N/m^3.
"""
import json

import numpy as np
import pytest

import tolerances as tol
from conftest import requires_yade, run_case
from drystone.postprocess import summary as summ

pytestmark = [requires_yade, pytest.mark.yade]
G = 9.81
SLAB = [0.4, 0.4, 0.04]
MASS = 2300 * 0.4 * 0.4 * 0.04
W = MASS * G


DETECTION = "yade"  # set per test by the ``detection`` fixture


@pytest.fixture(params=["native", "yade"], autouse=True)
def detection(request):
    """Every test of the law runs with both contact geometries: the project's exact
    overlap kernel (native) and YADE's polyhedra intersection."""
    global DETECTION
    DETECTION = request.param
    return request.param


def case(boxes, stages, forces=(), law="penalty_coulomb", mu=0.7, damping=0.8, interval=0.01, contacts=()):
    contact = {"law": law}
    if law == "penalty_coulomb":
        contact["detection"] = DETECTION
    c = {"case": {"geometry": {"generator": "boxes_on_platform", "mu": mu, "damping": damping, "boxes": boxes}},
         "contact": contact, "stages": stages, "output": {"interval": interval, "contacts": list(contacts)}}
    if forces:
        c["forces"] = list(forces)
    return c


TWO = [{"id": 1, "center_xy": [0.0, 0.0], "size": SLAB}, {"id": 2, "center_xy": [0.6, 0.0], "size": SLAB}]
#: gravity ramped over 0.1 s and held to 0.15 s: the slabs' normal (235 Hz) and shear (166 Hz)
#: modes on the platform die out within a few hundredths of a second (the push tests' deflection,
#: drift and acceleration are those after 0.3 s of settling to 1e-14 of their tolerances)
SETTLE = [{"type": "gravity", "duration": 0.15, "ramp": 0.1}]
PUSH_T = 0.15


def disp(h, block):
    j = list(h["block_ids"]).index(block)
    return h["pos"][:, j] - h["pos0"][j]


#: the push tests' slabs, in one run per contact geometry (``pushed``): slab 1 pushed at 0.4 W
#: (below friction), slab 2 beside it unloaded, slab 3 in a row of its own pushed at 0.8 W
#: (above friction); the platform is fixed, so the slabs share nothing but the run
PUSHED = TWO + [{"id": 3, "center_xy": [0.0, 0.6], "size": SLAB}]
PUSHES = [{"block": 1, "force": [0.4 * W, 0.0, 0.0], "start": PUSH_T},
          {"block": 3, "force": [0.8 * W, 0.0, 0.0], "start": PUSH_T}]
#: the run ends this long after the pushes (s), at the end of the sticking slab's drift window
PUSHED_FOR = 0.5


@pytest.fixture(scope="module")
def pushed(tmp_path_factory):
    """(summary, histories, spec) of the pushes' run with the test's contact geometry, made
    once per geometry for the module's tests."""
    made = {}

    def get():
        if DETECTION not in made:
            made[DETECTION] = run_case(case(PUSHED, SETTLE + [{"type": "rest", "duration": PUSHED_FOR}], PUSHES),
                                       tmp_path_factory.mktemp(f"push_{DETECTION}"))
        return made[DETECTION]
    return get


def test_push_below_friction_sticks_elastically(pushed):
    """0.4 W with mu = 0.7: the block deflects by F / (K_t A) (elastic joint) and stops:
    drift between 0.25 s and 0.5 s after the push below 1e-7 m per 1.5 s; the unloaded
    neighbour moves < 1e-9 m (with YADE's stock law it creeps: test_stock_law_leaks_shear)."""
    F = 0.4 * W
    s, h, _ = pushed()
    t = h["t"]
    x = disp(h, 1)[:, 0]
    i1, i2 = np.searchsorted(t, PUSH_T + 0.25), len(t) - 1
    assert t[i2] == pytest.approx(PUSH_T + PUSHED_FOR, abs=0.5 * (t[1] - t[0]))
    assert abs(x[i2] - x[i1]) < tol.STICK_DRIFT_RATE_M_S * (t[i2] - t[i1])
    # elastic deflection F / (K_t A); 3 % covers the slab's tilt under the push (1.5 %)
    assert x[i2] == pytest.approx(F / (1e8 * 0.16), rel=tol.ELASTIC_DEFLECTION_REL)
    assert np.abs(disp(h, 2)[:, :2]).max() < tol.NEIGHBOUR_M  # horizontal: it only settles vertically


def test_push_above_friction_slides_with_coulomb_acceleration(pushed):
    """0.8 W with mu = 0.7: uniform acceleration (0.8 - 0.7) g, within 2 % (fitted over 0.3 s
    from 0.1 s after the push: 30 samples, 4.4 cm of slide)."""
    s, h, _ = pushed()
    t = h["t"]
    x = disp(h, 3)[:, 0]
    win = (t > PUSH_T + 0.1) & (t <= PUSH_T + 0.4 + 1e-9)
    assert win.sum() == 30
    a = 2 * np.polyfit(t[win], x[win], 2)[0]
    assert a == pytest.approx(0.1 * G, rel=tol.COULOMB_ACCELERATION_REL)


def test_stacked_blocks_penetrations(outdir):
    """Two stacked slabs: joint penetrations W/(K_n A) (top) and 2W/(K_n A) (bottom), 1 %
    (gravity ramped over 0.1 s, held 0.15 s more)."""
    boxes = [{"id": 1, "center_xy": [0.0, 0.0], "size": SLAB},
             {"id": 2, "center_xy": [0.0, 0.0], "size": SLAB, "z0": 0.04}]
    c = case(boxes, [{"type": "gravity", "duration": 0.25, "ramp": 0.1}],
             contacts=[{"name": "top", "blocks": [1, 2]}, {"name": "bottom", "blocks": [0, 1]}])
    s, h, spec = run_case(c, outdir)
    d0 = W / (2e8 * 0.16)
    assert summ.penetration(spec, h, "top")["penetration_1_2_m"] == pytest.approx(d0, rel=tol.STACK_PENETRATION_REL)
    assert summ.penetration(spec, h, "bottom")["penetration_0_1_m"] == pytest.approx(2 * d0, rel=tol.STACK_PENETRATION_REL)


def test_drop_comes_to_rest_and_energy_never_grows(outdir):
    """A slab dropped from 1 mm: kinetic + potential + elastic energy (recorded at the
    half step) never grows by more than 1e-3 of the drop energy, and the slab comes to
    rest at its static penetration (0.2 s: kinetic energy 3e-12 of the drop energy, 0.15 s
    is not enough). The step is 2e-5 s, 1/16 of the automatic one: at
    the automatic step the slab moves 45 um in the step it touches down, ten times its
    static penetration, and that first step alone adds ~10 % of the drop energy (the
    penalty force starts one step late: explicit integration, not the law)."""
    boxes = [{"id": 1, "center_xy": [0.0, 0.0], "size": SLAB, "z0": 0.001}]
    c = case(boxes, [{"type": "gravity", "duration": 0.2, "ramp": 0.0}], damping=0.08, interval=2e-4)
    c["time"] = {"step": 2e-5}
    s, h, _ = run_case(c, outdir)
    e = h["kinetic"] + h["potential"] + h["elastic"]
    scale = W * 0.001
    assert np.max(np.diff(e)) < tol.ENERGY_GROWTH * scale
    assert e[-1] < e[0]
    assert h["kinetic"][-1] < tol.AT_REST_ENERGY * scale
    z = disp(h, 1)[-1, 2]
    assert z == pytest.approx(-0.001 - W / (2e8 * 0.16), abs=tol.REST_POSITION_M)


LEAKY_YADE = "2023.02a"  # the YADE whose stock law shares one shear force between contacts


def test_stock_law_leaks_shear(outdir, detection):
    """Characterises YADE 2023.02a's stock law: its single running shear force, shared by
    all contacts, makes the unloaded neighbour creep when only block 1 is pushed below
    its friction limit (our law: < 1e-9 m, test above). A bug of that version: on any
    other (the run's run_info.json names the YADE that ran) the test is skipped, so a
    fixed YADE does not fail the suite."""
    if detection == "native":
        pytest.skip("the stock law has only YADE's contact geometry")
    F = 0.4 * W
    settle = [{"type": "gravity", "duration": 0.3, "ramp": 0.2}]
    s, h, _ = run_case(case(TWO, settle + [{"type": "rest", "duration": 1.0}],
                            [{"block": 1, "force": [F, 0.0, 0.0], "start": 0.5}], law="stock_volumetric",
                            damping=0.0), outdir)
    version = str(json.loads((outdir / "case" / "run_info.json").read_text())["yade_version"]).strip()
    if version != LEAKY_YADE:
        pytest.skip(f"documents a bug of YADE {LEAKY_YADE}'s stock law; this is YADE {version}")
    assert np.abs(disp(h, 2)[:, 0]).max() > tol.STOCK_LEAK_M
