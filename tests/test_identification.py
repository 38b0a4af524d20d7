"""Identification (drystone/postprocess/identification.py, motions.generators.white_noise):

* the paper's procedure (one 4096-point FFT at 1000 Hz) can only give k x 1000/4096 Hz,
  and the paper's eight peaks are such bins;
* the H1 transfer function of known linear systems (SDOF, 2DOF) driven by white noise
  gives back their natural frequencies and half-power damping;
* the displacement-white generator has a flat displacement spectrum.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy import linalg, signal

import tolerances as tol
from drystone.motions import generators
from drystone.postprocess import compare
from drystone.postprocess import identification as idf


def test_paper_peaks_are_fft_bins_of_a_4096_point_window():
    """Every peak of the paper is within 1.5 mHz (0.6 % of a bin; 3 decimals, some
    truncated) of k x 0.244140625 Hz, with the k issue 11 lists; by chance, 8 frequencies
    would all be within 1 % of a bin with probability 0.02^8."""
    peaks = compare.paper("sacsayhuaman")["identification"]["white_noise_peaks_hz"]
    k, res = idf.grid_indices(peaks)
    assert list(k) == [2, 4, 6, 19, 39, 42, 55, 61]
    assert np.all(idf.on_grid(peaks))
    assert np.abs(res).max() < tol.PAPER_PEAKS_ON_GRID_HZ
    # a step of 1/4000 or 1/5000 Hz would not do: the grid is specific to 4096 points
    assert not np.all(idf.on_grid(peaks, nfft=4000)) and not np.all(idf.on_grid(peaks, nfft=5000))


def test_paper_procedure_puts_any_peak_on_the_grid():
    """A synthetic absolute displacement (two sines off the grid, at 200 Hz as the runs
    record it) analysed as the paper did: its peaks land on k x 1000/4096 Hz, the nearest
    bins to the true frequencies (within half a bin), whatever those are."""
    t = np.arange(0, 10, 0.005)
    f_true = [1.13, 7.77]
    x = 1e-3 * np.sin(2 * np.pi * f_true[0] * t) + 2e-4 * np.sin(2 * np.pi * f_true[1] * t + 0.3)
    sp = idf.paper_spectrum(t, x)
    assert sp["nfft"] == 4096 and sp["window_s"] == pytest.approx([0.0, 4.096])
    pk = idf.largest_peaks(sp["freq_hz"], sp["amplitude"], n=2, fmin_hz=0.3)
    assert np.all(idf.on_grid(pk, tol_hz=tol.EXACT_ABS))
    df = idf.grid_step()
    assert df == 1000 / 4096
    for p, f in zip(pk, f_true):
        assert abs(p - f) <= 0.5 * df + tol.SLACK_TIGHT


def _simulate(M, C, K, fs, duration, seed=0):
    """Relative displacements (m) of a base-excited linear system M z'' + C z' + K z =
    -M 1 a_g under a Gaussian white-noise base acceleration a_g (m/s^2) sampled at fs;
    exact for a piecewise-linear input (first-order hold)."""
    n = len(M)
    a_g = np.random.default_rng(seed).standard_normal(int(duration * fs))
    Mi = np.linalg.inv(M)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Mi @ K, -Mi @ C]])
    B = np.concatenate([np.zeros(n), -np.ones(n)])[:, None]
    sysd = signal.cont2discrete((A, B, np.hstack([np.eye(n), np.zeros((n, n))]), np.zeros((n, 1))), 1 / fs,
                                method="foh")
    _, y, _ = signal.dlsim(sysd, a_g, t=np.arange(len(a_g)) / fs)
    return a_g, y


def test_transfer_function_sdof():
    """SDOF, f_n = 5 Hz, zeta = 5 %: |H| (base acceleration -> relative displacement, the
    receptance 1 / (w_n^2 - w^2 + 2 i zeta w w_n)) peaks at f_n sqrt(1 - 2 zeta^2) and its
    half-power band gives zeta. Tolerances: frequency within a tenth of the 0.024 Hz bin
    (the parabolic vertex of a peak 20 bins wide); damping within 3 %: the half-power
    formula is exact to O(zeta^2) (0.3 % here), the Hann window (41 s) widens a 0.5 Hz
    band by < 1 %, and with coherence ~1 the 58 averages leave little random error."""
    fn, zeta, fs = 5.0, 0.05, 100.0
    w = 2 * np.pi * fn
    a_g, z = _simulate(np.eye(1), np.array([[2 * zeta * w]]), np.array([[w * w]]), fs, 1200.0)
    tf = idf.transfer_function(a_g, z[:, 0], fs, 4096)
    assert tf["n_segments"] == 57
    peaks = idf.modal_peaks(tf, fmin_hz=0.5, fmax_hz=20.0)
    assert len(peaks) == 1
    p = peaks[0]
    assert abs(p["frequency_hz"] - fn * np.sqrt(1 - 2 * zeta ** 2)) < tol.TF_PEAK_BINS * tf["df_hz"]
    assert p["damping_ratio"] == pytest.approx(zeta, rel=tol.TF_DAMPING_SDOF_REL)
    assert p["coherence"] > tol.COHERENCE_LINEAR
    assert p["amplitude"] == pytest.approx(1 / (2 * zeta * w ** 2 * np.sqrt(1 - zeta ** 2)), rel=tol.TF_AMPLITUDE_REL)


def _two_dof(f1=2.0, f2=4.0, zeta=0.04, angle_deg=20.0):
    """M = I, modes (cos a, sin a) and (-sin a, cos a), modal damping zeta: both modes show
    in the second coordinate (participation x shape 0.44 and 0.56 at 20 deg)."""
    a = np.radians(angle_deg)
    phi = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    w = 2 * np.pi * np.array([f1, f2])
    K = phi @ np.diag(w ** 2) @ phi.T
    C = phi @ np.diag(2 * zeta * w) @ phi.T
    return np.eye(2), C, K


def test_transfer_function_2dof_frequencies_and_damping():
    """2DOF with modal damping 4 % at 2 and 4 Hz: both peaks found, each within 5 % of its
    half-power bandwidth 2 zeta f_n of the peak of the exact FRF (the vertex of a peak 30-50
    bins wide whose top is rippled by ~1 % random error) and within 1 % of the natural frequency (the other
    mode's tail shifts the peaks of |H| by up to 0.4 % here: modal interference), and
    damping within 10 %: besides the SDOF errors, that tail adds a sloping background
    under each peak (a few per cent at a frequency ratio of 2)."""
    M, C, K = _two_dof()
    lam = linalg.eigh(K, M, eigvals_only=True)
    fn = np.sqrt(lam) / (2 * np.pi)
    fs, zeta = 50.0, 0.04
    a_g, z = _simulate(M, C, K, fs, 2400.0, seed=1)
    tf = idf.transfer_function(a_g, z[:, 1], fs, 8192)
    peaks = idf.modal_peaks(tf, fmin_hz=0.5, fmax_hz=20.0)
    assert len(peaks) == 2
    fine = np.linspace(0.5, 10.0, 200001)
    w = 2 * np.pi * fine
    dyn = K[None] - (w ** 2)[:, None, None] * M[None] + 1j * w[:, None, None] * C[None]  # one matrix per frequency
    exact = np.linalg.solve(dyn, np.broadcast_to(-np.ones((2, 1)), (len(w), 2, 1)))[:, 1, 0]
    exact_peaks = fine[signal.find_peaks(np.abs(exact))[0]]
    assert len(exact_peaks) == 2
    for p, f, fe in zip(peaks, fn, exact_peaks):
        assert abs(p["frequency_hz"] - fe) < tol.TF_2DOF_BANDWIDTHS * 2 * zeta * f
        assert p["frequency_hz"] == pytest.approx(f, rel=tol.TF_2DOF_FREQUENCY_REL)
        assert p["damping_ratio"] == pytest.approx(zeta, rel=tol.TF_2DOF_DAMPING_REL)
        assert p["resolvable"]


def test_coherence_rejects_noise_peaks():
    """Output noise as large as the response (rms) makes |H1| ragged wherever the response
    is small; hundreds of wiggles pass the prominence test, but only the two modes keep a
    coherence >= 0.9 (seeded: the highest wiggle has 0.88)."""
    M, C, K = _two_dof()
    fs = 50.0
    a_g, z = _simulate(M, C, K, fs, 2400.0, seed=2)
    y = z[:, 1] + z[:, 1].std() * np.random.default_rng(3).standard_normal(len(a_g))
    tf = idf.transfer_function(a_g, y, fs, 8192)
    loose = idf.modal_peaks(tf, coherence_min=0.0, fmin_hz=0.5, fmax_hz=20.0, prominence=0.05)
    kept = idf.modal_peaks(tf, coherence_min=0.9, fmin_hz=0.5, fmax_hz=20.0, prominence=0.05)
    assert len(loose) > 100
    assert [round(p["frequency_hz"], 1) for p in kept] == [2.0, 4.0]


def test_displacement_white_noise_is_flat_in_displacement():
    """spectrum = "displacement": peak displacement as asked, starts at rest, Fourier
    amplitude of the displacement flat over the band within 6 % (the start-at-rest
    correction changes each amplitude by ~1/sqrt(2 x 600 bins) = 3 % rms), and its
    acceleration is the exact second derivative (the record's own integral gives the
    displacement back). At 1 mm the PGA is hundreds of times the acceleration-white one."""
    r = generators.white_noise(spectrum="displacement", peak_displacement=1e-3)
    d = generators.white_noise_displacement(r)
    assert np.abs(d).max() == pytest.approx(1e-3, rel=tol.NUMERICAL_REL)
    assert abs(d[0]) < tol.ZERO_ABS
    f = np.fft.rfftfreq(r.n, r.dt)
    X = np.abs(np.fft.rfft(d))
    band = (f >= r.info["fmin_hz"] - tol.SLACK) & (f <= 20.0)
    flat = tol.DISPLACEMENT_WHITE_FLAT
    assert X[band].min() > (1 - flat) * X[band].mean() and X[band].max() < (1 + flat) * X[band].mean()
    assert X[f > 20.5].max() < tol.NUMERICAL_REL * X[band].mean()
    v0 = np.sum(2j * np.pi * f * np.fft.rfft(d) * np.r_[1, 2 * np.ones(len(f) - 2), 1]).real / r.n
    assert abs(v0) < tol.NUMERICAL_ABS
    acc_white = generators.white_noise(peak_displacement=1e-3)
    assert r.pga > 100 * acc_white.pga
    with pytest.raises(ValueError, match="spectrum"):
        generators.white_noise(spectrum="velocity")
