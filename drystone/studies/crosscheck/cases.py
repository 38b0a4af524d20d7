"""The cross-check cases: one case dict (this package's case format) per case, run by both
engines, with the rigid closed form where there is one.

* ``toppling``: one 0.2 x 0.2 x 0.4 m block (b/h = 0.5, mu 0.7 > b/h: it topples, it
  cannot slide) on the tilting platform; the programme of tests/test_tilt_block.py (gravity
  ramp, 5 deg/s to 22 deg, then 0.5 deg/s until collapse). Closed form atan(b/h) = 26.565
  deg; the rigid rocking equation with the same programme, read with the package's
  collapse rule, gives what a rigid engine must report (atan(b/h) + the rule's lag); the
  package's own closed form at finite K_n is the Winkler angle
  (``drystone.mechanics.analytic.toppling_tilt_deg``), which tends to atan(b/h) as K_n^(-1/3).
* ``pulse``: one 0.2 m cube (mu 0.4) on the platform, a half-sine base pulse along y,
  A = 0.6 g = 5.886 m/s^2, T = 0.5 s (the package's sine excitation at 1 Hz from rest, run
  for half a period, then a rest stage). Closed form: the rigid-plastic slide
  (``closed_forms.half_sine_slide``): 80.44 mm for the continuous pulse, 80.10 mm for the
  pulse as applied (the package samples a sine at 64 points per period and interpolates
  linearly: ``closed_forms.rigid_plastic_slide`` on those samples). LMGC90 moves the platform with the pulse's
  velocity history (a moving base); the package applies the pulse as the body force -a_b
  in the platform frame: two formulations of the same motion.
* ``wall``: the 40-block running-bond wall (``drystone/geometry/running_bond.py``: 8.64 x
  4 x 0.8 m, 5 courses of 8, the first fixed) tilted out of plane (+y). Rigid closed form
  (ASSUMED: the free courses rock as one body about the toe of the lowest free bed joint,
  the joints being continuous through the thickness and mu = 0.4 > t/H): tan(theta) =
  t / H_free = 0.8 / 3.2, 14.04 deg.
* ``tilt_wall``: the Santa-Cruz tilt walls (``cases/tilt_wall.toml``, generator
  ``tilt_wall``, seeds 0-4) with the tilt study's faster protocol (drystone/studies/tilt/study.py ``FAST``:
  2 deg/s to 10 deg, then 1 deg/s). No closed form: the experiment (14.33 +- 0.76 deg,
  data/papers/sacsayhuaman.toml) and the paper's model (14.3 deg) are given beside.
  LMGC90's common-plane detection finds no supporting contact between these irregular
  stones (they fall through each other from the first step: checked on seed 0, with and
  without the varying depth, alert 1e-3 to 2e-2 m), so this case runs with the "sto"
  face-to-face detection, which carries the wall at rest (reaction = weight within 1e-5)
  but loses the contact of faces that rotate apart: its collapse angle is valid up to the
  onset of rocking, not after (ASSUMED adequate for the onset angle), and it costs 50-110
  ms per step (about 20-40 min per wall).

The package runs each case at K_n = 2e8 N/m^3 (the papers' value) times ``kn_factors``
(K_t = K_n / 2 throughout, as the cases' block files have it): its time step scales as
1/sqrt(K_n), so each factor of 10 costs ~3.2 times the steps.
"""
from __future__ import annotations

import copy
import math
import tomllib
from dataclasses import dataclass, field

import numpy as np

from drystone.mechanics import analytic

from drystone import paths
from drystone.studies.crosscheck import closed_forms as cf

KN0 = 2e8  # N/m^3, the papers' (Table 1, FEM column)
G = 9.81


def _stage_start(spec: dict, k: int) -> float:
    return float(spec["stages"][k]["start"])


# -- (a) toppling block ------------------------------------------------------------------
TOPPLE_SIZE = (0.2, 0.2, 0.4)  # m: x, y (along the tilt), z
TOPPLE_MU = 0.7
#: contact damping of the package's side (fraction of critical): light, as in
#: tests/test_tilt_block.py's 1 deg/s check; with 0.8 the damped run-away dates the onset
#: later (docs/physics.md). LMGC90's rigid contact has restitution 0 and no damping while
#: rocking. ASSUMED for the comparison.
TOPPLE_DAMPING = 0.08


