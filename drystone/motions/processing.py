"""Processing of records with obspy and scipy: each function returns a new Record and
appends what it did to ``history`` (nothing changes a record silently).

* ``baseline_correct(r, "demean"|"linear"|"polynomial", order)``  obspy ``Trace.detrend``
* ``taper(r, fraction=0.05)``     Hann-shaped cosine taper on each end (obspy ``Trace.taper``)
* ``bandpass(r, fmin_hz, fmax_hz, corners=4)``  zero-phase Butterworth (obspy ``Trace.filter``);
  ``fmin_hz=None`` gives a low-pass, ``fmax_hz=None`` a high-pass
* ``resample(r, dt, method="lanczos"|"linear")``  to a new step (s): down-sampling first
  low-passes at 0.8 x the new Nyquist frequency (zero-phase, 8 corners), then obspy
  ``Trace.interpolate`` (Lanczos, a = 20) or linear interpolation; the new record covers
  the same time span, floor(duration / dt) + 1 samples
* ``integrate(r, highpass_hz=None, poly_order=6)``  velocity (m/s) and displacement (m),
  cumulative trapezoid (scipy). Drift control: optional zero-phase high-pass of the
  acceleration, then a polynomial p(t) = sum_{k=2..order} c_k t^k fitted (least squares)
  to the displacement is removed from it, and p'' from the acceleration, so the three
  histories stay consistent (a -> v -> d) and start at rest; returns ``Kinematics``
* ``scale_to_pga(r, pga_g=... | pga=...)``  multiply so that max|a| equals the target (to
  rounding, relative 1e-15); ``scale(r, factor)``
* ``trim(r, t0, t1)``  samples with t0 <= time <= t1 (time as in ``Record.time``)
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
from scipy import integrate as sint

from drystone.motions.record import G, Record


def to_trace(r: Record):
    """obspy Trace of the samples (m/s^2), starting at UTCDateTime(start_time)."""
    import obspy

    return obspy.Trace(data=r.acc.copy(), header={"delta": r.dt, "starttime": obspy.UTCDateTime(r.start_time),
                                                  "station": r.station[:5], "channel": r.component[:3]})


def _from_trace(r: Record, tr, note: str) -> Record:
    return r.replaced(note, acc=np.asarray(tr.data, float), dt=float(tr.stats.delta))


def baseline_correct(r: Record, kind: str = "linear", order: int = 2) -> Record:
    """Remove the mean ('demean'), a straight line ('linear') or a polynomial of ``order``."""
    tr = to_trace(r)
    if kind == "polynomial":
        tr.detrend("polynomial", order=order)
        note = f"baseline: polynomial of order {order} removed (obspy detrend)"
    elif kind in ("demean", "linear"):
        tr.detrend(kind)
        note = f"baseline: {kind} (obspy detrend)"
    else:
        raise ValueError(f"unknown baseline correction {kind!r}: demean, linear or polynomial")
    return _from_trace(r, tr, note)


def taper(r: Record, fraction: float = 0.05) -> Record:
    """Hann (cosine) taper over ``fraction`` of the length at each end."""
    if not 0 < fraction <= 0.5:
        raise ValueError(f"taper fraction must be in (0, 0.5], got {fraction}")
    tr = to_trace(r)
    tr.taper(max_percentage=fraction, type="hann")
    return _from_trace(r, tr, f"taper: Hann, {fraction:.3g} of the length at each end (obspy)")


def bandpass(r: Record, fmin_hz: float | None, fmax_hz: float | None, corners: int = 4) -> Record:
    """Zero-phase Butterworth band-pass (or high-/low-pass when one limit is None)."""
    tr = to_trace(r)
    nyq = 0.5 / r.dt
    if fmax_hz is not None and fmax_hz >= nyq:
        raise ValueError(f"fmax_hz = {fmax_hz} Hz is not below the Nyquist frequency {nyq:g} Hz")
    if fmin_hz is not None and fmax_hz is not None:
        tr.filter("bandpass", freqmin=fmin_hz, freqmax=fmax_hz, corners=corners, zerophase=True)
        note = f"band-pass {fmin_hz:g}-{fmax_hz:g} Hz"
    elif fmin_hz is not None:
        tr.filter("highpass", freq=fmin_hz, corners=corners, zerophase=True)
        note = f"high-pass {fmin_hz:g} Hz"
    elif fmax_hz is not None:
        tr.filter("lowpass", freq=fmax_hz, corners=corners, zerophase=True)
        note = f"low-pass {fmax_hz:g} Hz"
    else:
        raise ValueError("bandpass needs fmin_hz, fmax_hz or both")
    return _from_trace(r, tr, f"{note}: Butterworth, {corners} corners, zero-phase (obspy)")


def resample(r: Record, dt: float, method: str = "lanczos") -> Record:
    """The record at step ``dt`` (s) over the same span; see the module docstring."""
    dt = float(dt)
    if not dt > 0:
        raise ValueError(f"resample: dt must be positive, got {dt}")
    if abs(dt - r.dt) <= 1e-12 * r.dt:
        return r
    n = int(np.floor(r.duration / dt + 1e-9)) + 1
    notes = []
    src = r
    if dt > r.dt:  # down-sampling: anti-alias first
        fc = 0.8 * 0.5 / dt
        src = bandpass(r, None, fc, corners=8)
        notes.append(f"anti-alias low-pass {fc:g} Hz")
    if method == "linear":
        t_old = np.arange(src.n) * src.dt
        acc = np.interp(np.arange(n) * dt, t_old, src.acc)
    elif method == "lanczos":
        tr = to_trace(src)
        tr.interpolate(sampling_rate=1.0 / dt, method="lanczos", a=20, npts=n)
        acc = np.asarray(tr.data, float)
        if len(acc) != n:
            raise RuntimeError(f"resample: obspy returned {len(acc)} samples, expected {n}")
    else:
        raise ValueError(f"unknown resampling method {method!r}: lanczos or linear")
    note = f"resampled from dt = {r.dt:g} s to {dt:g} s ({method}{'; ' + notes[0] if notes else ''}): {r.n} -> {n} samples"
    return r.replaced(note, acc=acc, dt=dt)


class Kinematics(NamedTuple):
    """Consistent ground motion: ``record`` (corrected acceleration, m/s^2), velocity (m/s)
    and displacement (m) at the record's sample times."""

    record: Record
    velocity: np.ndarray
    displacement: np.ndarray


