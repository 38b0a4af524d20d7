"""Case files (TOML): every key declared once, with default, unit and meaning.

``load(path, overrides)`` reads a case, applies ``--set key=value`` overrides, refuses
unknown keys, fills defaults and checks values, raising CaseError naming the file and
key. ``python -m drystone keys`` prints the table below and the stage types' keys
(drystone/model/stages.py; README points to it).
"""
from __future__ import annotations

import copy
import dataclasses
import math
import re
import tomllib
from pathlib import Path

from drystone import inputfiles
from drystone.geometry.blockfile import CONTACT_PROPERTIES, MATERIAL_PROPERTIES
from drystone.model.keys import REQUIRED, CaseError, Key  # noqa: F401 (casemod.CaseError: callers read them here)
from drystone.mechanics import collapse, laws
from drystone.model.loads import REGISTRY as LOAD_TYPES
from drystone.model.stages import REGISTRY as STAGE_TYPES
from drystone.units import GRAVITY

# -- the declaration --------------------------------------------------------------
_PROPERTY = {  # each material property (the names: blockfile.MATERIAL_PROPERTIES)
    "density": Key(None, "kg/m^3", "density", float, positive=True),
    "kn": Key(None, "N/m^3", "normal stiffness per unit area", float, positive=True),
    "kt": Key(None, "N/m^3", "tangential stiffness per unit area", float, positive=True),
    "mu": Key(None, "-", "friction coefficient", float, nonneg=True),
    "damping": Key(None, "-", "contact damping, fraction of critical", float, nonneg=True)}
#: [materials.NAME]: any material property of that material
MATERIAL_OVERRIDE = {k: _PROPERTY[k] for k in MATERIAL_PROPERTIES}
_EVERY = {"kn": "K_n", "kt": "K_t", "mu": "the friction coefficient",
          "damping": "the contact damping (fraction of critical)"}
#: [contact]: a contact property of every material
CONTACT_OVERRIDE = {k: dataclasses.replace(_PROPERTY[k], meaning=f"override {_EVERY[k]} of every material")
                    for k in CONTACT_PROPERTIES}

SECTIONS: dict[str, dict[str, Key]] = {
    "case": {
        "name": Key(None, "-", "case name, one folder name (letters, digits, _ . + -, at most 100 characters, "
                    "no '/'); results go to results/<name>/ (default: file stem)", str),
        "description": Key("", "-", "free text", str),
        "geometry": Key(REQUIRED, "-", "block file (path relative to the case file) or a table "
                        "{generator = NAME, ...parameters}", (str, dict)),
    },
    "contact": {
        "law": Key(laws.DEFAULT, "-", " or ".join(f"{n} ({law.meaning})" for n, law in laws.REGISTRY.items())
                   + " (drystone/mechanics/laws.py)", str, tuple(laws.REGISTRY)),
        "detection": Key("auto", "-", "contact geometry: native (drystone/mechanics/overlap.py: exact overlap volume, "
                         "normal and area from its gradient, compiled; the project's laws only), yade (YADE's "
                         "polyhedra intersection, CGAL) or auto (native with the project's laws, yade with the "
                         "stock law)", str, ("auto", "native", "yade")),
        **CONTACT_OVERRIDE,
    },
    "time": {
        "step": Key("auto", "s", "time step, or 'auto' = safety x the critical step of the stiffest "
                    "contact; a step above the critical one is refused", (float, str)),
        "safety": Key(0.5, "-", "safety factor in (0, 1] applied to the critical step when step = 'auto'", float,
                      positive=True),
    },
    "physics": {
        "gravity": Key(GRAVITY, "m/s^2", "gravitational acceleration", float, positive=True),
    },
    "output": {
        "interval": Key(0.01, "s", "time between recorded samples", float, positive=True),
        "contacts": Key([], "-", "named contacts to record: list of {name, blocks = [a, b]}", list),
        "collapse_displacement": Key("auto", "m", "a block whose residual displacement exceeds this is reported "
                                     "beyond the displacement threshold (damage, not collapse: collapse is the "
                                     "rule of drystone/mechanics/collapse.py), and a tilt run stops once a block "
                                     "moved this far; 'auto' = half the block's smallest dimension", (float, str)),
        "onset_rate": Key(collapse.RATE_M_PER_DEG, "m/deg", "in a tilt, a block that moves more than this "
                          "per degree of tilt (over onset_window) is moving: the collapse angle is the tilt "
                          "where the motion that led to collapse began (drystone/mechanics/collapse.py)", float,
                          positive=True),
        "onset_window": Key(collapse.WINDOW_DEG, "deg", "tilt over which the onset rate is measured (filters "
                            "vibrations)", float, positive=True),
        "stop_when_fallen": Key(False, "-", "stop the run at the first sample after gravity at which a stone is "
                                "certain to have collapsed: it left the model or fell (its centroid dropped by "
                                "more than half its height; drystone/mechanics/monitors.py Fallen); the "
                                "collapse analysis sets it (a collapsed run needs no more)", bool),
    },
    "analysis": {
        "penetration": Key(None, "-", "name of a recorded contact whose final normal penetration is "
                           "reported as penetration_<name>_m", str),
        "slip": Key(None, "-", "name of a recorded contact whose first slip is reported "
                    "(slip_time_s, slip_force_N, slip_normal_force_N, slip_tilt_deg)", str),
        "tilt_block": Key(None, "-", "block whose tilt (deg) is recorded for the slip report", int),
    },
}
# the keys of each stage type ([[stages]] type = ...) are declared with it: drystone/model/stages.py,
# and of each load type ([[loads]] type = ...) with it: drystone/model/loads.py


