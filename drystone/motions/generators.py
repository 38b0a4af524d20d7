"""Synthetic base motions, returned as ``Record`` objects like the readers'.

* ``sine(frequency_hz, duration=10, amplitude=0.5, pga_g=None, dt=None)``: the
  Sacsayhuaman paper's Eq. 9, base displacement d(t) = (A / omega^2) sin(omega t) with
  A = 0.5 m/s^2 and omega = 2 pi f, hence acceleration a(t) = -A sin(omega t) (m/s^2),
  for ``duration`` s (10 s in the paper). ``pga_g`` replaces A by pga_g x 1 g
  (``drystone.units.G_STANDARD``; same shape). The default step gives 64 samples per
  period, so that the peaks fall on samples and the sampled PGA is exactly A; the
  displacement amplitude A / omega^2 is in ``info["displacement_amplitude_m"]``. A given
  ``dt`` must put ``frequency_hz`` below its Nyquist frequency 1 / (2 dt).
* ``white_noise(duration=30, fmax_hz=20, rate_hz=1000, peak_displacement=0.9e-3,
  seed=0, fmin_hz=None, spectrum="acceleration")``: band-limited white noise: random
  phases (numpy ``default_rng(seed)``) with a flat Fourier amplitude from ``fmin_hz``
  (default 1 / duration, the first bin: a displacement history has no static offset) to
  ``fmax_hz``, zero elsewhere. ``spectrum`` says which quantity is white:
  ``"acceleration"`` (flat acceleration, displacement spectrum falling as 1/f^2: the
  displacement is dominated by the lowest frequencies and a peak displacement of 0.9 mm
  gives a PGA of only about 2e-4 g) or ``"displacement"`` (flat displacement, acceleration
  rising as f^2: the Sacsayhuaman paper's "white noise ... less than 1 mm" read as a
  displacement signal, PGA of several m/s^2 at 1 mm). The displacement is scaled so its
  peak is ``peak_displacement`` (m) and the record is its exact second derivative in the
  frequency domain (acceleration, m/s^2); it starts at rest (zero displacement and
  velocity at t = 0) and, being periodic, ends where it started.
* ``white_noise_displacement(record)``: the displacement (m) of such a record from rest.

Both refuse (ValueError, before allocating) a motion of more than ``MAX_SAMPLES`` samples.
"""
from __future__ import annotations

import numpy as np

from drystone import libm
from drystone.motions.record import G, Record

SAMPLES_PER_PERIOD = 64  # a multiple of 4: the peaks fall on samples, the sampled PGA is exact
MAX_SAMPLES = 10 ** 7  # 80 MB per float64 array; a 60 s record at 200 Hz has 12,000 samples


def _check_samples(n: float, what: str):
    """Refuse (ValueError) a motion of more than MAX_SAMPLES samples, before allocating it."""
    if not n <= MAX_SAMPLES:
        raise ValueError(f"{what} would need {n:.3g} samples, more than {MAX_SAMPLES:.0e}")


def sine(frequency_hz: float, duration: float = 10.0, amplitude: float = 0.5, pga_g: float | None = None,
         dt: float | None = None) -> Record:
    """Eq. 9 of the Sacsayhuaman paper: a(t) = -A sin(2 pi f t), A in m/s^2 (or pga_g in g)."""
    f = float(frequency_hz)
    if not f > 0 or not duration > 0:
        raise ValueError(f"sine needs a positive frequency and duration, got {frequency_hz}, {duration}")
    amp = float(amplitude) if pga_g is None else float(pga_g) * G
    if dt is None:
        dt = 1.0 / (SAMPLES_PER_PERIOD * f)
    elif not 0 < dt:
        raise ValueError(f"sine sample step dt must be positive, got {dt}")
    elif not f < 0.5 / dt:
        raise ValueError(f"sine frequency_hz = {f:g} Hz is at or above the Nyquist frequency {0.5 / dt:g} Hz of "
                         f"its sample step dt = {dt:g} s")
    _check_samples(duration / dt + 1,
                   f"a sine of frequency_hz = {f:g} Hz over duration = {duration:g} s (dt = {dt:.3g} s)")
    n = int(round(duration / dt)) + 1
    t = np.arange(n) * dt
    w = 2 * np.pi * f
    acc = -amp * libm.sin(w * t)  # not np.sin: the samples are hashed (drystone.libm)
    note = f"generated: Eq. 9 sine, f = {f:g} Hz, acceleration amplitude {amp:g} m/s^2, {duration:g} s, dt = {dt:g} s"
    return Record(acc, dt, event=f"sine {f:g} Hz", station="synthetic", component="horizontal",
                  units_in_file="m/s^2", source="generators.sine (Sacsayhuaman paper Eq. 9)",
                  history=[note], info={"motion": "sine", "frequency_hz": f, "amplitude_m_s2": amp,
                                        "displacement_amplitude_m": amp / w ** 2, "duration_s": float(duration)})


