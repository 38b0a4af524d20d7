"""A finished run's report: one self-contained HTML page, ``<run>/report.html``.

``write(run_dir)`` reads the run's summary.json, spec.json, histories.npz and geometry.json
(plain Python, no YADE) and writes ``report.html``: what ran (case file, its inputs as a
table with units, the resolved key parameters: time step, contact law, K_n, K_t, mu,
damping, stages, excitations), the ASSUMED inputs flagged (the geometry generator's
assumptions and stand-in records, summary.json ``inputs.assumed``, and the case file's
comments that say ASSUMED), the console summary (drystone/postprocess/console.py), the
tables (per-stone residuals and collapse, named contacts, control points, energy), the
figures (control points, initial and final state, energy terms against time, and the run's
standard figures) and the provenance (versions, git commit, record sources). Figures are
written into the run folder as PNG too and embedded in the page as ``data:`` URIs: the page
fetches nothing. ``python -m drystone report RUN_DIR`` and ``make report DIR=...`` call it.
A folder that is not a complete run (drystone/postprocess/runfolder.py: a file missing,
unreadable or without what the page reads) is refused (``NotARun``, naming the file). A study's folder
(a report.md, no spec.json) gets its report.md converted (drystone/postprocess/markdown.py).
Units: SI in the files; the page shows mm for displacements, deg for angles, J for energy.
"""
from __future__ import annotations

import json
import re
import tomllib
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from drystone import atomic  # noqa: E402
from drystone.model.spec import stage_type  # noqa: E402
from drystone.postprocess import console, markdown, plots, snapshots  # noqa: E402
from drystone.postprocess import runfolder  # noqa: E402
from drystone.postprocess import summary as summ  # noqa: E402
from drystone.postprocess.html import esc, image, page, table  # noqa: E402

#: figures the report draws into the run folder
FINAL_STATE_PNG, ENERGY_PNG = "final_state.png", "energy.png"
#: energy histories (J) the energy figure draws when histories.npz has them, with their labels
ENERGY_TERMS = {"kinetic": "kinetic", "potential": "potential (change since t = 0)", "elastic": "elastic (contacts)",
                "work_loads": "work of the loads", "dissipated_damping": "dissipated by damping",
                "dissipated_friction": "dissipated by friction",
                "removed_kinetic": "carried out by stones that left the model"}
#: the terms of the balance drawn when the histories have all of them and no balance of their own
BALANCE_TERMS = ("work_loads", "dissipated_damping", "dissipated_friction")
#: the energy figure's size (in) and resolution (dots per inch)
ENERGY_FIGSIZE, ENERGY_DPI = (8.0, 6.5), 110
#: at most this many stones in the per-stone table (largest residuals first)
MAX_BLOCK_ROWS = 400


#: a folder that is not a complete run (drystone/postprocess/runfolder.py)
NotARun = runfolder.NotARun


def check(run_dir: Path) -> Path:
    """``run_dir`` if it holds a complete run, else NotARun naming it and the missing or
    unreadable file (``runfolder.load``)."""
    return runfolder.load(run_dir).folder


# -- what ran -------------------------------------------------------------------------------
def _unit_and_meaning(path: list[str], stages: list) -> tuple[str, str]:
    """Unit and meaning of a case key (``path``: its dotted parts) from the declaration."""
    from drystone.model import case as casemod

    if path[0] == "stages" and path[-1] == "type":
        return "-", "stage type (drystone/model/stages.py REGISTRY)"
    try:
        if path[0] == "stages" and len(path) == 3:
            st = stages[int(path[1])]
            key = casemod.STAGE_TYPES[st.get("type")].keys[path[2]]
        else:
            key = casemod.SECTIONS[path[0]][path[1]]
        return key.unit, key.meaning
    except (KeyError, IndexError, ValueError, TypeError, AttributeError):
        return "", ""


