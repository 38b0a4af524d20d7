"""The fragility study's configuration: records, stripes and per-run seeded draws, for the
``fragility`` analysis (drystone/analyses/fragility.py, ``--method stripes``), which runs them.

The 40-stone Sacsayhuaman wall (cases/sacsayhuaman/record.toml: gravity to 2 s, the record
out of plane (y) scaled to the stripe's PGA, then rest until the motion has died out, at
most 20 s) under every record of the FEMA P695 far-field set (22 pairs; one horizontal
component of each, ``Config.component``, applied out of plane: the analysis's
``fema:<id><component>`` records), each scaled to PGA stripes 0.1, 0.2, ..., 1.0 g. Per run
the joint friction coefficient mu and K_n are drawn (``distributions``):

* mu ~ lognormal, median and logarithmic standard deviation of the 9 in-situ friction
  coefficients of Ogawa et al. Table 2 (Machu Picchu 5, Coricancha 4; data/ogawa/
  roughness_friction.csv read by drystone.studies.ogawa.insitu): median 0.4506, beta 0.137.
* K_n ~ log-uniform between the two calibrations of this wall's material in the
  Sacsayhuaman paper's Table 1 (DEM, Santa-Cruz et al.: 5e7 N/m^3; FEM, the case's value:
  2e8 N/m^3; data/papers/sacsayhuaman.toml); K_t = K_n / 2 (the ratio of both
  calibrations). Assumed: nothing measured gives a distribution of K_n.

One mu and one K_n per run, for every joint of the wall (``contact.mu``, ``contact.kn``,
``contact.kt`` override every material: the analysis's ``draws_given``). Each run's draws
come from its own generator, ``numpy.random.default_rng([seed, record id, component index,
stripe in mg])``, so a run's draws do not depend on which other runs are in the plan (the
small plan's runs draw what the full plan's runs with the same record and stripe draw); the
values are rounded (mu to 4 decimals, K_n to 4 significant digits) and the rounded values
are the ones run.

Where things go: ``<out>/plan.json`` (the seed, the distributions with their sources, every
run's record, name and draws; ``results/fragility/`` for the full config,
``results/fragility_small/`` for the small one) and the analysis's folder ``<out>/stripes/``
(drystone/analyses/fragility.py: ``records/`` the FEMA records it writes, ``runs/<record
stem>-pga_<g>/`` the runs, its own ``fragility.json`` with the package's collapse criterion).

The ``small`` config (2 records x 2 stripes = 4 runs) cuts the record to its first
``record_duration_s`` = 2 s (the excitation stage's ``duration`` key: small config
only) and the rest after it to at most 3 s: a check that the pipeline works end to end,
not a result.
"""
from __future__ import annotations

import hashlib
import json
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from drystone import atomic
from drystone import paths, tomlio

CASE = paths.CASES / "sacsayhuaman" / "record.toml"
#: the base case's stage indices (cases/sacsayhuaman/record.toml: gravity, excitation, rest)
EXCITATION_STAGE = 1
REST_STAGE = 2
#: what the base case does around the record (s): gravity stage, and the rest stage's bounds
GRAVITY_S = 2.0
REST_MIN_S = 1.5   # settle_window: the rest lasts at least this long
REST_MAX_S = 20.0  # the rest stage's duration (its cap)


@dataclass(frozen=True)
class Config:
    """One configuration of the study (``CONFIGS``)."""

    name: str
    out: str                              # study outputs: results/<out>/, the analysis's in results/<out>/stripes/
    set_name: str = "farfield"
    component: str = "a"                  # 'a', 'b' (one per pair) or 'both'
    record_ids: tuple | None = None       # None: every record of the set
    stripes_g: tuple = tuple(round(0.1 * k, 1) for k in range(1, 11))
    seed: int = 695
    record_duration_s: float | None = None  # cut the record (excitation 'duration'): small config only
    rest_max_s: float | None = None         # cap the rest stage: small config only
    friction_tables: tuple = (2,)
    kn_bounds: tuple = (5e7, 2e8)
    kt_over_kn: float = 0.5
    n_boot: int = 1000
    notes: tuple = field(default_factory=tuple)

    @property
    def out_dir(self) -> Path:
        return paths.RESULTS / self.out


CONFIGS = {
    "full": Config(name="full", out="fragility"),
    "small": Config(name="small", out="fragility_small", record_ids=(1, 2),
                    stripes_g=(0.5, 1.0), record_duration_s=2.0, rest_max_s=3.0,
                    notes=("records cut to their first 2 s and the rest capped at 3 s: a pipeline check, "
                           "not a result",)),
}


def get(config: str | Config) -> Config:
    if isinstance(config, Config):
        return config
    if config not in CONFIGS:
        raise KeyError(f"unknown fragility config {config!r} (known: {', '.join(CONFIGS)})")
    return CONFIGS[config]


