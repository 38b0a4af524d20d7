"""Run the cross-check cases in both engines and keep the numbers in
``results/crosscheck/crosscheck.json`` (updated after every case, so a long ``all`` that
stops half-way keeps what it finished).

Per case: LMGC90 (rigid) at its step dt and, for the small cases, at dt/2 (the time
discretisation's share of the difference to the closed form); the rigid closed forms; this
package at K_n = 2e8 x each factor. Each entry records what it cost (wall-clock seconds,
steps, ms per step).
"""
from __future__ import annotations

import json
import math
import shutil
import time
from pathlib import Path

from drystone import atomic
from drystone import paths
from drystone.studies.crosscheck import VERSION, cases, lmgc90, package

OUT = paths.RESULTS / "crosscheck"
JSON = "crosscheck.json"
FORMAT = "drystone.studies.crosscheck"


def load(out: Path = OUT) -> dict:
    p = Path(out) / JSON
    if p.is_file():
        return json.loads(p.read_text())
    return {"format": FORMAT, "version": 1, "lmgc90": f"compas_lmgc90 {VERSION}", "cases": {}}


def save(data: dict, out: Path = OUT) -> Path:
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    p = out / JSON
    atomic.write_text(p, json.dumps(data, indent=1, default=_jsonable))
    return p


def _jsonable(x):
    try:
        import numpy as np
        if isinstance(x, np.generic):
            return x.item()
        if isinstance(x, np.ndarray):
            return x.tolist()
    except ImportError:  # pragma: no cover
        pass
    raise TypeError(f"not JSON serialisable: {type(x)}")


def key(name: str, variant) -> str:
    return name if variant is None else f"{name}_{variant}"


def _value(cc: cases.CrossCase, engine: str, run: dict):
    """The compared quantity of a finished run (``engine``: lmgc90 or package)."""
    if cc.quantity == "slide_m":
        return cases.slide_m(run["histories"], run["spec"])
    if engine == "lmgc90":
        on = lmgc90.onset_angle(run)
        return None if on is None else on["angle_deg"]
    return run["summary"].get("collapse_angle_deg")


def _make(cc: cases.CrossCase, kn: float, variant):
    return cc.make(kn) if variant is None else cc.make(kn, variant)


def run_lmgc90(cc: cases.CrossCase, folder: Path, variant=None, dt: float | None = None, log=print) -> dict:
    dt = cc.dt if dt is None else dt
    t0 = time.time()
    r = lmgc90.run(_make(cc, cases.KN0, variant), folder, dt=dt, base=cc.base, detection=cc.detection)
    res = r["result"]
    out = {"value": _value(cc, "lmgc90", r), "dt_s": dt, "theta": res["theta"], "base": res["base"],
           "detection": res["detection"], "steps": res["steps"], "ms_per_step": res["ms_per_step"],
           "wall_s": time.time() - t0, "stopped": res["stopped"], "n_bodies": res["n_bodies"],
           "mu": r["model"]["mu"], "law": r["model"]["law"], "folder": str(folder)}
    if cc.quantity == "collapse_angle_deg":
        out["collapse"] = lmgc90.onset_angle(r)
    log(f"[crosscheck] {cc.name}{'' if variant is None else f' {variant}'}: LMGC90 (dt {dt:g} s) "
        f"{cc.quantity} = {_fmt(out['value'])} in {out['wall_s']:.1f} s ({out['steps']} steps, "
        f"{out['ms_per_step']:.3f} ms/step)")
    return {"out": out, "run": r}


def run_package(cc: cases.CrossCase, folder: Path, kn: float, variant=None, log=print) -> dict:
    r = package.run(_make(cc, kn, variant), folder)
    s = r["summary"]
    out = {"kn": kn, "value": _value(cc, "package", r), "dt_s": r["spec"]["dt"], "wall_s": r["wall_s"],
           "steps": int(round(s["run"]["simulated_time_s"] / r["spec"]["dt"])) if "run" in s else None,
           "folder": r["folder"]}
    if cc.quantity == "collapse_angle_deg":
        out["reaction_drop_angle_deg"] = s.get("reaction_drop_angle_deg")
    log(f"[crosscheck] {cc.name}{'' if variant is None else f' {variant}'}: package K_n = {kn:.3g} "
        f"{cc.quantity} = {_fmt(out['value'])} in {out['wall_s']:.1f} s (dt {out['dt_s']:.3g} s)")
    return out


