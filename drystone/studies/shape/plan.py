"""The shape study's plan: wall variants, seeds, records, and the files its runs read.

Four walls of the Sacsayhuaman section's footprint, height and weight (``footprint``: read
from the generated section, drystone/geometry/sacsayhuaman.py: 8.64 m long, 0.8 m thick,
4 m high, 2300 kg/m^3, every stone through the full thickness), per seed (``VARIANTS``):

* ``coursed`` (a): today's generated section, coursed irregular stones (the
  ``sacsayhuaman`` generator: drystone/geometry/irregular_wall.py, 40 stones, the paper's
  numbering, course 1 fixed, side blocks 8, 9, 14, 15, 24, 25, 34 with blocked_dofs "xYZ");
* ``polygonal`` (b): polygonal masonry of convex stones (``polygonal_wall``, typology
  "sacsayhuaman", ``reentrant`` 0, stone sizes ``STONE_SIZE``: about 40 stones, as (a));
* ``interlocking`` (c): the same seed's layout with ``REENTRANT`` of the stones made
  re-entrant by merging pairs of neighbouring cells (``polygonal_wall`` with reentrant > 0:
  for the sacsayhuaman typology the seeds, and so the cells, are those of (b); the merged
  stones are single rigid bodies of several convex ``parts``, block file version 2);
* ``interlocking_split`` (c'): the stones of (c) with every part its own block
  (drystone/geometry/split.py ``split_parts``): what the package forced before multi-part
  stones.

The same boundary conditions as (a) for (b), (c), (c'): stones touching the platform are
fixed (the generator's ``fix_bottom``; ``fix_bottom`` here), and free blocks with a face on
either end of the wall (x = 0 or x = L) get blocked_dofs "xYZ" (``hold_ends``: the wall
goes on beyond the section, so they may move out of plane and up and rotate out of plane
only). For (c') both rules are applied after the split, block by block: a part of a fixed
stone that does not reach the platform is free, and a part that does not reach an end is
not held. (a) keeps its generator's rules (the paper's: course 1 fixed, its top-right
stone 40 stays free).

Weights: every variant tiles the L x H face with stones extruded through T, so the
volumes, and at one density the weights, agree to round-off (``WEIGHT_REL_TOL``, checked
by ``geometries`` and reported).

Records (``write_records``): the three records of the Sacsayhuaman study
(cases/sweeps/sacsayhuaman_table3.toml: ``paruro2014``, ``cusco2023``, ``ancash1970`` from
drystone/motions/catalogue.py: the user's files in data/records/user/ if present, else the
FEMA P695 far-field analogues, ASSUMED stand-ins), each cut to its strong-motion window
(``WINDOW``: 5-95 % of the Arias intensity, or where that is longer than ``MAX_CORE_S``
the window of that length holding the most intensity: the paruro2014 analogue's; plus
``PAD_S`` before and after, the pads Hann-tapered so the base starts and ends at rest in
acceleration; the record's PGA lies inside, ``pga_inside``) and
written as plain text in g (``results/<out>/records/<name>_window.txt``: rewritten only
when different, so a finished run is recognised by its fingerprint).

Where things go: ``results/<out>/`` (``results/shape/`` for the full config) holds
``plan.json``, ``geometry/<variant>_s<seed>.json``, ``records/`` and, per wall, the folders
of its analyses ``walls/<variant>_s<seed>/tilt/`` and ``.../collapse/`` (drystone/analyses/:
their JSON, report and runs).
"""
from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from drystone import atomic
from drystone import paths, tomlio
from drystone.studies.common import StudyFolders, quick_gravity, quick_note, write_if_changed