def toppling_case(kn: float = KN0) -> dict:
    return {
        "case": {"name": "crosscheck_toppling",
                 "geometry": {"generator": "boxes_on_platform", "mu": TOPPLE_MU, "damping": TOPPLE_DAMPING,
                              "kn": KN0, "kt": KN0 / 2,
                              "boxes": [{"id": 1, "center_xy": [0.0, 0.0], "size": list(TOPPLE_SIZE)}]}},
        "contact": {"kn": kn, "kt": kn / 2},
        "stages": [{"type": "gravity", "duration": 0.5, "ramp": 0.25},
                   {"type": "tilt", "rate_deg_s": 5.0, "to_deg": 22.0},
                   {"type": "tilt", "rate_deg_s": 0.5, "until_collapse": True, "max_deg": 28.0,
                    "after_collapse": 0.3}],
        "output": {"interval": 0.01},
    }


def toppling_closed_forms(spec: dict, kns, folder=None) -> dict:
    from drystone.model.loading import LoadProgramme

    _, b, h = TOPPLE_SIZE
    prog = LoadProgramme.from_spec(spec)
    towards = spec["stages"][1]["params"]["towards"]
    rigid_rule = cf.rocking_onset_deg(b, h, prog, towards, spec["stages"][-1]["end"], spec["output"]["interval"],
                                      spec.get("onset_rate", 5e-3), spec.get("onset_window_deg", 0.2))
    return {"rigid_deg": cf.toppling_deg(b, h), "rigid_with_rule_deg": rigid_rule,
            "winkler_deg": {f"{kn:g}": analytic.toppling_tilt_deg(b, h, TOPPLE_SIZE[0], 2300.0, kn) for kn in kns},
            "winkler_params": [b, h, TOPPLE_SIZE[0], 2300.0], "winkler_label": "Winkler closed form (package's law, static)"}


# -- (b) half-sine pulse -----------------------------------------------------------------
PULSE_A = 0.6 * G  # m/s^2
PULSE_T = 0.5  # s (half a period of a 1 Hz sine)
PULSE_MU = 0.4
PULSE_DAMPING = 0.8  # Table 1; irrelevant to a slide on a flat joint except during stick (ASSUMED)


def pulse_case(kn: float = KN0) -> dict:
    return {
        "case": {"name": "crosscheck_pulse",
                 "geometry": {"generator": "boxes_on_platform", "mu": PULSE_MU, "damping": PULSE_DAMPING,
                              "kn": KN0, "kt": KN0 / 2,
                              "boxes": [{"id": 1, "center_xy": [0.0, 0.0], "size": [0.2, 0.2, 0.2]}]}},
        "contact": {"kn": kn, "kt": kn / 2},
        "stages": [{"type": "gravity", "duration": 0.4, "ramp": 0.2},
                   {"type": "excitation", "motion": "sine", "frequency_hz": 1.0 / (2 * PULSE_T),
                    "amplitude": PULSE_A, "direction": "y", "duration": PULSE_T, "start": "rest"},
                   {"type": "rest", "duration": 0.5}],
        "output": {"interval": 0.002},
    }


def pulse_closed_forms(spec: dict, kns, folder=None) -> dict:
    """The continuous half-sine's closed form and, with the run ``folder`` (its excitation
    samples), the rigid-plastic slide under the pulse as both engines apply it (the
    package's samples, linearly interpolated)."""
    out = {"rigid_plastic": cf.half_sine_slide(PULSE_A, PULSE_T, PULSE_MU, spec["gravity"])}
    if folder is not None:
        from drystone.model.loading import LoadProgramme

        prog = LoadProgramme.from_spec(spec, folder)
        t0 = _stage_start(spec, 1)
        axis = 1  # y
        out["rigid_plastic_as_sampled"] = cf.rigid_plastic_slide(
            lambda t: float(prog.base_acceleration(t0 + t)[axis]), spec["stages"][-1]["end"] - t0, PULSE_MU,
            spec["gravity"])
    return out


def slide_m(h: dict, spec: dict) -> float:
    """Final displacement (m) of the block along y relative to the platform, from the start
    of the pulse (the sample at the excitation stage's start)."""
    t0 = _stage_start(spec, 1)
    i0 = int(np.searchsorted(h["t"], t0 - 1e-9))
    return float(h["pos"][-1, 0, 1] - h["pos"][i0, 0, 1])