def _flatten(d, prefix=()) -> list[tuple[list[str], object]]:
    out = []
    for k, v in d.items():
        p = [*prefix, str(k)]
        if isinstance(v, dict) and not (len(p) == 2 and p[0] == "case" and p[1] == "geometry"):
            out += _flatten(v, p)
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v) and p == ["stages"]:
            for i, x in enumerate(v):
                out += _flatten(x, [*p, str(i)])
        else:
            out.append((p, v))
    return out


def case_inputs(spec: dict) -> dict:
    """The case as given: file, description, text, overrides, its keys as (key, value,
    unit, meaning) rows (stages numbered from 0, as overrides number them), and the comment
    lines that say ASSUMED (or assumed)."""
    prov = spec.get("provenance") or {}
    text = prov.get("case_text") or ""
    try:
        case = tomllib.loads(text) if text else {}
    except tomllib.TOMLDecodeError:
        case = {}
    rows = []
    for path, v in _flatten(case):
        unit, meaning = _unit_and_meaning(path, case.get("stages") or [])
        rows.append([".".join(path), v if isinstance(v, (str, int, float)) else json.dumps(v), unit, meaning])
    lines = text.splitlines()
    comments = []  # (line number, the comment with the comment line above it: the sentence may begin there)
    for n, line in enumerate(lines):
        if "#" in line and re.search(r"assumed", line.split("#", 1)[1], re.IGNORECASE):
            above = lines[n - 1].strip() if n > 0 and lines[n - 1].lstrip().startswith("#") else ""
            comments.append((n + 1, (above + " " + line.strip().lstrip("#").strip()) if above else line.strip()))
    return {"file": prov.get("case_file"), "description": (case.get("case") or {}).get("description", ""),
            "text": text, "overrides": prov.get("overrides") or [], "rows": rows, "assumed_comments": comments}


def key_parameters(spec: dict) -> list[list]:
    """The resolved run's key parameters as (quantity, value, unit) rows."""
    roles: dict[str, int] = {}
    for b in spec.get("blocks", []):
        roles[b.get("role", "?")] = roles.get(b.get("role", "?"), 0) + 1
    rows = [["time step dt", spec["dt"], "s"],
            ["critical time step", spec.get("dt_critical"), "s"],
            ["contact law", spec.get("law"), "-"],
            ["contact geometry (detection)", spec.get("detection"), "-"],
            ["gravity", spec.get("gravity"), "m/s^2"],
            ["blocks", ", ".join(f"{n} {r}" for r, n in sorted(roles.items())), "-"],
            ["recording interval", (spec.get("output") or {}).get("interval"), "s"]]
    thr = list((spec.get("collapse_threshold") or {}).values())
    if thr:
        rows.append(["displacement threshold (damage; a tilt's detection)", f"{1e3 * min(thr):.4g} to {1e3 * max(thr):.4g}", "mm"])
    return rows


MATERIAL_UNITS = {"density": "kg/m^3", "kn": "N/m^3", "kt": "N/m^3", "mu": "-", "damping": "- (of critical)"}


def materials_table(spec: dict) -> str:
    keys = list(MATERIAL_UNITS)
    rows = [[name] + [m.get(k) for k in keys] for name, m in (spec.get("materials") or {}).items()]
    out = table(["material"] + [f"{'K_n' if k == 'kn' else 'K_t' if k == 'kt' else k} ({MATERIAL_UNITS[k]})"
                                for k in keys], rows)
    jo = spec.get("joint_overrides") or {}
    if jo:
        out += "<p>Joint overrides (these joints only):</p>" + table(
            ["joint (blocks)", "overrides"],
            [[j, ", ".join(f"{k} = {v}" for k, v in o.items())] for j, o in jo.items()])
    return out


def stages_table(spec: dict) -> str:
    rows = [[k, stage_type(st), st["start"], st["end"],
             ", ".join(f"{p} = {json.dumps(v)}" for p, v in st.get("params", {}).items()
                       if v is not None and (p not in ("acc", "initial_relative_velocity") or any(v)))]
            for k, st in enumerate(spec.get("stages", []))]
    return table(["stage (from 0)", "type", "start (s)", "end (s)", "parameters (SI; angles deg)"], rows)