def _kinds(spec: Key) -> tuple:
    return spec.kind if isinstance(spec.kind, tuple) else (spec.kind,)


def _check_value(where: str, key: str, spec: Key, value):
    kinds = _kinds(spec)
    names = "/".join(k.__name__ for k in kinds)
    if isinstance(value, bool) and bool not in kinds:  # bool is an int subclass: true is not 1
        raise CaseError(f"{where}: '{key}' must be of type {names}, got {value!r} (bool)")
    if float in kinds and isinstance(value, int) and not isinstance(value, bool):
        value = float(value)
    if not isinstance(value, kinds):
        raise CaseError(f"{where}: '{key}' must be of type {names}, got {value!r} ({type(value).__name__})")
    if spec.choices and value not in spec.choices:
        raise CaseError(f"{where}: '{key}' must be one of {list(spec.choices)}, got {value!r}")
    if isinstance(value, float):
        if not math.isfinite(value):
            raise CaseError(f"{where}: '{key}' must be finite, got {value!r}")
        if spec.positive and value <= 0:
            raise CaseError(f"{where}: '{key}' must be > 0, got {value!r}")
        if spec.nonneg and value < 0:
            raise CaseError(f"{where}: '{key}' must be >= 0, got {value!r}")
    return value


def _fill(where: str, table: dict, keys: dict[str, Key]) -> dict:
    if not isinstance(table, dict):
        raise CaseError(f"{where}: must be a table of keys ({sorted(keys)}), got {table!r}")
    unknown = sorted(set(table) - set(keys))
    if unknown:
        raise CaseError(f"{where}: unknown key(s) {unknown}; allowed: {sorted(keys)}")
    out = {}
    for name, spec in keys.items():
        if name in table:
            out[name] = _check_value(where, name, spec, table[name])
        elif spec.default is REQUIRED:
            raise CaseError(f"{where}: missing required key '{name}'")
        else:
            out[name] = copy.deepcopy(spec.default)
    return out


FORCE = {"block": Key(REQUIRED, "-", "id of the free block the force acts on (at its centroid)", int),
         "force": Key(REQUIRED, "N", "force vector [fx, fy, fz] in the platform frame", list),
         "start": Key(0.0, "s", "time the force is switched on", float, nonneg=True),
         "end": Key(None, "s", "time it is switched off (default: never)", float, positive=True)}


def _parse_value(text: str, where: str, item: str):
    try:
        value = tomllib.loads(f"v = {text}")["v"]
    except (ValueError, RecursionError):  # not a TOML value (TOMLDecodeError is a ValueError)
        return text  # a bare string
    inputfiles.check_values(value, f"{where}: override {item!r}", CaseError)
    return value


def _index(node: list, part: str, dotted: str, bad) -> int:
    """Index of ``part`` in the list at ``dotted`` (stages, forces: counted from 0)."""
    n = len(node)
    span = f"{dotted}.0 .. {dotted}.{n - 1}" if n else "none"
    if not (part.isascii() and part.isdigit()):
        named = [k for k, x in enumerate(node) if isinstance(x, dict) and x.get("name") == part]
        if named:
            return named[0]
        names = [x["name"] for x in node if isinstance(x, dict) and isinstance(x.get("name"), str)]
        raise bad(f"{dotted} are addressed by index from 0 ({span}; {dotted}.0 is the first)"
                  + (f" or by name ({', '.join(names)})" if names else "") + f", not {part!r}")
    if int(part) >= n:
        raise bad(f"there are {n} {dotted} ({span}; {dotted}.0 is the first): no {dotted}.{part}")
    return int(part)


