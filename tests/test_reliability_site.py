"""Site profiles, ``spectrum`` and ``site``, and two load inputs tried as a careless user would:
every key of a site profile bounded to its physical range (named, before any run), the FFT's
size bounded before pystrata allocates it, a site response that did not converge warned of,
non-finite spectrum results refused, outputs written aside and renamed together, a stone with
every dof blocked run as a stone that does not move, an absurd surcharge refused. Each test
reproduces a fault and asserts the named error or the right result."""
from __future__ import annotations

import errno
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from conftest import requires_yade
from drystone import paths, runner
from drystone.model import case as casemod
from drystone.model.keys import CaseError
from drystone.motions import cli, excitation, site
from drystone.motions.record import Record
from drystone.postprocess import console

EXAMPLE = paths.ROOT / "data" / "site" / "sacsayhuaman.toml"
LINEAR = ('bedrock = "rigid"\n[[layers]]\nname = "sand"\nthickness_m = 20.0\nvs_m_s = 200.0\n'
          'unit_weight_kn_m3 = 18.0\ndamping = {xi}\ncurves = "linear"\nsublayers = {n}\n')


def _edit(tmp_path: Path, old: str, new: str) -> Path:
    text = EXAMPLE.read_text()
    assert old in text
    p = tmp_path / "bad.toml"
    p.write_text(text.replace(old, new))
    return p


def _cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "drystone.motions", *args], capture_output=True, text=True,
                          cwd=cwd)


# -- every key bounded, named with its layer and range, before pystrata is imported ---------------
@pytest.mark.parametrize("old, new, key", [
    ("name = \"Sacsayhuaman", "strain_ratio = 1e6\nname = \"Sacsayhuaman", "strain_ratio"),
    ("name = \"Sacsayhuaman", "max_iterations = 0\nname = \"Sacsayhuaman", "max_iterations"),
    ("vs_m_s = 450.0", "vs_m_s = 1e-3", "vs_m_s"),
    ("thickness_m = 50.0", "thickness_m = 1e6", "thickness_m"),
    ("unit_weight_kn_m3 = 20.0", "unit_weight_kn_m3 = 20000.0", "unit_weight_kn_m3"),
    ("ocr = 1.0", "ocr = 1.0\ndamping = 1e-9", "damping"),
    ("pi_percent = 15.0", "pi_percent = 1e6", "pi_percent"),
    ("ocr = 1.0", "ocr = 1e6", "ocr"),
    ("ocr = 1.0", "ocr = 1.0\nstress_mean_kpa = 1e-6", "stress_mean_kpa"),
    ("ocr = 1.0", "ocr = 1.0\nstress_mean_kpa = 1e9", "stress_mean_kpa"),
    ("ocr = 1.0", "ocr = 1.0\nk0 = 1e6", "k0"),
    ("sublayers = 5", "sublayers = 1000000", "sublayers"),
    ("vs_m_s = 650.0", "vs_m_s = 1e9", "vs_m_s"),
])
def test_profile_keys_outside_their_physical_range_are_refused(tmp_path, old, new, key):
    """strain_ratio = 1e6 ran to "converged: true" with the surface PGA at 0.15 x its value;
    vs 1e-3 and a 1e6 m layer were blamed on the record ("non-finite samples"); an extreme
    PI or stress gave "cannot convert float NaN to integer"; damping 1e-9 asked for 1 TiB."""
    p = _edit(tmp_path, old, new)
    with pytest.raises(site.SiteError, match=f"'{key}' = .* must be .*allowed") as e:
        site.read_profile(p)
    msg = str(e.value)
    assert msg.startswith(str(p)) and "\n" not in msg
    lo, hi, unit, _ = site.RANGES["bedrock_damping" if key == "damping" and "bedrock" in msg else key]
    assert f"{lo:g}, {hi:g}" in msg and unit in msg


def test_layer_counts_are_bounded_before_the_layers_are_built(tmp_path):
    """10 000 layers took 73 s and 5.3 GB, then an ArrayMemoryError: refused at once."""
    p = tmp_path / "many.toml"
    p.write_text('bedrock = "rigid"\n' + "[[layers]]\nthickness_m = 0.1\nvs_m_s = 200.0\nunit_weight_kn_m3 = 18.0\n"
                 "damping = 0.05\n" * 10000)
    with pytest.raises(site.SiteError, match=f"10000 \\[\\[layers\\]\\], more than {site.MAX_LAYERS}"):
        site.read_profile(p)
    p.write_text(LINEAR.format(xi=0.05, n=site.MAX_LAYERS) + LINEAR.split("\n", 1)[1].format(xi=0.05, n=1))
    with pytest.raises(site.SiteError, match=r"\[\[layers\]\] #2: 'sublayers' = 1 brings the column to 201 layers"):
        site.read_profile(p)