def excitations_table(spec: dict) -> str:
    rows = []
    for e in spec.get("excitations") or []:
        cat = (e.get("info") or {}).get("catalogue") or {}
        rows.append([e.get("stage"), e.get("motion"), e.get("record") or "", e.get("event") or "",
                     f"{e.get('station') or ''} {e.get('component') or ''}".strip(), e.get("scale_factor"),
                     e.get("pga_g"), e.get("direction"), e.get("duration_s"),
                     "ASSUMED analogue" if cat.get("source_kind") == "analogue" else (cat.get("source_kind") or "")])
    return table(["stage (from 1)", "motion", "record", "event", "station, component", "scale factor", "PGA (g)",
                  "direction", "duration (s)", "source kind"], rows) if rows else "<p>No excitation.</p>"


def assumed_items(summary: dict, spec: dict, run_dir: Path, case: dict) -> list[str]:
    """The run's assumed inputs: summary.json ``inputs.assumed`` (or, for older summaries,
    drystone/postprocess/summary.py ``assumed_inputs``) and the case file's ASSUMED comments."""
    items = (summary.get("inputs") or {}).get("assumed")
    if items is None:
        items = summ.assumed_inputs(spec, run_dir)
    items = list(items)
    for k, e in enumerate(spec.get("excitations") or []):  # a record file cut from an analogue (a study's window)
        if "analogue of" in str(e.get("event") or "") and not any(x.startswith(f"excitation {k + 1}:") for x in items):
            items.append(f"excitation {k + 1}: record {e.get('event')} ({e.get('source') or e.get('record')}) is an "
                         "ASSUMED analogue (its event says so)")
    items += [f"case file line {n}: {line}" for n, line in case["assumed_comments"]]
    return items


# -- tables of results ------------------------------------------------------------------
def blocks_table(summary: dict) -> str:
    blocks = summary.get("blocks") or {}
    order = sorted(blocks.items(), key=lambda kv: -(kv[1].get("residual_displacement_norm_m") or np.inf))
    rows = []
    for bid, r in order[:MAX_BLOCK_ROWS]:
        d = r.get("residual_displacement_m")
        rot = r.get("residual_rotation_angle_rad")
        mm = (lambda x: None if x is None else 1e3 * x)
        rows.append([bid, r.get("motion", ""), mm(r.get("residual_displacement_norm_m")),
                     *(["-"] * 3 if d is None else [1e3 * x for x in d]), mm(r.get("max_displacement_norm_m")),
                     None if rot is None else float(np.degrees(rot)), "yes" if r.get("beyond_displacement_threshold") else "no",
                     "yes" if r.get("collapsed") else "no", "yes" if r.get("fell") else "no"])
    note = (f"<p>The {MAX_BLOCK_ROWS} largest residuals of {len(blocks)} stones.</p>"
            if len(blocks) > MAX_BLOCK_ROWS else "")
    return note + table(["stone", "motion", "residual |d| (mm)", "d_x (mm)", "d_y (mm)", "d_z (mm)", "max |d| (mm)",
                         "residual rotation (deg)", "residual beyond threshold", "collapsed", "fell"], rows)


def contacts_table(summary: dict, spec: dict, h: dict) -> str:
    """Final state of every named contact (N, m^2) and the analysis keys of the summary."""
    rows = []
    for c in (spec.get("output") or {}).get("contacts", []):
        rec = h["contacts"].get(c["name"])
        if rec is None:
            continue
        fn = float(rec["fn"][-1]) if len(rec["fn"]) else None
        ft = float(np.linalg.norm(rec["ft"][-1])) if len(rec["ft"]) else None
        area = float(rec["area"][-1]) if "area" in rec and len(rec["area"]) else None
        slipping = bool(rec["slipping"][-1]) if "slipping" in rec and len(rec["slipping"]) else None
        rows.append([c["name"], " and ".join(str(b) for b in c["blocks"]), fn, ft, area,
                     "" if slipping is None else ("yes" if slipping else "no")])
    out = table(["contact", "blocks", "final F_n (N)", "final |F_t| (N)", "final area (m^2)", "slipping at the end"],
                rows) if rows else "<p>No named contacts recorded.</p>"
    keys = [[k, v] for k, v in summary.items() if k.startswith(("penetration_", "contact_area_", "normal_force_",
                                                                 "slip_"))]
    if keys:
        out += "<p>Analysis (summary.json; units in the key's suffix: _m, _N, _s, _deg, _m2):</p>" + table(
            ["key", "value"], keys)
    return out


