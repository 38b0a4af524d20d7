"""The paper comparisons with both contact laws: ``penalty_coulomb`` (the paper's incremental
shear force, the default) and ``penalty_coulomb_area`` (the carried shear force scaled with
the contact area where the patch shrinks: drystone/mechanics/contact.py ``carried_share``),
same inputs, one machine, side by side (docs/energy.md).

``python -m drystone.studies.contact_law [--only push,table3,fragility]`` runs, one run at a
time (resumable: a finished run folder is read, not rerun), into results/contact_law/:

* ``push``: the eccentric push, a 1.0 x 0.8 x 1.0 m block (mu 0.6, undamped, K_n 2e8, K_t
  1e8 N/m^3) pushed at its centroid by 3000 N out of plane under a 2 Hz, 2 m/s^2 base sine
  along the push: its heel lifts. Its energy balance error against leapfrog's bound
  ``SHADOW`` (omega_max dt)^2 K_max (omega_max: stability.box_joint_omega_max; tests/tolerances.py BALANCE_SHADOW, derived there);
* ``table3``: cells of the Sacsayhuaman paper's Table 3 (cases/sacsayhuaman/record.toml, the
  records ASSUMED analogues as in the study): the largest out-of-plane residual of any
  stone after the motion has died out (drystone/studies/sacsayhuaman/analysis.py residuals);
* ``fragility``: the fragility study's curves (drystone/studies/fragility) on a subset of its
  plan, ``FRAGILITY``: the same draws of mu and K_n per run, both laws; the medians theta
  of its three damage states. A subset: not the published curves.

The tilt-table wall's angles (``TILT``) were measured with both laws earlier and are
reported, not rerun. It writes results/contact_law/results.json and report.md (``make
docs`` copies report.md's table into docs/energy.md, block ``contact_law``).
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from drystone import atomic
from drystone import paths
from drystone.mechanics import stability

OUT = paths.RESULTS / "contact_law"
LAWS = ("penalty_coulomb", "penalty_coulomb_area")
#: leapfrog's energy bound factor: |B(t) - B(t0)| <= SHADOW (omega_max dt)^2 K_max
#: (tests/tolerances.py BALANCE_SHADOW, where it is derived and measured)
SHADOW = 0.5
#: the Table 3 cells: (record, PGA in g) where the residuals are not trivial
TABLE3_CELLS = (("cusco2023", 1.0), ("ancash1970", 1.0), ("cusco2023", 0.5), ("ancash1970", 1.5))
#: the fragility subset: six of the shortest records of the far-field set (20-30 s) at
#: stripes around the full study's medians (0.8-1.0 g): 18 runs per law, what one core
#: affords in about 15 min a law (two records gave no finite fit)
FRAGILITY = {"record_ids": (1, 2, 9, 12, 17, 21), "stripes_g": (0.6, 0.9, 1.2)}
#: the tilt-table wall, seed 0, stones of varying depth, the tilt study's faster protocol
#: (drystone/studies/tilt group ``seeds``): onset and reaction-drop angles (deg) measured
#: with each law earlier (docs/energy.md), not rerun here
TILT = {"penalty_coulomb": (14.93, 16.01), "penalty_coulomb_area": (14.88, 15.96)}
TILT_EXPERIMENT = "14.33 +- 0.76 deg"
PUSH_SIZE = (1.0, 0.8, 1.0)  # m: along the wall (x), out of plane (y, pushed), height
PUSH = {"force_N": 3000.0, "mu": 0.6, "kn": 2e8, "kt": 1e8, "density": 2300.0, "sine_hz": 2.0, "sine_m_s2": 2.0,
        "sine_s": 0.6, "gravity_s": 0.3}


def push_case(law: str) -> dict:
    """The eccentric push (module docstring): gravity 0.3 s (ramp 0.15 s), the sine 0.6 s,
    rest 0.1 s; the force on from the start."""
    p = PUSH
    geo = {"generator": "boxes_on_platform", "mu": p["mu"], "damping": 0.0, "density": p["density"], "kn": p["kn"],
           "kt": p["kt"], "platform_size": [3.0, 3.0],
           "boxes": [{"id": 1, "center_xy": [0.0, 0.0], "size": list(PUSH_SIZE)}]}
    return {"case": {"name": f"push_{law}", "geometry": geo}, "contact": {"law": law},
            "stages": [{"type": "gravity", "duration": p["gravity_s"], "ramp": p["gravity_s"] / 2},
                       {"type": "excitation", "motion": "sine", "frequency_hz": p["sine_hz"],
                        "amplitude": p["sine_m_s2"], "duration": p["sine_s"], "direction": "y"},
                       {"type": "rest", "duration": 0.1}],
            "forces": [{"block": 1, "force": [0.0, -p["force_N"], 0.0], "start": 0.0}],
            "output": {"interval": 1e-3}}


def _done(folder: Path) -> bool:
    return (folder / "summary.json").is_file()


def _run(case_path, overrides, folder: Path, log) -> float | None:
    """Run a case into ``folder`` unless it is finished there; the wall time (s) of a new run."""
    from drystone import runner

    if _done(folder):
        return None
    log(f"running {folder.relative_to(OUT)}")
    t0 = time.time()
    runner.run(case_path, overrides, out_dir=folder, quiet=True)
    return time.time() - t0


def _wall(folder: Path) -> float | None:
    return json.loads((folder / "summary.json").read_text()).get("wall_time_total_s")


def push(out: Path = OUT, log=print, save=None) -> dict:
    from drystone.postprocess import summary as summ
    from drystone.tomlio import to_toml

    res = {}
    for law in LAWS:
        folder = out / "push" / law
        case = out / "push" / f"{law}.toml"
        case.parent.mkdir(parents=True, exist_ok=True)
        atomic.write_text(case, to_toml(push_case(law)))
        _run(case, [], folder, log)
        h = summ.load_histories(folder)
        spec = json.loads((folder / "spec.json").read_text())
        err = float(np.abs(summ.balance_history(h)).max())
        bound = SHADOW * (stability.box_joint_omega_max(PUSH_SIZE, PUSH["kn"], PUSH["kt"], PUSH["density"]) * spec["dt"]) ** 2 * float(
            h["kinetic"].max())
        res[law] = {"balance_error_J": err, "bound_J": bound, "heel_lift_m": _heel_lift(h, spec),
                    "wall_s": _wall(folder)}
    return res


def _heel_lift(h, spec) -> float:
    """The largest rise (m) of the block's lowest corner from where it was after gravity."""
    from drystone.mechanics import rotations

    verts = np.asarray(next(b for b in spec["blocks"] if b["role"] != "platform")["vertices"], float)
    rel = verts - verts.mean(axis=0)  # the box's corners about its centroid, as built
    r0 = rotations.to_matrix(h["quat0"][-1])
    low = np.array([float((rel @ (rotations.to_matrix(q) @ r0.T).T)[:, 2].min() + x[2])
                    for x, q in zip(h["pos"][:, -1], h["quat"][:, -1])])
    k = int(np.searchsorted(h["t"], PUSH["gravity_s"] - 1e-9))  # the end of gravity
    return float(low[k:].max() - low[k])


