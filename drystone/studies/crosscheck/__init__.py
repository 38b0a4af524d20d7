"""Peer-engine cross-check with LMGC90 (issue 15, item 2): an optional, YADE-free study.

LMGC90 (non-smooth contact dynamics, Moreau-Jean time stepping, the reference code for
masonry) runs the same block file and load programme as this package, with **rigid**
contacts (Signorini condition and Coulomb friction, restitution 0): the limit the penalty
law of this package must approach as K_n grows. LMGC90 comes from PyPI as
``compas_lmgc90`` (a manylinux wheel with the Fortran library inside), pinned in
``requirements-crosscheck.txt``; where it is not importable every entry point says so
and ``make crosscheck`` prints a "skipped" line and exits 0.

Modules:

* ``translate``: block file (``drystone.geometry.blockfile``) -> LMGC90 model (rigid
  convex polyhedra, triangulated outward; platform and fixed blocks with all six
  velocities imposed; one Coulomb law); needs neither YADE nor LMGC90.
* ``engine``: runs one model in LMGC90, **in its own process** (LMGC90 holds one
  simulation per process and a Fortran STOP ends the process): gravity (tilted, ramped)
  is written into LMGC90's module variables ``grav1..3`` before every step; a base motion
  is the platform's imposed velocity history; contact detection is re-run every step.
* ``lmgc90``: the parent side: prepares a case exactly as the package does
  (``drystone.model.resolve``: same geometry, materials, stages), starts the engine in a
  subprocess, reads its histories back and dates collapses with the package's own rule
  (``drystone.mechanics.collapse``).
* ``closed_forms``: the rigid-body references (toppling angle atan(b/h) and the rigid
  rocking equation with the same tilt programme; the rigid-plastic half-sine slide).
* ``cases``: the four cross-check cases and the package-side runs at K_n = 2e8 and higher.
* ``report``: ``results/crosscheck/``: crosscheck.json, report.md, figures.

``python -m drystone.studies.crosscheck {small,all,report}``.
"""
from __future__ import annotations

import importlib.util
import subprocess
import sys

#: the PyPI package that brings LMGC90 and the version this study was written against: the
#: engine uses exported module variables and routines of its Fortran library
#: (``__bulk_behaviour_MOD_grav1..3``, ``__prprx_MOD_sto_set_explicit_detection_prprx``)
#: that another version may rename or drop, so another version counts as unavailable
PACKAGE = "compas_lmgc90"
VERSION = "0.1.11"
#: COMPAS (compas_lmgc90's Python-side dependency; the engine itself does not import it)
COMPAS_VERSION = "2.15.1"
REQUIREMENTS = "requirements-crosscheck.txt"
INSTALL_HINT = (f"install it with: .venv/bin/python -m pip install -c constraints.txt --no-deps -r {REQUIREMENTS} "
                f"(pins {PACKAGE}=={VERSION} and compas=={COMPAS_VERSION}; a manylinux x86-64 wheel for CPython 3.11)")


def installed_version() -> str | None:
    """The installed version of compas_lmgc90, or None."""
    try:
        from importlib.metadata import PackageNotFoundError, version
    except ImportError:  # pragma: no cover - Python < 3.8
        return None
    try:
        return version(PACKAGE)
    except PackageNotFoundError:
        return None


def lmgc90_status() -> tuple[bool, str]:
    """(available, message): whether compas_lmgc90 == VERSION is installed and its compiled
    LMGC90 library loads. The library is loaded in a child process (a broken wheel, e.g. a
    missing system library, must not take this process down)."""
    try:
        found = importlib.util.find_spec(PACKAGE) is not None
    except (ImportError, ValueError):  # a broken or blocked package (sys.modules entry None)
        found = False
    if not found:
        return False, f"{PACKAGE} {VERSION} (LMGC90) is not installed; {INSTALL_HINT}"
    have = installed_version()
    if have != VERSION:
        return False, (f"{PACKAGE} {have} is installed but this cross-check is pinned to {VERSION} (it uses internal "
                       f"symbols of LMGC90's library); {INSTALL_HINT}")
    code = ("import ctypes; from compas_lmgc90 import _lmgc90 as L; lib = ctypes.CDLL(L.__file__); "
            "[ctypes.c_double.in_dll(lib, f'__bulk_behaviour_MOD_grav{i}') for i in (1, 2, 3)]; "
            "lib.__prprx_MOD_sto_set_explicit_detection_prprx; print('ok')")
    try:
        r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    except (OSError, subprocess.TimeoutExpired) as exc:
        return False, f"{PACKAGE} {VERSION} could not be loaded: {exc}"
    if r.returncode != 0 or "ok" not in r.stdout:
        tail = (r.stderr or r.stdout).strip().splitlines()[-1:] or ["(no message)"]
        return False, f"{PACKAGE} {VERSION} is installed but its LMGC90 library does not load: {tail[0]}"
    return True, f"{PACKAGE} {VERSION} (LMGC90) available"
