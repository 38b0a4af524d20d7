"""Registry of geometry generators usable from a case file:
``geometry = {generator = "NAME", ...parameters}``. Each returns a block-file dict."""
from __future__ import annotations

import importlib

# name -> (module, function); modules are imported on use
GENERATORS = {
    "four_blocks": ("geometry.four_blocks", "make"),
    "boxes_on_platform": ("geometry.simple", "boxes_on_platform"),
    "running_bond": ("geometry.running_bond", "make"),
    "ogawa_blocks": ("geometry.ogawa_blocks", "make"),
    "irregular_wall": ("geometry.irregular_wall", "make"),
    "tilt_wall": ("geometry.irregular_wall", "tilt_wall"),
    "sacsayhuaman": ("geometry.sacsayhuaman", "make"),
    "outlines": ("geometry.outlines", "make"),
}


def generate(spec: dict) -> dict:
    """Call the generator named in ``spec['generator']`` with the other keys."""
    params = dict(spec)
    name = params.pop("generator")
    if name not in GENERATORS:
        raise KeyError(f"unknown geometry generator {name!r}; known: {sorted(GENERATORS)}")
    mod, fn = GENERATORS[name]
    func = getattr(importlib.import_module(mod), fn)
    try:
        return func(**params)
    except TypeError as exc:
        raise KeyError(f"geometry generator {name!r}: {exc}") from None