def test_a_column_thicker_than_the_range_is_refused(tmp_path):
    p = tmp_path / "deep.toml"
    p.write_text(LINEAR.format(xi=0.05, n=1).replace("20.0", "2000.0") + LINEAR.split("\n", 1)[1].format(
        xi=0.05, n=1).replace("20.0", "1500.0"))
    with pytest.raises(site.SiteError, match=r"#2: 'thickness_m' = 1500 makes the column 3500 m thick"):
        site.read_profile(p)


def test_the_padding_of_a_lightly_damped_column_is_refused_before_pystrata_allocates(tmp_path):
    """Damping within range (1e-4) but a column that rings for 2 ln(1e4)/(xi w0) = 2.3 h: at a
    0.5 ms step the FFT would need 1.7e7 samples; refused naming the layer and its damping."""
    p = tmp_path / "light.toml"
    p.write_text(LINEAR.format(xi=1e-4, n=1))
    sp = site.read_profile(p)
    rec = Record(np.sin(np.arange(20000) * 0.01), 0.0005, source="sine")
    with pytest.raises(site.SiteError, match=r"layer 'sand': small-strain damping 0.0001 \('damping'\) lets the "
                                             r"column ring for .* raise the damping") as e:
        site.fft_samples(rec, sp)
    assert str(p.resolve()) in str(e.value)
    pad, nfft = site.fft_samples(Record(rec.acc, 0.02, source="sine"), sp)  # at a 20 ms step it fits
    assert nfft >= 20000 + pad / 0.02 and nfft <= site.MAX_FFT_SAMPLES


def test_layers_times_samples_are_bounded(tmp_path):
    p = tmp_path / "fine.toml"
    p.write_text(LINEAR.format(xi=0.05, n=site.MAX_LAYERS))
    sp = site.read_profile(p)
    rec = Record(np.sin(np.arange(400_000) * 0.01), 0.001, source="long")
    with pytest.raises(site.SiteError, match=rf"{site.MAX_LAYERS} layers \(after 'sublayers'\) and 524288 FFT "
                                             r"samples .* fewer 'sublayers'"):
        site.fft_samples(rec, sp)


# -- a site response that did not converge is said -------------------------------------------------
@pytest.fixture(scope="module")
def unconverged(tmp_path_factory):
    d = tmp_path_factory.mktemp("nc")
    p = d / "nc.toml"
    p.write_text("max_iterations = 1\n" + EXAMPLE.read_text())
    s = {"motion": "record", "record": "kobe1995", "pga_g": 0.4, "duration": 8.0, "site": str(p)}
    m = excitation.motion_for_stage(s)
    return p, s, m


def test_a_site_response_that_did_not_converge_is_warned_of_and_recorded(unconverged):
    """It drove the run with no warning line (last change 7.5 %): the excitation's provenance
    (spec.json, summary inputs.excitations) carries the warning, which the run prints to stderr
    and the console summary repeats."""
    p, s, m = unconverged
    assert not m.site["converged"]
    meta = excitation.stage_meta(s, m)
    w = meta["site"]["warning"]
    assert w.startswith("warning: site response through ") and str(p) in w and "did not converge" in w
    assert "max_iterations 1" in w and "\n" not in w
    lines = console.warnings({"inputs": {"excitations": [dict(meta, stage=2)]}})
    assert any(line.startswith("warning: site response") and "stage 2" in line for line in lines)
    ok = excitation.stage_meta(dict(s, site=str(EXAMPLE)), excitation.motion_for_stage(dict(s, site=str(EXAMPLE))))
    assert ok["site"]["converged"] and "warning" not in ok["site"]


def test_site_cli_prints_the_warning_and_records_it(unconverged, tmp_path):
    p, _, _ = unconverged
    r = _cli("site", str(p), "--pga-g", "0.4", "--duration", "8", "--out", str(tmp_path / "o"))
    assert r.returncode == 0, r.stderr
    assert [ln for ln in r.stderr.splitlines() if ln.startswith("warning: site response")]
    js = json.loads((tmp_path / "o" / "nc_site.json").read_text())
    assert js["site_response"]["warning"].startswith("warning:") and json.loads(r.stdout)["converged"] is False


# -- site --out ----------------------------------------------------------------------------------
def test_site_out_an_existing_file_is_refused(tmp_path):
    f = tmp_path / "taken"
    f.write_text("the user's")
    r = _cli("site", str(EXAMPLE), "--duration", "5", "--out", str(f))
    assert r.returncode == 2 and r.stderr.strip().count("\n") == 0
    assert f"--out {f}: exists and is not a folder" in r.stderr and f.read_text() == "the user's"
    r = _cli("site", str(EXAMPLE), "--duration", "5", "--out", str(f / "below"))
    assert r.returncode == 2 and r.stderr.startswith(f"error: {f / 'below'}") and "Traceback" not in r.stderr


