"""Load types: one class per ``type`` of a case's [[loads]], registered in ``REGISTRY`` (as
the stage types are in drystone/model/stages.py).

A load is a wrench on some free stones that follows the load programme's body-force field
(drystone/model/loading.py). Each type declares its case keys (``keys``; docs/case-keys.md is
generated from them), checks a filled case table (``validate``), turns it into the
``params`` of spec.json (``resolve``: everything the engines need, so that no geometry is
redone inside YADE), and, for the engines, gives its wrench in the cheap form

    F_i(t) = sum_j c_j(t) F_ij,    M_i(t) = sum_j c_j(t) M_ij

(``basis``: the fixed vectors per stone, N and N m about the stone's centroid; and
``coefficients``: c_j at many steps in one call, from the body-force field there).
``AppliedLoads`` composes the loads of a spec over the bodies of a run.

The one type so far, ``earth_pressure``: the retained soil's active pressure on the back
faces of the stones, Coulomb and Mononobe-Okabe (drystone/mechanics/earth_pressure.py,
docs/earth-pressure.md), with the pseudo-static coefficients from the platform-frame body
force g_eff(t) at each step:

    s = gravity scale of the programme (0..1, the gravity stage's ramp),
    k_h = max(0, g_eff . e_w) / (s g),   1 - k_v = -g_eff . e_z / (s g),

e_w the horizontal unit vector from the soil towards the wall (the opposite of
``into_soil``), g the case's gravity. Gravity alone gives k_h = k_v = 0 (exactly); a tilt
theta towards the wall gives k_h = sin theta, 1 - k_v = cos theta, so the wedge sees the
tilted field: theta_MO = atan(k_h / (1 - k_v)) = theta; a base acceleration a towards the
soil gives k_h = a / g. With ``vertical = false`` (the default) the vertical component of
the base acceleration is left out of k_v (the tilt's and the ramp's are not: they are the
field the soil stands in). The whole load is scaled by s, so that during the gravity ramp
the soil is as heavy as the stones. Water: its hydrostatic part scales with s only.

Units: SI inside (m, N/m^3, Pa, N, N m, rad, s); angles in degrees in the case file only.
No YADE import.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np

from drystone.mechanics import earth_pressure as ep
from drystone.model.keys import REQUIRED, CaseError, Key

#: every load may carry a name (a label for messages and overrides: loads.NAME.KEY)
NAME = Key(None, "-", "optional label of the load (unique, not a number): overrides may address it as "
           "loads.NAME.KEY as well as loads.INDEX.KEY", str)


@dataclass
class LoadContext:
    """What resolving a load needs: the case file (``where``), the run folder (``out``:
    excitation samples lie there), the geometry (a drystone.geometry.blockfile.BlockSet),
    the resolved stages (drystone.model.spec.StageSpec), the gravity (m/s^2) and the time
    step (s)."""

    where: str
    out: Path
    blocks: object
    stages: list
    gravity: float
    dt: float


class LoadType:
    """A load type (module docstring). ``validate`` and ``resolve`` take the filled case
    table; ``basis`` and ``coefficients`` the resolved ``params``."""

    name: ClassVar[str]
    keys: ClassVar[dict[str, Key]]

    def __init_subclass__(cls, **kw):
        super().__init_subclass__(**kw)
        cls.keys = {**cls.keys, "name": NAME}

    def validate(self, table: dict, where: str) -> None:
        """Check the filled case table (completing it in place). Raises CaseError."""

    def resolve(self, table: dict, k: int, ctx: LoadContext) -> dict:
        """The spec.json ``params`` of the validated table, number ``k`` from 0."""
        raise NotImplementedError

    def basis(self, params: dict) -> tuple[list, np.ndarray, np.ndarray]:
        """(block ids, forces (J, n, 3) N, moments (J, n, 3) N m about each stone's centroid)."""
        raise NotImplementedError

    def coefficients(self, params: dict, field: Field) -> tuple[np.ndarray, int | None, str]:
        """(c (T, J), index of the first step where the load is undefined or None, why) at the
        steps of ``field``; the rows from that index on are zero."""
        raise NotImplementedError


REGISTRY: dict[str, LoadType] = {}


def register(cls: type[LoadType]) -> type[LoadType]:
    """Class decorator: add a load type to REGISTRY under its ``name``."""
    REGISTRY[cls.name] = cls()
    return cls


@dataclass
class Field:
    """The load programme's body-force field at steps ``t`` (s, (T,)): ``g_eff`` (T, 3) m/s^2,
    ``base`` (T, 3) the base acceleration in it (m/s^2), ``scale`` (T,) the gravity scale,
    ``gravity`` g (m/s^2)."""

    t: np.ndarray
    g_eff: np.ndarray
    base: np.ndarray
    scale: np.ndarray
    gravity: float

    @classmethod
    def of(cls, prog, ts, g_eff=None) -> Field:
        """The field of a drystone.model.loading.LoadProgramme at times ``ts`` (``g_eff``: its
        body_acceleration_at(ts), if already computed)."""
        ts = np.asarray(ts, float)
        g = prog.body_acceleration_at(ts) if g_eff is None else np.asarray(g_eff, float).reshape(-1, 3)
        return cls(ts, g, prog.base_acceleration_at(ts), prog.gravity_scale_at(ts), prog.gravity)


def _soil(table: dict, z_base: float) -> ep.EarthPressure:
    """The EarthPressure of a filled case table (degrees to rad here)."""
    return ep.EarthPressure(
        gamma=table["gamma"], phi=math.radians(table["phi_deg"]), z_top=table["z_top"], z_base=z_base,
        into_soil=table["into_soil"], back=table["back"], delta=math.radians(table["delta_deg"]),
        beta=math.radians(table["beta_deg"]), alpha=math.radians(table["alpha_deg"]), surcharge=table["surcharge"],
        water_level=table["water_level"], gamma_sat=table["gamma_sat"], gamma_w=table["gamma_w"],
        increment=table["increment"])


def soil_from_params(p: dict) -> ep.EarthPressure:
    """The EarthPressure of resolved params (``soil``: SI, rad)."""
    return ep.EarthPressure(**p["soil"])


@register
class EarthPressureLoad(LoadType):
    """The retained soil's active earth pressure, static (Coulomb) and seismic
    (Mononobe-Okabe), on the free stones' faces on the back plane (module docstring)."""

    name = "earth_pressure"
    keys = {
        "phi_deg": Key(REQUIRED, "deg", "the soil's friction angle phi, in (0, 90)", float, positive=True),
        "delta_deg": Key(0.0, "deg", "wall friction delta, in [0, phi]: the thrust is inclined by delta from the "
                         "face normal, pointing down the face", float, nonneg=True),
        "beta_deg": Key(0.0, "deg", "backfill slope, rising away from the wall (< phi)", float),
        "alpha_deg": Key(0.0, "deg", "batter of the back face from the vertical, positive when the face leans over "
                         "the soil (a wall leaning back into the hill: negative)", float),
        "gamma": Key(REQUIRED, "N/m^3", "the soil's unit weight above the water table", float, positive=True),
        "gamma_sat": Key(None, "N/m^3", "its unit weight below the water table (default: gamma)", float,
                         positive=True),
        "gamma_w": Key(ep.GAMMA_WATER, "N/m^3", "unit weight of water", float, positive=True),
        "into_soil": Key("+y", "-", "horizontal direction from the wall into the soil: +x, -x, +y, -y", str,
                         tuple(ep.INTO_SOIL)),
        "back": Key(REQUIRED, "m", "coordinate (along into_soil's axis, platform frame, not signed by the "
                    "direction) of the back plane at z_base", float),
        "z_base": Key(None, "m", "elevation of the base of the retained soil (default: the lowest point of the free "
                      "stones' faces on the back plane; required when alpha_deg is not 0)", float),
        "z_top": Key(REQUIRED, "m", "elevation of the top of the retained soil against the wall", float),
        "surcharge": Key(0.0, "Pa", "uniform surcharge q per unit area of the backfill surface", float, nonneg=True),
        "water_level": Key(None, "m", "elevation of the water table (default: dry); at or below z_top", float),
        "increment": Key(ep.DEFAULT_INCREMENT, "-", "distribution of the seismic increment: seed_whitman "
                         "(resultant at 0.6 H), inverted_triangle (2/3 H) or static (with the static pressure)",
                         str, tuple(ep.INCREMENTS)),
        "vertical": Key(False, "-", "let the vertical component of the base acceleration enter k_v (the tilt and "
                        "the gravity ramp always do)", bool),
        "start": Key(0.0, "s", "time the load is switched on", float, nonneg=True),
        "end": Key(None, "s", "time it is switched off (default: never)", float, positive=True),
    }

    def validate(self, table, where):
        if table["end"] is not None and table["end"] <= table["start"]:
            raise CaseError(f"{where}: 'end' ({table['end']} s) must be after 'start' ({table['start']} s)")
        if table["alpha_deg"] != 0.0 and table["z_base"] is None:
            raise CaseError(f"{where}: 'z_base' is required when 'alpha_deg' is not 0 (the back plane passes "
                            "through 'back' at z_base)")
        z_base = table["z_base"] if table["z_base"] is not None else table["z_top"] - 1.0  # a stand-in for the check
        try:
            _soil(table, z_base)
        except ValueError as exc:
            raise CaseError(f"{where}: {exc}") from None

    def resolve(self, table, k, ctx):
        where = f"{ctx.where}: [[loads]] #{k + 1} ({self.name})"
        free = [b for b in ctx.blocks.blocks if b.role == "free"]
        stones = {b.id: [np.asarray(p, float) for p in b.parts] for b in free}
        z_base = table["z_base"]
        if z_base is None:  # the lowest point of the faces on the (vertical) back plane
            probe = _soil(table, -1e9)
            zs = [float(f[:, 2].min()) for parts in stones.values() for f in ep.back_faces(parts, probe)]
            if not zs:
                raise CaseError(self._no_stone(where, table))
            z_base = min(zs)
            if not z_base < table["z_top"]:
                raise CaseError(f"{where}: 'z_top' = {table['z_top']} m is not above the lowest back face "
                                f"({z_base} m, the default z_base)")
        try:
            soil = _soil(table, z_base)
        except ValueError as exc:
            raise CaseError(f"{where}: {exc}") from None
        loads = ep.wall_loads(stones, soil)
        hit = [i for i, sl in enumerate(loads.force) if np.any(sl != 0.0)]
        if not hit:
            raise CaseError(self._no_stone(where, table))
        params = {
            "soil": {"gamma": soil.gamma, "phi": soil.phi, "z_top": soil.z_top, "z_base": soil.z_base,
                     "into_soil": soil.into_soil, "back": soil.back, "delta": soil.delta, "beta": soil.beta,
                     "alpha": soil.alpha, "surcharge": soil.surcharge, "water_level": soil.water_level,
                     "gamma_sat": soil.gamma_sat, "gamma_w": soil.gamma_w, "increment": soil.increment},
            "vertical": table["vertical"], "start": table["start"],
            "end": table["end"], "K_A": soil.ka,
            "fields": list(ep.FIELDS),
            "blocks": [int(loads.ids[i]) for i in hit],
            "force_N": [loads.force[i].tolist() for i in hit],
            "moment_Nm": [loads.moment[i].tolist() for i in hit],
            "centroid_m": [loads.centroids[i].tolist() for i in hit],
        }
        self._check_programme(params, ctx, where)
        return params

    @staticmethod
    def _no_stone(where, table) -> str:
        return (f"{where}: no free stone has a face on the back plane (into_soil = {table['into_soil']!r}, back = "
                f"{table['back']} m, alpha_deg = {table['alpha_deg']}, z_base = {table['z_base']}): the back plane "
                "must contain faces of the stones whose outward normal points into the soil")

    def _check_programme(self, params, ctx, where):
        """Refuse, before the run, a programme whose k_h(t), k_v(t) leave Mononobe-Okabe
        without a solution at some time known in advance (``check_times``)."""
        from drystone.model.loading import LoadProgramme, Stage
        from drystone.model.spec import thaw

        prog = LoadProgramme([Stage(st.type, st.start, st.end, thaw(st.params)) for st in ctx.stages], ctx.gravity)
        for s in prog.stages:
            s.behaviour.load_samples(s, ctx.out)
        ts = check_times(prog)
        _, bad, why = self.coefficients(params, Field.of(prog, ts))
        if bad is not None:
            t = float(ts[bad])
            k = prog.stage_index(t)
            raise CaseError(f"{where}: at t = {t:.6g} s ({prog.stages[k].type} stage #{k + 1}): {why}")

    def basis(self, params):
        f = np.asarray(params["force_N"], float).reshape(-1, 3, 3)  # (n, field, 3)
        m = np.asarray(params["moment_Nm"], float).reshape(-1, 3, 3)
        return list(params["blocks"]), f.transpose(1, 0, 2).copy(), m.transpose(1, 0, 2).copy()

    def coefficients(self, params, field):
        """Rows (static, increment, water) per step: s (1 - k_v) K_A, s (1 - k_v)(K_AE - K_A)
        and s, zero outside [start, end) and where s = 0 (module docstring)."""
        soil = soil_from_params(params)
        t, g = field.t, field.g_eff
        n = len(t)
        end = math.inf if params["end"] is None else params["end"]
        on = (params["start"] <= t) & (t < end) & (field.scale > 0.0)
        den = np.where(on, field.scale * field.gravity, 1.0)
        towards = -soil.horizontal
        k_h = np.where(on, np.maximum(g @ towards, 0.0) / den, 0.0)
        gz = g[:, 2] if params["vertical"] else g[:, 2] + field.base[:, 2]
        k_v = np.where(on, 1.0 + gz / den, 0.0)
        bad = first_invalid(soil, k_h, k_v)
        why = ""
        if bad is not None:
            try:
                ep.check(soil.phi, soil.delta, soil.beta, soil.alpha, k_h[bad], k_v[bad])
            except ValueError as exc:
                why = str(exc)
            on[bad:] = False
            k_h[bad:] = 0.0
            k_v[bad:] = 0.0
        ka = soil.ka
        kae = np.atleast_1d(soil.kae(k_h, k_v))
        c = np.zeros((n, 3))
        w = np.where(on, field.scale, 0.0)
        c[:, 0] = w * (1.0 - k_v) * ka
        c[:, 1] = w * (1.0 - k_v) * (kae - ka)
        c[:, 2] = w
        return c, bad, why


def first_invalid(soil: ep.EarthPressure, k_h, k_v) -> int | None:
    """Index of the first (k_h, k_v) for which Mononobe-Okabe has no solution (``ep.check``),
    or None."""
    k_h, k_v = np.asarray(k_h, float), np.asarray(k_v, float)
    theta = ep.seismic_angle(k_h, np.where(np.abs(k_v) < 1.0, k_v, 0.0))
    ok = (np.abs(k_v) < 1.0) & (soil.phi - soil.beta - theta >= 0.0) & (np.cos(soil.delta + soil.alpha + theta) > 0.0)
    bad = np.flatnonzero(~ok)
    return int(bad[0]) if len(bad) else None


#: points per stage at which a programme is checked besides its breakpoints and samples
CHECK_POINTS = 1001


def check_times(prog) -> np.ndarray:
    """The times (s) at which a load programme is known in advance, to check a load over: each
    stage's start and last instant, every excitation sample, and ``CHECK_POINTS`` evenly
    spaced times per stage; up to the first tilt that runs until collapse (its course after
    the collapse is not known: the run checks it, step by step). Between two excitation
    samples the base acceleration is linear in t, so k_h / (1 - k_v), a ratio of two linear
    functions, is monotone there: its extremes are at the samples."""
    out = []
    for s in prog.stages:
        if s.type == "tilt" and s.params.get("until_collapse"):
            out.append([s.start])
            break
        last = np.nextafter(s.end, -math.inf)
        out.append(np.linspace(s.start, last, CHECK_POINTS))
        if s.type == "excitation" and "acc" in s.params:
            ts = s.start + s.params["dt"] * np.arange(len(s.params["acc"]))
            out.append(ts[ts < s.end])
    return np.unique(np.concatenate(out)) if out else np.zeros(1)


class AppliedLoads:
    """The loads of a run over its bodies (body index = YADE id): ``force`` and ``moment``
    (J, nb, 3), the basis of every load stacked (N, N m about each body's centroid), and
    their coefficients at many steps (``coefficients``). Keeps the last step's coefficients
    (``last``) and, for the stability checks, the integral of |c_j| dt (``abs_integral``, s).
    Moments about each stone's centroid from the initial geometry, fixed in the platform
    frame (the stone's rotation does not turn them: small rotations)."""

    def __init__(self, loads: list[dict], prog, index: dict, nb: int):
        self.prog = prog
        self.loads = [(REGISTRY[d["type"]], d["params"]) for d in loads]
        force, moment, self.slices = [], [], []
        j = 0
        for lt, params in self.loads:
            ids, f, m = lt.basis(params)
            F = np.zeros((len(f), nb, 3))
            T = np.zeros((len(f), nb, 3))
            for col, b in enumerate(ids):
                F[:, index[b]] += f[:, col]
                T[:, index[b]] += m[:, col]
            force.append(F)
            moment.append(T)
            self.slices.append(slice(j, j + len(f)))
            j += len(f)
        self.force = np.concatenate(force) if force else np.zeros((0, nb, 3))
        self.moment = np.concatenate(moment) if moment else np.zeros((0, nb, 3))
        self.last = np.zeros(j)
        self.abs_integral = np.zeros(j)
        self.loaded = np.flatnonzero(np.any(self.force != 0, axis=(0, 2)) | np.any(self.moment != 0, axis=(0, 2)))
        # each loaded body's |F_j| and |M_j| (N, N m; fixed): what ``impulses`` weighs at every sample
        self._norms = [(i, np.linalg.norm(self.force[:, i], axis=1), np.linalg.norm(self.moment[:, i], axis=1))
                       for i in self.loaded]

    @classmethod
    def from_spec(cls, spec, prog, index: dict, nb: int) -> AppliedLoads | None:
        loads = list(spec.get("loads", []) or [])
        return cls(loads, prog, index, nb) if loads else None

    def coefficients(self, ts, g_eff=None) -> tuple[np.ndarray, int | None, str]:
        """(c (T, J), first step index where a load is undefined or None, why) at times ``ts``."""
        field = Field.of(self.prog, ts, g_eff)
        c = np.zeros((len(field.t), len(self.last)))
        bad, why = None, ""
        for (lt, params), sl in zip(self.loads, self.slices):
            c[:, sl], b, w = lt.coefficients(params, field)
            if b is not None and (bad is None or b < bad):
                bad, why = b, w
        if bad is not None:
            c[bad:] = 0.0
        return c, bad, why

    def taken(self, c: np.ndarray, dt: float) -> None:
        """Steps with coefficients ``c`` (T, J) were taken (step ``dt`` s)."""
        if len(c):
            self.last = c[-1].copy()
            self.abs_integral += np.abs(c).sum(axis=0) * dt

    def wrench(self, c=None) -> tuple[np.ndarray, np.ndarray]:
        """Forces and moments (nb, 3) for coefficients ``c`` (J,) (default: the last step's)."""
        c = self.last if c is None else c
        return np.einsum("j,jbk->bk", c, self.force), np.einsum("j,jbk->bk", c, self.moment)

    def power(self, vel, angvel) -> float:
        """Upper bound of the loads' power on the bodies (W) at the last step: sum |F . v| + |M . w|."""
        F, T = self.wrench()
        return float(np.sum(np.abs(np.sum(F * vel, axis=1))) + np.sum(np.abs(np.sum(T * angvel, axis=1))))

    def impulses(self, mass, inertia) -> list[tuple[float, float]]:
        """(bound of int |F| dt (N s), mass kg) and (bound of int |M| dt (N m s), smallest
        principal moment kg m^2) per loaded body, for ``stability.speed_budget`` (d sqrt(E_k)/dt
        <= |F| / sqrt(2 m) + |M| / sqrt(2 I_min))."""
        out = []
        for i, f_norm, m_norm in self._norms:
            out += [(float(self.abs_integral @ f_norm), float(mass[i])),
                    (float(self.abs_integral @ m_norm), float(np.min(inertia[i])))]
        return out
