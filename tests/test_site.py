"""Site response (drystone/motions/site.py, pystrata's equivalent-linear calculator) against
closed forms of a uniform layer; the example Sacsayhuaman profile against its targets; the
excitation stage's ``site`` option and its refusals. No YADE."""
from __future__ import annotations

import hashlib
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import tolerances as tol
from drystone import paths
from drystone.model import case as casemod
from drystone.model.keys import CaseError
from drystone.motions import excitation, site
from drystone.motions.record import Record

EXAMPLE = paths.ROOT / "data" / "site" / "sacsayhuaman.toml"
H, VS, GAMMA, XI = 20.0, 200.0, 18.0, 0.05  # m, m/s, kN/m^3, -: the test layer
VR, GAMMA_R, XI_R = 600.0, 22.0, 0.01  # the elastic half-space


def _profile(tmp_path: Path, bedrock: str, xi: float = XI, name: str = "p.toml", xi_r: float = XI_R
             ) -> site.SiteProfile:
    rock = ('bedrock = "rigid"' if bedrock == "rigid" else
            f"bedrock = {{ vs_m_s = {VR}, unit_weight_kn_m3 = {GAMMA_R}, damping = {xi_r} }}")
    p = tmp_path / name
    p.write_text(f"{rock}\n[[layers]]\nthickness_m = {H}\nvs_m_s = {VS}\nunit_weight_kn_m3 = {GAMMA}\n"
                 f"damping = {xi}\ncurves = \"linear\"\n")
    return site.read_profile(p)


def _vs_complex(vs: float, xi: float) -> complex:
    """pystrata's complex velocity: G* = G (sqrt(1 - 4 xi^2) + 2 i xi) (Dormieux and Canou)."""
    return vs * np.sqrt(np.sqrt(1 - 4 * xi ** 2) + 2j * xi)


F = np.linspace(0.01, 20.0, 4001)  # Hz


def test_uniform_layer_on_rigid_rock_is_the_closed_form(tmp_path):
    """|H(f)| = 1/|cos(k* H)|, k* = w / Vs*: pystrata's surface / base transfer function is
    the closed form to round-off (the same complex modulus; no discretisation: a layer is
    exact in the wave solution, so the tolerance is round-off, tol.NUMERICAL_REL). Its peak
    lies at Vs/4H = 2.5 Hz within xi^2 (the damped peak moves by O(xi^2): measured -1.3e-3,
    0.5 xi^2). The usual approximation k* = w/(Vs (1 + i xi)) differs from pystrata's modulus
    by O(xi^2) in Vs* (|Vs*| = Vs exactly in pystrata's, (1 + xi^2)^(1/2) Vs in the
    approximation; the phases differ by O(xi^3)), hence |H| by O(xi^2) relative: measured
    4.3 xi^2 at the peak and 5.7 xi^2 at most up to 20 Hz (xi = 0.05); bound 8 xi^2 = 2 %."""
    sp = _profile(tmp_path, "rigid")
    tf = site.transfer_function(sp, F)
    closed = 1.0 / np.cos(2 * np.pi * F * H / _vs_complex(VS, XI))
    assert np.max(np.abs(tf - closed) / np.abs(closed)) < tol.NUMERICAL_REL
    f0, amp = site.fundamental(sp)
    assert sp.f_quarter_wave_hz == pytest.approx(VS / (4 * H), rel=tol.FEW_ULP_REL)
    assert abs(f0 / (VS / (4 * H)) - 1) < XI ** 2
    assert amp == pytest.approx(abs(1 / np.cos(2 * np.pi * f0 * H / _vs_complex(VS, XI))), rel=tol.NUMERICAL_REL)
    kramer = 1.0 / np.abs(np.cos(2 * np.pi * F * H / (VS * (1 + 1j * XI))))
    assert np.max(np.abs(np.abs(tf) - kramer) / kramer) < 8 * XI ** 2


