"""Site response: a motion at bedrock propagated up a 1-D soil column to the ground surface.

``read_profile(path) -> SiteProfile`` reads a site-profile file (TOML, SI units: lengths m,
velocities m/s, unit weights kN/m^3, stresses kPa, damping ratios as fractions; format in
docs/motions.md, "Site response"); every fault is a ``SiteError`` naming the file and key.
``propagate(record, profile) -> (surface Record, info)`` runs pystrata's equivalent-linear
calculator (``pystrata.propagation.EquivalentLinearCalculator``: vertically propagating SH
waves, complex shear modulus G* = G (sqrt(1 - 4 xi^2) + 2 i xi), strain-compatible G and xi
iterated from the effective strain = ``strain_ratio`` x peak strain at each layer's mid-depth).

Input and output. Over an elastic half-space the record is taken as an OUTCROP motion of the
bedrock (what a station on rock records, twice the up-going wave); over ``bedrock = "rigid"``
it is the motion of the rigid base itself (within = outcrop there: nothing below matters).
The output is the motion at the top of the column (the free surface, where within and outcrop
coincide), i.e. the base of the wall.

Time history. pystrata works in the frequency domain: the record's FFT times the transfer
function, back by the inverse FFT. Its own FFT length is the next power of two of the record,
which would wrap the column's free vibration after the record's end onto its start (the
transform is circular), so the record is padded with zeros first, by ``padding_s``: long
enough for the slowest decay the column can have, exp(-xi_min w0 t) down to 1e-4, with the
smallest small-strain damping of its layers and its small-strain fundamental w0 = 2 pi f0
(strain-compatible damping is larger), twice over. The surface record keeps the record's
step and length: the free vibration after the record's end is dropped (``info`` gives its
peak, ``tail_peak_m_s2``).

Numbers reported (``info``): the small-strain (linear) transfer function |surface/rock|, its
peak frequency f0 and amplification |H(f0)|, the quarter-wavelength estimate Vs/4H (Vs the
travel-time average: exact for a uniform layer on rigid rock), the same peak with the
strain-compatible properties, per layer the strain-compatible Vs, G/Gmax, damping, effective
and peak strain, and the iterations, their last relative change (percent) and convergence.

pystrata 0.5.4 is imported here only (its import is slow and warns about numba keywords:
silenced). No YADE, no package layer above motions/.
"""
from __future__ import annotations

import hashlib
import importlib.metadata as md
import math
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from drystone.inputfiles import load_toml
from drystone.kept import Kept
from drystone.motions.record import Record
from drystone.units import G_STANDARD

#: pystrata's damping model needs sqrt(1 - 4 xi^2): a damping ratio must stay below 0.5
MAX_DAMPING = 0.5
#: the free vibration of the column decays to this fraction within the zero padding
PAD_DECAY = 1e-4
#: frequencies (Hz) searched for the transfer function's peak, 200 per decade
F_SEARCH_HZ = (0.05, 50.0)
#: frequencies (Hz) of the transfer functions kept in ``info`` (log grid, 0.1-25 Hz)
F_INFO_HZ = np.geomspace(0.1, 25.0, 241)
#: equivalent-linear defaults (pystrata's): effective/peak strain, iterations, change (%) to stop
STRAIN_RATIO, MAX_ITERATIONS, TOLERANCE_PERCENT = 0.65, 15, 0.01
#: coefficient of earth pressure at rest used for the mean stress of Darendeli's curves
K0 = 0.5
#: most layers in a column after splitting into ``sublayers`` (a 1-D profile has tens; pystrata's
#: time and memory grow with layers x FFT samples: 100 sublayers about 45 s, 400 about 150 s, 1.5 GB)
MAX_LAYERS = 200
#: most FFT samples (record + padding) and most layers x FFT samples of one propagation (pystrata
#: keeps several complex arrays per layer and frequency: about 50 bytes each, 2**26 about 3 GB)
MAX_FFT_SAMPLES, MAX_LAYER_SAMPLES = 2 ** 22, 2 ** 26

