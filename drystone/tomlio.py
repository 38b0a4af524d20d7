"""TOML writing (the one home for it): case dicts and sweep files. Reading is tomllib."""
from __future__ import annotations

import json
import math


def value(v) -> str:
    """One TOML value: bool, string, number (inf), inline table or array."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, float) and math.isinf(v):
        return "inf" if v > 0 else "-inf"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k} = {value(x)}" for k, x in v.items()) + "}"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(value(x) for x in v) + "]"
    return repr(v)


def sweep_file(name: str, case, runs, common=(), header: str = "") -> str:
    """A sweep file (drystone/sweep.py): base ``case`` path, ``common`` overrides and
    ``runs`` as (run name, [overrides]) or (run name, [overrides], out folder)."""
    lines = ([f"# {header}"] if header else []) + ["[sweep]", f"name = {value(name)}", f"case = {value(str(case))}",
                                                   f"set = {value(list(common))}", ""]
    for rn, sets, *out in runs:
        lines += ["[[runs]]", f"name = {value(rn)}", *(f"out = {value(o)}" for o in out), f"set = {value(list(sets))}", ""]
    return "\n".join(lines)


def to_toml(d: dict) -> str:
    """Minimal TOML writer for case dicts (tables, arrays of tables, scalars, lists)."""
    lines = []
    scalar = value

    for sec, body in d.items():
        if isinstance(body, list):
            for item in body:
                lines.append(f"[[{sec}]]")
                lines += [f"{k} = {scalar(v)}" for k, v in item.items()]
                lines.append("")
        elif sec == "materials":
            for name, m in body.items():
                lines.append(f"[materials.{name}]")
                lines += [f"{k} = {scalar(v)}" for k, v in m.items()]
                lines.append("")
        else:
            lines.append(f"[{sec}]")
            lines += [f"{k} = {scalar(v)}" for k, v in body.items()]
            lines.append("")
    return "\n".join(lines)


def stage_durations(durations: dict, windows: tuple = ()) -> list[str]:
    """Case overrides setting stage durations, ``stages.K.duration=V`` (s), for each stage
    index K of ``durations`` whose value is given (None or 0 leaves that stage as it is):
    the studies' shortened records and rests. A rest stage K in ``windows`` gets its
    ``settle_window`` set to that duration too (a rest cut below the case's window, which the
    case check refuses: it then ends by its duration unless the blocks were quiet throughout)."""
    return [f"stages.{k}.{key}={value(float(d))}" for k, d in durations.items() if d
            for key in (("duration", "settle_window") if k in windows else ("duration",))]
