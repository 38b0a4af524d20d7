"""Run one LMGC90 model: ``python -m drystone.studies.crosscheck.engine JOB.json`` (one per process).

LMGC90 keeps one simulation per process and a Fortran STOP ends the process, so the
parent (``drystone.studies.crosscheck.lmgc90``) starts this module in a subprocess for every run
and reads back what it wrote into the job's folder: ``lmgc90_histories.npz`` and
``lmgc90_result.json`` (written last: its presence marks a complete run).

The job (JSON): ``model`` (``drystone.studies.crosscheck.translate.to_lmgc90``), ``spec`` (path
of the run's spec.json, whose stages give the load programme, ``drystone.model.loading``),
``folder`` (the run folder: excitation samples), ``dt`` (s), ``theta`` (the theta
method's parameter, 0.5 to 1), ``base`` (``"body_force"``: a base acceleration is the
inertial body force -a_b on every block, as this package applies it; ``"moving"``: the
platform and fixed blocks are given the base velocity history, the blocks ride on a
moving base), ``interval`` (s between recorded samples), ``max_wall_s`` (optional).

What is done to LMGC90 (compas_lmgc90 0.1.11, the raw binding ``_lmgc90``):

* gravity is fixed to (0, 0, -9.81) by its API, but the solver reads the module variables
  ``__bulk_behaviour_MOD_grav1..3`` when it computes the external forces of every step:
  they are set before each step to the programme's body acceleration at the middle of the
  step (ramped and tilted gravity, minus the base acceleration with ``base = body_force``);
* contact detection: compas_lmgc90 selects LMGC90's "STO" face-to-face detection in its
  *explicit* mode, which detects the contact polygons once and keeps them in the
  antagonist's frame (a masonry assumption: no large sliding); a block sliding by more than
  a fraction of its size then loses its support. ``__prprx_MOD_sto_set_explicit_detection_prprx``
  (false) re-runs the detection every step;
* imposed velocities (platform, fixed blocks) must be declared before the bodies are
  closed: a base motion is given as the velocity history sampled at every step.
"""
from __future__ import annotations

import ctypes
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

from drystone.model.loading import LoadProgramme

HISTORIES = "lmgc90_histories.npz"
RESULT = "lmgc90_result.json"


def base_velocity(prog: LoadProgramme, times: np.ndarray) -> np.ndarray:
    """Base velocity (m/s, (n, 3)) at ``times`` from rest: the trapezoidal integral of the
    programme's base acceleration on the ``times`` grid (its samples are linearly
    interpolated: the trapezoid rule is exact between samples that fall on the grid)."""
    acc = prog.base_acceleration_at(np.asarray(times, float))
    v = np.zeros_like(acc)
    v[1:] = np.cumsum(0.5 * (acc[1:] + acc[:-1]) * np.diff(times)[:, None], axis=0)
    return v


#: contact detection (``set_detection``)
DETECTION = "cundall"
DETECTIONS = ("sto", "sto_nc", "cundall")


def _fn(lib, name, argtypes):
    f = getattr(lib, name)  # getattr: a literal lib.__name inside a class would be name-mangled
    f.argtypes = argtypes
    f.restype = None
    return f


def set_detection(lib, method: str) -> None:
    """Choose LMGC90's polyhedron contact detection (after ``initialize``).

    * ``sto``: compas_lmgc90's choice, LMGC90's "STO" detection (face-to-face polygons
      between parallel faces, node-to-face otherwise), with the explicit mode switched
      off (``__prprx_MOD_sto_set_explicit_detection_prprx(false)``): detected every step;
    * ``sto_nc``: the same, node-to-face for every pair (``sto_force_nc_detection``);
    * ``cundall``: the common-plane detection (Cundall's iterations, clipper polygon
      intersection): the wrapper's private method switch is set to 2 as its own
      ``initialize`` would for 'CpCundall', with the same parameters (200 iterations, no
      shrink); the switch is found at a fixed offset from an exported symbol of the pinned
      0.1.11 library.
    """
    ref_i, ref_d = ctypes.POINTER(ctypes.c_int), ctypes.POINTER(ctypes.c_double)
    if method not in DETECTIONS:
        raise ValueError(f"detection must be one of {DETECTIONS}, got {method!r}")
    _fn(lib, "__prprx_MOD_sto_set_explicit_detection_prprx", [ref_i])(ctypes.byref(ctypes.c_int(0)))
    if method == "sto_nc":
        _fn(lib, "__prprx_MOD_sto_force_nc_detection_prprx", [])()
    elif method == "cundall":
        anchor = ctypes.addressof(ctypes.c_char.in_dll(
            lib, "__wrap_lmgc90_compas_MOD___vtab_wrap_lmgc90_compas_Lmgc90_rigid_body_3d"))
        switch = ctypes.c_int.from_address(anchor - 0x24)
        if switch.value != 7:  # STO, set by initialize(): anything else means another binary layout
            raise RuntimeError(f"unexpected LMGC90 detection switch value {switch.value} (expected 7): not the "
                               "compas_lmgc90 0.1.11 library layout")
        switch.value = 2
        _fn(lib, "__prprx_MOD_set_cundall_iteration_prprx", [ref_i])(ctypes.byref(ctypes.c_int(200)))
        z = [ctypes.byref(ctypes.c_double(0.0)) for _ in range(3)]
        _fn(lib, "__prprx_MOD_set_clipper_parameters", [ref_d, ref_d, ref_d])(*z)
        _fn(lib, "__prprx_MOD_with_nodal_contact_prprx", [])()


