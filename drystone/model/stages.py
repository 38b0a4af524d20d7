"""Stage types: one class per ``type`` of a case's [[stages]], registered in ``REGISTRY``.

Each type declares its case keys (``keys``; the key table of docs/case-keys.md is generated from
them), checks a filled case stage (``validate``), turns it into its duration and the
``params`` of spec.json (``resolve``), and says what a resolved stage imposes at time t
(the load hooks that drystone/model/loading.py's ``LoadProgramme`` composes). A hook of a type
that imposes nothing returns its neutral value (None, zero, empty).

Units: times s, angles deg, accelerations m/s^2, velocities m/s, lengths m; vectors in
the platform frame (drystone/model/loading.py). No YADE import.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar

import numpy as np

from drystone.mechanics import monitors
from drystone.model.keys import REQUIRED, CaseError, Key
from drystone.mechanics.monitors import Monitor
from drystone.units import G_STANDARD

Z = np.array([0.0, 0.0, 1.0])
TOWARDS = {"+x": [1.0, 0.0, 0.0], "-x": [-1.0, 0.0, 0.0], "+y": [0.0, 1.0, 0.0], "-y": [0.0, -1.0, 0.0]}
AXES = {"x": [1.0, 0.0, 0.0], "y": [0.0, 1.0, 0.0], "z": [0.0, 0.0, 1.0]}
MAX_TILT_DEG = 90.0  # deg: a tilt target (to_deg, max_deg) above vertical is refused

#: every stage may carry a name: overrides then address it as stages.NAME.KEY
NAME = Key(None, "-", "optional label of the stage (unique, not a number): overrides may address it as "
           "stages.NAME.KEY as well as stages.INDEX.KEY", str)


@dataclass
class ResolveContext:
    """What resolving a stage needs, and what one stage passes to the next: the case file
    (``where``), the run folder (``out``, excitation samples are saved there), the time
    step ``dt`` (s), the block ids (all, free), the platform tilt reached so far (deg) and
    the excitations' metadata (spec.json ``excitations``)."""

    where: str
    out: Path
    dt: float
    ids: set
    free: set
    tilt_deg: float = 0.0
    excitations: list = field(default_factory=list)