#: the physical range of every number of a profile file: key -> (low, high, unit, why); both ends
#: allowed unless the low end is listed in OPEN_LOW (then it must be exceeded) or the high in OPEN_HIGH
RANGES = {
    "thickness_m": (0.0, 3000.0, "m", "a layer of soil or rock above the bedrock, at most the deepest basins' fill"),
    "vs_m_s": (20.0, 5000.0, "m/s", "from peat and very soft clay (30-60 m/s) to hard rock (3500 m/s)"),
    "unit_weight_kn_m3": (5.0, 35.0, "kN/m^3", "from peat (10) to dense rock (28); a unit weight, not a density"),
    "damping": (1e-4, MAX_DAMPING, "fraction", "measured small-strain damping is 0.2-5 %; pystrata's complex "
                "modulus needs < 0.5"),
    "bedrock_damping": (0.0, MAX_DAMPING, "fraction", "pystrata's complex modulus needs < 0.5"),
    "pi_percent": (0.0, 200.0, "percent", "plasticity index of soils (Darendeli's data: up to 132)"),
    "ocr": (1.0, 100.0, "-", "over-consolidation ratio (Darendeli's data: 1-8)"),
    "stress_mean_kpa": (0.1, 1e5, "kPa", "mean effective stress, up to that at a few km depth"),
    "k0": (0.1, 5.0, "-", "coefficient of earth pressure at rest (0.4-0.6 normally consolidated, up to 3 "
           "heavily over-consolidated)"),
    "strain_ratio": (0.0, 1.0, "-", "effective / peak strain (Idriss and Sun: (M - 1)/10, 0.4-0.8)"),
    "tolerance_percent": (0.0, 50.0, "percent", "the change of G and damping at which iterations stop"),
    "max_iterations": (1, 100, "-", "equivalent-linear iterations (pystrata's default 15)"),
    "sublayers": (1, MAX_LAYERS, "-", f"at most {MAX_LAYERS} layers in the column after splitting"),
    "amplification": (0.0, 1000.0, "-", "a target amplification"),
}
OPEN_LOW = {"thickness_m", "strain_ratio", "tolerance_percent", "amplification"}
OPEN_HIGH = {"damping", "bedrock_damping"}


class SiteError(ValueError):
    """A site-profile file that cannot be used; the message names the file and key."""


@dataclass
class SoilLayer:
    """One layer of the column (after splitting into ``sublayers``): thickness_m (m),
    vs_m_s (m/s, small strain), unit_weight_kn_m3 (kN/m^3), damping (small-strain ratio),
    curves ('linear' or 'darendeli') with pi_percent, ocr and stress_mean_kpa (kPa, the
    mean effective stress at mid-layer: given, or from depth with K0)."""

    name: str
    thickness_m: float
    vs_m_s: float
    unit_weight_kn_m3: float
    damping: float | None
    curves: str
    pi_percent: float = 0.0
    ocr: float = 1.0
    stress_mean_kpa: float | None = None
    depth_top_m: float = 0.0


@dataclass
class SiteProfile:
    """A site profile read from ``path``: layers top down, the bedrock (None: rigid; else a
    dict of vs_m_s, unit_weight_kn_m3, damping), the equivalent-linear settings, the
    ``assumed`` label (empty if measured), the ``target`` ranges it was set to (optional)
    and the file's SHA-256."""

    path: str
    sha256: str
    name: str
    assumed: str
    layers: list[SoilLayer]
    bedrock: dict | None
    strain_ratio: float = STRAIN_RATIO
    max_iterations: int = MAX_ITERATIONS
    tolerance_percent: float = TOLERANCE_PERCENT
    target: dict = field(default_factory=dict)
    source: str = ""

    @property
    def thickness_m(self) -> float:
        """Total thickness of the column (m)."""
        return sum(la.thickness_m for la in self.layers)

    @property
    def vs_average_m_s(self) -> float:
        """Travel-time average shear-wave velocity H / sum(h_i / Vs_i) (m/s)."""
        return self.thickness_m / sum(la.thickness_m / la.vs_m_s for la in self.layers)

    @property
    def f_quarter_wave_hz(self) -> float:
        """Quarter-wavelength fundamental frequency Vs_avg / (4 H) (Hz)."""
        return self.vs_average_m_s / (4.0 * self.thickness_m)

    def provenance(self) -> dict:
        """JSON-ready description of the profile (its file and hash, the layers as used)."""
        return {"file": self.path, "sha256": self.sha256, "name": self.name, "assumed": self.assumed,
                "source": self.source, "target": self.target,
                "units": "thickness m, Vs m/s, unit weight kN/m^3, stress kPa, damping fraction",
                "bedrock": "rigid" if self.bedrock is None else dict(self.bedrock),
                "strain_ratio": self.strain_ratio, "max_iterations": self.max_iterations,
                "tolerance_percent": self.tolerance_percent,
                "layers": [dict(vars(la)) for la in self.layers]}