def test_site_outputs_are_renamed_together_or_not_at_all(tmp_path, monkeypatch, capsys):
    """A full disk while the figure is written (the last file): none of the four files is
    replaced (the earlier set stays whole), no temporary is left, one line names the file."""
    out = tmp_path / "o"
    argv = ["site", str(EXAMPLE), "--duration", "5", "--out", str(out)]
    assert cli.main(argv) == 0
    before = {q.name: q.read_bytes() for q in out.iterdir()}
    assert sorted(before) == ["sacsayhuaman_bedrock.npy", "sacsayhuaman_site.json", "sacsayhuaman_site.png",
                              "sacsayhuaman_surface.npy"]
    capsys.readouterr()

    def full(*a, **k):
        raise OSError(errno.ENOSPC, "No space left on device")

    from drystone.motions import plots
    monkeypatch.setattr(plots, "plot_site", full)
    assert cli.main(argv + ["--pga-g", "0.1"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"error: {out / 'sacsayhuaman_site.png'}: No space left on device"
    assert {q.name: q.read_bytes() for q in out.iterdir()} == before


# -- spectrum --------------------------------------------------------------------------------------
def test_spectrum_refuses_non_finite_results_and_prints_valid_json(tmp_path):
    """Samples of 1e300 printed JSON with NaN and Infinity, exit 0."""
    f = tmp_path / "huge.txt"
    f.write_text("\n".join(["1e300", "-1e300"] * 500))
    r = _cli("spectrum", str(f), "--dt", "0.01", "--units", "g", "--out", str(tmp_path / "s"))
    assert r.returncode == 2 and r.stdout == "" and not (tmp_path / "s").exists()
    assert r.stderr.startswith(f"error: {f}: the record gives non-finite results (") and r.stderr.count("\n") == 1
    g = tmp_path / "fine.txt"
    g.write_text("\n".join(f"{0.1 * np.sin(0.3 * k):.6f}" for k in range(800)))
    r = _cli("spectrum", str(g), "--dt", "0.01", "--units", "g", "--out", str(tmp_path / "s"))
    assert r.returncode == 0, r.stderr
    json.loads(r.stdout, parse_constant=lambda c: pytest.fail(f"{c} in the JSON"))
    assert (tmp_path / "s" / "fine_unknown.png").is_file() or len(list((tmp_path / "s").glob("*.png"))) == 1


@pytest.mark.parametrize("samples, dt, words", [
    (3, "0.01", "{f}: 3 samples at dt 0.01 s (0.02 s) resolve no frequency in the spectrum's band"),
    (2, "0.01", "{f}: 2 samples at dt 0.01 s"),
    (800, "1e-300", "--dt 1e-300 s: the time step must be in [1e-05, 1] s"),
])
def test_spectrum_of_too_few_samples_or_an_absurd_step_names_the_file_or_option(tmp_path, samples, dt, words):
    """Both gave "log_grid needs 0 < fmin < fmax", naming nothing."""
    f = tmp_path / "short.txt"
    f.write_text("\n".join(["0.1", "0.2", "-0.1"] * 300)[: 4 * samples - 1])
    r = _cli("spectrum", str(f), "--dt", dt, "--units", "g", "--out", str(tmp_path / "s"))
    assert r.returncode == 2 and r.stderr.startswith("error: " + words.format(f=f)), r.stderr
    assert r.stderr.count("\n") == 1 and "log_grid" not in r.stderr


def test_spectrum_out_an_existing_file_is_refused(tmp_path):
    f = tmp_path / "taken.png"
    f.write_bytes(b"user")
    r = _cli("spectrum", "kobe1995", "--out", str(f))
    assert r.returncode == 2 and f"--out {f}: exists and is not a folder" in r.stderr and f.read_bytes() == b"user"


# -- loads and blocked dofs --------------------------------------------------------------------------
@pytest.mark.parametrize("override, words", [
    ("loads.0.surcharge=1e300", "surcharge = 1e+300 Pa: must be in [0, 1e+06] Pa"),
    ("loads.0.gamma=1e300", "gamma = 1e+300 N/m^3: must be in [0, 30000] N/m^3"),
])
def test_absurd_earth_pressure_inputs_are_refused_naming_the_key(override, words):
    """surcharge = 1e300 stopped inside YADE with "non-finite kinetic_energy", naming nothing."""
    with pytest.raises(CaseError, match=r"\[\[loads\]\]") as e:
        casemod.load(paths.ROOT / "cases" / "examples" / "retaining_block.toml", [override])
    assert words in str(e.value) and "\n" not in str(e.value)


@requires_yade
def test_a_stone_with_every_dof_blocked_stays_put(outdir):
    """blocked_dofs = "xyzXYZ" (documented, legal) stopped with "non-finite kinetic_energy":
    YADE reports such a body as not dynamic and the run took its mass as infinite. It is a
    free stone that cannot move: zero displacement and kinetic energy, a finite summary."""
    geo = json.loads((paths.ROOT / "cases" / "examples" / "one_block.json").read_text())
    geo["blocks"][1]["blocked_dofs"] = "xyzXYZ"
    (outdir / "held.json").write_text(json.dumps(geo))
    case = {"case": {"name": "held", "geometry": "held.json"},
            "stages": [{"type": "gravity", "duration": 0.05, "ramp": 0.025}], "output": {"interval": 0.01}}
    s = runner.run_dict(case, outdir / "held.toml", out_dir=outdir / "held", quiet=True)
    h = np.load(outdir / "held" / "histories.npz")
    assert np.all(h["kinetic"] == 0.0) and np.all(h["pos"] == h["pos"][0])  # exact: never integrated
    assert s["blocks"]["1"]["residual_displacement_norm_m"] == 0.0


@requires_yade
def test_a_run_driven_by_an_unconverged_site_response_warns(unconverged, outdir, capfd):
    """The run prints the warning on stderr before YADE starts and keeps it in the summary's
    inputs (the excitation's provenance); the console summary repeats it."""
    p, _, _ = unconverged
    box = {"id": 1, "center_xy": [0.0, 0.0], "size": [0.2, 0.2, 0.2]}
    case = {"case": {"name": "nc", "geometry": {"generator": "boxes_on_platform", "damping": 0.5, "boxes": [box]}},
            "stages": [{"type": "gravity", "duration": 0.05, "ramp": 0.025},
                       {"type": "excitation", "motion": "record", "record": "kobe1995", "pga_g": 0.4,
                        "duration": 3.0, "direction": "y", "site": str(p)}],
            "output": {"interval": 0.05}}
    s = runner.run_dict(case, outdir / "nc.toml", out_dir=outdir / "nc", quiet=True)
    err = capfd.readouterr().err
    assert [ln for ln in err.splitlines() if ln.startswith("warning: site response through") and "#2" in ln], err
    (e,) = s["inputs"]["excitations"]
    assert e["site"]["converged"] is False and e["site"]["warning"].startswith("warning:")
    assert any("did not converge" in ln for ln in console.warnings(s))


def test_a_column_too_slow_for_the_fundamental_search_is_refused(tmp_path):
    """3000 m at 20 m/s (each within range): Vs/4H = 0.0017 Hz, below the 0.05 Hz the peak is
    searched from; its padding would be computed from a wrong f0."""
    p = tmp_path / "slow.toml"
    p.write_text(LINEAR.format(xi=0.05, n=1).replace("20.0", "2000.0").replace("200.0", "20.0"))
    with pytest.raises(site.SiteError, match=r"travel time 100 s .* below the 0.05 Hz searched"):
        site.read_profile(p)


def test_spectrum_on_a_full_disk_names_the_file_and_leaves_nothing(tmp_path, monkeypatch, capsys):
    """A traceback before; now one line naming the figure, and no temporary left behind."""
    from drystone.motions import plots

    def full(*a, **k):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(plots, "plot_record", full)
    out = tmp_path / "s"
    assert cli.main(["spectrum", "kobe1995", "--out", str(out)]) == 2
    cap = capsys.readouterr()
    assert cap.err.strip() == f"error: {out / 'kobe1995_NIS000.png'}: No space left on device" and cap.out == ""
    assert list(out.iterdir()) == []


def test_a_non_finite_surface_motion_names_the_layer_or_the_column(tmp_path):
    """Within the ranges no case found reaches it (PI 200, OCR 100, 0.1 kPa under 2 g: damping
    0.45 at most); should one, the layer whose strain-compatible damping left pystrata's
    range is named instead of the record ("non-finite samples")."""
    from types import SimpleNamespace

    p = tmp_path / "p.toml"
    p.write_text(LINEAR.format(xi=0.05, n=2))
    sp = site.read_profile(p)
    bad = np.array([0.0, np.nan])
    layers = [SimpleNamespace(damping=np.array([0.1])), SimpleNamespace(damping=np.array([0.7])), None]
    with pytest.raises(site.SiteError, match=r"layer 'sand \(2/2\)': its strain-compatible damping reached 0.7"):
        site._check_finite(sp, layers, bad)
    layers[1] = SimpleNamespace(damping=np.array([0.2]))
    with pytest.raises(site.SiteError, match=r"the surface motion through the column is not finite \(thickness 20 m"):
        site._check_finite(sp, layers, bad)
    site._check_finite(sp, layers, np.zeros(3))  # finite: nothing to say
