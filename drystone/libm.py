"""sin and cos of arrays by the C library (Python's ``math``), the same on every x86-64
machine with the same libc (no YADE import).

numpy's own ``np.sin``/``np.cos`` switch to another implementation (SVML) on processors
with AVX-512, whose last bits differ from the C library's. Where a value must not depend
on the processor (generated samples hashed into a run's fingerprint,
``resolve.fingerprint``; the body-force field, which a scalar and an array path must give
bit for bit, ``loading.LoadProgramme``), these are used instead. Equal to numpy's where
numpy uses the C library.
"""
from __future__ import annotations

import math

import numpy as np


def _each(f, x) -> np.ndarray:
    a = np.asarray(x, float)
    return np.fromiter(map(f, a.ravel().tolist()), float, a.size).reshape(a.shape)


def sin(x) -> np.ndarray:
    """sin of each element (radians) by the C library's ``sin``; the shape of ``x``."""
    return _each(math.sin, x)


def cos(x) -> np.ndarray:
    """cos of each element (radians) by the C library's ``cos``; the shape of ``x``."""
    return _each(math.cos, x)
