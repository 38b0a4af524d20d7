"""The package's layers, the one list of them: each module belongs to one layer and imports
only from its own layer or those below (tests/test_layers.py checks every import against
``layer_of``; the Layout table of docs/maintainers-guide.md is generated from ``LAYERS`` by ``readme_block``:
``python -m drystone layout --update-readme``). A leaf module: it imports nothing.

Why one namespace: the design's folders (``geometry/``, ``motions/``, the core,
``yade_scripts/``, ``postprocess/``, ``studies/``) are subpackages of ``drystone`` rather
than top-level packages, so that one ``pip install -e .`` puts all of them on the path of
the interpreter YADE runs, no name can clash with another installed package (a top-level
``geometry`` or ``postprocess`` would), and every import says which layer it reaches.
"""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Layer:
    """A layer: its rank (imports go to the same or a lower rank), name, the modules it
    holds by name (``modules``) and by package (``packages``: a package and everything in
    it), the folders it shows in the README, what it holds, and whether it imports YADE."""

    rank: int
    name: str
    modules: tuple[str, ...]
    packages: tuple[str, ...]
    folders: str
    what: str
    yade: bool = False


LAYERS = (
    Layer(0, "leaves", ("drystone", "drystone.paths", "drystone.units", "drystone.libm", "drystone.inputfiles",
                        "drystone.layers", "drystone.atomic", "drystone.kept", "drystone.numba_cache"), (),
          "`drystone/` (`paths.py`, `units.py`, `libm.py`, `inputfiles.py`, `layers.py`, `atomic.py`, `kept.py`, "
          "`numba_cache.py`)",
          "where things are, units and g, processor-independent sin/cos, reading input files with one-line "
          "errors, this list of layers, every file written aside and renamed into place, a process's results "
          "kept by their inputs, numba's cache safe for processes compiling at once and keyed by the kernels' "
          "source text"),
    Layer(1, "inputs", (), ("drystone.geometry", "drystone.motions"),
          "`drystone/geometry/`, `drystone/motions/`",
          "block files (`blockfile.py`: the format and its checks), hull helpers, generated walls and outlines; "
          "ground motions: readers (one registry entry per format), catalogue, processing, spectra"),
    Layer(2, "core", ("drystone.simulate", "drystone.provenance", "drystone.tomlio"),
          ("drystone.model", "drystone.mechanics"),
          "`drystone/model/`, `drystone/mechanics/`, `drystone/` (`simulate.py`, `provenance.py`, `tomlio.py`)",
          "the case model: keys and case files, stage types, the resolved run spec, the load programme, the time "
          "step; the mechanics: contact laws (a registry), exact overlaps, the compiled contact step, rigid-body "
          "integration, stability checks and the per-sample monitors, collapse onsets, modes, closed forms; "
          "running YADE in a staging folder, provenance, TOML writing"),
    Layer(3, "YADE", (), ("drystone.yade_scripts",), "`drystone/yade_scripts/`",
          "the one YADE driver (`run_case.py`), its step engines (`engines.py`), recorder, scene builder and "
          "per-contact engine", yade=True),
    Layer(4, "postprocess", (), ("drystone.postprocess",), "`drystone/postprocess/`",
          "`summary.json` from histories, figures, comparison with the papers, identification, VTK"),
    Layer(5, "applications", ("drystone.runner", "drystone.sweep", "drystone.cli", "drystone.bench",
                              "drystone.kernel_profile", "drystone.bench_baseline", "drystone.clean",
                              "drystone.__main__"),
          ("drystone.analyses",),
          "`drystone/` (`runner.py`, `sweep.py`, `cli.py`, `bench.py`, `bench_baseline.py`, `kernel_profile.py`, "
          "`clean.py`), "
          "`drystone/analyses/` (with `free_decay.py`, `restitution.py`: the analyses of one block)",
          "run a case, sweeps (local or Dask), the command line, speed figures (also back to back with an earlier "
          "commit) and the kernels' profile under perf, "
          "the free-decay check and the "
          "rocking restitution, `make clean` (only what the package wrote); the analyses of any case (tilt, modal, "
          "collapse, fragility, ...: one command each, the one collapse criterion `analyses/common.py` outcome)"),
    Layer(6, "studies", (), ("drystone.studies",), "`drystone/studies/`",
          "the papers and beyond, one package each: `tilt/`, `ogawa/`, `sacsayhuaman/`, `fragility/`, `shape/`, "
          "`site/`, `crosscheck/` (LMGC90), all built on the analyses; `common.py` (what the shape and site studies "
          "share: the collapse analysis's search on their grid, reading the analyses' JSON, their command line), "
          "`readme_tables.py`"),
)


def layer_of(module: str) -> Layer:
    """The layer of a drystone module (dotted name); KeyError if it has none."""
    for layer in LAYERS:
        if module in layer.modules or any(module == p or module.startswith(p + ".") for p in layer.packages):
            return layer
    raise KeyError(f"module {module} has no layer: add it to drystone/layers.py")


def readme_block() -> str:
    """The Layout table of docs/maintainers-guide.md (Markdown)."""
    rows = ["| layer | folders | what | imports YADE |", "|---|---|---|---|"]
    rows += [f"| {k.rank} {k.name} | {k.folders} | {k.what} | {'**yes (only here)**' if k.yade else 'no'} |"
             for k in LAYERS]
    return "\n".join(rows)


def readme_with_layout(text: str) -> str:
    """README text with the Layout table between its markers replaced by ``readme_block()``."""
    start, end = "<!-- layout:start -->", "<!-- layout:end -->"
    i, j = text.index(start) + len(start), text.index(end)
    return text[:i] + "\n" + readme_block() + "\n" + text[j:]
