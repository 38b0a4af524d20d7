"""The histories of a run (histories.npz): what the driver records at every sample, from
the state arrays and the engine's contacts (no YADE import of its own). SI units; the
energies at the half step t - dt/2, where leapfrog velocities live. The energy balance's
cumulative terms (J from the run's start; drystone/mechanics/energy.py): ``work_loads``,
``dissipated_damping``, ``dissipated_friction``, accumulated by the engine at every step
up to the same half step; NaN for an engine that cannot account (the stock YADE law).
``removed_kinetic``: the kinetic energy (J, cumulative) carried out of the model by the free
blocks taken out of the scene when they left it (the driver's ``retire``): from then on they
stay where they left (their samples repeat that position), with no kinetic nor potential
energy. A run with [[loads]] also records the loads' total force ``load_force`` (N) and their
total moment about the platform frame's origin ``load_moment`` (N m, each stone's force at
its initial centroid plus its moment), as applied at the sample's step.
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from drystone.mechanics import energy
from drystone.mechanics.monitors import Sample

#: histories.npz's format name and version (arrays ``format`` and ``version``)
HISTORIES_FORMAT, HISTORIES_VERSION = "drystone-histories", 1
CONTACT_KEYS = ("fn", "ft", "normal", "point", "slipping", "area", "volume")


class Recorder:
    """Histories of the run ``run`` (the driver): time, load, state of the free blocks,
    control points, reaction, energies and the named contacts of the spec's output."""

    def __init__(self, run):
        self.run = run
        y = run.yid
        self.cp = [(c["name"], y[c["block"]], np.asarray(c["position"], float)) for c in run.spec.control_points]
        # control point offsets in each body's local frame
        self.cp_local = [run.rot[b].T @ (p - run.pos0[b]) for _, b, p in self.cp]
        self.named = [(c["name"], y[c["blocks"][0]], y[c["blocks"][1]]) for c in run.spec.output["contacts"]]
        self.h = {k: [] for k in ("t", "tilt_deg", "g_eff", "base_acc", "pos", "quat", "vel", "angvel",
                                  "cp", "reaction", "n_contacts", "kinetic", "potential", "elastic",
                                  *energy.TERMS, "removed_kinetic")}
        if run.loads is not None:
            self.h.update(load_force=[], load_moment=[])
            self.centroid0 = run.pos0.copy()  # where the loads' forces act (fixed, drystone/model/loads.py)
        self.hc = {name: {k: [] for k in CONTACT_KEYS} for name, _, _ in self.named}
        self.max_contacts = 0

    def sample(self, t: float, g=None) -> Sample:
        """Record the state at time ``t`` (s); returns what the monitors need. ``g``: the body
        acceleration at t (m/s^2, ``prog.body_acceleration(t)``) where the caller has it."""
        run, h = self.run, self.h
        st = run.engine.contacts()
        h["t"].append(t)
        h["tilt_deg"].append(run.prog.tilt_deg(t))
        g = run.prog.body_acceleration(t) if g is None else np.array(g, float)  # (its own: the history keeps it)
        h["g_eff"].append(g)
        h["base_acc"].append(run.prog.base_acceleration(t))
        d = run.dyn
        h["pos"].append(run.pos[d].copy())
        h["quat"].append(run.quat[d].copy())
        h["vel"].append(run.vel[d].copy())
        h["angvel"].append(run.angvel[d].copy())
        h["cp"].append([run.pos[y] + run.rot[y] @ loc for (_, y, _), loc in zip(self.cp, self.cp_local)])
        fb = st.force_on_b() if len(st.fn) else np.zeros((0, 3))
        R = np.zeros(3)  # force of the moving blocks on the non-moving ones, N
        if len(st.fn):
            static_a = ~np.isfinite(run.mass[st.id1])
            static_b = ~np.isfinite(run.mass[st.id2])
            R -= fb[static_a].sum(axis=0)
            R += fb[static_b].sum(axis=0)
        h["reaction"].append(R)
        h["n_contacts"].append(len(st.fn))
        self.max_contacts = max(self.max_contacts, len(st.fn))
        m = run.mass[d]
        ke_b = 0.5 * m * np.sum(run.vel[d] ** 2, axis=1)  # per free block
        w_loc = np.einsum("bji,bj->bi", run.rot[d], run.angvel[d])  # R^T w per block
        ke_b += 0.5 * np.sum(run.inertia[d] * w_loc ** 2, axis=1)
        ke = float(ke_b.sum())
        h["kinetic"].append(ke)
        x_half = run.pos[d] - 0.5 * run.O.dt * run.vel[d]
        live = ~run.removed[d]  # blocks taken out of the scene hold no potential energy of the model
        h["potential"].append(-float(np.sum((m * (x_half @ g))[live])))
        h["elastic"].append(run.engine.elastic_energy())
        terms = run.engine.energy_terms()
        for k, v in zip(energy.TERMS, terms if terms is not None else (np.nan,) * len(energy.TERMS)):
            h[k].append(v)
        h["removed_kinetic"].append(run.removed_kinetic)
        if run.loads is not None:
            F, T = run.loads.wrench()
            h["load_force"].append(F.sum(axis=0))
            h["load_moment"].append((np.cross(self.centroid0, F) + T).sum(axis=0))
        self._contacts(st, fb)
        return Sample(t, g, ke, ke_b, h["elastic"][-1], st, R)

    def _contacts(self, st, fb) -> None:
        for name, ya, yb in self.named:
            hc = self.hc[name]
            row = np.flatnonzero(((st.id1 == ya) & (st.id2 == yb)) | ((st.id1 == yb) & (st.id2 == ya))) if len(st.fn) else []
            if len(row) == 0:
                for k, v in (("fn", 0.0), ("ft", np.zeros(3)), ("normal", np.full(3, np.nan)),
                             ("point", np.full(3, np.nan)),
                             ("slipping", False), ("area", 0.0), ("volume", 0.0)):
                    hc[k].append(v)
                continue
            sign = np.where(st.id1[row] == ya, 1.0, -1.0)[:, None]  # orient normal and force from a to b
            if len(row) == 1:
                r = int(row[0])
                n, f, point = sign[0] * st.normal[r], sign[0] * fb[r], st.point[r].copy()
            else:  # stones of several parts: the joint is the sum of its contacts (one per pair of parts)
                f = (sign * fb[row]).sum(axis=0)
                n = (sign * st.normal[row] * st.area[row][:, None]).sum(axis=0)  # area-weighted normal
                n = n / np.linalg.norm(n)
                w = st.fn[row] if st.fn[row].sum() > 0 else np.ones(len(row))
                point = (st.point[row] * w[:, None]).sum(axis=0) / w.sum()  # the normal forces' centre
            fn = float(f @ n)
            hc["fn"].append(fn)
            hc["ft"].append(f - fn * n)
            hc["normal"].append(n)
            hc["point"].append(point)
            hc["slipping"].append(bool(st.slipping[row].any()))
            hc["area"].append(float(st.area[row].sum()))
            hc["volume"].append(float(st.volume[row].sum()))

    def save(self, folder: Path) -> None:
        """Write histories.npz into ``folder`` (under a temporary name, renamed when complete)."""
        run = self.run
        arrays = {k: np.asarray(v) for k, v in self.h.items()}
        arrays["format"], arrays["version"] = np.array(HISTORIES_FORMAT), np.array(HISTORIES_VERSION)
        arrays["block_ids"] = np.array([run.bid[int(i)] for i in run.dyn])
        arrays["mass"] = run.mass[run.dyn]
        arrays["pos0"] = run.pos0[run.dyn]
        arrays["quat0"] = run.quat0[run.dyn]
        arrays["cp_names"] = np.array([c[0] for c in self.cp], dtype="U32")
        arrays["cp0"] = np.array([c[2] for c in self.cp]).reshape(-1, 3)
        for name, hc in self.hc.items():
            for k, v in hc.items():
                arrays[f"contact:{name}:{k}"] = np.asarray(v)
        tmp = Path(folder) / "histories.tmp.npz"
        np.savez_compressed(tmp, **arrays)
        os.replace(tmp, Path(folder) / "histories.npz")
