"""python -m drystone.studies.site {plan,run,report,all} [--config full|small] [--workers N] [--dask ADDRESS]

plan     the records' strong-motion windows (and reversed copies), the retained wall's caps
         -> results/<out>/plan.json
run      plan, the tilt analyses, the retained wall's static runs (dry, then the water level at failure),
         then the PGA at collapse of every wall, site (rock, surface), record and polarity by the collapse
         analysis (results/<out>/tilt/, static/, searches/; resumable: finished runs are reused)
report   the analyses' results read back -> site.json, runs.csv, site.png, spectra.png, report.md,
         report.html
all      run, then report
--config small: 1 record cut to 0.75 s, coarse brackets (results/site_small/): a pipeline check, not a result."""
from __future__ import annotations

from drystone.studies import exit_status
from drystone.studies import common as sc
from drystone.studies.site import plan as planmod
from drystone.studies.site import report
from drystone.studies.site import run as runmod


def _plan(cfg) -> str:
    p = planmod.build(cfg)
    return f"{cfg.out_dir / 'plan.json'}: walls {', '.join(p['walls'])}, records {', '.join(p['records'])}"


def main(argv=None) -> int:
    return sc.main(argv, "python -m drystone.studies.site", __doc__, planmod.CONFIGS, _plan, runmod.run,
                       report.write, "site")


if __name__ == "__main__":
    raise SystemExit(exit_status(main()))