def control_points_table(summary: dict) -> str:
    rows = []
    for name, r in (summary.get("control_points") or {}).items():
        res = r.get("residual_relative_displacement_m")
        rows.append([name, None if r.get("max_relative_displacement_norm_m") is None
                     else 1e3 * r["max_relative_displacement_norm_m"],
                     *(["-"] * 3 if res is None else [1e3 * x for x in res])])
    return table(["control point", "max |relative displacement| (mm)", "residual x (mm)", "residual y (mm)",
                  "residual z (mm)"], rows) if rows else "<p>No control points.</p>"


def energy_table(summary: dict, h: dict) -> str:
    rows = [[ENERGY_TERMS[k], float(h[k][-1] - (h[k][0] if k == "potential" else 0.0)), "J"]
            for k in ENERGY_TERMS if k in h and len(h[k])]
    e = summary.get("energy")
    if isinstance(e, dict):
        rows += [[f"summary.json energy.{k}", v, "J" if k.endswith("_J") else "-"] for k, v in e.items()
                 if isinstance(v, (int, float)) and not isinstance(v, bool)]
    return table(["at the end of the run", "value", "unit"], rows) if rows else "<p>No energy recorded.</p>"


# -- figures ----------------------------------------------------------------------------
def energy_figure(h: dict, path: Path, spec: dict) -> Path | None:
    """Energy terms (J) against time, two panels: every term of ENERGY_TERMS the histories
    have (the potential as its change since t = 0) and their balance when present, then
    the kinetic and elastic energies and the balance on their own scale (a ramped gravity's
    potential change would flatten them). The balance: the histories' own
    ``energy_balance`` or, with every BALANCE_TERMS term recorded, summary.balance_history:
    dE_k + dE_el + D_damping + D_friction + removed_kinetic - W_loads (zero for an exact integration; the
    potential is drawn for reference only: gravity's work is in W_loads)."""
    terms = {k: np.asarray(h[k], float) for k in ENERGY_TERMS if k in h and np.size(h[k]) == np.size(h["t"])}
    if "removed_kinetic" in terms and not terms["removed_kinetic"].any():
        del terms["removed_kinetic"]  # no stone left the model: nothing to draw, nothing in the balance
    if not terms or not len(h["t"]):
        return None
    t = np.asarray(h["t"], float)
    bal, label = None, None
    if "energy_balance" in h and np.size(h["energy_balance"]) == np.size(t):
        bal, label = np.asarray(h["energy_balance"], float), "balance (histories.npz energy_balance)"
    elif all(k in terms for k in BALANCE_TERMS + ("kinetic", "elastic")):
        bal = summ.balance_history(terms)  # summary.json's balance_error_J is its largest magnitude
        label = "balance error: ΔE_k + ΔE_el + D_damp + D_fric − W_loads (W_loads holds gravity's work)"
    fig, (a1, a2) = plt.subplots(2, 1, figsize=ENERGY_FIGSIZE, sharex=True)
    for k, v in terms.items():
        a1.plot(t, v - v[0] if k == "potential" else v, label=ENERGY_TERMS[k])
    small = [k for k in ("kinetic", "elastic") if k in terms]
    for k in small:
        a2.plot(t, terms[k], label=ENERGY_TERMS[k], color=a1.lines[list(terms).index(k)].get_color())
    for a in (a1, a2) if bal is not None else ():
        a.plot(t, bal, "k--", lw=1.0, label=label)
    for a in (a1, a2):
        for st in spec.get("stages", [])[1:]:
            a.axvline(st["start"], color="0.75", lw=0.6)
        a.set_ylabel("energy (J)")
        a.grid(alpha=0.3)
        if a.lines:
            a.legend(fontsize=8, loc="best")
    a2.set_xlabel("time (s)")
    a1.set_title(f"{spec.get('name', '')}: energy terms (stage starts in grey)", fontsize=10)
    a2.set_title("kinetic and elastic" + (" and the balance" if bal is not None else "") + ", on their own scale",
                 fontsize=9)
    fig.tight_layout()
    atomic.savefig(fig, path, dpi=ENERGY_DPI)
    plt.close(fig)
    return Path(path)