def _declared(parts: list[str]) -> Key | None:
    """The declaration of ``section.key``, if ``parts`` names one."""
    return SECTIONS.get(parts[0], {}).get(parts[1]) if len(parts) == 2 else None


def apply_overrides(data: dict, overrides: list[str], where: str) -> dict:
    """Apply ``key.path=value`` overrides (values in TOML syntax, bare words as strings).
    Arrays of tables are addressed by index from 0: ``stages.1.duration`` is the second
    stage's. A path into a scalar, past the end of an array, or replacing a table by a
    scalar raises CaseError naming the override."""
    data = copy.deepcopy(data)
    if isinstance(overrides, str) or not all(isinstance(o, str) for o in overrides):
        raise CaseError(f"{where}: overrides must be a list of 'key=value' strings, got {overrides!r}")
    for item in overrides:
        if "=" not in item:
            raise CaseError(f"{where}: override {item!r} is not of the form key=value")
        path, text = item.split("=", 1)
        parts = [q.strip() for q in path.split(".")]

        def bad(why, item=item):
            return CaseError(f"{where}: override {item!r}: {why}")

        if not all(parts):
            raise bad("empty key (expected a dotted path such as time.step or stages.1.duration)")
        value = _parse_value(text.strip(), where, item)
        node = data
        for depth, part in enumerate(parts):
            dotted = ".".join(parts[:depth])
            key = _index(node, part, dotted, bad) if isinstance(node, list) else part
            here = ".".join(parts[:depth + 1])
            spec = _declared(parts[:depth + 1])
            if depth == len(parts) - 1:  # the key to set
                old = node[key] if isinstance(node, list) else node.get(key)
                allowed = spec is not None and isinstance(value, _kinds(spec))
                if depth == 0 and not isinstance(value, (dict, list)):
                    raise bad(f"{here} is a section: set its keys ({here}.KEY=value), not {value!r}")
                if isinstance(old, (dict, list)) and not isinstance(value, type(old)) and not allowed:
                    what = "a table" if isinstance(old, dict) else "an array"
                    raise bad(f"{here} is {what}: set its keys ({here}.KEY=value), not {value!r}")
                node[key] = value
            elif isinstance(node, dict) and key not in node:
                if spec is not None and dict not in _kinds(spec):
                    raise bad(f"{here} is a {'/'.join(k.__name__ for k in _kinds(spec))}, not a table: "
                              f"it has no key {parts[depth + 1]!r}")
                node = node.setdefault(key, {})
            elif isinstance(node[key], (dict, list)):
                node = node[key]
            else:
                raise bad(f"{here} is {node[key]!r}, not a table: it has no key {parts[depth + 1]!r}")
    return data


def load(path, overrides: list[str] | None = None, sweep_run: bool = False) -> dict:
    """Read, override, validate and complete a case file. Returns a plain dict with every
    section filled (``stages`` a list of dicts with a ``type``). ``sweep_run``: the name
    may be ``<sweep>/<run>`` (drystone/sweep.py names its runs so; ``check_name``)."""
    p = Path(path)
    raw = inputfiles.load_toml(p, CaseError, "case file")
    raw = apply_overrides(raw, overrides or [], str(p))
    return validate(raw, str(p), p.parent, p.stem, sweep_run)