def white_noise(duration: float = 30.0, fmax_hz: float = 20.0, rate_hz: float = 1000.0,
                peak_displacement: float = 0.9e-3, seed: int = 0, fmin_hz: float | None = None,
                spectrum: str = "acceleration") -> Record:
    """Band-limited white-noise base acceleration (module docstring); seeded and reproducible.
    ``spectrum``: "acceleration" (flat acceleration spectrum) or "displacement" (flat
    displacement spectrum); ``peak_displacement`` in m either way."""
    if spectrum not in ("acceleration", "displacement"):
        raise ValueError(f"spectrum must be 'acceleration' or 'displacement', got {spectrum!r}")
    dt = 1.0 / float(rate_hz)
    _check_samples(duration * rate_hz, f"a white noise of duration = {duration:g} s at rate_hz = {rate_hz:g} Hz")
    n = int(round(duration * rate_hz))
    if not 0 < fmax_hz < 0.5 * rate_hz:
        raise ValueError(f"fmax_hz must be in (0, {0.5 * rate_hz}) Hz, got {fmax_hz}")
    if not 0 < peak_displacement:
        raise ValueError(f"peak_displacement must be positive, got {peak_displacement}")
    rng = np.random.default_rng(seed)
    freq = np.fft.rfftfreq(n, dt)
    w = 2 * np.pi * freq
    lo = freq[1] if fmin_hz is None else float(fmin_hz)
    if not lo > 0:
        raise ValueError(f"fmin_hz must be positive, got {fmin_hz}")
    band = np.flatnonzero((freq >= lo) & (freq <= fmax_hz))
    if len(band) < 2:
        raise ValueError(f"the band {lo:g}-{fmax_hz:g} Hz holds fewer than 2 frequencies of a {duration:g} s record")
    phase = np.exp(2j * np.pi * rng.random(len(band)))  # unit modulus, random phase
    X = np.zeros(len(freq), complex)  # displacement spectrum
    X[band] = -phase / w[band] ** 2 if spectrum == "acceleration" else phase
    # start at rest: v(0) = -(2/n) sum w_k Im X_k = 0, by the imaginary part of the lowest
    # band frequency; d(0) = 0 by a constant offset of the displacement (no acceleration)
    if spectrum == "acceleration":
        k1, rest = band[0], band[1:]
        X[k1] = X[k1].real + 1j * (-(w[rest] * X[rest].imag).sum() / w[k1])
    else:  # the lowest bin would dominate a flat displacement: the least-squares correction
        # spread over the band instead (each amplitude changes by ~ 1/sqrt(2 x bins): 3 % at 600)
        wb = w[band]
        X[band] -= 1j * wb * (wb * X[band].imag).sum() / (wb ** 2).sum()
    A = np.zeros_like(X)
    A[band] = -w[band] ** 2 * X[band]  # acceleration spectrum
    disp = np.fft.irfft(X, n)
    disp -= disp[0]
    s = peak_displacement / np.abs(disp).max()
    acc = np.fft.irfft(A, n) * s
    disp *= s
    note = (f"generated: band-limited white noise, flat {spectrum} {lo:g}-{fmax_hz:g} Hz, {rate_hz:g} Hz sampling, "
            f"{n * dt:g} s, peak displacement {peak_displacement * 1e3:g} mm, seed {seed}")
    return Record(acc, dt, event=f"white noise ({spectrum})", station="synthetic", component="horizontal",
                  units_in_file="m/s^2", source="generators.white_noise", history=[note],
                  info={"motion": "white_noise", "spectrum": spectrum, "seed": int(seed), "fmin_hz": float(lo),
                        "fmax_hz": float(fmax_hz), "rate_hz": float(rate_hz), "duration_s": float(n * dt),
                        "peak_displacement_m": float(np.abs(disp).max()),
                        "rms_acceleration_m_s2": float(np.sqrt(np.mean(acc ** 2)))})


def white_noise_displacement(record: Record) -> np.ndarray:
    """Displacement (m) of a ``white_noise`` record from rest: the periodic double integral
    of its band-limited acceleration, shifted to start at zero (exact for these records;
    for measured records use ``motions.processing.integrate``)."""
    n = record.n
    A = np.fft.rfft(record.acc)
    w = 2 * np.pi * np.fft.rfftfreq(n, record.dt)
    X = np.zeros_like(A)
    X[1:] = -A[1:] / w[1:] ** 2
    d = np.fft.irfft(X, n)
    return d - d[0]
