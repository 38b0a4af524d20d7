"""Analyses that take any case file: each a plain function, a CLI subcommand, a JSON with
documented keys and a report.html (docs/user-guide.md, "Analyses of any wall").

One floor above the runner and the sweeps (drystone.runner, drystone.sweep), one below the
studies (drystone/studies/): an analysis changes a case only through overrides (``--set``
keys), so every run it makes is an ordinary run folder a user could rerun by hand, and its
rounds of runs are sweeps (resumable: finished runs with the same fingerprint are reused;
local pool or Dask).

``REGISTRY`` names each analysis and its module; ``python -m drystone NAME`` is its
command (drystone/cli.py adds one subcommand per entry). Each module has ``HELP`` (one
line), ``add_arguments(parser)``, ``main(args) -> exit code`` and one plain function doing
the work, returning what it writes to its JSON. What they share (output folder, the one
collapse criterion ``outcome``, running rounds of runs): drystone/analyses/common.py.
Modules are imported when their command runs (``load``), so an analysis that is missing
or broken does not stop the others.
"""
from __future__ import annotations

import importlib

#: analysis name -> module (adding an analysis = one line here)
REGISTRY: dict[str, str] = {
    "tilt": "drystone.analyses.tilt",
    "modal": "drystone.analyses.modal",
    "collapse": "drystone.analyses.collapse",
    "fragility": "drystone.analyses.fragility",
    "limit": "drystone.analyses.limit",
    "assess": "drystone.analyses.assess",
}


def load(name: str):
    """The module of analysis ``name`` (KeyError for an unknown name)."""
    return importlib.import_module(REGISTRY[name])


def available() -> dict[str, object]:
    """The analyses whose module is present and imports: name -> module."""
    out = {}
    for name in REGISTRY:
        try:
            out[name] = load(name)
        except ModuleNotFoundError as exc:
            if exc.name != REGISTRY[name]:  # the module exists but something it imports does not
                raise
    return out