# --- the file ------------------------------------------------------------------------------
TOP_KEYS = {"name", "assumed", "source", "layers", "bedrock", "strain_ratio", "max_iterations",
            "tolerance_percent", "target"}
LAYER_KEYS = {"name", "thickness_m", "vs_m_s", "unit_weight_kn_m3", "damping", "curves", "pi_percent", "ocr",
              "stress_mean_kpa", "k0", "sublayers"}
BEDROCK_KEYS = {"vs_m_s", "unit_weight_kn_m3", "damping"}
TARGET_KEYS = {"f0_hz", "amplification", "source"}
CURVES = ("linear", "darendeli")
DARENDELI_ONLY = ("pi_percent", "ocr", "stress_mean_kpa", "k0")


def _num(d: dict, key: str, where: str, *, default=None, integer=False, rng: str | None = None):
    """d[key] as a float (int) within its physical range ``RANGES[rng or key]``; SiteError
    naming ``where``, the key and the range."""
    if key not in d:
        if default is None:
            raise SiteError(f"{where}: '{key}' is missing")
        return default
    v = d[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or (integer and not isinstance(v, int)):
        raise SiteError(f"{where}: '{key}' = {v!r} must be {'an integer' if integer else 'a number'}")
    if integer and abs(v) > 2 ** 53:
        raise SiteError(f"{where}: '{key}' = {v} is out of range")
    v = int(v) if integer else float(v)
    if not math.isfinite(v):
        raise SiteError(f"{where}: '{key}' = {v!r} must be finite")
    name = rng or key
    lo, hi, unit, why = RANGES[name]
    lo_open, hi_open = name in OPEN_LOW, name in OPEN_HIGH
    allowed = f"{'(' if lo_open else '['}{lo:g}, {hi:g}{')' if hi_open else ']'} {unit}: {why}"
    if v <= lo if lo_open else v < lo:
        raise SiteError(f"{where}: '{key}' = {v:g} must be {'>' if lo_open else '>='} {lo:g} (allowed {allowed})")
    if v >= hi if hi_open else v > hi:
        raise SiteError(f"{where}: '{key}' = {v:g} must be {'<' if hi_open else '<='} {hi:g} (allowed {allowed})")
    return v


def _unknown(d: dict, known: set, where: str) -> None:
    extra = sorted(set(d) - known)
    if extra:
        raise SiteError(f"{where}: unknown key '{extra[0]}' (known: {', '.join(sorted(known))})")


def read_profile(path) -> SiteProfile:
    """Read and check a site-profile TOML file (format: module docstring, docs/motions.md)."""
    p = Path(path)
    raw = p.read_bytes() if p.is_file() else None
    d = load_toml(p, SiteError, "site-profile file")
    f = str(p)
    _unknown(d, TOP_KEYS, f)
    layers_in = d.get("layers")
    if not isinstance(layers_in, list) or not layers_in or not all(isinstance(x, dict) for x in layers_in):
        raise SiteError(f"{f}: 'layers' must be an array of tables ([[layers]]), at least one")
    if len(layers_in) > MAX_LAYERS:
        raise SiteError(f"{f}: {len(layers_in)} [[layers]], more than {MAX_LAYERS} (the column's limit, "
                        "sublayers included: site.MAX_LAYERS)")
    layers: list[SoilLayer] = []
    depth, stress_v = 0.0, 0.0  # m, kPa at the top of the next layer (dry column: total = effective)
    for i, la in enumerate(layers_in):
        w = f"{f}: [[layers]] #{i + 1}"
        _unknown(la, LAYER_KEYS, w)
        curves = la.get("curves", "linear")
        if curves not in CURVES:
            raise SiteError(f"{w}: 'curves' = {curves!r} must be one of {', '.join(CURVES)}")
        if curves == "linear":
            bad = [k for k in DARENDELI_ONLY if k in la]
            if bad:
                raise SiteError(f"{w}: '{bad[0]}' is a parameter of curves = \"darendeli\" only")
        h = _num(la, "thickness_m", w)
        vs = _num(la, "vs_m_s", w)
        gam = _num(la, "unit_weight_kn_m3", w)
        damping = (_num(la, "damping", w) if curves == "linear" or "damping" in la
                   else None)  # darendeli without it: its own small-strain damping
        n = _num(la, "sublayers", w, default=1, integer=True)
        pi = _num(la, "pi_percent", w, default=0.0)
        ocr = _num(la, "ocr", w, default=1.0)
        k0 = _num(la, "k0", w, default=K0)
        sm = _num(la, "stress_mean_kpa", w) if "stress_mean_kpa" in la else None
        name = str(la.get("name", f"layer {i + 1}"))
        if len(layers) + n > MAX_LAYERS:
            raise SiteError(f"{w}: 'sublayers' = {n} brings the column to {len(layers) + n} layers, more than "
                            f"{MAX_LAYERS} (site.MAX_LAYERS)")
        if depth + h > RANGES["thickness_m"][1]:
            raise SiteError(f"{w}: 'thickness_m' = {h:g} makes the column {depth + h:g} m thick, more than "
                            f"{RANGES['thickness_m'][1]:g} m (allowed for the whole column above the bedrock)")
        for j in range(n):
            hj = h / n
            mean = sm if sm is not None else (stress_v + 0.5 * gam * hj) * (1.0 + 2.0 * k0) / 3.0
            layers.append(SoilLayer(name if n == 1 else f"{name} ({j + 1}/{n})", hj, vs, gam, damping, curves,
                                    pi, ocr, mean if curves == "darendeli" else None, depth))
            depth += hj
            stress_v += gam * hj
    b = d.get("bedrock")
    if b == "rigid":
        bedrock = None
    elif isinstance(b, dict):
        _unknown(b, BEDROCK_KEYS, f"{f}: [bedrock]")
        bedrock = {"vs_m_s": _num(b, "vs_m_s", f"{f}: [bedrock]"),
                   "unit_weight_kn_m3": _num(b, "unit_weight_kn_m3", f"{f}: [bedrock]"),
                   "damping": _num(b, "damping", f"{f}: [bedrock]", rng="bedrock_damping")}
    else:
        raise SiteError(f"{f}: 'bedrock' must be a table [bedrock] (vs_m_s, unit_weight_kn_m3, damping) or "
                        f"\"rigid\", got {b!r}")
    target = d.get("target", {})
    if not isinstance(target, dict):
        raise SiteError(f"{f}: 'target' must be a table [target]")
    _unknown(target, TARGET_KEYS, f"{f}: [target]")
    if "f0_hz" in target:
        r = target["f0_hz"]
        ok = isinstance(r, list) and len(r) == 2 and all(isinstance(x, (int, float)) for x in r)
        if not (ok and 0 < r[0] <= r[1]):
            raise SiteError(f"{f}: [target] 'f0_hz' must be [low, high] in Hz, 0 < low <= high")
    if "amplification" in target:
        _num(target, "amplification", f"{f}: [target]")
    for key in ("name", "assumed", "source"):
        if key in d and not isinstance(d[key], str):
            raise SiteError(f"{f}: '{key}' must be a string")
    travel = sum(la.thickness_m / la.vs_m_s for la in layers)
    if 1.0 / (4.0 * travel) < F_SEARCH_HZ[0]:
        raise SiteError(f"{f}: the column's travel time {travel:.4g} s puts its fundamental near 1/(4 x travel) = "
                        f"{1.0 / (4.0 * travel):.3g} Hz, below the {F_SEARCH_HZ[0]:g} Hz searched for it: thinner "
                        "layers ('thickness_m') or faster ones ('vs_m_s')")
    return SiteProfile(path=str(p.resolve()), sha256=hashlib.sha256(raw or b"").hexdigest(),
                       name=d.get("name", p.stem), assumed=d.get("assumed", ""), source=d.get("source", ""),
                       layers=layers, bedrock=bedrock,
                       strain_ratio=_num(d, "strain_ratio", f, default=STRAIN_RATIO),
                       max_iterations=_num(d, "max_iterations", f, default=MAX_ITERATIONS, integer=True),
                       tolerance_percent=_num(d, "tolerance_percent", f, default=TOLERANCE_PERCENT),
                       target=dict(target))


# --- pystrata -------------------------------------------------------------------------------
def _pystrata():
    """The pystrata package (imported on first use; its numba deprecation warnings silenced)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        import pystrata
        import pystrata.motion
        import pystrata.propagation
        import pystrata.site
    return pystrata


def pystrata_version() -> str:
    """pystrata's distribution version (its ``__version__`` reports pyRVT's)."""
    return md.version("pystrata")


def _soil_type(la: SoilLayer, linear: bool):
    ps = _pystrata().site
    if la.curves == "darendeli" and not linear:
        return ps.DarendeliSoilType(unit_wt=la.unit_weight_kn_m3, plas_index=la.pi_percent, ocr=la.ocr,
                                    stress_mean=la.stress_mean_kpa, damping_min=la.damping)
    return ps.SoilType(la.name, la.unit_weight_kn_m3, None, small_strain_damping(la))


def small_strain_damping(la: SoilLayer) -> float:
    """The layer's small-strain damping ratio: given, or Darendeli's D_min (pystrata's formula
    at its default 1 Hz loading frequency) for its PI, OCR and mean stress."""
    if la.damping is not None:
        return la.damping
    ps = _pystrata().site
    return float(ps.DarendeliSoilType(unit_wt=la.unit_weight_kn_m3, plas_index=la.pi_percent, ocr=la.ocr,
                                      stress_mean=la.stress_mean_kpa).damping_min)


def _profile(sp: SiteProfile, linear: bool = False):
    """pystrata Profile: the layers, then the half-space (for a rigid base any half-space
    will do: the input is then the total (within) motion at the base, independent of it)."""
    ps = _pystrata().site
    layers = [ps.Layer(_soil_type(la, linear), la.thickness_m, la.vs_m_s) for la in sp.layers]
    b = sp.bedrock or {"vs_m_s": sp.layers[-1].vs_m_s, "unit_weight_kn_m3": sp.layers[-1].unit_weight_kn_m3,
                       "damping": small_strain_damping(sp.layers[-1])}
    layers.append(ps.Layer(ps.SoilType("bedrock", b["unit_weight_kn_m3"], None, b["damping"]), 0.0, b["vs_m_s"]))
    return ps.Profile(layers)


def _locations(sp: SiteProfile, profile):
    """(input, output): the outcrop rock motion (the rigid base's motion for a rigid base)
    and the surface."""
    wave = "within" if sp.bedrock is None else "outcrop"
    return profile.location(wave, index=len(profile) - 1), profile.location("within", index=0)


def transfer_function(sp: SiteProfile, freqs_hz, iterated=None) -> np.ndarray:
    """Complex acceleration transfer function surface / rock (outcrop; rigid: base) at
    ``freqs_hz`` (Hz) with the small-strain properties, or with the strain-compatible ones
    of ``iterated`` (a pystrata Profile after an equivalent-linear run)."""
    ps = _pystrata()
    calc = ps.propagation.LinearElasticCalculator()
    motion = ps.motion.Motion(freqs=np.asarray(freqs_hz, float))
    if iterated is None:
        profile = _profile(sp, linear=True)
        calc(motion, profile, None)  # resets the layers to their small-strain properties
    else:
        profile = iterated  # keep its properties: the waves only
        calc._motion, calc._profile = motion, profile
        calc._calc_waves(motion.angular_freqs, profile)
    lin, lout = _locations(sp, profile)
    return calc.calc_accel_tf(lin, lout)


def fundamental(sp: SiteProfile, iterated=None) -> tuple[float, float]:
    """(f0 Hz, |H(f0)|): the peak of |transfer_function| over F_SEARCH_HZ (200 points per
    decade, then refined by a bounded scalar search between the neighbours of the best point)."""
    from scipy.optimize import minimize_scalar

    f = np.geomspace(*F_SEARCH_HZ, int(200 * math.log10(F_SEARCH_HZ[1] / F_SEARCH_HZ[0])) + 1)
    a = np.abs(transfer_function(sp, f, iterated))
    i = int(np.argmax(a))
    lo, hi = f[max(i - 1, 0)], f[min(i + 1, len(f) - 1)]
    res = minimize_scalar(lambda x: -abs(transfer_function(sp, [x], iterated)[0]), bounds=(lo, hi),
                          method="bounded", options={"xatol": 1e-9 * f[i]})
    return (float(res.x), float(-res.fun)) if -res.fun >= a[i] else (float(f[i]), float(a[i]))


def padding_s(sp: SiteProfile) -> float:
    """Zero padding (s) appended before the FFT: 2 ln(1/PAD_DECAY) / (xi_min w0), the
    small-strain fundamental w0 and smallest small-strain damping (module docstring), plus
    the travel time through the column."""
    f0, _ = fundamental(sp)
    xi = min(small_strain_damping(la) for la in sp.layers)
    return 2.0 * math.log(1.0 / PAD_DECAY) / (xi * 2.0 * math.pi * f0) + sum(
        la.thickness_m / la.vs_m_s for la in sp.layers)


def _counting_eql(sp: SiteProfile):
    """pystrata's EquivalentLinearCalculator with ``sp``'s settings, counting its iterations
    in ``waves`` (calls of _calc_waves: one for the linear start, then one per iteration)."""
    ps = _pystrata()

    class Counting(ps.propagation.EquivalentLinearCalculator):
        waves = 0

        def _calc_waves(self, angular_freqs, profile):
            self.waves += 1
            return super()._calc_waves(angular_freqs, profile)

    return Counting(strain_ratio=sp.strain_ratio, tolerance=sp.tolerance_percent, max_iterations=sp.max_iterations)


def fft_samples(record: Record, sp: SiteProfile) -> tuple[float, int]:
    """(padding s, FFT length) of ``record`` through ``sp``, refused (SiteError naming the
    profile, the layer and key responsible) beyond MAX_FFT_SAMPLES or MAX_LAYER_SAMPLES,
    before pystrata allocates anything."""
    pad = padding_s(sp)
    need = record.n + pad / record.dt
    nfft = 1 << max(0, int(math.ceil(math.log2(need)))) if math.isfinite(need) else math.inf
    if nfft <= MAX_FFT_SAMPLES and nfft * (len(sp.layers) + 1) <= MAX_LAYER_SAMPLES:
        return pad, int(nfft)
    pad_samples = pad / record.dt if math.isfinite(pad) else math.inf
    limit = (f"more than {MAX_FFT_SAMPLES} FFT samples, or {MAX_LAYER_SAMPLES} layers x samples "
             f"(site.MAX_FFT_SAMPLES, MAX_LAYER_SAMPLES; {len(sp.layers)} layers)")
    if pad_samples > record.n:  # the padding makes the FFT long: the least damped layer's
        i = min(range(len(sp.layers)), key=lambda k: small_strain_damping(sp.layers[k]))
        la = sp.layers[i]
        given = "'damping'" if la.damping is not None else "its Darendeli D_min: set 'damping'"
        raise SiteError(
            f"{sp.path}: layer '{la.name}': small-strain damping {small_strain_damping(la):.3g} ({given}) lets the "
            f"column ring for {pad:.4g} s after the record (padding 2 ln(1e4)/(xi w0), f0 {fundamental(sp)[0]:.3g} "
            f"Hz), {pad_samples:.4g} samples at dt {record.dt:g} s: {limit}; raise the damping")
    raise SiteError(
        f"{sp.path}: {len(sp.layers)} layers (after 'sublayers') and {nfft} FFT samples ({record.n} samples of the "
        f"record at dt {record.dt:g} s, {pad:.4g} s of padding): {limit}; fewer 'sublayers' or a shorter record")


def _check_finite(sp: SiteProfile, profile, acc) -> None:
    """Refuse a non-finite surface motion, naming the layer whose strain-compatible
    damping left pystrata's range (0, 0.5) or, if none did, the column."""
    if np.all(np.isfinite(acc)):
        return
    for la, pl in zip(sp.layers, profile[:-1]):
        xi = np.atleast_1d(np.asarray(pl.damping, float))
        if not np.all(np.isfinite(xi)) or np.max(xi) >= MAX_DAMPING:
            raise SiteError(f"{sp.path}: layer '{la.name}': its strain-compatible damping reached "
                            f"{float(np.max(xi)):.3g} (curves {la.curves!r}, pi_percent {la.pi_percent:g}, ocr "
                            f"{la.ocr:g}, mean stress {la.stress_mean_kpa} kPa), beyond pystrata's < {MAX_DAMPING:g}: "
                            "the surface motion is not finite")
    raise SiteError(f"{sp.path}: the surface motion through the column is not finite (thickness "
                    f"{sp.thickness_m:.4g} m, travel time {sum(la.thickness_m / la.vs_m_s for la in sp.layers):.3g} s: "
                    "the waves' attenuation over the column overflows); check 'thickness_m', 'vs_m_s', 'damping'")


def convergence_warning(info: dict) -> str | None:
    """The ``warning:`` line for a propagation (``propagate``'s info) whose equivalent-linear
    iterations did not converge, or None when they did."""
    if info["converged"]:
        return None
    p = info["profile"]
    return (f"warning: site response through {p['file']} did not converge: G and damping still changed "
            f"{info['max_change_percent']:.3g} % at the last of {info['iterations']} iterations (tolerance "
            f"{p['tolerance_percent']:g} %, max_iterations {p['max_iterations']}): the surface motion is that of "
            "the last iteration; raise 'max_iterations' or check the profile")


#: this process's last propagations (``propagate``), by their inputs (``_inputs``): an analysis
#: checks each run's case before it runs it and the run reads it again, a study sizes its caps
#: from the same motions (drystone/kept.py)
_KEPT = Kept(32)


def _inputs(record: Record, sp: SiteProfile) -> tuple:
    """Everything a propagation depends on: the profile as read (every field), the record's
    names, step and samples (their digest)."""
    acc = np.ascontiguousarray(record.acc)
    return (repr(sp), record.source, record.event, float(record.dt), acc.dtype.str, acc.shape,
            hashlib.sha256(acc.tobytes()).hexdigest())


def propagate(record: Record, sp: SiteProfile) -> tuple[Record, dict]:
    """The surface motion of ``record`` (taken at rock, module docstring) through the site
    profile ``sp``: (Record at the record's step and length, m/s^2; info, JSON-ready). The
    same inputs again in this process give copies of the first result (``_KEPT``)."""
    key = _inputs(record, sp)
    acc, info = _KEPT.get(key, lambda: _propagate(record, sp))
    note = (f"site response: {Path(sp.path).name} (sha256 {sp.sha256[:12]}), {info['method']}; input "
            f"{'rigid base' if sp.bedrock is None else 'outcrop rock'} -> surface; f0 {info['f0_linear_hz']:.3g} Hz "
            f"(small strain), {info['iterations']} iterations{'' if info['converged'] else ' (NOT converged)'}; "
            f"PGA {record.pga_g:.4g} g -> {info['pga_surface_g']:.4g} g")
    out = record.replaced(note, acc=acc)
    out.info["site_response"] = {"profile": sp.path, "sha256": sp.sha256, "name": sp.name, "assumed": sp.assumed,
                                 "f0_linear_hz": info["f0_linear_hz"],
                                 "amplification_linear": info["amplification_linear"],
                                 "pga_rock_g": record.pga_g, "pga_surface_g": info["pga_surface_g"]}
    return out, info


def _propagate(record: Record, sp: SiteProfile) -> tuple[np.ndarray, dict]:
    """``propagate``'s work: the surface acceleration (m/s^2, the record's samples) and info."""
    ps = _pystrata()
    n = record.n
    pad, nfft = fft_samples(record, sp)
    motion = ps.motion.TimeSeriesMotion(record.source, record.event, record.dt, record.acc / G_STANDARD,
                                        fa_length=nfft)
    profile = _profile(sp)
    calc = _counting_eql(sp)
    lin, lout = _locations(sp, profile)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        calc(motion, profile, lin)
    full = motion.calc_time_series(calc.calc_accel_tf(lin, lout)) * G_STANDARD  # m/s^2, nfft samples
    acc = full[:n]
    _check_finite(sp, profile, full)
    f0_lin, amp_lin = fundamental(sp)
    f0_eq, amp_eq = fundamental(sp, profile)
    max_err = float(max(np.max(np.atleast_1d(la.max_error)) for la in profile[:-1]))
    iterations = calc.waves - 1
    layers = []
    for la, pl in zip(sp.layers, profile[:-1]):
        layers.append({"name": la.name, "depth_top_m": la.depth_top_m, "thickness_m": la.thickness_m,
                       "curves": la.curves, "stress_mean_kpa": la.stress_mean_kpa,
                       "vs_initial_m_s": la.vs_m_s, "vs_compatible_m_s": float(pl.shear_vel),
                       "g_over_gmax": float(pl.shear_mod_reduc), "damping_small_strain": small_strain_damping(la),
                       "damping_compatible": float(np.max(pl.damping)),
                       "strain_effective": float(np.max(pl.strain)), "strain_max": float(np.max(pl.strain_max))})
    info = {
        "method": f"pystrata {pystrata_version()} EquivalentLinearCalculator (SH waves, vertical incidence)",
        "input": ("motion of the rigid base (within = outcrop)" if sp.bedrock is None
                  else "outcrop motion at the bedrock (top of the elastic half-space)"),
        "output": "surface (top of the column; within = outcrop at a free surface)",
        "profile": sp.provenance(),
        "thickness_m": sp.thickness_m, "vs_average_m_s": sp.vs_average_m_s,
        "f0_quarter_wave_hz": sp.f_quarter_wave_hz,
        "f0_linear_hz": f0_lin, "amplification_linear": amp_lin,
        "amplification_definition": "|H(f0)|, H = acceleration transfer function surface / outcrop rock "
                                    "(rigid base: surface / base), small-strain properties",
        "f0_compatible_hz": f0_eq, "amplification_compatible": amp_eq,
        "iterations": iterations, "max_change_percent": max_err,
        "converged": bool(max_err < sp.tolerance_percent),
        "layers": layers,
        "pga_rock_m_s2": record.pga, "pga_rock_g": record.pga_g,
        "pga_surface_m_s2": float(np.abs(acc).max()), "pga_surface_g": float(np.abs(acc).max() / G_STANDARD),
        "fft_samples": nfft, "padding_s": (nfft - n) * record.dt,
        "tail_peak_m_s2": float(np.abs(full[n:]).max()) if nfft > n else 0.0,
        "dt_s": record.dt, "n_samples": n,
        "tf_freqs_hz": F_INFO_HZ.tolist(),
        "tf_linear_abs": np.abs(transfer_function(sp, F_INFO_HZ)).tolist(),
        "tf_compatible_abs": np.abs(transfer_function(sp, F_INFO_HZ, profile)).tolist(),
    }
    return acc, info