# -- (c) running-bond wall ---------------------------------------------------------------
def wall_case(kn: float = KN0) -> dict:
    return {
        "case": {"name": "crosscheck_wall", "geometry": {"generator": "running_bond"}},
        "contact": {"kn": kn, "kt": kn / 2},
        "stages": [{"type": "gravity", "duration": 1.0, "ramp": 0.5},
                   {"type": "tilt", "rate_deg_s": 2.0, "to_deg": 10.0},
                   {"type": "tilt", "rate_deg_s": 0.5, "until_collapse": True, "max_deg": 20.0,
                    "after_collapse": 1.0}],
        "output": {"interval": 0.02},
    }


def wall_closed_forms(spec: dict, kns, folder=None) -> dict:
    from drystone.geometry import running_bond as rb

    h_free = rb.HEIGHT * (rb.COURSES - 1) / rb.COURSES
    params = [rb.THICKNESS, h_free, rb.LENGTH, 2300.0]
    return {"rigid_deg": math.degrees(math.atan2(rb.THICKNESS, h_free)),
            "assumed": "the free courses rock as one rigid body about the toe of the lowest free bed joint",
            # the package's law on that mechanism with the lowest bed joint as the only compliant one
            # (an upper bound of the penalty angle: the three joints above rotate too)
            "winkler_deg": {f"{kn:g}": analytic.toppling_tilt_deg(*params[:3], params[3], kn) for kn in kns},
            "winkler_params": params, "winkler_label": "Winkler, lowest free joint only (upper bound, ASSUMED)"}


# -- (d) Santa-Cruz tilt walls -----------------------------------------------------------
TILT_WALL_SEEDS = (0, 1, 2, 3, 4)


def tilt_wall_case(kn: float = KN0, seed: int = 0) -> dict:
    c = tomllib.loads((paths.CASES / "tilt_wall.toml").read_text())
    c = copy.deepcopy(c)
    c["case"]["name"] = f"crosscheck_tilt_wall_{seed}"
    c["case"]["geometry"] = dict(c["case"]["geometry"], seed=seed)
    c["contact"] = {"kn": kn, "kt": kn / 2}
    c["stages"][1]["rate_deg_s"] = 2.0  # the tilt study's faster protocol (studies/tilt/study.py FAST)
    c["stages"][2]["rate_deg_s"] = 1.0
    return c


def tilt_wall_closed_forms(spec: dict, kns, folder=None) -> dict:
    p = tomllib.loads((paths.DATA / "papers" / "sacsayhuaman.toml").read_text())["tilt"]
    return {"experiment_deg": p["experiment_collapse_deg"], "experiment_sd_deg": p["experiment_collapse_sd_deg"],
            "paper_model_deg": p["model_collapse_deg"]}


@dataclass
class CrossCase:
    """One cross-check case: ``make(kn)`` its case dict; ``quantity`` what is compared
    (``collapse_angle_deg`` or ``slide_m``); LMGC90's step ``dt`` (s) and base formulation."""

    name: str
    title: str
    make: object
    quantity: str
    unit: str
    closed_forms: object
    dt: float
    base: str = "body_force"
    detection: str = "cundall"
    kn_factors: tuple = (1.0, 10.0, 100.0)
    heavy: bool = False
    variants: tuple = field(default_factory=lambda: (None,))


CASES = {
    "toppling": CrossCase("toppling", "one block toppling under tilted gravity", toppling_case, "collapse_angle_deg",
                          "deg", toppling_closed_forms, dt=1e-3),
    "pulse": CrossCase("pulse", "half-sine base pulse, sliding block", pulse_case, "slide_m", "m",
                       pulse_closed_forms, dt=1e-3, base="moving"),
    "wall": CrossCase("wall", "40-block running-bond wall, tilted out of plane", wall_case, "collapse_angle_deg", "deg",
                      wall_closed_forms, dt=2e-3, kn_factors=(1.0, 10.0), heavy=True),
    "tilt_wall": CrossCase("tilt_wall", "Santa-Cruz tilt walls (generated, seeds 0-4)", tilt_wall_case,
                           "collapse_angle_deg", "deg", tilt_wall_closed_forms, dt=1e-3, detection="sto",
                           kn_factors=(1.0,), heavy=True, variants=TILT_WALL_SEEDS),
}
SMALL = ("toppling", "pulse")