class StageType:
    """A stage type. ``validate`` and ``resolve`` take the case stage (a dict filled with
    the defaults of ``keys``); the load hooks take a resolved stage ``st`` (``start``,
    ``end`` s and ``params``, a drystone.model.loading.Stage) and a time ``t`` (s): the body-force
    hooks (``gravity_scale``, ``tilt_increment``, ``base_acceleration``) a 1-D array of times,
    evaluated element by element with the scalar formula (a programme's values at many steps
    in one call are those of one step at a time, bit for bit), the others one time."""

    name: ClassVar[str]
    keys: ClassVar[dict[str, Key]]

    def __init_subclass__(cls, **kw):
        super().__init_subclass__(**kw)
        cls.keys = {**cls.keys, "name": NAME}

    # -- the case ---------------------------------------------------------------
    def validate(self, s: dict, where: str, *, last: bool, base_dir: Path) -> None:
        """Check the filled case stage ``s`` (completing it in place); ``last``: it is the
        case's last stage; relative paths are relative to ``base_dir``. Raises CaseError."""

    def resolve(self, s: dict, k: int, ctx: ResolveContext) -> tuple[float, dict]:
        """(duration s, params) of the validated case stage ``s``, number ``k`` from 0."""
        raise NotImplementedError

    # -- the load at t ------------------------------------------------------------
    def gravity_scale(self, st, t: np.ndarray) -> np.ndarray | None:
        """Fraction of gravity at each time of ``t`` if this stage governs it, else None."""
        return None

    def tilt_increment(self, st, t: np.ndarray) -> np.ndarray:
        """Platform rotation (deg) this stage has added by each time of ``t``."""
        return np.zeros(len(t))

    def towards(self, st) -> np.ndarray | None:
        """Horizontal unit vector the platform tilts towards, if this stage tilts it."""
        return None

    def base_acceleration(self, st, t: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """Where among the times ``t`` this stage shakes the base, and the base acceleration
        vectors there (m/s^2): (mask of t, (mask.sum(), 3) array); None if it never does."""
        return None

    def imposed_velocities(self, st, t: float) -> dict[int, np.ndarray]:
        """Velocities (m/s) this stage imposes on non-moving blocks at t, by block id."""
        return {}

    def velocity_jump(self, st) -> np.ndarray:
        """Relative velocity (m/s) every free block gets when the stage begins."""
        return np.zeros(3)

    def settle(self, st, weight: float) -> dict | None:
        """Early end on low kinetic energy: {"threshold_J", "window_s"}, or None."""
        return None

    def moving_blocks(self, st) -> list[int]:
        """Ids of the non-moving blocks whose velocity this stage imposes."""
        return []

    def monitor(self, st, k: int, run) -> Monitor | None:
        """The job this stage (number ``k`` from 0) adds to every recorded sample from its
        start (drystone/mechanics/monitors.py; ``run``: the driver), or None."""
        return None

    def load_samples(self, st, folder: Path) -> None:
        """Load the files the stage needs from the run ``folder`` into ``st.params``."""


REGISTRY: dict[str, StageType] = {}


def register(cls: type[StageType]) -> type[StageType]:
    """Class decorator: add a stage type to REGISTRY under its ``name``."""
    REGISTRY[cls.name] = cls()
    return cls


@register
class Gravity(StageType):
    """Gravity grows linearly over ``ramp`` s from the stage start, then holds."""

    name = "gravity"
    keys = {
        "duration": Key(REQUIRED, "s", "stage length", float, positive=True),
        "ramp": Key(None, "s", "gravity grows linearly over this time, then holds (default: half the "
                    "duration)", float, nonneg=True),
    }

    def validate(self, s, where, *, last, base_dir):
        if s["ramp"] is None:
            s["ramp"] = 0.5 * s["duration"]
        if s["ramp"] > s["duration"]:
            raise CaseError(f"{where}: 'ramp' ({s['ramp']} s) exceeds 'duration' ({s['duration']} s)")

    def resolve(self, s, k, ctx):
        return s["duration"], {"ramp": s["ramp"]}

    def gravity_scale(self, st, t):
        ramp = st.params.get("ramp", 0.0)
        if ramp <= 0:
            return np.where(t >= st.start, 1.0, 0.0)
        return np.clip((t - st.start) / ramp, 0.0, 1.0)


@register
class Settlement(StageType):
    """A fixed block moves down by ``displacement`` (m) at constant speed over the stage."""

    name = "settlement"
    keys = {
        "duration": Key(REQUIRED, "s", "stage length; the settlement is linear over it", float, positive=True),
        "block": Key(REQUIRED, "-", "id of the fixed block that settles", int),
        "displacement": Key(REQUIRED, "m", "downward settlement", float, positive=True),
    }

    def resolve(self, s, k, ctx):
        if s["block"] not in ctx.ids or s["block"] in ctx.free:
            raise CaseError(f"{ctx.where}: [[stages]] #{k + 1}: settlement block {s['block']} must be a "
                            "fixed block of the geometry")
        return s["duration"], {"block": s["block"], "displacement": s["displacement"]}

    def imposed_velocities(self, st, t):
        v = np.zeros(3)
        if st.start <= t < st.end:
            v = -Z * st.params["displacement"] / (st.end - st.start)
        return {st.params["block"]: v}

    def moving_blocks(self, st):
        return [st.params["block"]]


@register
class Tilt(StageType):
    """The platform rotates at ``rate_deg_s`` towards ``towards`` (a horizontal unit vector)
    from the tilt reached by the earlier tilt stages."""

    name = "tilt"
    keys = {
        "rate_deg_s": Key(REQUIRED, "deg/s", "platform rotation rate", float, positive=True),
        "to_deg": Key(None, "deg", "stop the stage at this platform angle", float, positive=True),
        "until_collapse": Key(False, "-", "run until collapse (or max_deg)", bool),
        "max_deg": Key(45.0, "deg", "upper bound of an until_collapse stage", float, positive=True),
        "towards": Key("+y", "-", "horizontal direction the platform tilts towards: +x, -x, +y, -y", str,
                       ("+x", "-x", "+y", "-y")),
        "reaction_drop": Key(0.05, "-", "collapse when the vertical reaction of the moving blocks drops "
                             "by this fraction of their weight", float, positive=True),
        "after_collapse": Key(1.0, "s", "keep running this long after collapse", float, nonneg=True),
    }

    def validate(self, s, where, *, last, base_dir):
        if (s["to_deg"] is None) == (not s["until_collapse"]):
            raise CaseError(f"{where}: give either 'to_deg' or 'until_collapse = true'")
        for key in ("to_deg", "max_deg"):
            if s[key] is not None and s[key] > MAX_TILT_DEG:
                raise CaseError(f"{where}: '{key}' = {s[key]:g} deg exceeds {MAX_TILT_DEG:g} deg (a platform "
                                "tilted beyond vertical is upside down)")

    def resolve(self, s, k, ctx):
        target = s["to_deg"] if s["to_deg"] is not None else s["max_deg"]
        if target <= ctx.tilt_deg:
            raise CaseError(f"{ctx.where}: [[stages]] #{k + 1}: tilt target {target} deg is not above "
                            f"the current {ctx.tilt_deg} deg")
        dur = (target - ctx.tilt_deg) / s["rate_deg_s"]
        ctx.tilt_deg = target
        return dur, {"rate_deg_s": s["rate_deg_s"], "towards": TOWARDS[s["towards"]],
                     "until_collapse": s["until_collapse"], "reaction_drop": s["reaction_drop"],
                     "after_collapse": s["after_collapse"]}

    def tilt_increment(self, st, t):
        return np.where(t <= st.start, 0.0, st.params["rate_deg_s"] * (np.minimum(t, st.end) - st.start))

    def monitor(self, st, k, run):
        return monitors.Collapse(k, st.params) if st.params.get("until_collapse") else None

    def towards(self, st):
        return np.asarray(st.params["towards"], float)


def _record(where: str, record: str, base_dir: Path) -> str:
    """A catalogue name as given; a FEMA P695 id ('fema:12a') checked and written as
    ``motions.fema.canonical_id``; a file path resolved against the case file's folder
    (as 'geometry'), returned absolute."""
    from drystone.motions import catalogue, fema

    if record in catalogue.names():
        return record
    if fema.parse_id(record):
        try:
            return fema.canonical_id(fema.entry(record))
        except (KeyError, fema.FemaDataMissing) as exc:
            raise CaseError(f"{where}: 'record' = {exc.args[0] if isinstance(exc, KeyError) else exc}") from None
    rp = Path(record) if Path(record).is_absolute() else base_dir / record
    if not rp.is_file():
        raise CaseError(f"{where}: 'record' = {record!r} is neither a catalogue name ({', '.join(catalogue.names())}), "
                        f"a FEMA P695 id (fema:12a) "
                        f"nor a file ({rp} not found; a path is relative to the case file's folder)")
    return str(rp.resolve())


def _site(where: str, site: str, base_dir: Path) -> str:
    """A site-profile file resolved against the case file's folder (as 'record'), checked
    (``motions.site.read_profile``) before any run, returned absolute."""
    from drystone.motions import site as msite

    sp = Path(site) if Path(site).is_absolute() else base_dir / site
    if not sp.is_file():
        raise CaseError(f"{where}: 'site' = {site!r}: {sp} not found (a path is relative to the case file's folder)")
    try:
        msite.read_profile(sp)
    except msite.SiteError as exc:
        raise CaseError(f"{where}: 'site': {exc}") from None
    return str(sp.resolve())


def _excitation(s: dict, where: str, out: Path, k: int) -> tuple[np.ndarray, float, dict]:
    """Acceleration samples (m/s^2), their step (s) and metadata for an excitation stage
    (sine, white noise or record: drystone/motions/excitation.py), saved beside the run as
    ``excitation_<k>.npy``; with a ``site``, that is the surface motion, and the record at
    rock (``excitation_<k>_bedrock.npy``) and the site response's profile, info and
    provenance (``excitation_<k>_site.json``) are saved beside it."""
    import json

    from drystone.motions import excitation as mex

    try:
        m = mex.motion_for_stage(s)
        meta = mex.stage_meta(s, m)
    except (ValueError, FileNotFoundError, KeyError, OSError) as exc:
        raise CaseError(f"{where}: [[stages]] #{k + 1} ({s['motion']}): {exc}") from None
    acc, dt = np.asarray(m.applied.acc, float), m.applied.dt
    if not np.all(np.isfinite(acc)):
        raise CaseError(f"{where}: [[stages]] #{k + 1}: the excitation has non-finite samples")
    name = f"excitation_{k + 1}.npy"
    np.save(out / name, acc)
    if m.site is not None:
        rock, info = f"excitation_{k + 1}_bedrock.npy", f"excitation_{k + 1}_site.json"
        np.save(out / rock, m.bedrock.acc)
        (out / info).write_text(json.dumps({
            "units": "accelerations m/s^2, dt s, frequencies Hz, lengths m, velocities m/s, stresses kPa",
            "surface_acc_file": name, "bedrock_acc_file": rock, "dt_s": dt,
            "bedrock_record": m.bedrock.metadata(), "surface_record": m.applied.metadata(),
            "site_response": m.site}, indent=1))
        meta["site"] = dict(meta["site"], bedrock_acc_file=rock, site_file=info)
    meta = dict(meta, acc_file=name, dt_s=dt, pga_m_s2=float(np.abs(acc).max()),
                pga_g=float(np.abs(acc).max() / G_STANDARD), direction=s["direction"])
    return acc, dt, meta


def initial_relative_velocity(s: dict, meta: dict) -> list[float]:
    """Velocity (m/s, platform frame) every free block gets when an excitation stage begins.

    ``start = "displacement"`` (sine only) imposes the paper's Eq. 9 as the base displacement
    d(t) = (A / w^2) sin(w t) from t = 0 (stage time), the base at rest before. Its velocity
    d'(t) = (A / w) cos(w t) jumps from 0 to v_b = A / w at t = 0, while its acceleration
    d''(t) = -A sin(w t) is what ``motions.generators.sine`` samples (and the load programme
    applies as the body force -d'' e). The jump is an acceleration impulse v_b delta(t) e that
    the samples cannot carry: at t = 0+ the free blocks, held only by finite contact forces,
    still have their world velocity (zero), so relative to the platform they move at
    0 - v_b e = -(A / w) e. With A = 0.5 m/s^2: 0.080 m/s at 1 Hz, 0.8 m/s at 0.1 Hz.
    ``start = "rest"`` (and every other motion) gives zero. At the end of the stage nothing
    is applied: the base keeps its final velocity (an inertial frame, no load on the wall)."""
    if s.get("start", "rest") != "displacement":
        return [0.0, 0.0, 0.0]
    info = meta["info"]
    v_b = info["amplitude_m_s2"] / (2.0 * math.pi * info["frequency_hz"])
    return [0.0 - v_b * c for c in AXES[s["direction"]]]


@register
class Excitation(StageType):
    """A base acceleration a_b(t) along ``direction`` (samples ``acc`` at step ``dt``,
    linearly interpolated) acts as the body force -a_b e; a sine started as a displacement
    also gives every free block ``initial_relative_velocity`` when the stage begins."""

    name = "excitation"
    keys = {
        "duration": Key(None, "s", "stage length (default: the motion's length)", float, positive=True),
        "motion": Key(REQUIRED, "-", "sine, white_noise or record", str, ("sine", "white_noise", "record")),
        "direction": Key("y", "-", "base acceleration direction: x, y or z", str, ("x", "y", "z")),
        "frequency_hz": Key(None, "Hz", "sine frequency", float, positive=True),
        "amplitude": Key(0.5, "m/s^2", "sine acceleration amplitude (the paper's Eq. 9 uses 0.5)", float,
                         positive=True),
        "pga_g": Key(None, "g", "scale the motion to this peak ground acceleration", float, positive=True),
        "record": Key(None, "-", "catalogue name, or file of an acceleration record (relative to the case file)", str),
        "seed": Key(0, "-", "white-noise seed", int),
        "site": Key(None, "-", "site-profile file (TOML, relative to the case file; docs/motions.md, Site response): "
                    "the motion, scaled to pga_g AT ROCK, is propagated up the 1-D soil column (pystrata, equivalent "
                    "linear) and the surface motion drives the platform; the rock record and the site response are "
                    "saved beside the run (excitation_<k>_bedrock.npy, excitation_<k>_site.json)", str),
        "start": Key("rest", "-", "how a sine starts (motion = 'sine' only): 'rest' = the acceleration "
                     "a(t) = -A sin(wt) from a base at rest (the base velocity grows from 0); 'displacement' = the "
                     "paper's Eq. 9, base displacement d(t) = A/w^2 sin(wt), whose velocity A/w cos(wt) jumps from 0 "
                     "to A/w at the start: every free block gets the relative velocity -A/w along 'direction' when "
                     "the stage begins (derivation: drystone/model/stages.py initial_relative_velocity)", str,
                     ("rest", "displacement")),
    }

    def validate(self, s, where, *, last, base_dir):
        m = s["motion"]
        if m == "sine" and s["frequency_hz"] is None:
            raise CaseError(f"{where}: a sine needs 'frequency_hz'")
        if m == "record" and s["record"] is None:
            raise CaseError(f"{where}: motion 'record' needs 'record' (catalogue name or file)")
        if m != "record" and s["duration"] is None:
            raise CaseError(f"{where}: motion {m!r} needs 'duration'")
        if m != "sine" and s["start"] != "rest":
            raise CaseError(f"{where}: 'start' = {s['start']!r} is defined for motion 'sine' only (Eq. 9's "
                            f"displacement); a {m!r} motion starts from rest")
        if m == "record":
            s["record"] = _record(where, s["record"], base_dir)
        if s["site"] is not None:
            if s["start"] != "rest":
                raise CaseError(f"{where}: 'start' = {s['start']!r} cannot go with 'site': the surface motion is no "
                                "longer the sine whose displacement Eq. 9 prescribes")
            s["site"] = _site(where, s["site"], base_dir)

    def resolve(self, s, k, ctx):
        dt = ctx.dt
        if s["motion"] == "sine" and s["frequency_hz"] is not None and s["frequency_hz"] >= 0.5 / dt:
            raise CaseError(f"{ctx.where}: [[stages]] #{k + 1}: 'frequency_hz' = {s['frequency_hz']:g} Hz is at "
                            f"or above the Nyquist frequency {0.5 / dt:g} Hz of the time step {dt:.3g} s")
        acc, sdt, meta = _excitation(s, ctx.where, ctx.out, k)
        dur = s["duration"] if s["duration"] is not None else (len(acc) - 1) * sdt
        params = {"acc_file": meta["acc_file"], "dt": sdt, "direction": AXES[s["direction"]],
                  "start": s["start"], "initial_relative_velocity": initial_relative_velocity(s, meta)}
        meta = dict(meta, start=s["start"], initial_relative_velocity_m_s=params["initial_relative_velocity"])
        ctx.excitations.append(dict(meta, stage=k + 1))
        return dur, params

    def base_acceleration(self, st, t):
        """Linear interpolation of the samples; the last sample held to its end, zero past it."""
        on = (st.start <= t) & (t < st.end)
        acc = np.asarray(st.params["acc"], float)
        x = (t[on] - st.start) / st.params["dt"]
        i = x.astype(np.int64)  # x >= 0: truncation is the floor
        a = np.where(i < len(acc), acc[-1] if len(acc) else 0.0, 0.0)
        between = i + 1 < len(acc)
        j = i[between]
        a[between] = acc[j] + (x[between] - j) * (acc[j + 1] - acc[j])
        return on, a[:, None] * np.asarray(st.params["direction"], float)

    def velocity_jump(self, st):
        return np.asarray(st.params.get("initial_relative_velocity", (0.0, 0.0, 0.0)), float)

    def load_samples(self, st, folder):
        st.params["acc"] = np.load(Path(folder) / st.params["acc_file"])


@register
class Rest(StageType):
    """Free motion under the current loads; the last stage may end the run once the kinetic
    energy has settled (``settle``)."""

    name = "rest"
    keys = {
        "duration": Key(REQUIRED, "s", "free motion under the current loads; with until_kinetic_below(_per_weight), "
                        "the longest it may run", float, positive=True),
        "until_kinetic_below": Key(None, "J", "end the stage (and the run: last stage only) once the kinetic energy "
                                   "of the free blocks (those fallen below the platform left out) has stayed below "
                                   "this for settle_window s; run_info/summary say whether it was reached", float,
                                   positive=True),
        "until_kinetic_below_per_weight": Key(None, "m", "the same threshold as a fraction of the weight W of the "
                                              "free blocks: kinetic energy < W x this length (the energy that would "
                                              "lift them all by it; 1e-7 m ~ an rms speed sqrt(2 g x 1e-7) = 1.4 "
                                              "mm/s)", float, positive=True),
        "settle_window": Key(0.5, "s", "how long the kinetic energy must stay below the threshold: a rocking or "
                             "vibrating body passes through zero kinetic energy at its turning points, so take at "
                             "least half the period of the slowest oscillation expected", float,
                             positive=True),
    }

    def validate(self, s, where, *, last, base_dir):
        if s["until_kinetic_below"] is not None and s["until_kinetic_below_per_weight"] is not None:
            raise CaseError(f"{where}: give 'until_kinetic_below' (J) or 'until_kinetic_below_per_weight' (m), "
                            "not both")
        quiet = s["until_kinetic_below"] is not None or s["until_kinetic_below_per_weight"] is not None
        if quiet and s["settle_window"] > s["duration"]:
            raise CaseError(f"{where}: 'settle_window' ({s['settle_window']} s) exceeds 'duration' "
                            f"({s['duration']} s)")
        if quiet and not last:
            raise CaseError(f"{where}: 'until_kinetic_below(_per_weight)' ends the run early: only the last stage may "
                            "have it")

    def resolve(self, s, k, ctx):
        params = {"until_kinetic_below": s["until_kinetic_below"],
                  "until_kinetic_below_per_weight": s["until_kinetic_below_per_weight"],
                  "settle_window": s["settle_window"]}
        if params["until_kinetic_below"] is None and params["until_kinetic_below_per_weight"] is None:
            params = {}  # a plain rest: same fingerprint as before these keys existed
        return s["duration"], params

    def settle(self, st, weight):
        p = st.params
        if p.get("until_kinetic_below") is not None:
            thr = float(p["until_kinetic_below"])
        elif p.get("until_kinetic_below_per_weight") is not None:
            thr = float(p["until_kinetic_below_per_weight"]) * float(weight)
        else:
            return None
        return {"threshold_J": thr, "window_s": float(p.get("settle_window", 0.0))}

    def monitor(self, st, k, run):
        cfg = self.settle(st, run.w_free)
        return None if cfg is None else monitors.Settle(k, cfg, st.start, st.end, run.z_floor, run.region)