RECORD_CASE = paths.CASES / "shape" / "record.toml"
TILT_CASE = paths.CASES / "shape" / "tilt.toml"
#: the base case's stage indices (cases/shape/record.toml: gravity, excitation, rest)
EXCITATION_STAGE, REST_STAGE = 1, 2
#: the Sacsayhuaman study's records (cases/sweeps/sacsayhuaman_table3.toml)
RECORDS = ("paruro2014", "cusco2023", "ancash1970")
#: polygonal walls: [min, max] equivalent stone diameters (m), chosen so the convex wall has
#: about the section's 40 stones (38-39 for seeds 0-4)
STONE_SIZE = (0.6, 1.6)
#: fraction of re-entrant stones of (c): pairs merged = round(r n / (1 + r)) of n cells
#: (about 9 of 30 stones)
REENTRANT = 0.3
#: Lloyd steps of the polygonal generator (its default)
LLOYD = 3
#: weights of the variants of one seed must agree within this (relative)
WEIGHT_REL_TOL = 1e-9
#: strong-motion window: Arias intensity fractions, and the pad (s) before and after it
WINDOW = (0.05, 0.95)
PAD_S = 1.0
#: the window's core (without the pads) is at most this long (s): a longer one (the paruro2014
#: analogue's 5-95 % lasts 38 s) is replaced by the window of this length holding the most
#: Arias intensity; the study's cost is about proportional to the records' length
MAX_CORE_S = 18.0
#: blocked_dofs of the stones at the wall's ends (as the section's side blocks)
END_DOFS = "xYZ"


@dataclass(frozen=True)
class Config(StudyFolders):
    """One configuration of the study (``CONFIGS``). PGAs in g."""

    name: str
    out: str                                   # results/<out>/: plan, geometries, the walls' analyses, report
    variants: tuple = ("coursed", "polygonal", "interlocking", "interlocking_split")
    seeds: tuple = (0, 1, 2)
    records: tuple = RECORDS
    pga_cap_g: float = 3.2                     # the highest PGA run; a wall standing there: "> cap"
    resolution_g: float = 0.1                  # the bracket's final width (0 g, gravity alone, assumed standing)
    tilt: bool = True
    record_duration_s: float | None = None     # cut the window further (small config only)
    rest_max_s: float | None = None            # cap the rest stage below the case's (small config only)
    quick: bool = False                        # the shortened gravity and tilt (common.QUICK_*; small config only)
    notes: tuple = field(default_factory=tuple)
    results_root: str | None = None            # instead of results/ (tests)


CONFIGS = {
    "full": Config(name="full", out="shape"),
    "small": Config(name="small", out="shape_small", variants=("coursed", "polygonal"), seeds=(0,), records=("ancash1970",), resolution_g=1.6,
                    record_duration_s=1.0, rest_max_s=0.5, quick=True,
                    notes=("1 seed, 1 record cut to 1 s, 2 variants, a 1.6 g bracket, rest 0.5 s, "
                           f"{quick_note()}: a pipeline check, not a result",)),
}


def get(config) -> Config:
    if isinstance(config, Config):
        return config
    if config not in CONFIGS:
        raise KeyError(f"unknown shape-study config {config!r} (known: {', '.join(CONFIGS)})")
    return CONFIGS[config]


# --- geometries -------------------------------------------------------------------------------------------
def footprint(seed: int = 0) -> dict:
    """Length, height, thickness (m) and material of the generated Sacsayhuaman section
    (its stones' bounding box)."""
    from drystone.geometry import blockfile as bf
    from drystone.geometry import sacsayhuaman

    d = sacsayhuaman.make(seed=seed)
    bs = bf.parse(d, "sacsayhuaman section", check_overlaps=False)
    pts = np.vstack([b.points for b in bs.blocks if b.role != "platform"])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    mat = d["materials"]["stone"]
    return {"length": float(hi[0] - lo[0]), "thickness": float(hi[1] - lo[1]), "height": float(hi[2] - lo[2]),
            "x0": float(lo[0]), "material": dict(mat)}


def hold_ends(d: dict, length: float, x0: float = 0.0, dofs: str = END_DOFS) -> dict:
    """``d`` with ``dofs`` blocked on every free block that has a face on either end of the
    wall (at least 3 corners of one part within 1e-9 x L of x = x0 or x = x0 + L)."""
    tol = 1e-9 * length
    out = dict(d, blocks=[])
    for b in d["blocks"]:
        b = dict(b)
        if b.get("role", "free") == "free":
            parts = b["parts"] if "parts" in b else [b["vertices"]]
            for part in parts:
                x = np.asarray(part, float)[:, 0]
                if (np.abs(x - x0) < tol).sum() >= 3 or (np.abs(x - x0 - length) < tol).sum() >= 3:
                    b["blocked_dofs"] = dofs
                    break
        out["blocks"].append(b)
    return out


