"""python -m drystone.studies.sacsayhuaman {identify, sine, resonance, table3, all, report, demo} [--workers N] [--dask ADDRESS]

identify   white noise out of plane -> peaks of A-D (results/sacsayhuaman_white_noise)
sine       Eq. 9 sines (as a displacement) over 0.1-20 Hz, 0.976 Hz and at the white-noise peaks -> dominant frequency
resonance  the sine at the paper's 0.976 Hz and at the wall's own peak [--frequency HZ] scaled to PGA 0.1-0.9 g
table3     three records x nine PGAs (Table 3)
all        the four above in order, then the report
report     results/sacsayhuaman/: identification.json, table3.csv, figures, report.md
demo       one record at two PGAs with a short report (make demo)
Every step is a resumable sweep: finished runs are skipped."""
from __future__ import annotations

import argparse

from drystone.studies import exit_status
from drystone.studies.sacsayhuaman import study


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="sacsayhuaman", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("step", choices=("identify", "sine", "resonance", "table3", "all", "report", "demo"))
    ap.add_argument("--workers", type=int, default=None, help="parallel runs (default: cores)")
    ap.add_argument("--dask", metavar="ADDRESS", default=None, help="Dask scheduler address, or 'local'")
    ap.add_argument("--frequency", type=float, default=None, help="resonance frequency (Hz) for 'resonance'")
    a = ap.parse_args(argv)
    backend = "dask" if a.dask else "local"
    kw = {"workers": a.workers, "backend": backend, "address": a.dask}
    if a.step == "identify":
        r = study.identify(**kw)
        for k, v in r["control_points"].items():
            print(f"{k}: peaks {', '.join(f'{f:.3f}' for f in v['peaks_hz'])} Hz")
    elif a.step == "sine":
        print(f"dominant frequency: {study.sine(**kw)['dominant_frequency_hz']} Hz")
    elif a.step == "resonance":
        for r in study.resonance(frequency_hz=a.frequency, **kw):
            print(f"{r['frequency_hz']:.3f} Hz, PGA {r['pga_g']:g} g: max out-of-plane residual "
                  f"{r['max_residual_mm']:.2f} mm ({r['max_residual_3d_mm']:.2f} mm in 3D), moved {r['moved']}, "
                  f"collapsed {r['collapsed']}, motion died out: {r['settled']}")
    elif a.step == "table3":
        study.table3(**kw)
    elif a.step == "all":
        study.run_all(**kw)
    elif a.step == "demo":
        print(open(study.demo(a.workers)).read())
        return 0
    path = study.report()
    print(open(path).read())
    print(f"report: {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(exit_status(main()))