def figures(run_dir: Path, spec: dict, summary: dict, h: dict) -> list[tuple[Path, str]]:
    """(PNG, caption) of every figure of the page; draws into the run folder what is not
    there yet (the standard figures are those the run drew: drystone/postprocess/plots.py)."""
    d = Path(run_dir)
    out = []
    if h["cp"].size:
        p = d / "control_points.png"
        if not p.is_file():
            plots.control_points(h, p)
        out.append((p, "Control points: displacement out of plane (y) relative to the base (mm) against time (s)"))
    left = bool(((summary.get("run") or {}).get("left_model") or {}).get("count"))
    if (d / "geometry.json").is_file() and len(h["t"]):
        p = snapshots.render(d, [0.0, float(h["t"][-1])], d / FINAL_STATE_PNG, frame_on_first=left)
        out.append((p, "Initial and final state (world frame); stone colour: free, light grey: fixed, dark: platform"
                    + ("; framed on the initial state (stones left the model)" if left else "")))
    p = energy_figure(h, d / ENERGY_PNG, spec)
    if p is not None:
        out.append((p, "Energy terms (J) against time (s)"))
    an = spec.get("analysis") or {}
    for c in (spec.get("output") or {}).get("contacts", []):
        out.append((d / f"contact_{c['name']}.png", f"Contact {c['name']}: normal and tangential force (N) against "
                    "time (s)" + (" with the first slip" if an.get("slip") == c["name"] else "")))
    if an.get("penetration"):
        out.append((d / f"penetration_{an['penetration']}.png",
                    f"Contact {an['penetration']}: relative normal displacement (mm) against time (s)"))
    if any(stage_type(st) == "tilt" for st in spec.get("stages", [])):
        out.append((d / "reaction.png", "Vertical reaction of the moving stones (N) against time (s) and tilt (deg)"))
    return out


# -- the page ---------------------------------------------------------------------------
def _section(title: str, body: str) -> str:
    return f"<h2>{esc(title)}</h2>\n{body}\n"


def provenance_html(spec: dict) -> str:
    prov = spec.get("provenance") or {}
    git = prov.get("git") or {}
    rows = [["drystone", prov.get("drystone_version")], ["YADE", prov.get("yade_version")],
            ["Python", prov.get("python")], ["numpy", prov.get("numpy")], ["scipy", prov.get("scipy")],
            ["git commit", f"{git.get('commit')}" + (" (working tree modified)" if git.get("dirty") else "")],
            ["host", prov.get("host")], ["date (UTC)", prov.get("date_utc")],
            ["case file", prov.get("case_file")], ["overrides", " ".join(prov.get("overrides") or []) or "none"],
            ["geometry", json.dumps(spec.get("geometry_source"))]]
    out = table(["item", "value"], rows)
    recs = []
    for e in spec.get("excitations") or []:
        hist = "<br>".join(esc(x) for x in e.get("history") or [])
        recs.append([esc(e.get("stage")), esc(e.get("source") or e.get("motion")), hist])
    if recs:
        out += "<p>Record sources and processing:</p>" + table(["stage", "source", "processing"], recs, raw=True)
    return out