def fix_bottom(d: dict, tol: float = 1e-9) -> dict:
    """``d`` with every non-platform block on the platform (its lowest corner within ``tol``
    m of z = 0) ``fixed`` and every other one ``free`` (the polygonal generator's
    ``fix_bottom`` rule, applied again after a split: a part of a fixed stone that does not
    reach the platform is then free); blocked dofs of a block made fixed are dropped."""
    out = dict(d, blocks=[])
    for b in d["blocks"]:
        b = dict(b)
        if b.get("role") != "platform":
            pts = np.vstack([np.asarray(p, float) for p in (b["parts"] if "parts" in b else [b["vertices"]])])
            b["role"] = "fixed" if pts[:, 2].min() <= tol else "free"
            if b["role"] == "fixed":
                b.pop("blocked_dofs", None)
        out["blocks"].append(b)
    return out


def _polygonal(seed: int, reentrant: float, fp: dict) -> dict:
    from drystone.geometry import polygonal_wall

    m = fp["material"]
    return polygonal_wall.make(length=fp["length"], height=fp["height"], thickness=fp["thickness"],
                               stone_size=STONE_SIZE, seed=seed, reentrant=reentrant, typology="sacsayhuaman",
                               lloyd=LLOYD, density=m["density"], kn=m["kn"], kt=m["kt"], mu=m["mu"],
                               damping=m["damping"], name="shape_polygonal")


def build_variant(variant: str, seed: int, fp: dict | None = None) -> dict:
    """The block-file dict of one variant and seed (module docstring)."""
    from drystone.geometry import sacsayhuaman, split

    fp = fp or footprint()
    if variant == "coursed":
        d = sacsayhuaman.make(seed=seed)
    elif variant == "polygonal":
        d = hold_ends(_polygonal(seed, 0.0, fp), fp["length"], fp["x0"])
    elif variant == "interlocking":
        d = hold_ends(_polygonal(seed, REENTRANT, fp), fp["length"], fp["x0"])
    elif variant == "interlocking_split":
        d = split.split_parts(_polygonal(seed, REENTRANT, fp), f"interlocking seed {seed}")
        d = hold_ends(fix_bottom(d), fp["length"], fp["x0"])
    else:
        raise KeyError(f"unknown variant {variant!r} (known: {', '.join(VARIANTS)})")
    d = dict(d, name=f"shape_{variant}_s{seed}")
    d["generator"] = dict(d.get("generator", {}), shape_study={"variant": variant, "seed": seed})
    return d


#: variant -> (label, one-line description)
VARIANTS = {
    "coursed": ("(a) coursed", "today's coursed irregular stones (sacsayhuaman generator)"),
    "polygonal": ("(b) polygonal, convex", "polygonal masonry of convex stones (polygonal_wall, reentrant 0)"),
    "interlocking": ("(c) interlocking", f"polygonal masonry, {REENTRANT:g} re-entrant stones as single "
                                         "multi-part bodies (polygonal_wall, reentrant > 0)"),
    "interlocking_split": ("(c') interlocking, split", "the stones of (c), every convex part its own block "
                                                       "(geometry/split.py)"),
}


def stats(d: dict) -> dict:
    """Counts, volume (m^3) and weight (N) of a block-file dict's non-platform stones."""
    from drystone.geometry import blockfile as bf
    from drystone.units import G_STANDARD

    bs = bf.parse(d, d.get("name", "<geometry>"), check_overlaps=False)
    st = [b for b in bs.blocks if b.role != "platform"]
    vol = sum(b.volume for b in st)
    weight = sum(bs.mass(b.id) for b in st) * G_STANDARD
    free = [b for b in st if b.role == "free"]
    return {"stones": len(st), "free": len(free), "fixed": len(st) - len(free),
            "multi_part": sum(len(b.parts) > 1 for b in st), "parts": sum(len(b.parts) for b in st),
            "held_ends": sum(bool(b.blocked_dofs) for b in free), "volume_m3": vol, "weight_N": weight,
            "free_weight_N": sum(bs.mass(b.id) for b in free) * G_STANDARD}


