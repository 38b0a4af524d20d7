"""python -m drystone.studies.shape {plan,run,report,all} [--config full|small] [--workers N] [--dask ADDRESS]

plan     the four walls x seeds (results/<out>/geometry/) and the records' strong-motion windows
         (results/<out>/records/) -> results/<out>/plan.json
run      plan, then per wall the tilt analysis and the collapse analysis (PGA at collapse on the study's grid),
         results/<out>/walls/<wall>/{tilt,collapse}/ (resumable: finished runs are reused; local pool or Dask)
report   the analyses' results read back -> shape.json, runs.csv, shape.png, report.md
all      run, then report
--config small: 2 variants, 1 seed, 1 record cut to 1 s, a 1.6 g bracket (results/shape_small/): a
pipeline check, not a result."""
from __future__ import annotations

from drystone.studies import exit_status
from drystone.studies import common as sc
from drystone.studies.shape import plan as planmod
from drystone.studies.shape import study


def _plan(cfg) -> str:
    p = planmod.build(cfg)
    return f"{cfg.out_dir / 'plan.json'}: {len(p['geometries'])} walls, records {', '.join(p['records'])}"


def main(argv=None) -> int:
    return sc.main(argv, "python -m drystone.studies.shape", __doc__, planmod.CONFIGS, _plan, study.run,
                       study.report, "shape")


if __name__ == "__main__":
    raise SystemExit(exit_status(main()))
