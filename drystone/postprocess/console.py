"""What a finished run prints on the console: a few plain lines by the kind of run, with units.

``lines(summary, spec, out_dir)`` reads only the run's summary.json and spec.json dicts (no
histories, no YADE) and returns the lines ``python -m drystone run`` prints at the end (its
``--json`` flag keeps the old machine output) and the run report repeats
(drystone/postprocess/report.py). The kinds come from the spec's stages (a run may have
several): an *excitation* run says its largest residual displacement and its stones, the
collapsed stones and whether the settle criterion was reached; a *tilt* run its onset and
reaction-drop angles (deg) and the stone that moved first; a *gravity* or *settlement*
run the penetration and slip of the named contacts (``[analysis]``). Every run says its
simulated time, steps and wall time, its warnings (motion not settled, stones that left
the model, contact integration beyond its stability limit) and its results folder.
Lengths in mm, angles in deg, times in s, forces in N, energies in J.
"""
from __future__ import annotations

from drystone.model.spec import stage_type

#: how many stones a line names before it says "..."
MAX_IDS = 20
#: how many stones the residual line ranks
TOP_RESIDUALS = 3


def kinds(spec: dict) -> list[str]:
    """The run's kinds in stage order, each once: ``gravity``, ``settlement``, ``tilt``,
    ``excitation`` (``rest`` is no kind of its own)."""
    out = []
    for st in spec.get("stages", []):
        k = stage_type(st)
        if k != "rest" and k not in out:
            out.append(k)
    return out


def _mm(x) -> str:
    return "n/a" if x is None else f"{1e3 * x:.4g} mm"


def _ids(ids) -> str:
    ids = list(ids)
    return ", ".join(str(i) for i in ids[:MAX_IDS]) + (", ..." if len(ids) > MAX_IDS else "")


def _stages_line(spec: dict) -> str:
    return "stages: " + "; ".join(f"{stage_type(st)} {st['start']:g}-{st['end']:g} s" for st in spec["stages"])


def run_lines(summary: dict) -> list[str]:
    """Simulated time, steps and wall time (s)."""
    r = summary.get("run", {})
    wall = f"{r['wall_time_s']:.1f} s wall" if r.get("wall_time_s") is not None else "wall time n/a"
    total = summary.get("wall_time_total_s")
    if total is not None:
        wall += f" ({total:.1f} s with checks and post-processing)"
    return [f"{summary.get('name', '?')}: {r.get('simulated_time_s', float('nan')):.3f} s simulated in "
            f"{r.get('steps', 0)} steps of {r.get('dt_s', float('nan')):.3g} s, {wall}"]


def contact_lines(summary: dict, spec: dict) -> list[str]:
    """Penetration (mm, N) and first gross slip (s, N, deg) of the analysed contacts."""
    an = spec.get("analysis") or {}
    out = []
    name = an.get("penetration")
    if name:
        pen = {k: v for k, v in summary.items() if k.startswith("penetration_") and k.endswith("_m")}
        kin = next((v for k, v in pen.items() if not k.endswith("_contact_m")), None)
        vol = next((v for k, v in pen.items() if k.endswith("_contact_m")), None)
        fn = next((v for k, v in summary.items() if k.startswith("normal_force_") and k.endswith("_N")), None)
        line = f"contact {name}: penetration {_mm(kin)} (relative normal displacement)"
        if vol is not None:
            line += f", {_mm(vol)} (overlap volume / area)"
        if fn is not None:
            line += f", normal force {fn:.4g} N"
        out.append(line)
    name = an.get("slip")
    if name:
        if summary.get("slip_time_s") is None:
            out.append(f"contact {name}: no gross slip (relative sliding stayed below 1 mm)")
        else:
            ratio = summary.get("slip_force_ratio")
            line = (f"contact {name}: slips at t = {summary['slip_time_s']:.3f} s, "
                    f"F_t = {summary['slip_force_N']:.4g} N, "
                    f"F_n = {summary['slip_normal_force_N']:.4g} N, F_t/F_n = "
                    + ("n/a" if ratio is None else f"{ratio:.4g}"))
            if summary.get("slip_tilt_deg") is not None:
                line += f", block {an.get('tilt_block')} tilted {summary['slip_tilt_deg']:.3f} deg"
            out.append(line)
    return out


