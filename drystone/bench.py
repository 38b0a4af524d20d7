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


#: (law, detection) pairs measured: the stock law on its only geometry, ours on both
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
        sacs = sacsayhuaman_times(Path(tmp))
    print(f"\nSacsayhuaman section, one core, {sacs[0]['detection']} contacts, against the paper's Abaqus/Explicit "
          "on 8 cores:")
    for r in sacs:
        done = (f"; study runs: {min(r['study_runs_wall_s']):.0f}-{max(r['study_runs_wall_s']):.0f} s"
                if r["study_runs_wall_s"] else "")
        print(f"  {r['analysis']:17s} {r['simulated_s']:5.1f} s simulated: ~{r['estimated_wall_s']:6.0f} s "
              f"(Abaqus {r['abaqus_8_cores_s'] / 60:5.0f} min: {r['speedup_vs_abaqus']:5.1f} x faster){done}", flush=True)
    out = paths.RESULTS / "bench"
    out.mkdir(parents=True, exist_ok=True)
    (out / "bench.json").write_text(json.dumps({"running_bond": rows, "sacsayhuaman": sacs}, indent=1))
    print(f"written {out / 'bench.json'}")
    return rows


#: the Sacsayhuaman paper's Abaqus/Explicit run times on 8 cores (data/papers/sacsayhuaman.toml)
ANALYSES = (("white noise 30 s", "white_noise_30s", "sacsayhuaman_white_noise", 30.0),
            ("sine 10 s", "sine_10s", "sacsayhuaman_sine", 10.0),
            ("Paruro 60 s", "paruro_60s", "paruro2014", None),
            ("Cusco", "cusco", "cusco2023", None),
            ("Ancash", "ancash", "ancash1970", None))


def sacsayhuaman_times(workdir: Path) -> list[dict]:
    """Wall time per analysis of the 40-stone section on one core: measured ms/step of a
    short white-noise run times the analysis's steps (gravity 2 s + the motion; a sine
    also has 2 s of rest, a record 2 s), beside the paper's Abaqus times on 8 cores, and
    the times of finished study runs where there are some. The case leaves the contact
    geometry to its default (``drystone.contact.default_detection``), as the study's cases do."""
    from drystone.motions import catalogue
    from drystone.postprocess import compare

    case = {"case": {"name": "bench_sacsayhuaman", "geometry": {"generator": "sacsayhuaman", "seed": 0}},
            "stages": [{"type": "gravity", "duration": 0.5, "ramp": 0.25},
                       {"type": "excitation", "motion": "white_noise", "duration": 1.5, "direction": "y"}],
            "output": {"interval": 0.01}}
    s = runner.run_dict(case, workdir / "sacs.toml", out_dir=workdir / "sacs", threads=1, quiet=True)
    ms, dt = s["run"]["us_per_step"] / 1e3, s["run"]["dt_s"]
    detection = json.loads((workdir / "sacs" / "spec.json").read_text())["detection"]
    abaqus = compare.paper("sacsayhuaman")["run_times_s"]
    rows = []
    for label, key, source, dur in ANALYSES:
        if dur is None:
            dur = catalogue.get(source).duration
            if source == "paruro2014":
                dur = min(dur, 60.0)
        sim = 2.0 + dur + (2.0 if key != "white_noise_30s" else 0.0)
        est = sim / dt * ms / 1e3
        actual = _actual_wall_times(source)
        rows.append({"analysis": label, "simulated_s": sim, "estimated_wall_s": est, "abaqus_8_cores_s": abaqus[key],
                     "speedup_vs_abaqus": abaqus[key] / est, "ms_per_step": ms, "dt_s": dt, "detection": detection,
                     "study_runs_wall_s": actual})
    return rows


def _actual_wall_times(source: str) -> list[float]:
    """Wall times (s) of finished study runs of this analysis, if any."""
    import glob
    if source.startswith("sacsayhuaman_"):
        pattern = str(paths.RESULTS / source / "*" / "summary.json")
    else:
        pattern = str(paths.RESULTS / "sacsayhuaman_table3" / f"record_{source}-*" / "summary.json")
    return [json.loads(Path(p).read_text())["run"]["wall_time_s"] for p in sorted(glob.glob(pattern))]