def table3(out: Path = OUT, log=print, save=None) -> dict:
    from drystone.studies.sacsayhuaman import analysis as an

    case = paths.CASES / "sacsayhuaman" / "record.toml"
    res = {}
    for rec, pga in TABLE3_CELLS:
        cell = {}
        for law in LAWS:
            folder = out / "table3" / f"{rec}-{pga:g}g" / law
            _run(case, [f"stages.1.record={rec}", f"stages.1.pga_g={pga}", f"contact.law={law}"], folder, log)
            r = an.residuals(folder)
            cell[law] = {"max_out_of_plane_mm": 1e3 * r["max_out_of_plane_m"], "stones": r["stones"],
                         "collapsed": r["collapsed"], "all_collapsed": r["all_collapsed"], "settled": r["settled"],
                         "wall_s": _wall(folder)}
        res[f"{rec} {pga:g} g"] = cell
        if save:  # each finished cell
            save(res)
    return res


def fragility(out: Path = OUT, log=print, save=None) -> dict:
    from drystone.analyses import fragility as analysis
    from drystone.studies.fragility import plan as planmod
    from drystone.studies.fragility import study

    res = {}
    for law in LAWS:
        cfg = planmod.Config(name=f"contact_law_{law}", out=f"contact_law/fragility/{law}",
                             record_ids=FRAGILITY["record_ids"], stripes_g=FRAGILITY["stripes_g"],
                             notes=(f"a subset of the full plan run with contact.law = {law} "
                                    "(drystone/studies/contact_law.py): not the published curves",))
        folder = out / "fragility" / law
        p = planmod.load_plan(planmod.write(cfg, folder).parent)
        analysis.fragility(planmod.CASE, p["analysis"]["records"], method="stripes", levels=p["analysis"]["levels_g"],
                           n_boot=cfg.n_boot, seed=cfg.seed, component=cfg.component,
                           overrides=list(p["common_overrides"]) + [f"contact.law={law}"],
                           draws_given=planmod.draws(p), out=planmod.analysis_dir(folder), workers=1, log=log)
        d = study.fit_step(cfg, folder)
        wall = sum(float(r.get("wall_s") or r.get("yade_wall_s") or 0.0) for r in d["rows"])
        res[law] = {"runs": d["runs"], "wall_s": wall,
                    "theta_g": {n: (e["fit"] or {}).get("theta") for n, e in d["fits"].items()},
                    "beta": {n: (e["fit"] or {}).get("beta") for n, e in d["fits"].items()},
                    "no_fit": {n: e.get("reason") for n, e in d["fits"].items() if not e["fit"]},
                    "max_out_of_plane_mm": {r["name"]: r.get("max_out_of_plane_mm") for r in d["rows"]},
                    "states": {r["name"]: [k for k in ("DS1", "DS2", "DS3") if r.get(k)] for r in d["rows"]}}
        if save:
            save(res)
    return res