def test_uniform_layer_on_elastic_rock_is_the_closed_form(tmp_path):
    """Outcrop rock to surface over an elastic half-space: H = 1/(cos k*H + i a* sin k*H),
    a* = (gamma_s Vs*_s)/(gamma_r Vs*_r) the complex impedance ratio: to round-off. With
    almost no soil damping (xi = 1e-4) and none in the rock (its damping makes a* complex,
    which moves the peak by a xi_r / (pi/2): 1.7e-3 for 1 %), the peak is at Vs/4H within
    xi (hysteretic damping attenuates over the layer as exp(-xi k H), more at higher
    frequency: a first-order shift downwards, measured 0.38 xi), and at Vs/4H
    k*H = (pi/2)(1 - i xi') with xi' = xi (1 + O(xi^2)), so
    |H| = 1/(sinh b + a cosh b), b = pi xi'/2: 1/(a + pi xi/2) (a = 0.2727) within b^2 + 2 xi^2."""
    sp = _profile(tmp_path, "elastic")
    tf = site.transfer_function(sp, F)
    k = 2 * np.pi * F * H / _vs_complex(VS, XI)
    a = GAMMA * _vs_complex(VS, XI) / (GAMMA_R * _vs_complex(VR, XI_R))
    closed = 1.0 / (np.cos(k) + 1j * a * np.sin(k))
    assert np.max(np.abs(tf - closed) / np.abs(closed)) < tol.NUMERICAL_REL
    xi = 1e-4
    sp = _profile(tmp_path, "elastic", xi=xi, name="q.toml", xi_r=0.0)
    f0, amp = site.fundamental(sp)
    assert abs(f0 / (VS / (4 * H)) - 1) < xi
    alpha = GAMMA * VS / (GAMMA_R * VR)
    h_qw = abs(site.transfer_function(sp, [VS / (4 * H)])[0])
    assert h_qw == pytest.approx(1 / (alpha + np.pi * xi / 2), rel=(np.pi * xi / 2) ** 2 + 2 * xi ** 2)
    assert h_qw <= amp <= h_qw * (1 + xi)  # the peak is above its value at Vs/4H, by second order in the shift


def _sine_amplitude(sp, f_hz: float, amp: float = 0.5, dt: float = 0.005, t_end: float = 60.0):
    """Fitted steady-state amplitude ratio of the propagated sine amp sin(2 pi f t) over
    10-50 s (tolerances.SITE_SINE_STEADY_REL says why that window)."""
    t = np.arange(int(round(t_end / dt)) + 1) * dt
    surface, info = site.propagate(Record(amp * np.sin(2 * np.pi * f_hz * t), dt, source="sine"), sp)
    assert surface.n == len(t) and surface.dt == dt and info["converged"]
    w = (t >= 10.0) & (t <= 50.0)
    basis = np.c_[np.sin(2 * np.pi * f_hz * t[w]), np.cos(2 * np.pi * f_hz * t[w])]
    c = np.linalg.lstsq(basis, surface.acc[w], rcond=None)[0]
    return float(np.hypot(*c) / amp)


def test_propagated_sine_is_amplified_by_the_transfer_function(tmp_path):
    """On the time history: a sine at f0 comes out amplified by |H(f0)| (2.85 here), one at
    f0/20 nearly unchanged (|H| - 1 below (pi/40)^2 = 1/cos(pi/40)^2 - 1 bound of a rigid base,
    measured 2.5e-3), both within SITE_SINE_STEADY_REL of |H(f)|."""
    sp = _profile(tmp_path, "elastic")
    f0, amp0 = site.fundamental(sp)
    assert _sine_amplitude(sp, f0) == pytest.approx(amp0, rel=tol.SITE_SINE_STEADY_REL)
    low = f0 / 20
    h_low = abs(site.transfer_function(sp, [low])[0])
    assert _sine_amplitude(sp, low) == pytest.approx(h_low, rel=tol.SITE_SINE_STEADY_REL)
    assert 0 < h_low - 1 < (np.pi / 2 * low / sp.f_quarter_wave_hz) ** 2


def test_example_profile_falls_in_alvas_ranges():
    """data/site/sacsayhuaman.toml (ASSUMED, labelled): small-strain f0 in Alva et al.'s
    1.75-2.86 Hz (quoted by the Sacsayhuaman paper; the file's [target]) and |H(f0)| = 1.56
    within half a unit of its last digit."""
    sp = site.read_profile(EXAMPLE)
    assert "ASSUMED" in sp.assumed and "ASSUMED" in sp.name
    assert sp.target["f0_hz"] == [1.75, 2.86] and sp.target["amplification"] == 1.56
    f0, amp = site.fundamental(sp)
    lo, hi = sp.target["f0_hz"]
    assert lo <= f0 <= hi and lo <= sp.f_quarter_wave_hz <= hi
    assert amp == pytest.approx(sp.target["amplification"], rel=tol.ALVA_AMPLIFICATION_REL)
    assert [la.stress_mean_kpa for la in sp.layers] == pytest.approx([66.667, 200.0, 333.33, 466.67, 600.0],
                                                                     rel=1e-4)  # (1 + 2 K0)/3 x 20 kN/m^3 x depth


