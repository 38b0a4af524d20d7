"""Issue 24: the contact-law registry (drystone/mechanics/laws.py), the step engines' registry
(drystone/yade_scripts/engines.py) and the monitors (drystone/mechanics/monitors.py) that any engine
runs, with the stage types adding theirs. Plain Python: the monitors are driven with a
stand-in for the driver; the engines' histories are held bit for bit by test_regression.py
and test_yade_compiled.py."""
from __future__ import annotations

import ast
import math
import re
from types import SimpleNamespace

import numpy as np
import pytest

from drystone.model import case as casemod
from drystone.mechanics import laws, monitors, stability
from drystone import paths
from drystone.model.loading import LoadProgramme, Stage

MAT = {"density": 2300.0, "kn": 2e8, "kt": 1e8, "mu": 0.6, "damping": 0.8}


# -- contact laws ---------------------------------------------------------------------------
def test_every_law_is_complete_and_named_in_the_case_keys():
    assert set(casemod.SECTIONS["contact"]["law"].choices) == set(laws.REGISTRY)
    assert casemod.SECTIONS["contact"]["law"].default == laws.DEFAULT in laws.REGISTRY
    engines = _engine_names()
    for name, law in laws.REGISTRY.items():
        assert law.name == name and law.meaning and law.detections and law.engines
        assert law.default_detection == law.detections[0]
        assert set(law.engines) <= engines, (name, law.engines, engines)
        for det in law.detections:
            for requested in ("compiled", "python"):
                assert law.engine(requested, det) in law.engines


def _engine_names() -> set[str]:
    """The ``name`` of each engine class in engines.py (read without importing YADE)."""
    tree = ast.parse((paths.PACKAGE / "yade_scripts" / "engines.py").read_text())
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ClassDef):
            for st in node.body:
                if (isinstance(st, ast.Assign) and [getattr(t, "id", None) for t in st.targets] == ["name"]
                        and isinstance(st.value, ast.Constant) and st.value.value):
                    names.add(st.value.value)
    return names


def test_yade_material_mappings():
    """young = 2 K_n gives YADE's volumetric F_n = K_n V for both laws (pair stiffness
    young1 young2 / (young1 + young2)); the stock law's ks = K_n nu = K_t A_ref and its
    friction angle atan(mu); ours zeroes the stock shear (friction angle 0)."""
    ours = laws.get("penalty_coulomb").yade_material(MAT, 0.5)
    stock = laws.get("stock_volumetric").yade_material(MAT, 0.5)
    assert ours["young"] == stock["young"] == 2 * MAT["kn"]
    assert ours["frictionAngle"] == 0.0 and ours["poisson"] > 0
    assert stock["poisson"] * MAT["kn"] == pytest.approx(MAT["kt"] * 0.5)
    assert stock["frictionAngle"] == pytest.approx(math.atan(MAT["mu"]))


def test_engine_and_detection_choices():
    ours, stock = laws.get("penalty_coulomb"), laws.get("stock_volumetric")
    assert ours.engine("compiled", "native") == "compiled"
    assert ours.engine("python", "native") == ours.engine("compiled", "yade") == "python"
    assert stock.engine("compiled", "yade") == "yade" and stock.default_detection == "yade"
    area = laws.get("penalty_coulomb_area")  # the opt-in scaling of the carried shear force (docs/energy.md)
    assert area.area_scaling and not ours.area_scaling
    assert [area.engine(r, d) for r in ("compiled", "python") for d in ("native", "yade")] == \
        [ours.engine(r, d) for r in ("compiled", "python") for d in ("native", "yade")]
    assert area.yade_material(MAT, 0.5) == ours.yade_material(MAT, 0.5)
    with pytest.raises(KeyError, match="known: penalty_coulomb, penalty_coulomb_area, stock_volumetric"):
        laws.get("hertz")


def test_no_law_is_chosen_by_name_outside_the_registry():
    """'if law == ...' branches were spread over 7 modules; a law is now one class."""
    pattern = re.compile(r"""law(_name)?\s*[!=]=|[!=]=\s*["'](penalty_coulomb|stock_volumetric)["']""")
    offenders = [f"{p.relative_to(paths.ROOT)}:{k}" for p in paths.PACKAGE.rglob("*.py") if p.name != "laws.py"
                 for k, line in enumerate(p.read_text().splitlines(), 1) if pattern.search(line.split("#")[0])]
    assert not offenders, offenders