STEPS = {"push": push, "table3": table3, "fragility": fragility}


def _mm(c: dict) -> str:
    if c["all_collapsed"]:
        return "collapse (all)"
    s = f"{c['max_out_of_plane_mm']:.1f} ({', '.join(map(str, c['stones']))})"
    if c["collapsed"]:
        s += f", {len(c['collapsed'])} collapsed"
    return s + ("" if c["settled"] in (True, None) else " ‡")


def _fmm(v) -> str:
    return "-" if v is None else f"{v:.1f}"


def report(data: dict) -> str:
    """The before/after table (Markdown)."""
    a, b = LAWS
    rows = [f"| comparison | `{a}` (default) | `{b}` | reference |", "|---|---|---|---|"]
    rows.append(f"| tilt-table wall, seed 0, stones of varying depth: onset; reaction drop (measured earlier, not "
                f"rerun) | {TILT[a][0]:.2f}; {TILT[a][1]:.2f} deg | {TILT[b][0]:.2f}; {TILT[b][1]:.2f} deg | "
                f"experiment {TILT_EXPERIMENT} |")
    paper = _paper_table3()
    for cell, c in data.get("table3", {}).items():
        rows.append(f"| Table 3, {cell} (ASSUMED record analogue): largest out-of-plane residual, mm (stones) | {_mm(c[a])} | "
                    f"{_mm(c[b])} | paper {paper.get(cell, '-')} |")
    f = data.get("fragility") or {}
    if all(law in f for law in LAWS):
        for ds in ("DS1", "DS2", "DS3"):
            def th(law):
                t = f[law]["theta_g"].get(ds)
                return f"{t:.3g} g (beta {f[law]['beta'][ds]:.2g})" if t else f"no fit ({f[law]['no_fit'].get(ds)})"
            n = sum(f[a]["runs"].values())
            rows.append(f"| fragility median {ds}, subset: far-field records {FRAGILITY['record_ids']} x "
                        f"{', '.join(f'{s:g}' for s in FRAGILITY['stripes_g'])} g ({n} runs each) | {th(a)} | {th(b)} | "
                        f"full study (220 runs, default law): [beyond the papers](beyond-the-papers.md#fragility-curves) |")
        differ = [r for r in f[a]["states"] if f[a]["states"][r] != f[b]["states"].get(r)]
        sa, sb = f[a]["max_out_of_plane_mm"], f[b]["max_out_of_plane_mm"]
        def per_run(law, mm):
            return ", ".join("C" if "DS3" in f[law]["states"].get(r, ()) else _fmm(mm.get(r)) for r in sa)
        rows.append(f"| fragility subset: runs whose damage states differ; the largest residual (mm) per run, C: "
                    f"collapse | {len(differ)} of {len(f[a]['states'])}; {per_run(a, sa)} | {per_run(b, sb)} | "
                    "in the plan's order (record by record, stripes increasing) |")
    p = data.get("push") or {}
    if all(law in p for law in LAWS):
        rows.append(f"| eccentric push, 1.0 x 0.8 x 1.0 m block, 3000 N at the centroid, mu 0.6, undamped, 2 Hz 2 m/s^2 "
                    f"sine: balance error (J) | {p[a]['balance_error_J']:.3g} | {p[b]['balance_error_J']:.3g} | "
                    f"bound {p[a]['bound_J']:.3g} ({p[b]['bound_J']:.3g}) |")
    cost = []
    for step in ("table3", "fragility", "push"):
        if step in data:
            w = [c[law]["wall_s"] for c in data[step].values() for law in c] if step == "table3" else \
                [e["wall_s"] for e in data[step].values()]
            w = [x for x in w if x]
            if w:
                cost.append(f"{step} {sum(w) / 60:.1f} min")
    return ("# The contact laws side by side\n\n" + "\n".join(rows) + "\n\n"
            + "Wall time on this machine (one run at a time, 1 thread, other load included): " + ", ".join(cost)
            + ". ‡: not settled within the rest stage.\n")