def integrate(r: Record, highpass_hz: float | None = None, poly_order: int | None = 6) -> Kinematics:
    """Velocity and displacement with drift control (module docstring); ``poly_order=None``
    integrates without correction."""
    rec = r
    if highpass_hz is not None:
        rec = bandpass(rec, highpass_hz, None, corners=4)
    t = np.arange(rec.n) * rec.dt
    v = sint.cumulative_trapezoid(rec.acc, dx=rec.dt, initial=0.0)
    d = sint.cumulative_trapezoid(v, dx=rec.dt, initial=0.0)
    if poly_order is not None:
        if poly_order < 2:
            raise ValueError("poly_order must be at least 2 (the fit starts at t^2 to keep d(0) = v(0) = 0)")
        T = t[-1]
        x = t / T  # scaled time for conditioning
        powers = np.arange(2, poly_order + 1)
        A = x[:, None] ** powers[None, :]
        c, *_ = np.linalg.lstsq(A, d, rcond=None)
        ddp = (x[:, None] ** (powers - 2)[None, :]) @ (c * powers * (powers - 1)) / T ** 2
        acc = rec.acc - ddp
        # integrate the corrected acceleration (d - p up to the trapezoid's error), so that
        # a -> v -> d holds to round-off
        v = sint.cumulative_trapezoid(acc, dx=rec.dt, initial=0.0)
        d = sint.cumulative_trapezoid(v, dx=rec.dt, initial=0.0)
        rec = rec.replaced(f"drift control: polynomial t^2..t^{poly_order} fitted to the displacement removed "
                           f"(peak correction {np.abs(ddp).max():.3g} m/s^2)", acc=acc)
    return Kinematics(rec, v, d)


def scale(r: Record, factor: float) -> Record:
    """Multiply the samples by ``factor`` (recorded in scale_factor and history)."""
    factor = float(factor)
    if not np.isfinite(factor) or factor == 0:
        raise ValueError(f"scale factor must be finite and non-zero, got {factor}")
    return r.replaced(f"scaled by {factor:.6g}", acc=r.acc * factor, scale_factor=r.scale_factor * factor)


def scale_to_pga(r: Record, pga_g: float | None = None, pga: float | None = None) -> Record:
    """Scale so that max|a| equals ``pga_g`` (g) or ``pga`` (m/s^2)."""
    if (pga_g is None) == (pga is None):
        raise ValueError("scale_to_pga: give exactly one of pga_g (g) or pga (m/s^2)")
    target = pga if pga is not None else pga_g * G
    if not target > 0:
        raise ValueError(f"scale_to_pga: the target must be positive, got {target}")
    if r.pga == 0:
        raise ValueError(f"{r.source}: cannot scale a record of zeros")
    factor = target / r.pga
    out = scale(r, factor)
    out.history[-1] += f" to PGA {target / G:.6g} g ({target:.6g} m/s^2)"
    return out


def trim(r: Record, t0: float | None = None, t1: float | None = None) -> Record:
    """Samples with t0 <= time <= t1 (s, ``Record.time``); None keeps that end."""
    t = r.time
    lo = t[0] if t0 is None else t0
    hi = t[-1] if t1 is None else t1
    eps = 1e-9 * r.dt
    m = (t >= lo - eps) & (t <= hi + eps)
    idx = np.flatnonzero(m)
    if len(idx) < 2:
        raise ValueError(f"{r.source}: the window [{lo}, {hi}] s keeps fewer than 2 samples "
                         f"(record spans {t[0]:g}..{t[-1]:g} s)")
    note = f"trimmed to {t[idx[0]]:g}..{t[idx[-1]]:g} s ({len(idx)} of {r.n} samples)"
    if t1 is not None and t1 > t[-1] + r.dt:
        note += f"; the window asked for up to {t1:g} s but the record ends at {t[-1]:g} s"
    return r.replaced(note, acc=r.acc[idx[0]:idx[-1] + 1].copy(), start_time=float(t[idx[0]]))