def tilt_lines(summary: dict, spec: dict) -> list[str]:
    """Collapse onset and reaction-drop angles (deg), the stone that moved first."""
    col = summary.get("collapse")
    tilts = [st for st in spec["stages"] if stage_type(st) == "tilt"]
    if not col:
        top = max((st["params"].get("max_deg") or st["params"].get("to_deg") or 0.0) for st in tilts) if tilts else None
        return ["tilt: no collapse" + (f" up to {top:g} deg" if top else "")]
    onset_block = col.get("onset_block")
    out = [f"tilt: collapse onset at {col['angle_deg']:.2f} deg (t = {col['time_s']:.3f} s"
           + (f", stone {onset_block} first" if onset_block is not None else "") + ")"]
    rd = col.get("reaction_drop") or {}
    drop = rd.get("drop")
    what = f"reaction drop ({100 * drop:g} % of the moving stones' weight)" if drop is not None else "reaction drop"
    if col.get("reaction_drop_angle_deg") is not None:
        out.append(f"tilt: {what} at {col['reaction_drop_angle_deg']:.2f} deg "
                   f"(t = {rd.get('time_s', float('nan')):.3f} s)")
    else:
        low = rd.get("min_fraction")
        out.append(f"tilt: {what} not reached before the run stopped"
                   + (f" (lowest reaction {100 * low:.1f} % of the weight)" if low is not None else ""))
    if col.get("detected_angle_deg") is not None:
        out.append(f"tilt: detected at {col['detected_angle_deg']:.2f} deg ({col.get('criterion', '?')}), "
                   f"first stones {_ids(col.get('first_blocks') or [])}")
    return out


def excitation_lines(summary: dict) -> list[str]:
    """Each excitation (motion, PGA g, direction), the largest residual displacements (mm)
    and their stones, the collapsed stones, the settle criterion."""
    out = []
    for e in (summary.get("inputs") or {}).get("excitations") or []:
        what = e.get("motion", "?")
        if what == "record":
            cat = (e.get("info") or {}).get("catalogue") or {}
            what = (f"record {e.get('record')}" + (f" ({e.get('event')}, {e.get('station')} {e.get('component')})"
                                                     if e.get("event") else "")
                    + (" ASSUMED analogue" if cat.get("source_kind") == "analogue"
                       or "analogue of" in str(e.get("event") or "") else ""))
        elif what == "sine":
            info = e.get("info") or {}
            if info.get("frequency_hz") is not None:
                what = f"sine {info['frequency_hz']:g} Hz"
        pga = e.get("pga_g")
        out.append(f"excitation (stage {e.get('stage', '?')}): {what}, PGA "
                   + ("n/a" if pga is None else f"{pga:.3g} g") + f" along {e.get('direction', '?')}")
    blocks = summary.get("blocks") or {}
    bounded = [(b, r["residual_displacement_norm_m"]) for b, r in blocks.items()
               if r.get("residual_displacement_norm_m") is not None]
    bounded.sort(key=lambda x: (-x[1], int(x[0]) if str(x[0]).isdigit() else 0))
    if bounded:
        top = bounded[0][1]
        tied = [b for b, v in bounded if v == top]
        line = f"largest residual displacement: {_mm(top)} (3D), stone {_ids(tied)}"
        rest = [(b, v) for b, v in bounded if b not in tied][: TOP_RESIDUALS - 1]
        if rest:
            line += "; next: " + ", ".join(f"stone {b} {_mm(v)}" for b, v in rest)
        out.append(line)
        dirs = {e.get("direction") for e in (summary.get("inputs") or {}).get("excitations") or []}
        for d in sorted(x for x in dirs if x in ("x", "y", "z")):
            j = "xyz".index(d)
            comp = [(b, blocks[b]["residual_displacement_m"][j]) for b, _ in bounded]
            b, v = max(comp, key=lambda x: abs(x[1]))
            out.append(f"largest residual along {d} (the excitation's direction): {_mm(v)}, stone {b}")
    else:
        out.append("largest residual displacement: none (no stone has a bounded motion)")
    collapsed = sorted((b for b, r in blocks.items() if r.get("collapsed")),
                       key=lambda b: int(b) if str(b).isdigit() else 0)
    def why(b):
        w = blocks[b].get("collapse_why")
        return f"{b} {'+'.join(w)}" if w else str(b)

    out.append(f"collapsed stones (left the model, fell, overturned or out of plane): {len(collapsed)} of "
               f"{len(blocks)}" + (f" ({', '.join(why(b) for b in collapsed[:MAX_IDS])}"
                                   + (", ..." if len(collapsed) > MAX_IDS else "") + ")" if collapsed else ""))
    sliding = [b for b, r in blocks.items() if r.get("in_plane_sliding")]
    if sliding:
        out.append(f"in-plane sliding (damage, not collapse): stone {_ids(sliding)}")
    beyond = [b for b, r in blocks.items() if r.get("beyond_displacement_threshold") and not r.get("collapsed")]
    if beyond:
        out.append(f"standing stones with a residual displacement beyond the displacement threshold (damage): "
                   f"{_ids(beyond)}")
    settle = (summary.get("run") or {}).get("settle")
    if settle is None:
        out.append("settle criterion: none (the last stage ran its full length)")
    elif settle.get("reached"):
        out.append(f"settle criterion reached at t = {settle['time_s']:.3f} s (kinetic energy below "
                   f"{settle['threshold_J']:.3g} J for {settle['window_s']:g} s)")
    else:
        end = settle.get("time_s") or (summary.get("run") or {}).get("simulated_time_s")
        ke = settle.get("final_kinetic_J")
        out.append("settle criterion NOT reached" + (f" by t = {end:.3f} s" if end is not None else "")
                   + " (kinetic energy " + ("n/a" if ke is None else f"{ke:.3g} J")
                   + f" at the end, threshold {settle['threshold_J']:.3g} J)")
    return out