def validate(raw: dict, where: str, base_dir: Path, stem: str = "case", sweep_run: bool = False) -> dict:
    allowed = set(SECTIONS) | {"stages", "materials", "forces", "loads"}
    unknown = sorted(set(raw) - allowed)
    if unknown:
        raise CaseError(f"{where}: unknown section(s) {unknown}; allowed: {sorted(allowed)}")
    case = {name: _fill(f"{where} [{name}]", raw.get(name, {}), keys) for name, keys in SECTIONS.items()}
    if case["case"]["name"] is None:
        case["case"]["name"] = stem
    check_name(f"{where}: [case] 'name'", case["case"]["name"], nested=sweep_run)
    if case["time"]["safety"] > 1:
        raise CaseError(f"{where}: [time] 'safety' must be in (0, 1] (the step is safety x the critical step; "
                        f"above 1 the integration is unstable), got {case['time']['safety']!r}")
    geo = case["case"]["geometry"]
    if isinstance(geo, str):
        gp = (base_dir / geo) if not Path(geo).is_absolute() else Path(geo)
        if not gp.is_file():
            raise CaseError(f"{where}: [case] 'geometry': block file {gp} not found")
        case["case"]["geometry"] = str(gp.resolve())
    elif "generator" not in geo:
        raise CaseError(f"{where}: [case] 'geometry' table needs a 'generator' key")
    else:  # generators reading files (outlines, dxf, meshes): their paths relative to the case file
        case["case"]["geometry"] = _generator_paths(geo, base_dir, where)
    if isinstance(case["time"]["step"], str) and case["time"]["step"] != "auto":
        raise CaseError(f"{where}: [time] 'step' must be a number (s) or 'auto', got {case['time']['step']!r}")
    if isinstance(case["time"]["step"], float) and case["time"]["step"] <= 0:
        raise CaseError(f"{where}: [time] 'step' must be > 0, got {case['time']['step']}")
    cd = case["output"]["collapse_displacement"]
    if isinstance(cd, str) and cd != "auto" or isinstance(cd, float) and cd <= 0:
        raise CaseError(f"{where}: [output] 'collapse_displacement' must be > 0 (m) or 'auto', got {cd!r}")
    for k, c in enumerate(case["output"]["contacts"]):
        if not (isinstance(c, dict) and set(c) == {"name", "blocks"} and isinstance(c["name"], str)
                and isinstance(c["blocks"], list) and len(c["blocks"]) == 2 and all(map(_is_int, c["blocks"]))):
            raise CaseError(f"{where}: [output] contacts[{k}] must be {{name = '...', blocks = [a, b]}} with "
                            f"integer block ids, got {c!r}")
    mats = raw.get("materials", {})
    if not isinstance(mats, dict):
        raise CaseError(f"{where}: [materials] must be tables [materials.NAME], got {mats!r}")
    case["materials"] = {}
    for name, table in mats.items():
        filled = _fill(f"{where} [materials.{name}]", table, MATERIAL_OVERRIDE)
        case["materials"][name] = {k: v for k, v in filled.items() if v is not None}
    case["forces"] = []
    if not isinstance(raw.get("forces", []), list):
        raise CaseError(f"{where}: 'forces' must be an array of tables [[forces]], got {raw['forces']!r}")
    for k, f in enumerate(raw.get("forces", [])):
        w = f"{where} [[forces]] #{k + 1}"
        if not isinstance(f, dict):
            raise CaseError(f"{w}: must be a table")
        filled = _fill(w, f, FORCE)
        vec = filled["force"]
        if len(vec) != 3 or not all(_is_number(x) and math.isfinite(x) for x in vec):
            raise CaseError(f"{w}: 'force' must be three finite numbers (N), got {vec!r}")
        filled["force"] = [float(x) for x in vec]
        if filled["end"] is not None and filled["end"] <= filled["start"]:
            raise CaseError(f"{w}: 'end' ({filled['end']} s) must be after 'start' ({filled['start']} s)")
        case["forces"].append(filled)
    case["loads"] = _loads(raw.get("loads", []), where)
    stages = raw.get("stages", [])
    if not isinstance(stages, list) or not stages:
        raise CaseError(f"{where}: at least one [[stages]] is required")
    types = STAGE_TYPES
    case["stages"] = []
    for k, s in enumerate(stages):
        w = f"{where} [[stages]] #{k + 1}"
        filled = _typed(w, s, types, "stage")
        types[filled["type"]].validate(filled, w, last=k == len(stages) - 1, base_dir=base_dir)
        _labelled(w, filled, case["stages"], "stage")
        case["stages"].append(filled)
    names = [c["name"] for c in case["output"]["contacts"]]
    for key in ("penetration", "slip"):
        ref = case["analysis"][key]
        if ref is not None and ref not in names:
            raise CaseError(f"{where}: [analysis] '{key}' names contact {ref!r}, not among [output] contacts {names}")
    return case


def _typed(w: str, raw, types: dict, what: str) -> dict:
    """A [[stages]] or [[loads]] table filled with its type's keys (``types``: a registry of
    classes with ``keys``); a missing or unknown ``type`` refused, naming the table."""
    if not isinstance(raw, dict) or "type" not in raw:
        raise CaseError(f"{w}: missing 'type' (one of {sorted(types)})")
    kind = raw["type"]
    if kind not in types:
        raise CaseError(f"{w}: unknown {what} type {kind!r}; allowed: {sorted(types)}")
    filled = _fill(w, {key: v for key, v in raw.items() if key != "type"}, types[kind].keys)
    filled["type"] = kind
    return filled


def _labelled(w: str, filled: dict, earlier: list[dict], what: str) -> None:
    """A [[stages]] or [[loads]] table's optional ``name``: a label, unique among ``earlier``."""
    if filled["name"] is not None:
        if not filled["name"].strip() or filled["name"].isdigit() or "." in filled["name"]:
            raise CaseError(f"{w}: 'name' {filled['name']!r} must be a non-empty label, not a number, without '.'")
        if any(x["name"] == filled["name"] for x in earlier):
            raise CaseError(f"{w}: 'name' {filled['name']!r} is already the name of another {what}")