# -- monitors -------------------------------------------------------------------------------
def _run(pos, prog, mass=(1.0,), w_free=9.81):
    """A stand-in for the driver with free bodies 0..n-1 at ``pos`` (m)."""
    pos = np.asarray(pos, float).reshape(-1, 3)
    n = len(pos)
    return SimpleNamespace(spec_name="t", prog=prog, pos=pos, pos0=pos.copy(), vel=np.zeros((n, 3)),
                           angvel=np.zeros((n, 3)), quat=np.tile([0.0, 0.0, 0.0, 1.0], (n, 1)),
                           dyn=np.arange(n), mass=np.asarray(mass, float), bid={i: i + 1 for i in range(n)},
                           w_free=w_free, forces=[], g_integral=0.0, jump_dvs=[], stop_at=None, failure=None,
                           collapse=None, collapse_threshold={str(i + 1): 0.1 for i in range(n)},
                           z_floor=0.0, region=stability.ModelRegion.from_blocks([]),
                           fail=lambda msg: None)


def _sample(t, ke_b=(0.0,), reaction=(0.0, 0.0, -9.81)):
    ke_b = np.asarray(ke_b, float)
    return monitors.Sample(t, np.array([0.0, 0.0, -9.81]), float(ke_b.sum()), ke_b, 0.0, None, np.asarray(reaction))


def test_the_stage_types_add_their_monitors():
    prog = LoadProgramme([Stage("gravity", 0.0, 1.0, {"ramp": 0.5}),
                          Stage("tilt", 1.0, 2.0, {"rate_deg_s": 10.0, "towards": [0.0, 1.0, 0.0],
                                                   "until_collapse": True, "reaction_drop": 0.05,
                                                   "after_collapse": 0.5}),
                          Stage("rest", 2.0, 3.0, {"until_kinetic_below": 1e-3, "settle_window": 0.1})])
    run = _run([[0.0, 0.0, 0.1]], prog)
    assert prog.monitor(0, run) is None
    assert isinstance(prog.monitor(1, run), monitors.Collapse)
    settle = prog.monitor(2, run)
    assert isinstance(settle, monitors.Settle) and settle.cfg["threshold_J"] == 1e-3


def test_collapse_monitor_on_a_reaction_drop_and_only_in_its_stage():
    prog = LoadProgramme([Stage("gravity", 0.0, 1.0, {"ramp": 0.5}),
                          Stage("tilt", 1.0, 3.0, {"rate_deg_s": 10.0, "towards": [0.0, 1.0, 0.0],
                                                   "until_collapse": True, "reaction_drop": 0.05,
                                                   "after_collapse": 0.5})])
    run = _run([[0.0, 0.0, 0.1]], prog)
    m = monitors.Collapse(1, prog.stages[1].params)
    m.on_sample(run, _sample(0.5, reaction=(0.0, 0.0, 0.0)))  # the gravity stage: not looked at
    assert run.collapse is None
    m.on_sample(run, _sample(1.5))  # the full weight on the platform: standing
    assert run.collapse is None
    m.on_sample(run, _sample(2.0, reaction=(0.0, 0.0, -0.9 * 9.81)))  # 10 % of the weight gone
    assert run.collapse["criterion"] == "reaction_drop" and run.collapse["detected_time_s"] == 2.0
    assert run.collapse["detected_angle_deg"] == pytest.approx(10.0)
    assert run.stop_at == pytest.approx(2.5)


def test_settle_monitor_stops_after_the_window_below_the_threshold():
    prog = LoadProgramme([Stage("rest", 0.0, 5.0, {"until_kinetic_below": 1e-3, "settle_window": 0.2})])
    run = _run([[0.0, 0.0, 0.1]], prog)
    m = monitors.Settle(0, {"threshold_J": 1e-3, "window_s": 0.2}, 0.0, 5.0, run.z_floor, run.region)
    for t, ke in ((0.0, 1.0), (0.1, 5e-4), (0.2, 2e-3), (0.3, 5e-4), (0.4, 5e-4)):
        m.on_sample(run, _sample(t, [ke]))
        assert run.stop_at is None, t  # the window restarts at 0.3 s
    m.on_sample(run, _sample(0.5, [5e-4]))
    assert run.stop_at == 0.5 and m.cfg["reached"] and m.cfg["below_since_s"] == 0.3