def geometry_file(cfg: Config, variant: str, seed: int) -> Path:
    return cfg.out_dir / "geometry" / f"{variant}_s{seed}.json"


def geometries(cfg: Config) -> dict:
    """Write every variant x seed block file (validated; rewritten only when different);
    returns {"<variant>_s<seed>": {"file", "sha256", **stats}} and checks the weights of
    one seed's variants agree within WEIGHT_REL_TOL (ValueError otherwise)."""
    from drystone.geometry import blockfile as bf

    fp = footprint()
    out = {}
    for seed in cfg.seeds:
        for v in cfg.variants:
            d = build_variant(v, seed, fp)
            bf.parse(d, f"shape study {v} seed {seed}")  # with the overlap check
            path = write_if_changed(geometry_file(cfg, v, seed), json.dumps(d, indent=1) + "\n")
            out[f"{v}_s{seed}"] = {"variant": v, "seed": seed, "file": str(path),
                                   "sha256": hashlib.sha256(path.read_bytes()).hexdigest(), **stats(d)}
        w = [out[f"{v}_s{seed}"]["weight_N"] for v in cfg.variants]
        if max(w) - min(w) > WEIGHT_REL_TOL * max(w):
            raise ValueError(f"shape study seed {seed}: the variants' weights differ beyond {WEIGHT_REL_TOL:g}: "
                             + ", ".join(f"{v} {x:.6g} N" for v, x in zip(cfg.variants, w)))
    return out


# --- records ----------------------------------------------------------------------------------------------
def record_file(name: str, folder: Path) -> Path:
    return Path(folder) / f"{name}_window.txt"


def strong_motion(r, window=WINDOW, pad_s: float = PAD_S, max_core_s: float | None = MAX_CORE_S):
    """The record cut to [ta - pad, tb + pad], [ta, tb] the times at ``window`` fractions of
    its Arias intensity or, where that is longer than ``max_core_s``, the ``max_core_s``
    window holding the most Arias intensity; within the record, the pads Hann-tapered.
    Returns (record, info: the window, its share of the Arias intensity, the PGAs)."""
    from drystone.motions import processing

    e = np.cumsum(r.acc ** 2)
    e = e / e[-1]
    t = r.time
    ta, tb = float(np.interp(window[0], e, t)), float(np.interp(window[1], e, t))
    capped = False
    if max_core_s is not None and tb - ta > max_core_s:
        n = int(round(max_core_s / r.dt))
        gain = e[n:] - e[:-n]
        i = int(np.argmax(gain))
        ta, tb, capped = float(t[i]), float(t[i + n]), True
    share = float(np.interp(tb, t, e) - np.interp(ta, t, e))
    t0, t1 = max(t[0], ta - pad_s), min(t[-1], tb + pad_s)
    w = processing.trim(r, t0, t1)
    n_pad = max(1, int(round(pad_s / w.dt)))
    ramp = np.ones(w.n)
    k = np.arange(n_pad)
    half = 0.5 * (1.0 - np.cos(np.pi * k / n_pad))  # 0 -> 1 over the pad
    if ta - pad_s >= t[0]:
        ramp[:n_pad] = half
    if tb + pad_s <= t[-1]:
        ramp[-n_pad:] = np.minimum(ramp[-n_pad:], half[::-1])
    w = w.replaced(f"Hann taper over the first and last {pad_s:g} s", acc=w.acc * ramp)
    ipk = int(np.argmax(np.abs(r.acc)))
    info = {"arias_window": list(window), "t_arias_s": [ta, tb], "core_capped_to_s": max_core_s if capped else None,
            "arias_share": share, "pad_s": pad_s, "window_s": [float(w.time[0]), float(w.time[-1])],
            "duration_s": float(w.duration), "full_duration_s": float(r.duration), "pga_g": float(r.pga_g),
            "window_pga_g": float(w.pga_g), "t_pga_s": float(t[ipk]),
            "pga_inside": bool(np.isclose(w.pga_g, r.pga_g, rtol=1e-12))}
    return w, info