CASE = """[case]
geometry = {{ generator = "four_blocks" }}
[[stages]]
type = "gravity"
duration = 0.2
[[stages]]
type = "excitation"
motion = "record"
record = "kobe1995"
pga_g = 0.2
duration = 8.0
site = "{site}"
"""


def test_case_with_site_resolves_and_stores_both_records_with_provenance(tmp_path):
    """``site = ...`` resolves (no YADE): the platform gets the surface motion, the record at
    rock scaled to pga_g is saved beside it, and excitation_2_site.json holds the profile (file
    and SHA-256), f0, the PGA at rock and at the surface and the iterations."""
    from drystone.model.resolve import resolve

    (tmp_path / "soil.toml").write_bytes(EXAMPLE.read_bytes())
    (tmp_path / "c.toml").write_text(CASE.format(site="soil.toml"))
    c = casemod.load(tmp_path / "c.toml")
    out = tmp_path / "out"
    out.mkdir()
    spec = resolve(c, str(tmp_path / "c.toml"), out)
    meta = spec.excitations[0]
    sha = hashlib.sha256(EXAMPLE.read_bytes()).hexdigest()
    assert meta["site"]["sha256"] == sha and meta["site"]["profile"] == str((tmp_path / "soil.toml").resolve())
    rock = np.load(out / "excitation_2_bedrock.npy")
    surface = np.load(out / "excitation_2.npy")
    assert np.abs(rock).max() / 9.80665 == pytest.approx(0.2, rel=tol.CHAINED_ULP_REL)  # pga_g is at rock
    assert meta["site"]["pga_rock_g"] == pytest.approx(0.2, rel=tol.CHAINED_ULP_REL)
    assert meta["pga_g"] == pytest.approx(meta["site"]["pga_surface_g"], rel=tol.FEW_ULP_REL)
    assert len(rock) == len(surface) and not np.allclose(rock, surface)
    again, _ = site.propagate(Record(rock, meta["dt_s"], source="rock"), site.read_profile(EXAMPLE))
    assert np.max(np.abs(again.acc - surface)) < tol.NUMERICAL_ABS
    js = json.loads((out / "excitation_2_site.json").read_text())
    assert js["site_response"]["profile"]["sha256"] == sha
    assert js["bedrock_acc_file"] == "excitation_2_bedrock.npy" and js["surface_acc_file"] == "excitation_2.npy"
    assert js["site_response"]["converged"] and js["site_response"]["iterations"] >= 1
    assert "site response" in js["surface_record"]["history"][-1]
    assert js["site_response"]["input"].startswith("outcrop motion")


def test_without_site_the_stage_is_unchanged():
    s = {"motion": "white_noise", "duration": 5.0, "seed": 1, "pga_g": 0.1}
    m = excitation.motion_for_stage(s)
    assert m.bedrock is None and m.site is None
    acc, dt, meta = excitation.for_stage(s)
    assert np.array_equal(acc, m.applied.acc) and "site" not in meta


@pytest.mark.parametrize("edit, message", [
    (lambda t: "colour = 1\n" + t, "unknown key 'colour'"),
    (lambda t: t.replace("thickness_m = 50.0", "thickness_m = -5.0"), "'thickness_m' = -5 must be > 0"),
    (lambda t: t.replace('curves = "darendeli"', 'curves = "hardin"'), "'curves' = 'hardin'"),
    (lambda t: t.replace("damping = 0.01", "damping = 0.6"), "'damping' = 0.6 must be < 0.5"),
])
def test_bad_profiles_are_refused_naming_file_and_key(tmp_path, edit, message):
    p = tmp_path / "bad.toml"
    p.write_text(edit(EXAMPLE.read_text()))
    with pytest.raises(site.SiteError, match=message) as e:
        site.read_profile(p)
    assert str(p) in str(e.value) and "\n" not in str(e.value)
    (tmp_path / "c.toml").write_text(CASE.format(site="bad.toml"))
    with pytest.raises(CaseError, match=message):
        casemod.load(tmp_path / "c.toml")


def test_missing_profile_is_refused_before_any_run(tmp_path):
    """A missing file: one line naming the case file and the path, exit 2, nothing run."""
    (tmp_path / "c.toml").write_text(CASE.format(site="nowhere.toml"))
    r = subprocess.run([sys.executable, "-m", "drystone", "run", "c.toml", "--out", "out"], cwd=tmp_path,
                       capture_output=True, text=True)
    assert r.returncode == 2 and not (tmp_path / "out").exists()
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "'site' = 'nowhere.toml'" in lines[0] and "c.toml" in lines[0], r.stderr
    with pytest.raises(site.SiteError, match="site-profile file not found"):
        site.read_profile(tmp_path / "nowhere.toml")
