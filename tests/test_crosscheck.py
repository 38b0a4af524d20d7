"""The LMGC90 cross-check (issue 15, item 2; drystone/studies/crosscheck/).

Without YADE and without LMGC90: the translator (block file -> LMGC90 model) keeps every
block's volume, mass, centroid and inertia and winds its triangles outwards; it refuses
what the model cannot carry; the rigid closed forms agree with the independent reference
of tests/reference.py. With compas_lmgc90 (skipped, saying why, where it is not
importable): LMGC90 itself against the closed forms, on the toppling block and the
half-sine pulse (about 30 s), and the masses and centres of inertia LMGC90 builds from the
translated model.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import tolerances as tol
from reference import sliding_block
from drystone.studies.crosscheck import cases, closed_forms as cf, lmgc90_status, translate
from drystone.geometry import blockfile as bf
from drystone.geometry import polyhedron as ph
from drystone.geometry.generators import generate

LMGC90_OK, LMGC90_WHY = lmgc90_status()
requires_lmgc90 = pytest.mark.skipif(not LMGC90_OK, reason=f"crosscheck skipped: {LMGC90_WHY}")


def _parsed(d: dict) -> bf.BlockSet:
    return bf.parse(d, "test", check_overlaps=False)


# -- translator -------------------------------------------------------------------------
def test_translation_keeps_volume_mass_centroid_and_winds_outwards():
    """Boxes (running-bond wall) and irregular stones with leaning joints and varying depth
    (a Santa-Cruz tilt wall): the triangles' volume and centroid equal the hull's
    (polyhedron.volume_centroid, an independent decomposition), mass = density x volume,
    every triangle's normal points away from the centroid, the local vertices are centred
    on it. Tolerance NUMERICAL_REL: two sums over ~20 triangles of hull coordinates."""
    for data in (generate({"generator": "running_bond"}), generate({"generator": "tilt_wall", "seed": 0})):
        bs = _parsed(data)
        model = translate.to_lmgc90(bs)
        assert len(model["bodies"]) == len(bs.blocks)
        for b, body in zip(bs.blocks, model["bodies"]):
            vol, cen = ph.volume_centroid(b.vertices)
            assert body["volume"] == pytest.approx(vol, rel=tol.NUMERICAL_REL)
            assert body["mass"] == pytest.approx(bs.mass(b.id), rel=tol.NUMERICAL_REL)
            assert np.allclose(body["centroid"], cen, rtol=0, atol=tol.NUMERICAL_ABS)
            v = np.array(body["vertices"])
            t = np.array(body["triangles"])
            assert np.allclose(v + body["centroid"], b.vertices, rtol=0, atol=tol.NUMERICAL_ABS)
            n = np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]])
            assert np.all(np.einsum("ij,ij->i", n, v[t[:, 0]]) > 0)  # outward: the centroid is the origin
            assert body["imposed"] == (b.role != "free")
        assert model["mu"] == pytest.approx(0.4)
        assert model["law"] == "IQS_CLB" and model["restitution"] == 0.0


def test_translation_inertia_of_a_box():
    """A 0.2 x 0.4 x 0.6 m box of 2300 kg/m^3: I = m (b^2 + c^2) / 12 about each axis, no
    products (exact up to round-off)."""
    v = np.array(bf.box_vertices((1.0, 2.0, 3.0), (0.2, 0.4, 0.6)))
    p = translate.mass_properties(v, translate.outward_triangles(v), 2300.0)
    m = 2300.0 * 0.048
    expected = np.diag([m * (0.16 + 0.36), m * (0.04 + 0.36), m * (0.04 + 0.16)]) / 12
    assert p["mass"] == pytest.approx(m, rel=tol.EXACT_REL)
    assert np.allclose(p["centroid"], [1.0, 2.0, 3.0], rtol=0, atol=tol.EXACT_ABS)
    assert np.allclose(p["inertia"], expected, rtol=0, atol=tol.EXACT_REL * m)


def test_translation_takes_overrides_and_refuses_what_lmgc90_cannot_carry():
    """A case's material overrides (spec materials) set mu and density; two contact
    friction coefficients (two materials, or a joint) are refused, not averaged (one
    contact law in compas_lmgc90 0.1.11); blocked dofs are refused."""
    d = generate({"generator": "boxes_on_platform", "mu": 0.5,
                  "boxes": [{"id": 1, "center_xy": [0, 0], "size": [0.2, 0.2, 0.2]}]})
    bs = _parsed(d)
    over = {"stone": dict(density=2000.0, kn=1e9, kt=5e8, mu=0.3, damping=0.0)}
    m = translate.to_lmgc90(bs, over)
    assert m["mu"] == 0.3 and m["bodies"][1]["density"] == 2000.0
    d2 = dict(d, materials=dict(d["materials"], soft=dict(d["materials"]["stone"], mu=0.6)))
    d2["blocks"] = [dict(d["blocks"][0], material="soft"), d["blocks"][1]]
    assert translate.contact_friction(_parsed(d2)) == 0.5  # the pair takes the smaller mu: one value
    d3 = dict(d2, blocks=d2["blocks"] + [{"id": 2, "role": "free", "material": "soft",
                                         "vertices": bf.box_vertices((0.5, 0, 0.1), (0.2, 0.2, 0.2))}])
    with pytest.raises(translate.TranslationError, match="different friction"):
        translate.to_lmgc90(_parsed(d3))  # block 2 on the platform: mu 0.6, block 1: 0.5
    d4 = dict(d, joints=[{"blocks": [1, 0], "mu": 0.9}])
    with pytest.raises(translate.TranslationError, match="joint 0-1"):
        translate.to_lmgc90(_parsed(d4))
    d5 = dict(d, blocks=[d["blocks"][0], dict(d["blocks"][1], blocked_dofs="z")])
    with pytest.raises(translate.TranslationError, match="blocked_dofs"):
        translate.to_lmgc90(_parsed(d5))


# -- closed forms -----------------------------------------------------------------------
@pytest.mark.parametrize("amp, dur, mu", [(0.6 * 9.81, 0.5, 0.4), (5.0, 0.5, 0.4), (8.0, 0.2, 0.3)])
def test_half_sine_closed_form_against_the_reference_integration(amp, dur, mu):
    """The closed-form slide equals tests/reference.py's explicit integration (step 1e-5 s:
    its error is one step's slide at the start and stop, < v dt ~ 5e-6 m, and the
    trapezoid's O(dt^2)); ``rigid_plastic_slide`` (midpoint, located stops) on the
    continuous pulse agrees to its O(dt^2) = 1e-10 m."""
    a_b = lambda t: -amp * math.sin(math.pi * t / dur) if t <= dur else 0.0  # noqa: E731
    closed = cf.half_sine_slide(amp, dur, mu)
    t = np.linspace(0.0, 1.5, 301)
    ref = sliding_block(a_b, t, mu, dt=1e-5)
    assert closed["slide_m"] > 0.02  # it really slides
    assert closed["slide_m"] == pytest.approx(ref[-1], abs=tol.REFERENCE_SLIDE_M)
    assert cf.rigid_plastic_slide(a_b, 1.5, mu)["slide_m"] == pytest.approx(closed["slide_m"],
                                                                          abs=tol.RIGID_PLASTIC_SLIDE_M)
    assert cf.half_sine_slide(mu * 9.81 * 0.99, dur, mu)["slide_m"] == 0.0  # below mu g: no slide


def test_rigid_rocking_onset_is_atan_b_over_h_plus_the_rules_lag():
    """The rigid rocking equation under the toppling case's programme, read with the
    package's onset rule: the block does not move below atan(b/h) (phi stays 0 while the
    moment holds it down), and the rule dates the onset after it, by less than 0.2 deg
    (the run-away at 0.5 deg/s reaches 5 mm/deg within ~0.25 s: 0.11 deg measured)."""
    from drystone.studies.crosscheck import lmgc90
    from drystone.model.loading import LoadProgramme
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as d:
        spec, _ = lmgc90.prepare(cases.toppling_case(), Path(d))
    prog = LoadProgramme.from_spec(spec)
    _, b, h = cases.TOPPLE_SIZE
    hist = cf.rocking_history(b, h, prog, [0, 1, 0], spec["stages"][-1]["end"], 0.01, dt=5e-4)
    still = hist["tilt_deg"] < cf.toppling_deg(b, h) - tol.ROCKING_STILL_MARGIN_DEG
    assert np.all(hist["phi"][still] == 0.0)
    on = cf.rocking_onset_deg(b, h, prog, [0, 1, 0], spec["stages"][-1]["end"], 0.01, dt=5e-4)
    assert cf.toppling_deg(b, h) < on < cf.toppling_deg(b, h) + tol.ROCKING_RULE_LAG_DEG


def test_availability_message_names_package_version_and_install(monkeypatch):
    """Where compas_lmgc90 is missing the message says which package, which version and how
    to install it (make crosscheck prints it as its 'skipped' line)."""
    import importlib.util

    import drystone.studies.crosscheck as xc

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == xc.PACKAGE else real(name, *a))
    ok, msg = xc.lmgc90_status()
    assert not ok
    assert "compas_lmgc90 0.1.11" in msg and "requirements-crosscheck.txt" in msg and "pip install" in msg


# -- LMGC90 -----------------------------------------------------------------------------
@requires_lmgc90
def test_lmgc90_builds_the_translated_masses_and_centres(tmp_path):
    """An irregular stone (a square pyramid: its centroid is at h/4, its vertices' mean at
    h/5) resting on the platform: LMGC90's centre of inertia is the translator's centroid
    and, at rest, the platform carries the stone's weight. Tolerances: the centre to
    round-off of LMGC90's own volume integration (1e-9 m); the weight to LMGC90's
    Gauss-Seidel tolerance, fixed at 1.666e-4 (relative, quadratic mean) inside
    compas_lmgc90: 1e-3."""
    from drystone.studies.crosscheck import lmgc90

    pyr = [[-0.2, -0.2, 0.0], [0.2, -0.2, 0.0], [0.2, 0.2, 0.0], [-0.2, 0.2, 0.0], [0.05, 0.0, 0.6]]
    geo = {"format": bf.FORMAT, "version": 1, "name": "pyramid", "units": {"length": "m", "mass": "kg"},
           "materials": {"stone": {"density": 2300.0, "kn": 2e8, "kt": 1e8, "mu": 0.6, "damping": 0.8}},
           "blocks": [{"id": 0, "role": "platform", "material": "stone",
                       "vertices": bf.box_vertices((0, 0, -0.05), (2, 2, 0.1))},
                      {"id": 1, "role": "free", "material": "stone", "vertices": pyr}]}
    bf.write(geo, tmp_path / "pyramid.json")
    case = {"case": {"name": "pyramid", "geometry": str(tmp_path / "pyramid.json")},
            "stages": [{"type": "gravity", "duration": 0.2, "ramp": 0.05}], "output": {"interval": 0.01}}
    r = lmgc90.run(case, tmp_path / "run", dt=1e-3)
    vol, cen = ph.volume_centroid(np.array(pyr))
    assert cen[2] == pytest.approx(0.15, abs=tol.NUMERICAL_ABS)
    assert np.allclose(r["result"]["initial_centres"][1], cen, rtol=0, atol=tol.NUMERICAL_ABS)
    w = 2300.0 * vol * 9.81
    assert r["histories"]["reaction_N"][-1] == pytest.approx(w, rel=tol.LMGC90_REACTION_REL)
    assert np.abs(r["histories"]["pos"][-1, 0] - r["histories"]["pos"][0, 0]).max() < tol.LMGC90_AT_REST_M  # at rest


@requires_lmgc90
def test_lmgc90_toppling_block_matches_the_rigid_closed_form(tmp_path):
    """The toppling case (0.2 x 0.4 m block, mu 0.7, tilt 0.5 deg/s past 22 deg): LMGC90's
    collapse angle, read with the package's rule, equals the rigid rocking equation's read
    the same way. Tolerance 0.01 deg = two samples of the rule (0.01 s at 0.5 deg/s: 0.005
    deg each): LMGC90 (rigid, like the equation) differs from it only by its time step
    (1e-3 s, 5e-4 deg of tilt; the run-away's rate 5.7/s is integrated to (5.7 dt)^2 ~
    3e-5 relative), far below one sample. And it is atan(b/h) = 26.565 deg plus the rule's
    lag (< 0.2 deg, test above)."""
    from drystone.studies.crosscheck import lmgc90

    r = lmgc90.run(cases.toppling_case(), tmp_path, dt=1e-3)
    on = lmgc90.onset_angle(r)
    ref = cases.toppling_closed_forms(r["spec"], [])
    assert on is not None and on["onset_block"] == 1
    assert on["angle_deg"] == pytest.approx(ref["rigid_with_rule_deg"], abs=tol.LMGC90_ONSET_DEG)
    assert ref["rigid_deg"] < on["angle_deg"] < ref["rigid_deg"] + tol.ROCKING_RULE_LAG_DEG
    assert r["result"]["collapse"]["detected_angle_deg"] > on["angle_deg"]  # it fell after the onset


@requires_lmgc90
def test_lmgc90_half_sine_pulse_matches_the_rigid_plastic_slide(tmp_path):
    """The half-sine pulse (A = 0.6 g, T = 0.5 s, mu 0.4) on a moving base in LMGC90: the
    slide equals the rigid-plastic slide under the same (sampled) pulse. Tolerance
    2 (A + mu g) dt^2 = 2e-5 m: the Moreau-Jean step dates the start and the stop of the
    slide within one step, at zero relative velocity, so each shifts the slide by at most
    the relative acceleration times dt^2; between them the theta = 0.5 step is exact for a
    piecewise-linear base velocity. The continuous pulse's closed form is 0.34 mm longer
    (the samples' chords lie inside the sine): both are reported."""
    from drystone.studies.crosscheck import lmgc90

    dt = 1e-3
    r = lmgc90.run(cases.pulse_case(), tmp_path, dt=dt, base="moving")
    u = cases.slide_m(r["histories"], r["spec"])
    ref = cases.pulse_closed_forms(r["spec"], [], r["folder"])
    sampled = ref["rigid_plastic_as_sampled"]["slide_m"]
    assert u > 0.05  # it really slides
    assert u == pytest.approx(sampled, abs=2 * (cases.PULSE_A + cases.PULSE_MU * 9.81) * dt ** 2)
    assert ref["rigid_plastic"]["slide_m"] - sampled == pytest.approx(tol.PULSE_SAMPLING_DEFICIT_M,
                                                                      abs=tol.PULSE_SAMPLING_DEFICIT_ABS)
    # after the pulse the block rides with the base: the last samples do not move
    h = r["histories"]
    assert abs(h["pos"][-1, 0, 1] - h["pos"][-20, 0, 1]) < tol.LMGC90_RIDING_M


def test_package_only_rerun_keeps_lmgc90_and_the_other_stiffnesses(tmp_path, monkeypatch):
    """``run_case(lmgc90_side=False)`` adds package runs at new K_n to a case already run:
    LMGC90's entry and the package runs at the other K_n stay, sorted by K_n; without an
    LMGC90 run recorded it refuses, naming the case."""
    from drystone.studies.crosscheck import study

    def fake_package(cc, folder, kn, variant=None, log=print):
        return {"kn": kn, "value": 10.0 + math.log10(kn), "folder": str(folder)}

    monkeypatch.setattr(study, "run_package", fake_package)
    with pytest.raises(ValueError, match="tilt_wall_0: no LMGC90 run"):
        study.run_case("tilt_wall", tmp_path, kn_factors=[10.0], variants=(0,), lmgc90_side=False, log=lambda m: None)
    data = study.load(tmp_path)
    data["cases"]["tilt_wall_0"] = {"lmgc90": {"value": 19.0}, "closed_forms": {"experiment_deg": 14.33},
                                    "package": [{"kn": 2e8, "value": 14.8}, {"kn": 2e10, "value": 18.0}]}
    study.save(data, tmp_path)
    study.run_case("tilt_wall", tmp_path, kn_factors=[10.0], variants=(0,), lmgc90_side=False, log=lambda m: None)
    e = study.load(tmp_path)["cases"]["tilt_wall_0"]
    assert e["lmgc90"] == {"value": 19.0} and e["closed_forms"] == {"experiment_deg": 14.33}
    assert [p["kn"] for p in e["package"]] == [2e8, 2e9, 2e10]
    assert [p["value"] for p in e["package"]] == [14.8, pytest.approx(10.0 + math.log10(2e9)), 18.0]


def test_base_velocity_integrates_the_programmes_base_acceleration():
    """LMGC90's moving base gets v(t) from the programme's base acceleration by the
    trapezoid rule, exact for a piecewise-linear record sampled on the grid: samples
    0, 1, 2, 2 m/s^2 every 0.5 s give v = t^2 over the first second, then 1 + 2 (t - 1)."""
    from drystone.studies.crosscheck.engine import base_velocity
    from drystone.model.loading import LoadProgramme, Stage

    prog = LoadProgramme([Stage("gravity", 0.0, 1.0, {"ramp": 0.5}),
                          Stage("excitation", 1.0, 2.5, {"acc": np.array([0.0, 1.0, 2.0, 2.0]), "dt": 0.5,
                                                         "direction": [0, 1, 0]})], 9.81)
    t = np.linspace(1.0, 2.5, 61)[:-1]  # the stage's own times (its last time belongs to no stage)
    v = base_velocity(prog, t)
    s = t - 1.0
    expected = np.where(s <= 1.0, s ** 2, 1.0 + 2.0 * (s - 1.0))
    assert np.allclose(v[:, 1], expected, rtol=0, atol=tol.EXACT_ABS) and not v[:, [0, 2]].any()
