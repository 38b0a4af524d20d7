"""Processing and generators: exact PGA scaling, trimming, resampling, filtering,
integration with drift control, the Eq. 9 sine and the band-limited white noise."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import cumulative_trapezoid

import tolerances as tol
from drystone.motions import generators, processing as pr
from drystone.motions.record import G, Record
from drystone.motions import spectra as sp


def noisy(seed=3, n=2000, dt=0.01):
    rng = np.random.default_rng(seed)
    return Record(rng.normal(size=n), dt, source="test")


@pytest.mark.parametrize("target", [0.05, 0.3, 0.818, 1.7])
def test_scale_to_pga_is_exact(target):
    """max|a| equals the target to rounding (4 ulp, relative 1e-15) and the factor is kept."""
    r = noisy()
    s = pr.scale_to_pga(r, pga_g=target)
    assert abs(s.pga - target * G) <= tol.SCALE_ULPS * np.finfo(float).eps * target * G
    assert s.scale_factor == pytest.approx(target * G / r.pga, rel=tol.FEW_ULP_REL)
    assert "to PGA" in s.history[-1] and r.history == []  # the input is untouched
    s2 = pr.scale_to_pga(s, pga=2.0)
    assert s2.pga == pytest.approx(2.0, rel=tol.FEW_ULP_REL)
    assert s2.scale_factor == pytest.approx(2.0 / r.pga, rel=tol.CHAINED_ULP_REL)


def test_trim_keeps_times_and_says_so():
    r = noisy()
    t = pr.trim(r, 2.0, 5.0)
    assert t.time[0] == pytest.approx(2.0) and t.time[-1] == pytest.approx(5.0) and t.n == 301
    np.testing.assert_array_equal(t.acc, r.acc[200:501])
    assert "301 of 2000" in t.history[-1]
    assert "ends at" in pr.trim(r, 0.0, 60.0).history[-1]
    with pytest.raises(ValueError, match="fewer than 2"):
        pr.trim(r, 30.0, 40.0)


def test_resample_up_and_down():
    """Up-sampling a 2 Hz sine from 100 to 1000 Hz (Lanczos, a = 20) reproduces it within
    1e-3 of its amplitude away from the ends (1 s); down-sampling 1000 -> 100 Hz keeps a
    2 Hz sine within 1e-3 and removes an 80 Hz one (above the new Nyquist frequency)
    to below 1e-3 instead of aliasing it to 20 Hz."""
    s = generators.sine(2.0, duration=5, amplitude=1.0, dt=0.01)
    u = pr.resample(s, 0.001)
    assert u.n == 5001 and u.dt == 0.001
    inner = slice(1000, -1000)
    np.testing.assert_allclose(u.acc[inner], -np.sin(2 * np.pi * 2 * u.time[inner]), atol=tol.RESAMPLE_ABS)
    t = np.arange(0, 5, 0.001)
    r = Record(np.sin(2 * np.pi * 2 * t) + 0.5 * np.sin(2 * np.pi * 80 * t), 0.001)
    d = pr.resample(r, 0.01)
    inner = slice(100, -100)
    np.testing.assert_allclose(d.acc[inner], np.sin(2 * np.pi * 2 * d.time[inner]), atol=tol.RESAMPLE_ABS)
    assert "anti-alias" in d.history[-1]
    lin = pr.resample(s, 0.002, method="linear")
    assert lin.n == 2501


def test_bandpass_removes_out_of_band_and_baseline():
    """A 0.05 Hz + 5 Hz + 40 Hz mixture band-passed 1-10 Hz keeps the 5 Hz amplitude within
    2 % and the others below 2 % away from the ends; a linear trend is removed exactly."""
    dt = 0.005
    t = np.arange(0, 60, dt)
    x = np.sin(2 * np.pi * 0.05 * t) + np.sin(2 * np.pi * 5 * t) + np.sin(2 * np.pi * 40 * t)
    b = pr.bandpass(Record(x, dt), 1.0, 10.0)
    inner = slice(2000, -2000)
    assert np.abs(b.acc[inner] - np.sin(2 * np.pi * 5 * t[inner])).max() < tol.BANDPASS_ABS
    trend = Record(0.3 + 0.01 * t + np.sin(2 * np.pi * 5 * t), dt)
    c = pr.baseline_correct(trend, "linear")
    assert abs(np.polyfit(t, c.acc, 1)[0]) < tol.BASELINE_SLOPE
    tp = pr.taper(trend, 0.05)
    assert tp.acc[0] == pytest.approx(0.0, abs=tol.EXACT_ABS) and tp.acc[-1] == pytest.approx(0.0, abs=tol.EXACT_ABS)


def test_integrate_with_drift_control():
    """A record with a small constant offset (a baseline error of 0.01 m/s^2, which alone
    drifts 18 m in 60 s) integrates, with the polynomial correction, to a displacement
    that ends within 1 % of its peak (the clean signal's peak, 11.3 mm, within 2 %); the
    returned a, v, d are consistent to 1e-9. On the FEMA Kobe record, high-pass 0.1 Hz
    plus the polynomial leave a final displacement below 2 % of the peak."""
    dt = 0.01
    t = np.arange(0, 60, dt)
    env = np.exp(-((t - 20) / 6) ** 2)
    a = env * np.sin(2 * np.pi * 1.5 * t)
    raw = pr.integrate(Record(a + 0.01, dt), poly_order=None)
    assert abs(raw.displacement[-1]) > 10.0
    clean = pr.integrate(Record(a, dt), poly_order=None)
    k = pr.integrate(Record(a + 0.01, dt), poly_order=6)
    dmax = np.abs(k.displacement).max()
    assert abs(k.displacement[-1]) < tol.DRIFT_END_REL * dmax
    assert abs(k.velocity[-1]) < tol.DRIFT_END_REL * np.abs(k.velocity).max()
    assert dmax == pytest.approx(np.abs(clean.displacement).max(), rel=tol.DRIFT_PEAK_REL)
    v = cumulative_trapezoid(k.record.acc, dx=dt, initial=0.0)
    np.testing.assert_allclose(k.velocity, v, atol=tol.INTEGRATION_ABS)
    assert any("drift control" in h for h in k.record.history)
    from drystone.motions import fema

    kobe = pr.integrate(fema.load(7, "a"), highpass_hz=0.1, poly_order=6)
    assert abs(kobe.displacement[-1]) < tol.KOBE_DRIFT_END_REL * np.abs(kobe.displacement).max()


def test_sine_is_eq9():
    """Eq. 9: displacement (A / omega^2) sin(omega t) with A = 0.5 m/s^2, so the samples are
    its second derivative -A sin(omega t) (to 1e-12), 10 s long; at 64 samples per period
    the peaks fall on samples, so the sampled PGA is A (to 1e-12); ``pga_g`` keeps the
    shape (normalised samples equal to 1e-12)."""
    f = 2.5
    r = generators.sine(f)
    w = 2 * np.pi * f
    assert r.duration == pytest.approx(10.0) and r.pga == pytest.approx(0.5, abs=tol.EXACT_ABS)
    assert r.dt == pytest.approx(1 / (64 * f))
    d_amp = r.info["displacement_amplitude_m"]
    assert d_amp == pytest.approx(0.5 / w ** 2)
    np.testing.assert_allclose(r.acc, -w ** 2 * d_amp * np.sin(w * r.time), atol=tol.EXACT_ABS)
    s = generators.sine(f, pga_g=0.2)
    assert s.info["amplitude_m_s2"] == pytest.approx(0.2 * G) and s.pga == pytest.approx(0.2 * G, rel=tol.SAMPLED_SINE_REL)
    np.testing.assert_allclose(s.acc / s.info["amplitude_m_s2"], r.acc / 0.5, atol=tol.EXACT_ABS)


def test_white_noise_peak_displacement_and_flat_spectrum():
    """30 s at 1000 Hz, seeded: the displacement integrated from rest in the time domain
    (trapezoid) peaks below 1 mm (0.9 mm by construction, 1e-6 m integration error); the
    acceleration spectrum is flat: the rectangular-window FAS is the same in every bin
    from 2/T to 20 Hz to 1e-9 (unit modulus by construction; bin 1 carries the start-at-
    rest correction) and below 1e-9 of it above 20 Hz. With the 5 % cosine taper of
    ``motions.analysis`` the taper's leakage mixes random-phase neighbours (single bins
    scatter by about 20 %), so the user-visible checks are statistical: the RMS amplitude
    over 0.5-2, 2-8 and 8-16 Hz agrees within 10 % (>= 45 bins each: about 3 % expected
    scatter; 30 seeds gave at most 5 %) and the Konno-Ohmachi (b = 40) smoothed spectrum
    stays within +-30 % of its median on 0.5-16 Hz (30 seeds: at most 24 %; the window
    spans about +-20 % in frequency, so 16 Hz keeps it off the 20 Hz edge)."""
    r = generators.white_noise(seed=7)
    assert r.n == 30000 and r.dt == 0.001
    v = cumulative_trapezoid(r.acc, dx=r.dt, initial=0.0)
    d = cumulative_trapezoid(v, dx=r.dt, initial=0.0)
    assert np.abs(d).max() < tol.WHITE_NOISE_PEAK_M
    assert np.abs(d - generators.white_noise_displacement(r)).max() < tol.WHITE_NOISE_DISPLACEMENT_M
    f, a = sp.fourier_amplitude(r.acc, r.dt, window=None, detrend=False)
    band = (f >= 2 / 30) & (f <= 20.0 + tol.SLACK)
    level = np.median(a[band])
    np.testing.assert_allclose(a[band], level, rtol=tol.NUMERICAL_REL)
    assert a[f > 20.0 + tol.SLACK].max() < tol.NUMERICAL_REL * level
    f, a = sp.fourier_amplitude(r.acc, r.dt, window="tukey")
    rms = [np.sqrt(np.mean(a[(f >= lo) & (f < hi)] ** 2)) for lo, hi in ((0.5, 2), (2, 8), (8, 16))]
    assert max(rms) / min(rms) < 1 + tol.WHITE_NOISE_BAND_RMS
    g = sp.log_grid(0.5, 16.0, 50)
    s = sp.smooth(f, a, 40, g)
    assert np.abs(s / np.median(s) - 1).max() < tol.WHITE_NOISE_SMOOTHED
    # seeded: same seed same samples, another seed other samples
    np.testing.assert_array_equal(generators.white_noise(seed=7).acc, r.acc)
    assert not np.allclose(generators.white_noise(seed=8).acc, r.acc)


def test_sine_samples_are_the_c_librarys_on_every_processor():
    """The sine's samples are -A sin(w t_i) by the C library's sin, bit for bit (not numpy's
    AVX-512 variant, whose last bits differ on some processors): a run's fingerprint hashes
    these samples, so they must not depend on the machine (tests/test_spec.py pins it)."""
    import math

    r = generators.sine(2.7, duration=3.0, amplitude=0.5, dt=0.001)
    w = 2 * math.pi * 2.7
    t = np.arange(len(r.acc)) * 0.001
    expected = np.array([-0.5 * math.sin(w * x) for x in t])
    assert np.array_equal(r.acc, expected)
    x = np.linspace(-40.0, 40.0, 101).reshape(101, 1)
    from drystone import libm

    assert libm.sin(x).shape == (101, 1) and libm.cos(x).shape == (101, 1)
    assert np.array_equal(libm.sin(x).ravel(), [math.sin(v) for v in x.ravel()])
    assert np.array_equal(libm.cos(x).ravel(), [math.cos(v) for v in x.ravel()])