def _loads(loads, where: str) -> list[dict]:
    """The [[loads]] tables filled and checked by their types (drystone/model/loads.py)."""
    if not isinstance(loads, list):
        raise CaseError(f"{where}: 'loads' must be an array of tables [[loads]], got {loads!r}")
    out = []
    for k, raw in enumerate(loads):
        w = f"{where} [[loads]] #{k + 1}"
        filled = _typed(w, raw, LOAD_TYPES, "load")
        LOAD_TYPES[filled["type"]].validate(filled, w)
        _labelled(w, filled, out, "load")
        out.append(filled)
    return out


#: generator parameters that name input paths: key -> (what it must be, is it a list)
GENERATOR_PATHS = {"folder": ("folder", False), "file": ("file", False), "files": ("file", True)}


def _generator_paths(geo: dict, base_dir: Path, where: str) -> dict:
    """``geo`` with its path parameters (``GENERATOR_PATHS``) resolved relative to the case
    file's folder ``base_dir``; a missing file or folder is refused, naming it."""
    out = dict(geo)
    for key, (kind, many) in GENERATOR_PATHS.items():
        value = geo.get(key)
        items = value if many and isinstance(value, list) else [value]
        if not all(isinstance(v, str) for v in items) or (many and not isinstance(value, list)):
            continue  # not a path: the generator's own checks name it
        resolved = []
        for v in items:
            fp = Path(v) if Path(v).is_absolute() else base_dir / v
            if not (fp.is_dir() if kind == "folder" else fp.is_file()):
                raise CaseError(f"{where}: [case] geometry '{key}': {fp} " + ("is not a folder" if kind == "folder"
                                                                               else "not found"))
            resolved.append(str(fp.resolve()))
        out[key] = resolved if many else resolved[0]
    return out


def _is_int(x) -> bool:
    return isinstance(x, int) and not isinstance(x, bool)


def _is_number(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


#: names that become folder names (case, sweep and sweep run names): letters, digits and
#: ``_ . + -``, starting with a letter, digit or ``_``, at most 100 characters (the staging
#: folder ``.<name>.partial`` must fit a file system's 255), so a name is never a path, a
#: hidden folder or a string a shell or a file system treats specially
NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.+-]{0,99}")
NAME_RULE = "letters, digits and _ . + - (not first: . + -), at most 100 characters, no '/'"


def check_name(where: str, name, nested: bool = False) -> None:
    """Results go to results/<name>/: refuse a name that is not one plain folder name
    (``NAME``); ``nested``: a sweep's run, ``<sweep>/<run>``, each part such a name."""
    parts = name.split("/") if isinstance(name, str) and nested else [name]
    if not all(isinstance(q, str) and NAME.fullmatch(q) and q != ".." for q in parts) or len(parts) > 2:
        shown = repr(name) if len(repr(name)) <= 60 else f"{repr(name)[:50]}... ({len(name)} characters)"
        raise CaseError(f"{where} = {shown}: results go to results/<name>/, so the name must be one folder name: "
                        f"{NAME_RULE}")


def describe() -> str:
    """Markdown table of every case key (for README)."""
    lines = ["| section | key | default | unit | meaning |", "|---|---|---|---|---|"]

    def row(sec, name, k):
        d = "required" if k.default is REQUIRED else repr(k.default)
        lines.append(f"| {sec} | `{name}` | {d} | {k.unit} | {k.meaning} |")

    for sec, keys in SECTIONS.items():
        for name, k in keys.items():
            row(f"[{sec}]", name, k)
    for name, k in MATERIAL_OVERRIDE.items():
        row("[materials.NAME]", name, k)
    for name, k in FORCE.items():
        row("[[forces]]", name, k)
    for stype, t in STAGE_TYPES.items():
        for name, k in t.keys.items():
            row(f"[[stages]] type = \"{stype}\"", name, k)
    for ltype, t in LOAD_TYPES.items():
        for name, k in t.keys.items():
            row(f"[[loads]] type = \"{ltype}\"", name, k)
    return "\n".join(lines)


def readme_with_keys(text: str) -> str:
    """README text with the keys table between its markers replaced by ``describe()``."""
    start, end = "<!-- keys:start -->", "<!-- keys:end -->"
    i, j = text.index(start) + len(start), text.index(end)
    return text[:i] + "\n" + describe() + "\n" + text[j:]