def build_html(run_dir: Path) -> str:
    """The report page of the complete run in ``run_dir`` (draws its figures there)."""
    run = runfolder.load(run_dir)
    d, summary, spec, h = run.folder, run.summary, run.spec, run.h
    case = case_inputs(spec)
    name = summary.get("name") or spec.get("name") or d.name
    body = [f"<h1>drystone run: {esc(name)}</h1>",
            f"<p>{esc(case['description'])}</p>" if case["description"] else "",
            f"<p>Kinds: {esc(', '.join(console.kinds(spec)) or 'none')}. Folder: <code>{esc(d.resolve())}</code>. "
            "Units: SI (m, kg, s, N, J) unless a column says otherwise; displacements relative to the platform "
            "(x along the wall, y out of plane, z up).</p>"]
    lines = console.lines(summary, spec, d)
    body.append(_section("Summary", "<pre>" + "\n".join(
        f'<span class="warn">{esc(x)}</span>' if x.startswith("warning") else esc(x) for x in lines) + "</pre>"))
    assumed = assumed_items(summary, spec, d, case)
    a_html = ('<div class="assumed"><ul>' + "".join(f'<li><span class="flag">ASSUMED</span> {esc(a)}</li>'
                                                    for a in assumed) + "</ul></div>") if assumed else \
        "<p>None declared: no generator assumption, no stand-in record, no case-file comment marked ASSUMED.</p>"
    body.append(_section("ASSUMED inputs", a_html))
    what = (f"<p>Case file: <code>{esc(Path(case['file']).name if case['file'] else '?')}</code> "
            f"({esc(case['file'] or 'unknown path')}); overrides: "
            f"{esc(' '.join(case['overrides']) or 'none')}.</p>")
    what += "<h3>Case inputs</h3>" + (table(["key", "value", "unit", "meaning"], case["rows"]) if case["rows"]
                                       else "<p>The case text is not recorded.</p>")
    if case["text"]:
        what += f"<details><summary>case file text</summary><pre>{esc(case['text'])}</pre></details>"
    what += "<h3>Resolved key parameters (spec.json)</h3>" + table(["quantity", "value", "unit"], key_parameters(spec))
    what += "<h3>Materials</h3>" + materials_table(spec)
    what += "<h3>Stages</h3>" + stages_table(spec)
    what += "<h3>Excitations</h3>" + excitations_table(spec)
    if spec.get("forces"):
        what += "<h3>Applied forces</h3>" + table(["block", "force (N)", "start (s)", "end (s)"],
                                                  [[f.get("block"), json.dumps(f.get("force")), f.get("start"),
                                                    f.get("end")] for f in spec["forces"]])
    body.append(_section("What ran", what))
    res = "<h3>Stones</h3>" + blocks_table(summary)
    res += "<h3>Named contacts</h3>" + contacts_table(summary, spec, h)
    res += "<h3>Control points</h3>" + control_points_table(summary)
    res += "<h3>Energy</h3>" + energy_table(summary, h)
    body.append(_section("Results", res))
    figs = figures(d, spec, summary, h)
    body.append(_section("Figures", "\n".join(image(p, p.name, f"{p.name}: {cap}") for p, cap in figs)))
    body.append(_section("Provenance", provenance_html(spec)))
    return page(f"drystone run {name}", "\n".join(b for b in body if b))


def write(run_dir: Path) -> Path:
    """Write ``report.html`` into a complete run's folder (or, for a study's folder, one
    with a report.md and no spec.json, its report.md as report.html); returns its path.
    NotARun otherwise."""
    d = Path(run_dir)
    if d.is_dir() and not (d / "spec.json").exists() and (d / "report.md").is_file():  # a study's folder
        md = d / "report.md"
        out = md.with_suffix(".html")
        atomic.write_text(out, markdown.html_page(md.read_text(), d))
        return out
    text = build_html(d)
    out = d / "report.html"
    atomic.write_text(out, text)
    return out


def main(argv=None) -> int:
    import argparse
    import sys

    ap = argparse.ArgumentParser(prog="python -m drystone.postprocess.report", description=__doc__.split("\n")[0])
    ap.add_argument("run_dir")
    a = ap.parse_args(argv)
    try:
        print(write(a.run_dir))
    except NotARun as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:  # a full disk, a read-only folder: the file and the system's words
        print(f"error: {exc.filename or a.run_dir}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
