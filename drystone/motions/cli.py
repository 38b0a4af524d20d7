"""Command line: ``python -m drystone.motions records`` and ``python -m drystone.motions spectrum FILE``.

``records [--user-dir DIR] [--out DIR]`` resolves every paper record (user file or FEMA
P695 analogue), re-runs the analogue rule, writes ``catalogue.json`` and one PNG per
record to ``results/records/`` and prints a table; exit status 1 if the rule no longer
gives the frozen analogues of ``motions.catalogue.ANALOGUES``.

``spectrum FILE [--format F] [--component C] [--dt S] [--units U] [--out DIR]`` reads any
supported record (FILE may also be a catalogue name), prints a JSON object (PGA in g,
step, duration, predominant frequencies and band in Hz, ..., and the intensity measures of
``motions.intensity``: PGV in m/s, PGD in m, Arias intensity in m/s, 5 %-damped Sa in g at
``intensity.REPORT_PERIODS_S``) and writes the record, its Fourier spectrum and Sa(T) as a
PNG to ``results/spectra/``.

``site PROFILE [--record R] [--pga-g G] [--duration S] [--out DIR]`` propagates a record
(catalogue name or file, scaled to G at rock) through a site-profile file
(``motions.site``), prints f0 (Hz), the amplification, the PGA at rock and at the surface
(g) and the iterations as JSON, and writes ``<stem>_site.json`` (everything, with the
profile's provenance), ``<stem>_surface.npy`` and ``<stem>_bedrock.npy`` (m/s^2 at the
record's step) and ``<stem>_site.png`` to ``results/site/``.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import re
import sys
import warnings
from pathlib import Path

import numpy as np

import drystone
from drystone import atomic
from drystone.motions import analysis, catalogue, intensity, readers

from drystone.paths import RESULTS, ROOT  # noqa: E402


def _round(x, nd=4):
    if isinstance(x, float):
        return round(x, nd)
    if isinstance(x, list):
        return [_round(v, nd) for v in x]
    if isinstance(x, dict):
        return {k: _round(v, nd) for k, v in x.items()}
    return x


#: the time steps (s) ``spectrum --dt`` accepts: 100 kHz sampling to 1 Hz
DT_RANGE_S = (1e-5, 1.0)


def _out_dir(arg, default: Path) -> Path:
    """The output folder of ``--out`` (default ``default``): refused when it names an
    existing file (nothing is written then)."""
    out = Path(arg).expanduser() if arg else default
    if out.exists() and not out.is_dir():
        raise ValueError(f"--out {out}: exists and is not a folder; nothing written")
    return out


def _non_finite(x, key: str = "") -> list[str]:
    """Dotted keys of the non-finite floats in nested dicts and lists."""
    if isinstance(x, dict):
        return [k for n, v in x.items() for k in _non_finite(v, f"{key}.{n}" if key else str(n))]
    if isinstance(x, (list, tuple, np.ndarray)):
        return [k for i, v in enumerate(x) for k in _non_finite(v, f"{key}[{i}]")][:1]
    return [key] if isinstance(x, (float, np.floating)) and not math.isfinite(x) else []


def _write_together(writers: dict) -> list[Path]:
    """Write each file of ``writers`` ({final path: function writing a given path}) aside
    (``drystone.atomic``), then rename them all into place: a failure (a full disk, a
    read-only folder) replaces none of them and raises OSError naming the final path."""
    tmps = []
    try:
        for path, write in writers.items():
            tmps.append(atomic.temporary(path))
            try:
                write(tmps[-1])
            except OSError as exc:
                raise atomic.named(exc, path) from None
        for tmp, path in zip(tmps, writers):
            try:
                os.replace(tmp, path)
            except OSError as exc:
                raise atomic.named(exc, path) from None
            atomic.record(path)
    finally:
        for tmp in tmps:
            try:
                os.unlink(tmp)
            except OSError:
                pass
    return list(writers)


def cmd_records(args) -> int:
    from drystone.motions.plots import plot_record

    out = _out_dir(args.out, RESULTS / "records")
    out.mkdir(parents=True, exist_ok=True)
    table = catalogue.build(user_dir=args.user_dir)
    table["drystone_version"] = drystone.__version__
    for name, e in table["records"].items():
        r = catalogue.get(name, args.user_dir)
        png = out / f"{name}.png"
        with atomic.aside(png) as tmp:
            plot_record(r, tmp, title=f"{name}: {r.event}\n{r.station}, {r.component}, PGA {r.pga_g:.3f} g")
        e["png"] = str(png)
    atomic.write_text(out / "catalogue.json", json.dumps(table, indent=1, allow_nan=False))
    print(f"{'name':<11} {'source':<9} {'station':<22} {'comp':<9} {'PGA g':>6} {'dur s':>6} {'dt s':>6}  band Hz")
    bad = []
    for name, e in table["records"].items():
        lo, hi = e["predominant_band_hz"]
        print(f"{name:<11} {e['source_kind'].split()[0]:<9} {e['station'][:22]:<22} {e['component'][:9]:<9} "
              f"{e['pga_g']:6.3f} {e['duration_s']:6.1f} {e['dt_s']:6.3f}  {lo:.2f}-{hi:.2f}")
        if not e["analogue"]["rule_matches_frozen"]:
            bad.append(f"{name}: rule gives {e['analogue']['rule_gives']}, frozen {e['analogue']['frozen']}")
    print(f"wrote {out / 'catalogue.json'}")
    for b in bad:
        print(f"error: analogue rule and frozen choice differ: {b}", file=sys.stderr)
    return 1 if bad else 0


def cmd_spectrum(args) -> int:
    from drystone.motions.plots import plot_record

    if args.dt is not None and not DT_RANGE_S[0] <= args.dt <= DT_RANGE_S[1]:
        raise ValueError(f"--dt {args.dt:g} s: the time step must be in [{DT_RANGE_S[0]:g}, {DT_RANGE_S[1]:g}] s "
                         "(100 kHz to 1 Hz sampling)")
    out = _out_dir(args.out, RESULTS / "spectra")
    p = Path(args.file)
    if not p.is_file() and args.file in catalogue.names():
        r = catalogue.get(args.file)
        fmt = "catalogue"
        stem = args.file
    elif not p.is_file():
        raise FileNotFoundError(f"{p}: no such record file (nor a catalogue name: {', '.join(catalogue.names())})")
    else:
        fmt = args.format or readers.detect_format(p)
        r = readers.read(p, format=fmt, component=args.component, dt=args.dt, units=args.units)
        stem = p.stem
    with np.errstate(all="ignore"), warnings.catch_warnings():  # overflow: refused below, naming the keys
        warnings.simplefilter("ignore", RuntimeWarning)
        spec = analysis.smoothed_spectrum(r)
        d = analysis.describe(r, spec)
        im = intensity.measures(r)
        # the figure's Sa(T): 100 periods from 0.02 s (or two steps) to 5 s, log-spaced
        per = np.geomspace(max(0.02, 2 * r.dt), 5.0, 100)
        curve = {"periods_s": per, "psa_g": intensity.psa_g(r, per), "damping": intensity.DAMPING}
    comp = re.sub(r"[^A-Za-z0-9._-]+", "_", r.component)
    png = out / f"{stem}_{comp}.png"
    obj = {"file": str(args.file), "format": fmt, "event": r.event, "station": r.station, "component": r.component,
           "units_in_file": r.units_in_file, "pga_g": d["pga_g"], "pga_m_s2": d["pga_m_s2"], "dt_s": r.dt,
           "n_samples": r.n, "duration_s": r.duration, "predominant_frequencies_hz": d["predominant_frequencies_hz"],
           "predominant_band_hz": d["predominant_band_hz"], "significant_duration_s": d["significant_duration_s"],
           "onset_s": d["onset_s"], "pgv_m_s": im["pgv_m_s"], "pgd_m": im["pgd_m"], "arias_m_s": im["arias_m_s"],
           "sa_periods_s": im["sa"]["periods_s"], "sa_g": im["sa"]["psa_g"], "sa_damping": im["sa"]["damping"],
           "intensity_notes": "PGV, PGD: trapezoid integrals of the samples from rest, no baseline correction; "
                              "Arias pi/(2 g) int a^2 dt; Sa: pseudo-spectral acceleration omega^2 max|u|",
           "spectrum_settings": analysis.SETTINGS, "history": r.history, "png": str(png)}
    bad = _non_finite(dict(obj, figure_sa_g=curve["psa_g"], fourier=spec["smoothed"]))
    if bad:
        raise ValueError(f"{args.file}: the record gives non-finite results ({', '.join(bad[:6])}): its samples "
                         f"(peak {r.pga:.3g} m/s^2, dt {r.dt:g} s) overflow double precision; nothing written")
    text = json.dumps(_round(obj), indent=1, allow_nan=False)
    out.mkdir(parents=True, exist_ok=True)
    with atomic.aside(png) as tmp:
        plot_record(r, tmp, spec=spec, summary=d, response=curve)
    print(text)
    return 0


def cmd_site(args) -> int:
    from drystone.motions import excitation, site
    from drystone.motions.plots import plot_site

    out = _out_dir(args.out, RESULTS / "site")
    sp = site.read_profile(args.profile)
    rec = args.record if args.record in catalogue.names() or Path(args.record).is_absolute() \
        else str(Path(args.record).resolve()) if Path(args.record).is_file() else args.record
    rock = excitation.record_for_stage({"motion": "record", "record": rec, "pga_g": args.pga_g,
                                        "duration": args.duration})
    surface, info = site.propagate(rock, sp)
    warning = site.convergence_warning(info)
    stem = Path(args.profile).stem
    files = {k: out / f"{stem}_{k}" for k in ("surface.npy", "bedrock.npy", "site.json", "site.png")}
    text = json.dumps({
        "units": "accelerations m/s^2, dt s, frequencies Hz, lengths m, velocities m/s, stresses kPa",
        "drystone_version": drystone.__version__, "bedrock_record": rock.metadata(),
        "surface_record": surface.metadata(), "site_response": dict(info, warning=warning)}, indent=1,
        allow_nan=False)
    obj = {k: info[k] for k in ("f0_linear_hz", "amplification_linear", "f0_quarter_wave_hz", "f0_compatible_hz",
                                "amplification_compatible", "pga_rock_g", "pga_surface_g", "iterations",
                                "converged", "input", "output")}
    obj.update(warning=warning, profile=sp.path, sha256=sp.sha256, assumed=sp.assumed, record=rock.event,
               json=str(files["site.json"]), png=str(files["site.png"]))
    printed = json.dumps(_round(obj), indent=1, allow_nan=False)
    out.mkdir(parents=True, exist_ok=True)

    def npy(a):
        def write(tmp):
            with open(tmp, "wb") as f:
                np.save(f, a)
        return write

    _write_together({
        files["surface.npy"]: npy(surface.acc), files["bedrock.npy"]: npy(rock.acc),
        files["site.json"]: lambda tmp: Path(tmp).write_text(text),
        files["site.png"]: lambda tmp: plot_site(rock, surface, info, info["tf_freqs_hz"], info["tf_linear_abs"],
                                                 info["tf_compatible_abs"], tmp)})
    if warning:
        print(warning, file=sys.stderr)
    print(printed)
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m drystone.motions", description="ground-motion records and spectra")
    sub = ap.add_subparsers(dest="cmd", required=True)
    a = sub.add_parser("records", help="resolve the papers' records, write results/records/catalogue.json")
    a.add_argument("--user-dir", default=None, help=f"folder of the user's record files (default {catalogue.USER_DIR})")
    a.add_argument("--out", default=None, help="output folder (default results/records)")
    b = sub.add_parser("spectrum", help="PGA, PGV, Arias, Sa(T), step, duration and predominant frequencies of "
                                        "a record file")
    b.add_argument("file", help="record file (or a catalogue name)")
    b.add_argument("--format", choices=readers.FORMATS, default=None, help="file format (default: guessed)")
    b.add_argument("--component", default=None, help="component of a multi-component file (default NS)")
    b.add_argument("--dt", type=float, default=None, help="time step (s) when the file does not give it")
    b.add_argument("--units", default=None, help="units when the file does not declare them (gal, g, m/s^2)")
    b.add_argument("--out", default=None, help="output folder for the PNG (default results/spectra)")
    c = sub.add_parser("site", help="propagate a record at rock through a site profile (1-D soil column, "
                                    "equivalent linear) to the surface")
    c.add_argument("profile", help="site-profile file (TOML; docs/motions.md, Site response)")
    c.add_argument("--record", default="kobe1995", help="catalogue name or record file (default kobe1995)")
    c.add_argument("--pga-g", type=float, default=None, help="scale the record to this PGA AT ROCK (g)")
    c.add_argument("--duration", type=float, default=None, help="keep the first DURATION s of the record")
    c.add_argument("--out", default=None, help="output folder (default results/site)")
    args = ap.parse_args(argv)
    try:
        return {"records": cmd_records, "spectrum": cmd_spectrum, "site": cmd_site}[args.cmd](args)
    except (readers.RecordFormatError, FileNotFoundError, KeyError, ValueError) as exc:
        if isinstance(exc, FileNotFoundError) and exc.filename:
            print(f"error: {exc.filename}: {exc.strerror}", file=sys.stderr)
        else:
            print(f"error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:  # a read-only or full folder: the file named, nothing half-written
        print(f"error: {exc.filename or ''}: {exc.strerror or exc}", file=sys.stderr)
        return 2