# --- distributions ---------------------------------------------------------------------------------------
def friction_distribution(tables=(2,)) -> dict:
    """Lognormal of mu from Ogawa et al.'s friction measurements in ``tables`` (2: in situ,
    3: per surface finishing): median exp(mean ln mu), beta = sample standard deviation of
    ln mu (n - 1), i.e. the maximum-likelihood median and the unbiased log-variance."""
    from drystone.studies.ogawa import insitu

    rows = [r for r in insitu.load() if r["table"] in tuple(tables) and r["friction"] is not None]
    if len(rows) < 2:
        raise ValueError(f"Ogawa et al. tables {tables}: fewer than 2 friction values")
    v = np.array([r["friction"] for r in rows])
    ln = np.log(v)
    return {"parameter": "mu", "distribution": "lognormal", "median": float(np.exp(ln.mean())),
            "beta": float(ln.std(ddof=1)), "n": len(v), "values": v.tolist(),
            "sites": sorted({r["site"] for r in rows}), "tables": list(tables),
            "source": (f"Ogawa et al., 'Influence of the friction coefficient on the seismic behavior of Inca stone "
                       f"masonry', Table(s) {', '.join(map(str, tables))} ({len(v)} friction coefficients: "
                       f"data/ogawa/roughness_friction.csv); lognormal: median = exp(mean ln mu), beta = sd(ln mu)")}


def stiffness_distribution(bounds=(5e7, 2e8), kt_over_kn: float = 0.5) -> dict:
    """Log-uniform K_n (N/m^3) between ``bounds``; K_t = kt_over_kn x K_n."""
    from drystone.postprocess import compare

    t = compare.paper("sacsayhuaman")["tilt"]
    lo, hi = float(bounds[0]), float(bounds[1])
    if not 0 < lo < hi:
        raise ValueError(f"K_n bounds must be 0 < low < high, got {bounds}")
    return {"parameter": "kn", "distribution": "loguniform", "low": lo, "high": hi, "kt_over_kn": kt_over_kn,
            "unit": "N/m^3",
            "calibrations": {"dem": {"kn": t["dem_calibration"]["kn_N_m3"], "kt": t["dem_calibration"]["kt_N_m3"]},
                             "fem": {"kn": t["fem_calibration"]["kn_N_m3"], "kt": t["fem_calibration"]["kt_N_m3"]}},
            "source": ("assumed: log-uniform between the two calibrations of the Sacsayhuaman paper's Table 1 "
                       f"(DEM, Santa-Cruz et al.: K_n {t['dem_calibration']['kn_N_m3']:.3g}, K_t "
                       f"{t['dem_calibration']['kt_N_m3']:.3g}; FEM, present study and the case: K_n "
                       f"{t['fem_calibration']['kn_N_m3']:.3g}, K_t {t['fem_calibration']['kt_N_m3']:.3g} N/m^3; "
                       "data/papers/sacsayhuaman.toml); K_t = K_n / 2, the ratio of both; no measurement gives a "
                       "spread of K_n")}


def distributions(cfg: Config) -> dict:
    return {"mu": friction_distribution(cfg.friction_tables),
            "kn": stiffness_distribution(cfg.kn_bounds, cfg.kt_over_kn)}


def _sig(x: float, digits: int = 4) -> float:
    return float(f"{x:.{digits - 1}e}")


def draw(seed: int, record_id: int, component: str, pga_g: float, dists: dict) -> dict:
    """The draws of one run (mu, kn, kt), from its own generator (module docstring)."""
    key = [int(seed), int(record_id), "ab".index(component), int(round(pga_g * 1000))]
    rng = np.random.default_rng(key)
    m, k = dists["mu"], dists["kn"]
    mu = round(m["median"] * math.exp(m["beta"] * rng.standard_normal()), 4)
    kn = _sig(math.exp(math.log(k["low"]) + rng.uniform() * (math.log(k["high"]) - math.log(k["low"]))))
    return {"mu": mu, "kn": kn, "kt": _sig(kn * k["kt_over_kn"]), "rng_key": key}


# --- records ---------------------------------------------------------------------------------------------
def components(cfg: Config) -> list[dict]:
    """The catalogue entries (motions.fema.catalogue) of the components the plan uses, in
    record order."""
    from drystone.motions import fema

    cat = fema.catalogue(cfg.set_name)
    ids = sorted({c["record_id"] for c in cat})
    if cfg.record_ids is not None:
        missing = sorted(set(cfg.record_ids) - set(ids))
        if missing:
            raise KeyError(f"FEMA P695 {cfg.set_name}: no record(s) {missing}")
        ids = [i for i in ids if i in cfg.record_ids]
    comps = ("a", "b") if cfg.component == "both" else (cfg.component,)
    if not set(comps) <= {"a", "b"}:
        raise ValueError(f"component must be 'a', 'b' or 'both', got {cfg.component!r}")
    return [c for i in ids for c in cat if c["record_id"] == i and c["component"] in comps]


