"""The site study's plan: walls, sites, records, polarities, search grids, and the files its
runs read.

Walls (``WALLS``): the Sacsayhuaman section (cases/site/record.toml: the generated 40-stone
section, Table 1's FEM properties) free-standing, and retained: the same case plus one
``[[loads]]`` table, the active earth pressure of soil behind its back face over the full
height (cases/site/retained_*.toml; soil ASSUMED, stated there and in the report). The soil
is on +y, the open side -y.

Sites (``SITES``): ``rock``, the record as it is (scaled to the PGA), and ``surface``, the
same record scaled to the PGA AT ROCK and propagated up the example profile
(data/site/sacsayhuaman.toml, ASSUMED; the excitation key ``site``).

Records: the Sacsayhuaman study's three (``shape.plan.RECORDS``), each cut to its
strong-motion window by the shape study's ``write_records`` (``results/<out>/records/``).
Polarity (``POLARITIES``): ``+`` as recorded, ``-`` the window with its sign reversed
(``<name>_window_reversed.txt``): for the retained wall the outward half of the record's
peaks changes with it (a sample a > 0 accelerates the ground towards the soil: the stones'
inertia and Mononobe-Okabe's k_h point outwards).

Searches: the PGA at collapse at rock (g) of each wall, site, record and polarity, one
``collapse`` analysis each (drystone/analyses/collapse.py, its search set to the study's grid:
drystone/studies/common.py ``search_params``) between 0 (assumed standing) and a cap, to
the wall's ``resolution_g`` (its ``refine_g`` where given); the water level (m above the
platform) at which the retained wall fails statically, by the same search over static runs
(cases/site/retained_static.toml: the load type has a fixed ``water_level``, so each level is
its own run). For the retained wall the cap is lowered, per search, below the first grid PGA
whose motion would leave Mononobe-Okabe without a solution (k_h > tan(phi - beta) at some
sample: such a run is refused before it starts; ``admissible_cap``): a wall standing there
is reported as standing at that cap.

Where things go: ``results/<out>/`` (``results/site/`` for the full config) holds
``plan.json``, ``records/`` and the analyses' folders: ``tilt/<wall>/``,
``searches/<wall>-<site>-<record>[-reversed]/`` (collapse analyses) and ``static/`` (the
static runs, ``water.json``).
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
from drystone.studies.shape import plan as shape_plan

CASES = paths.CASES / "site"
#: wall -> (label, record case, tilt case)
WALLS = {"free": ("free-standing", CASES / "record.toml", CASES / "tilt.toml"),
         "retained": ("retained (soil behind, ASSUMED)", CASES / "retained_record.toml", CASES / "retained_tilt.toml")}
STATIC_CASE = CASES / "retained_static.toml"
PROFILE = paths.ROOT / "data" / "site" / "sacsayhuaman.toml"
SITES = {"rock": "at rock (the record as it is)",
         "surface": "at the surface of the example profile (scaled at rock, then propagated)"}
POLARITIES = {"+": "as recorded", "-": "reversed"}
#: the base cases' stage indices (gravity, excitation, rest)
EXCITATION_STAGE, REST_STAGE = 1, 2
#: the static case's rest stage
STATIC_REST_STAGE = 1
#: a retained run's largest k_h must stay below this fraction of Mononobe-Okabe's limit
#: tan(phi - beta) (a margin for the round-off of the runner's own check)
MO_MARGIN = 0.999


@dataclass(frozen=True)
class Config(StudyFolders):
    """One configuration of the study (``CONFIGS``). PGAs in g, levels in m."""

    name: str
    out: str                                   # results/<out>/: plan, records, the analyses, report
    walls: tuple = ("free", "retained")
    sites: tuple = ("rock", "surface")
    records: tuple = shape_plan.RECORDS
    polarities: dict = field(default_factory=lambda: {"free": ("+",), "retained": ("+", "-")})
    pga_cap_g: dict = field(default_factory=lambda: {"free": 3.2, "retained": 0.8})
    resolution_g: dict = field(default_factory=lambda: {"free": 0.1, "retained": 0.05})
    refine_g: dict = field(default_factory=lambda: {"retained": 0.01})  # the final bracket's width, if finer
    level_cap_m: float = 4.0                   # the water table at the top of the soil
    level_resolution_m: float = 0.25
    water: bool = True
    tilt: bool = True
    record_duration_s: float | None = None     # cut the window further (small config only)
    rest_max_s: float | None = None            # cap the rest stage below the case's (small config only)
    quick: bool = False                        # the shortened gravity and tilt (common.QUICK_*; small config only)
    notes: tuple = ()
    results_root: str | None = None            # instead of results/ (tests)


CONFIGS = {
    "full": Config(name="full", out="site"),
    "small": Config(name="small", out="site_small", records=("ancash1970",),
                    polarities={"free": ("+",), "retained": ("+",)}, pga_cap_g={"free": 3.2, "retained": 0.6},
                    resolution_g={"free": 1.6, "retained": 0.3}, refine_g={}, level_resolution_m=2.0,
                    record_duration_s=0.75, rest_max_s=0.5, quick=True,
                    notes=("1 record cut to 0.75 s, as recorded only, 1.6 g (free) and 0.3 g (retained) brackets, "
                           "a 2 m water-level bracket, rest 0.5 s (1 s in the static runs), in the seismic "
                           f"and tilt runs {quick_note()}: a pipeline check, not a result",)),
}


def get(config) -> Config:
    if isinstance(config, Config):
        return config
    if config not in CONFIGS:
        raise KeyError(f"unknown site-study config {config!r} (known: {', '.join(CONFIGS)})")
    return CONFIGS[config]


# --- records ----------------------------------------------------------------------------------------------
def record_file(cfg: Config, record: str, polarity: str) -> Path:
    f = shape_plan.record_file(record, cfg.records_dir)
    return f if polarity == "+" else f.with_name(f.stem + "_reversed.txt")


def write_records(cfg: Config) -> dict:
    """The records' strong-motion windows (the shape study's ``write_records``) and, where a
    wall runs them reversed, their sign-reversed copies."""
    out = shape_plan.write_records(cfg.records, cfg.records_dir)
    if any("-" in cfg.polarities.get(w, ()) for w in cfg.walls):
        for name, r in out.items():
            lines = Path(r["file"]).read_text().splitlines()
            head = [ln for ln in lines if ln.startswith("#")]
            body = [repr(-float(x)) for x in lines if x and not x.startswith("#")]
            head = [h + "; sign reversed by drystone.studies.site.plan" if h.startswith("# source") else h
                    for h in head]
            path = write_if_changed(record_file(cfg, name, "-"), "\n".join(head + body) + "\n")
            r["reversed"] = {"file": str(path), "sha256": hashlib.sha256(path.read_bytes()).hexdigest()}
    return out


# --- runs -------------------------------------------------------------------------------------------------
def record_case(wall: str) -> Path:
    return WALLS[wall][1]


def common_overrides(cfg: Config) -> list[str]:
    """Every seismic run's overrides: the record and the rest cut to the config's durations
    (the rest's settle window with it), gravity shortened in a quick config."""
    return (quick_gravity(cfg.quick)
            + tomlio.stage_durations({EXCITATION_STAGE: cfg.record_duration_s, REST_STAGE: cfg.rest_max_s},
                                     windows=(REST_STAGE,)))


def site_overrides(site: str) -> list[str]:
    """At the surface, the example profile on the excitation stage (``site``); at rock none."""
    return [f"stages.{EXCITATION_STAGE}.site={tomlio.value(str(PROFILE.resolve()))}"] if site == "surface" else []


def search_name(wall: str, site: str, record: str, polarity: str) -> str:
    return f"{wall}-{site}-{record}{'' if polarity == '+' else '-reversed'}"


def search_dir(cfg: Config, wall: str, site: str, record: str, polarity: str) -> Path:
    """The folder of one search's collapse analysis."""
    return cfg.out_dir / "searches" / search_name(wall, site, record, polarity)


def tilt_dir(cfg: Config, wall: str) -> Path:
    return cfg.out_dir / "tilt" / wall


def static_dir(cfg: Config) -> Path:
    return cfg.out_dir / "static"


def tolerance(cfg: Config, wall: str) -> float:
    """The width (g) of a wall's final bracket."""
    return cfg.refine_g.get(wall) or cfg.resolution_g[wall]


def static_run_name(level_m: float | None) -> str:
    return "static-dry" if level_m is None else f"static-water_{level_m:g}m"


def static_common(cfg: Config) -> list[str]:
    return tomlio.stage_durations({STATIC_REST_STAGE: cfg.rest_max_s and 2 * cfg.rest_max_s}, windows=(STATIC_REST_STAGE,))


def static_overrides(level_m: float | None) -> list[str]:
    """A static run's own override: the water level (m above the platform); none: dry."""
    return [] if level_m is None else [f"loads.soil.water_level={tomlio.value(float(level_m))}"]


# --- caps -------------------------------------------------------------------------------------------------
def soil(cfg: Config | None = None) -> dict:
    """The retained wall's [[loads]] table as the case file gives it (filled with defaults)."""
    from drystone.model import case as casemod

    return casemod.load(record_case("retained"))["loads"][0]


def max_k_h(cfg: Config, wall: str, site: str, record: str, polarity: str, pga_g: float) -> float:
    """The largest k_h = a.e / g towards the soil (+y) of a run's motion, as the runner makes
    it (drystone.motions.excitation.motion_for_stage: trimmed, scaled at rock, propagated)."""
    from drystone.analyses import common
    from drystone.model import case as casemod
    from drystone.motions import excitation as mex
    from drystone.units import G_STANDARD

    case = record_case(wall)
    over = common_overrides(cfg) + site_overrides(site)
    d = casemod.load(case, over)  # as the collapse analysis scales its run: the record, then the PGA
    over += common.record_override(d, record_file(cfg, record, polarity)) + common.pga_override(d, pga_g)
    st = casemod.load(case, over)["stages"][EXCITATION_STAGE]
    m = mex.motion_for_stage(st)
    return float(np.max(m.applied.acc) / G_STANDARD)


def admissible_cap(cfg: Config, wall: str, site: str, record: str, polarity: str) -> dict:
    """The highest grid PGA (g) at or below the config's cap whose motion keeps k_h below
    ``MO_MARGIN`` x tan(phi - beta) (Mononobe-Okabe has a solution at every sample); the
    config's cap for the free-standing wall."""
    cap, res = cfg.pga_cap_g[wall], cfg.resolution_g[wall]
    if wall != "retained":
        return {"cap_g": cap, "limited_by_mo": False}
    t = soil(cfg)
    limit = MO_MARGIN * float(np.tan(np.radians(t["phi_deg"] - t["beta_deg"])))
    k = int(round(cap / res))
    first = None
    while k > 0:
        p = round(k * res, 6)
        kh = max_k_h(cfg, wall, site, record, polarity, p)
        if kh < limit:
            return {"cap_g": p, "limited_by_mo": first is not None, "k_h_at_cap": kh, "k_h_limit": limit,
                    "refused_from_g": first}
        first = p
        k -= 1
    raise ValueError(f"{wall} {site} {record} {polarity}: every grid PGA exceeds Mononobe-Okabe's limit")


def build(cfg: Config, walls=None) -> dict:
    """Write the records, find the caps; returns the plan (also written to plan.json)."""
    cfg = get(cfg)
    walls = list(cfg.walls if walls is None else walls)
    cfg.out_dir.mkdir(parents=True, exist_ok=True)
    records = write_records(cfg)
    caps = {}
    for w in walls:
        for site in cfg.sites:
            for r in cfg.records:
                for pol in cfg.polarities[w]:
                    caps[search_id(w, site, r, pol)] = admissible_cap(cfg, w, site, r, pol)
    plan = {"format": "drystone.site_plan", "version": 1, "config": asdict(cfg), "walls": walls,
            "cases": {w: {"label": WALLS[w][0], "record": str(WALLS[w][1]), "tilt": str(WALLS[w][2])} for w in walls},
            "static_case": str(STATIC_CASE), "profile": str(PROFILE),
            "profile_sha256": hashlib.sha256(PROFILE.read_bytes()).hexdigest(),
            "soil": soil(cfg) if "retained" in walls else None,
            "records": records, "caps": caps, "common_overrides": common_overrides(cfg)}
    atomic.write_text(cfg.out_dir / "plan.json", json.dumps(plan, indent=1, default=str) + "\n")
    return plan


def search_id(wall: str, site: str, record: str, polarity: str) -> str:
    return f"{wall}/{site}/{record}/{polarity}"


def load_plan(cfg: Config) -> dict:
    p = get(cfg).out_dir / "plan.json"
    if not p.is_file():
        raise FileNotFoundError(f"{p}: no plan (python -m drystone.studies.site plan --config {get(cfg).name})")
    return json.loads(p.read_text())
