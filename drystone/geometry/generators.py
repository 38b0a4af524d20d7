"""Registry of geometry generators usable from a case file:
``geometry = {generator = "NAME", ...parameters}``. Each returns a block-file dict and
raises GeometryError (naming itself, the parameter and what is allowed) on a bad one."""
from __future__ import annotations

import importlib
import inspect

from .blockfile import GeometryError

# name -> (module, function); modules are imported on use
GENERATORS = {
    "four_blocks": ("drystone.geometry.four_blocks", "make"),
    "boxes_on_platform": ("drystone.geometry.simple", "boxes_on_platform"),
    "running_bond": ("drystone.geometry.running_bond", "make"),
    "ogawa_blocks": ("drystone.geometry.ogawa_blocks", "make"),
    "irregular_wall": ("drystone.geometry.irregular_wall", "make"),
    "tilt_wall": ("drystone.geometry.irregular_wall", "tilt_wall"),
    "sacsayhuaman": ("drystone.geometry.sacsayhuaman", "make"),
    "polygonal_wall": ("drystone.geometry.polygonal_wall", "make"),
    "outlines": ("drystone.geometry.outlines", "make"),
    "dxf": ("drystone.geometry.dxf", "make"),
    "meshes": ("drystone.geometry.meshes", "make"),
}
#: the generators whose block file is a function of their parameters alone (none reads a file): a
#: process may keep what they generate (drystone/model/resolve.py); a new generator that reads no
#: file belongs here
PURE = frozenset({"four_blocks", "boxes_on_platform", "running_bond", "ogawa_blocks", "irregular_wall", "tilt_wall",
                  "sacsayhuaman", "polygonal_wall"})


def generate(spec: dict) -> dict:
    """Call the generator named in ``spec['generator']`` with the other keys; unknown
    generators, unknown or missing parameters raise GeometryError."""
    if not isinstance(spec, dict) or "generator" not in spec:
        raise GeometryError(f"a generated geometry needs a table with a 'generator' key, got {spec!r}")
    params = dict(spec)
    name = params.pop("generator")
    if not isinstance(name, str) or name not in GENERATORS:
        raise GeometryError(f"unknown geometry generator {name!r}; known: {sorted(GENERATORS)}")
    mod, fn = GENERATORS[name]
    func = getattr(importlib.import_module(mod), fn)
    sig = inspect.signature(func).parameters
    allowed = [p for p, v in sig.items() if v.kind != v.VAR_KEYWORD and not p.startswith("_")]
    unknown = sorted(set(params) - set(allowed))
    if unknown and not any(v.kind == v.VAR_KEYWORD for v in sig.values()):
        raise GeometryError(f"geometry generator {name!r}: unknown parameter(s) {unknown}; allowed: {allowed}")
    missing = [p for p, v in sig.items() if v.default is v.empty and v.kind != v.VAR_KEYWORD and p not in params]
    if missing:
        raise GeometryError(f"geometry generator {name!r}: missing parameter(s) {missing}")
    return func(**params)