def _fmt(v) -> str:
    return "none" if v is None else f"{v:.6g}"


def run_case(name: str, out: Path = OUT, kn_factors=None, variants=None, package_side: bool = True,
             dt_check: bool | None = None, lmgc90_side: bool = True, log=print) -> dict:
    """Run one case (every variant) in both engines; updates crosscheck.json; returns its
    entries. ``package_side=False``: LMGC90 and the closed forms only (the package runs
    already recorded are kept); ``lmgc90_side=False``: the package only, at ``kn_factors``
    (LMGC90's entry and the package runs at other K_n already recorded are kept)."""
    cc = cases.CASES[name]
    factors = tuple(cc.kn_factors if kn_factors is None else kn_factors)
    dt_check = (name in cases.SMALL) if dt_check is None else dt_check
    data = load(out)
    done = {}
    for variant in (cc.variants if variants is None else variants):
        k = key(name, variant)
        base = Path(out) / "runs" / k
        old = data["cases"].get(k, {})
        entry = {"name": name, "title": cc.title, "variant": variant, "quantity": cc.quantity, "unit": cc.unit}
        if lmgc90_side:
            shutil.rmtree(base / "lmgc90", ignore_errors=True)
            try:
                lm = run_lmgc90(cc, base / "lmgc90", variant, log=log)
                entry["lmgc90"] = lm["out"]
                entry["closed_forms"] = cc.closed_forms(lm["run"]["spec"], [cases.KN0 * f for f in factors],
                                                       lm["run"]["folder"])
                if dt_check:
                    half = run_lmgc90(cc, base / "lmgc90_half_dt", variant, dt=cc.dt / 2, log=log)["out"]
                    entry["lmgc90_half_dt"] = half
            except lmgc90.LMGC90Error as exc:
                entry["lmgc90"] = {"error": str(exc)}
                log(f"[crosscheck] {k}: LMGC90 failed: {exc}")
        else:
            if "lmgc90" not in old:
                raise ValueError(f"{k}: no LMGC90 run recorded in {Path(out) / JSON}: run it first")
            for part in ("lmgc90", "closed_forms", "lmgc90_half_dt"):
                if part in old:
                    entry[part] = old[part]
        entry["package"] = []
        if package_side:
            for f in factors:
                kn = cases.KN0 * f
                folder = base / f"package_kn{kn:.0e}".replace("+", "")
                try:
                    entry["package"].append(run_package(cc, folder, kn, variant, log=log))
                except Exception as exc:  # a failed run is reported, the others go on
                    entry["package"].append({"kn": kn, "error": f"{type(exc).__name__}: {exc}"})
                    log(f"[crosscheck] {k}: package at K_n = {kn:.3g} failed: {exc}")
            if not lmgc90_side:  # keep the runs at the other K_n
                new = {p["kn"] for p in entry["package"]}
                entry["package"] = sorted([p for p in old.get("package", []) if p["kn"] not in new]
                                          + entry["package"], key=lambda p: p["kn"])
        elif old.get("package"):
            entry["package"] = old["package"]
        entry["time"] = time.strftime("%Y-%m-%d %H:%M:%S")
        data = load(out)  # again: another cross-check process may have saved a case meanwhile
        data["cases"][k] = entry
        save(data, out)
        done[k] = entry
    return done


def deficit_slope(kns, values, asymptote) -> float | None:
    """Least-squares slope of log|value - asymptote| against log K_n (the convergence rate;
    -1/3 for the Winkler toppling angle)."""
    pts = [(math.log(k), math.log(abs(v - asymptote))) for k, v in zip(kns, values)
           if v is not None and asymptote is not None and abs(v - asymptote) > 0]
    if len(pts) < 2:
        return None
    n = len(pts)
    mx = sum(p[0] for p in pts) / n
    my = sum(p[1] for p in pts) / n
    sxx = sum((p[0] - mx) ** 2 for p in pts)
    return sum((p[0] - mx) * (p[1] - my) for p in pts) / sxx if sxx > 0 else None