def _paper_table3() -> dict:
    """The paper's Table 3 cells ('cusco2023 1 g' -> '20.0 mm (35)'), data/papers/sacsayhuaman.toml."""
    from drystone.postprocess import compare

    t3 = compare.paper("sacsayhuaman")["table3"]
    out = {}
    for rec, _ in TABLE3_CELLS:
        for pga, mm, st in zip(t3["pga_g"], t3[f"{rec}_mm"], t3[f"{rec}_stones"]):
            out[f"{rec} {float(pga):g} g"] = f"{mm} ({st})" if isinstance(mm, str) else f"{mm} mm ({st})"
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m drystone.studies.contact_law", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--only", default=",".join(STEPS), help=f"comma-separated steps of {', '.join(STEPS)}")
    a = ap.parse_args(argv)
    steps = [s.strip() for s in a.only.split(",") if s.strip()]
    bad = [s for s in steps if s not in STEPS]
    if bad:
        print(f"error: --only: unknown step(s) {bad} (known: {', '.join(STEPS)})")
        return 2
    OUT.mkdir(parents=True, exist_ok=True)
    path = OUT / "results.json"
    data = json.loads(path.read_text()) if path.is_file() else {}
    for s in steps:
        def save(part, s=s):
            data[s] = part
            atomic.write_text(path, json.dumps(data, indent=1, default=str) + "\n")
            atomic.write_text(OUT / "report.md", report(data))

        save(STEPS[s](OUT, save=save))
    text = report(data)
    atomic.write_text(OUT / "report.md", text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