class Engine:
    def __init__(self, job: dict):
        from compas_lmgc90 import _lmgc90  # noqa: PLC0415 - only in the subprocess

        self.job = job
        self.model = job["model"]
        spec = json.loads(Path(job["spec"]).read_text())
        self.spec = spec
        self.prog = LoadProgramme.from_spec(spec, job["folder"])
        self.dt = float(job["dt"])
        self.theta = float(job.get("theta", 0.5))
        self.base = job.get("base", "body_force")
        if self.base not in ("body_force", "moving"):
            raise ValueError(f"base must be 'body_force' or 'moving', got {self.base!r}")
        if self.prog.moving_blocks():
            raise ValueError("settlement stages (imposed velocities of fixed blocks) are not translated to LMGC90")
        if self.base == "moving" and any(np.any(self.prog.velocity_jump(k)) for k in range(len(self.prog.stages))):
            raise ValueError("a base velocity jump (sine started as a displacement) needs base = 'body_force'")
        self.lib = ctypes.CDLL(_lmgc90.__file__)
        self.grav = [ctypes.c_double.in_dll(self.lib, f"__bulk_behaviour_MOD_grav{i}") for i in (1, 2, 3)]
        self.L = _lmgc90.LMGC90Solver()
        self.L.initialize(self.dt, self.theta, False)
        self.detection = job.get("detection", DETECTION)
        set_detection(self.lib, self.detection)  # after initialize(), which sets compas_lmgc90's own choice
        self.n_steps = int(math.ceil(self.prog.end / self.dt - 1e-9))
        self._build()

    # -- model -------------------------------------------------------------------------
    def _build(self):
        m, L = self.model, self.L
        bodies = m["bodies"]
        dens = sorted({b["density"] for b in bodies})
        names = {d: f"s{i + 1:04d}" for i, d in enumerate(dens)}
        L.set_materials([float(d) for d in dens])
        L.add_one_tact_behav("iqsc0", m["law"], [float(m["mu"])])
        L.set_see_tables(float(m["alert_m"]))
        L.set_nb_bodies(len(bodies))
        times = np.arange(self.n_steps + 2) * self.dt
        vb = base_velocity(self.prog, times) if self.base == "moving" else None
        self.base_v = vb
        for k, b in enumerate(bodies):
            faces = [int(i) + 1 for t in b["triangles"] for i in t]
            verts = [float(x) for p in b["vertices"] for x in p]
            L.set_one_polyr(names[b["density"]], [float(x) for x in b["centroid"]], faces, verts,
                            6 if b["imposed"] else 0, 0)
            if b["imposed"]:
                for dof in range(1, 7):
                    if vb is not None and dof <= 3 and np.any(vb[:, dof - 1]):
                        L.set_drvdof(k + 1, dof, list(np.concatenate([times, vb[:, dof - 1]])), True, True)
                    else:
                        L.set_drvdof(k + 1, dof, [0.0] * 6, True, False)
        L.close_before_computing()
        init = L.get_initial_state()
        self.coor0 = np.array(init.bodies, float)
        self.frame0 = np.array(init.body_frames, float).reshape(-1, 3, 3)
        self.free = [k for k, b in enumerate(bodies) if not b["imposed"]]
        self.platform = next((k for k, b in enumerate(bodies) if b["role"] == "platform"), None)
        self.ids = [bodies[k]["id"] for k in self.free]
        self.weight = sum(bodies[k]["mass"] for k in self.free) * float(self.spec["gravity"])
        self.thr = np.array([self.spec["collapse_threshold"][str(i)] for i in self.ids])

    # -- run ---------------------------------------------------------------------------
    def gravity_at(self, t: float) -> np.ndarray:
        g = self.prog.body_acceleration(t)
        if self.base == "moving":
            g = g + self.prog.base_acceleration(t)  # the base's motion is imposed, not a body force
        return g

    def run(self) -> dict:
        job, L = self.job, self.L
        interval = float(job.get("interval", 0.01))
        every = max(1, int(round(interval / self.dt)))
        max_wall = job.get("max_wall_s")
        h = {k: [] for k in ("t", "tilt_deg", "g_eff", "base_disp", "pos", "frame", "reaction_N", "contacts")}
        collapse, stop_at, stopped = None, None, "end of the programme"
        wall0 = time.time()
        last_print = wall0
        self._record(h, 0.0, L.get_initial_state(), None)
        k = 0
        for k in range(1, self.n_steps + 1):
            g = self.gravity_at((k - 1 + self.theta) * self.dt)
            for i in range(3):
                self.grav[i].value = float(g[i])
            r = L.compute_one_step()
            t = k * self.dt
            if k % every == 0 or k == self.n_steps:
                self._record(h, t, r, r)
                collapse = collapse or self._collapse(h, t)
                if collapse and stop_at is None:
                    stop_at = t + collapse["after_collapse_s"]
                now = time.time()
                if now - last_print > 10:
                    last_print = now
                    disp = np.linalg.norm(h["pos"][-1] - h["pos"][0], axis=1).max() if self.free else 0.0
                    print(f"[lmgc90] t = {t:.3f}/{self.prog.end:.3f} s  tilt {h['tilt_deg'][-1]:.3f} deg  "
                          f"max displacement {disp * 1e3:.2f} mm  {len(r.interaction_coords)} contacts  "
                          f"{1e3 * (now - wall0) / k:.3f} ms/step", flush=True)
                if stop_at is not None and t >= stop_at - 1e-12:
                    stopped = "after_collapse elapsed"
                    break
                if max_wall is not None and now - wall0 > max_wall:
                    stopped = f"wall-clock limit {max_wall} s"
                    break
        wall = time.time() - wall0
        arrays = {key: np.array(v) for key, v in h.items()}
        arrays["block_ids"] = np.array(self.ids)
        np.savez_compressed(Path(job["out"]) / HISTORIES, **arrays)
        result = {"steps": k, "dt": self.dt, "theta": self.theta, "base": self.base, "detection": self.detection,
                  "wall_s": wall,
                  "ms_per_step": 1e3 * wall / max(k, 1), "simulated_time_s": k * self.dt, "stopped": stopped,
                  "collapse": collapse, "n_bodies": len(self.model["bodies"]), "n_free": len(self.free),
                  "weight_free_N": self.weight, "initial_centres": self.coor0.tolist()}
        (Path(job["out"]) / RESULT).write_text(json.dumps(result, indent=1))
        return result

    def _record(self, h, t, state, inters):
        coor = np.array(state.bodies, float)
        frames = np.array(state.body_frames, float).reshape(-1, 3, 3)
        disp_base = coor[self.platform] - self.coor0[self.platform] if self.platform is not None else np.zeros(3)
        h["t"].append(t)
        h["tilt_deg"].append(self.prog.tilt_deg(t))
        h["g_eff"].append(self.gravity_at(t))
        h["base_disp"].append(disp_base)
        h["pos"].append(coor[self.free] - disp_base)  # platform frame (the platform translates only)
        h["frame"].append(frames[self.free])
        h["reaction_N"].append(self._vertical_reaction(t, inters))
        h["contacts"].append(0 if inters is None else len(inters.interaction_coords))

    def _vertical_reaction(self, t, r) -> float:
        """Force (N) of the platform and fixed blocks on the free blocks along the true
        vertical (up). LMGC90's ``interaction_force_global`` is the force on the candidate
        body (``interaction_bodies`` = [candidate, antagonist], 1-based)."""
        if r is None:
            return float("nan")
        bodies = self.model["bodies"]
        total = np.zeros(3)
        pairs = r.interaction_bodies
        forces = r.interaction_force_global
        for (cd, an), f in zip(pairs, forces):
            fcd, fan = not bodies[cd - 1]["imposed"], not bodies[an - 1]["imposed"]
            if fcd and not fan:
                total += f
            elif fan and not fcd:
                total -= f
        return float(total @ self.prog.true_vertical(t))

    def _collapse(self, h, t) -> dict | None:
        """The package's detection (drystone/yade_scripts/run_case.py): in a tilt stage with
        ``until_collapse``, the vertical reaction of the free blocks drops by the stage's
        ``reaction_drop`` of their weight, or a block moves more than its collapse threshold."""
        st = self.prog.stages[self.prog.stage_index(t)]
        if st.type != "tilt" or not st.params.get("until_collapse") or not self.free:
            return None
        disp = np.linalg.norm(h["pos"][-1] - h["pos"][0], axis=1)
        moved = disp > self.thr
        drop = h["reaction_N"][-1] < (1.0 - st.params["reaction_drop"]) * self.weight
        if not (moved.any() or drop):
            return None
        order = np.argsort(-(disp / self.thr))
        return {"detected_time_s": t, "detected_angle_deg": self.prog.tilt_deg(t),
                "criterion": "reaction_drop" if drop else "displacement",
                "vertical_reaction_N": h["reaction_N"][-1],
                "first_blocks": [int(self.ids[j]) for j in order[:5] if disp[j] > 0.5 * self.thr[j]],
                "after_collapse_s": float(st.params.get("after_collapse", 1.0))}


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 1:
        print("usage: python -m drystone.studies.crosscheck.engine JOB.json", file=sys.stderr)
        return 2
    job = json.loads(Path(argv[0]).read_text())
    res = Engine(job).run()
    print(f"[lmgc90] done: {res['steps']} steps of {res['dt']:g} s in {res['wall_s']:.1f} s "
          f"({res['ms_per_step']:.3f} ms/step), {res['stopped']}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