def write_records(names, folder: Path) -> dict:
    """Each catalogue record's strong-motion window as a plain text file in g; returns
    {name: {file, sha256, event, station, component, source, window...}}."""
    from drystone.motions import catalogue
    from drystone.motions.record import G

    out = {}
    for name in names:
        r = catalogue.get(name)
        w, info = strong_motion(r)
        cat = r.info.get("catalogue", {})
        head = [f"# event = {r.event}", f"# station = {r.station}", f"# component = {r.component}",
                f"# dt = {w.dt!r}", "# units = g",
                f"# source = catalogue {name!r} ({cat.get('source_kind', '?')}), strong-motion window "
                f"{info['window_s'][0]:.3f}-{info['window_s'][1]:.3f} s ("
                + (f"the {MAX_CORE_S:g} s of most Arias intensity" if info["core_capped_to_s"] else "Arias 5-95 %")
                + f" +- {PAD_S:g} s, Hann-tapered pads), written by drystone.studies.shape.plan"]
        text = "\n".join(head + [repr(float(a / G)) for a in w.acc]) + "\n"
        path = write_if_changed(record_file(name, folder), text)
        out[name] = {"file": str(path), "sha256": hashlib.sha256(path.read_bytes()).hexdigest(),
                     "event": r.event, "station": r.station, "component": r.component,
                     "source_kind": cat.get("source_kind"), "stands_for": cat.get("stands_for"),
                     "fema": ({k: cat[k] for k in ("fema_set", "fema_record_id", "fema_component")}
                              if cat.get("source_kind") == "analogue" else None), "dt_s": w.dt, **info}
    return out


# --- runs -------------------------------------------------------------------------------------------------
def wall_dir(cfg: Config, variant: str, seed: int) -> Path:
    """The folder of one wall's analyses (tilt/, collapse/)."""
    return cfg.out_dir / "walls" / f"{variant}_s{seed}"


def common_overrides(cfg: Config) -> list[str]:
    """Every seismic run's overrides: the record and the rest cut to the config's durations
    (the rest's settle window with it), gravity shortened in a quick config."""
    return (quick_gravity(cfg.quick)
            + tomlio.stage_durations({EXCITATION_STAGE: cfg.record_duration_s, REST_STAGE: cfg.rest_max_s},
                                     windows=(REST_STAGE,)))


def wall_overrides(cfg: Config, variant: str, seed: int) -> list[str]:
    """The override giving a case one wall's geometry (its block file)."""
    return [f"case.geometry={tomlio.value(str(geometry_file(cfg, variant, seed).resolve()))}"]


def build(cfg: Config) -> dict:
    """Write the geometries and records; returns the plan (also written to plan.json)."""
    cfg = get(cfg)
    cfg.out_dir.mkdir(parents=True, exist_ok=True)
    plan = {"format": "drystone.shape_plan", "version": 1, "config": asdict(cfg),
            "record_case": str(RECORD_CASE), "tilt_case": str(TILT_CASE), "footprint": footprint(),
            "variants": {v: {"label": VARIANTS[v][0], "description": VARIANTS[v][1]} for v in cfg.variants},
            "polygonal": {"stone_size_m": list(STONE_SIZE), "reentrant": REENTRANT, "lloyd": LLOYD,
                          "typology": "sacsayhuaman", "end_dofs": END_DOFS},
            "geometries": geometries(cfg), "records": write_records(cfg.records, cfg.records_dir),
            "common_overrides": common_overrides(cfg)}
    atomic.write_text(cfg.out_dir / "plan.json", json.dumps(plan, indent=1) + "\n")
    return plan


def load_plan(cfg: Config) -> dict:
    p = get(cfg).out_dir / "plan.json"
    if not p.is_file():
        raise FileNotFoundError(f"{p}: no plan (python -m drystone.studies.shape plan --config {get(cfg).name})")
    return json.loads(p.read_text())
