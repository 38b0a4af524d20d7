"""make bench: speed of the 40-block running-bond wall (8.64 x 4 x 0.8 m, 5 courses of 8,
K_n = 2e8 N/m^3, 2300 kg/m^3, on a fixed platform) under gravity, for YADE's stock law and
ours (on YADE's contact geometry and on the native one), on 1 and 2 threads. Prints
milliseconds per step, steps per second, active contacts and the share of the step spent
in our per-step Python engine. Not a test."""
from __future__ import annotations

import json
import tempfile
from pathlib import Path

from drystone import paths, runner

CASE = {
    "case": {"name": "bench_running_bond", "geometry": {"generator": "running_bond"}},
    "stages": [{"type": "gravity", "duration": 0.4, "ramp": 0.2}],
    "output": {"interval": 0.02},
}


VARIANTS = (("stock_volumetric", "yade"), ("penalty_coulomb", "yade"), ("penalty_coulomb", "native"))


def measure(law: str, detection: str, threads: int, workdir: Path) -> dict:
    out = workdir / f"{law}_{detection}_{threads}"
    s = runner.run_dict(CASE, workdir / f"{law}_{detection}_{threads}.toml", out_dir=out, threads=threads,
                        quiet=True, overrides=[f"contact.law={law}", f"contact.detection={detection}"])
    r = s["run"]
    info = json.loads((out / "run_info.json").read_text())
    return {"law": law, "detection": detection, "threads": threads, "ms_per_step": r["us_per_step"] / 1e3,
            "steps_per_s": 1e6 / r["us_per_step"], "contacts": info["max_contacts"],
            "python_ms_per_step": r["python_us_per_step"] / 1e3, "steps": r["steps"], "dt_s": r["dt_s"]}


def main() -> list[dict]:
    rows = []
    with tempfile.TemporaryDirectory(dir=paths.ROOT) as tmp:
        for law, detection in VARIANTS:
            for threads in (1, 2):
                rows.append(measure(law, detection, threads, Path(tmp)))
                r = rows[-1]
                print(f"{law:17s} {detection:6s} {threads} thread(s): {r['ms_per_step']:7.2f} ms/step  "
                      f"{r['steps_per_s']:7.1f} steps/s  "
                      f"{r['contacts']:4d} contacts  python {r['python_ms_per_step']:6.2f} ms/step  "
                      f"({r['steps']} steps of {r['dt_s']:.2e} s)", flush=True)
    out = paths.RESULTS / "bench"
    out.mkdir(parents=True, exist_ok=True)
    (out / "bench.json").write_text(json.dumps(rows, indent=1))
    print(f"written {out / 'bench.json'}")
    return rows