def record_id(c: dict) -> str:
    """The analysis's id of a catalogue entry (drystone.motions.fema.parse_id), e.g. fema:farfield:7a."""
    return f"fema:{c['set']}:{c['record_id']}{c['component']}"


def analysis_dir(out_dir: Path) -> Path:
    """The fragility analysis's folder within the study's (its records, runs, fragility.json)."""
    return Path(out_dir) / "stripes"


def run_name(record_file, pga_g: float) -> str:
    """A run's name as the analysis gives it (drystone/analyses/fragility.py: stripes)."""
    from drystone.analyses import common

    return f"{common.safe_name(str(record_file))}-pga_{common.number_tag(pga_g)}"


# --- the plan --------------------------------------------------------------------------------------------
def build(cfg: Config, out_dir: Path | None = None, write_records: bool = True) -> dict:
    """The plan as a dict (config, distributions, records, runs with their draws in the
    analysis's order: record by record, stripes increasing). The records are written by the
    analysis's own ``resolve_records`` into ``analysis_dir(out_dir)/records``."""
    from drystone.analyses import common, fragility as analysis
    from drystone.motions import fema

    cfg = get(cfg)
    if len(cfg.stripes_g) != len(set(cfg.stripes_g)) or any(s <= 0 for s in cfg.stripes_g):
        raise ValueError(f"stripes must be distinct positive PGAs, got {cfg.stripes_g}")
    out_dir = Path(out_dir) if out_dir is not None else cfg.out_dir
    folder = analysis_dir(out_dir) / "records"
    dists = distributions(cfg)
    comps = components(cfg)
    if write_records:  # into the analysis's folder (made as the analysis makes it), as the analysis writes them
        common.output_dir(CASE, "fragility", analysis_dir(out_dir))
        analysis.resolve_records([record_id(c) for c in comps], folder)
    runs, records = [], []
    for c in comps:
        path = folder / fema.file_name(c)
        dur = (c["npts"] - 1) * c["dt_s"]
        records.append({**{k: c[k] for k in ("set", "record_id", "component", "name", "event", "year", "station",
                                               "rsn", "dt_s", "npts", "pga_max_g")},
                        "id": record_id(c), "duration_s": dur, "file": str(path),
                        "sha256": hashlib.sha256(path.read_bytes()).hexdigest() if path.exists() else None})
        for pga in sorted(cfg.stripes_g):
            d = draw(cfg.seed, c["record_id"], c["component"], pga, dists)
            used = min(dur, cfg.record_duration_s) if cfg.record_duration_s else dur
            runs.append({"name": run_name(path, pga), "record_id": c["record_id"], "component": c["component"],
                         "record_name": c["name"], "record_file": str(path), "pga_g": float(pga),
                         "record_duration_s": used, **d})
    return {"format": "drystone.fragility_plan", "version": 2, "config": asdict(cfg), "case": str(CASE),
            "analysis": {"method": "stripes", "folder": str(analysis_dir(out_dir)),
                         "records": [r["id"] for r in records], "levels_g": sorted(cfg.stripes_g)},
            "distributions": dists, "records": records, "runs": runs,
            "common_overrides": common_overrides(cfg)}


def common_overrides(cfg: Config) -> list[str]:
    """Every run's overrides: the record and the rest cut to the config's durations."""
    return tomlio.stage_durations({EXCITATION_STAGE: cfg.record_duration_s, REST_STAGE: cfg.rest_max_s})


def draws(plan: dict) -> list[dict]:
    """The contact values of every run, in the analysis's order (``draws_given``)."""
    return [{"mu": r["mu"], "kn": r["kn"], "kt": r["kt"]} for r in plan["runs"]]


def write(cfg: Config | str, out_dir: Path | None = None) -> Path:
    """Write the records and ``<out>/plan.json``; returns plan.json's path. Deterministic:
    the same config writes the same plan."""
    cfg = get(cfg)
    out = Path(out_dir) if out_dir is not None else cfg.out_dir
    out.mkdir(parents=True, exist_ok=True)
    plan = build(cfg, out)
    path = out / "plan.json"
    atomic.write_text(path, json.dumps(plan, indent=1) + "\n")
    return path


def load_plan(out_dir: Path) -> dict:
    p = Path(out_dir) / "plan.json"
    if not p.is_file():
        raise FileNotFoundError(f"{p}: no plan (python -m drystone.studies.fragility plan)")
    return json.loads(p.read_text())