def energy_lines(summary: dict) -> list[str]:
    """The energy balance error (J, relative) when the summary has it."""
    e = summary.get("energy")
    if not isinstance(e, dict) or e.get("balance_error_J") is None:
        return []
    rel = e.get("balance_error_rel")
    return [f"energy balance error: {e['balance_error_J']:.3g} J"
            + (f" ({100 * rel:.3g} % relative)" if rel is not None else "")]


def warnings(summary: dict) -> list[str]:
    """Lines starting ``warning:``: motion not settled, stones that left the model, a site
    response that did not converge, contact integration beyond its stability limit."""
    r = summary.get("run") or {}
    out = []
    settle = r.get("settle")
    if settle is not None and not settle.get("reached"):
        out.append("warning: the motion had not settled when the run ended (run.settle): residuals may still change")
    left = r.get("left_model") or {}
    if left.get("count"):
        out.append(f"warning: {left['count']} of {left.get('free_blocks', '?')} free stone(s) left the model "
                   f"({_ids(b['block'] for b in left.get('blocks', []))}): their motion is unbounded and has no "
                   "residual (run.left_model)")
    for e in (summary.get("inputs") or {}).get("excitations") or []:
        if (e.get("site") or {}).get("warning"):
            out.append(f"{e['site']['warning']} (stage {e.get('stage', '?')}; inputs.excitations.site)")
    cs = r.get("contact_stability")
    if cs and not cs.get("within"):
        out.append(f"warning: contact integration beyond its stability limit (omega dt {cs['max_omega_dt']:.3g} > "
                   f"{cs['limit']:.3g}; run.contact_stability): lower time.safety")
    return out


def lines(summary: dict, spec: dict, out_dir=None) -> list[str]:
    """The console summary of a finished run (see the module's docstring)."""
    out = run_lines(summary) + [_stages_line(spec)]
    ks = kinds(spec)
    if "excitation" in ks:
        out += excitation_lines(summary)
    if "tilt" in ks:
        out += tilt_lines(summary, spec)
    for st in spec["stages"]:
        if stage_type(st) == "settlement":
            out.append(f"settlement: block {st['params'].get('block')} lowered by "
                       f"{_mm(st['params'].get('displacement'))} over {st['start']:g}-{st['end']:g} s")
    out += contact_lines(summary, spec)
    if not ({"excitation", "tilt"} & set(ks)) and not (spec.get("analysis") or {}).get("penetration") \
            and not (spec.get("analysis") or {}).get("slip"):
        blocks = summary.get("blocks") or {}
        moved = [(b, r["residual_displacement_norm_m"]) for b, r in blocks.items()
                 if r.get("residual_displacement_norm_m") is not None]
        if moved:
            b, v = max(moved, key=lambda x: x[1])
            out.append(f"largest displacement at the end: {_mm(v)}, stone {b}")
    out += energy_lines(summary)
    out += warnings(summary)
    if out_dir is not None:
        out.append(f"results: {out_dir}")
    return out
