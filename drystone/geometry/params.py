"""Checks of generator parameters. Each returns the value unchanged or raises GeometryError
naming the generator, the parameter, what is allowed and the value given."""
from __future__ import annotations

from .blockfile import DENSITY_RANGE, GeometryError, is_int, is_number


def fail(gen: str, name: str, allowed: str, value) -> GeometryError:
    """The error for parameter ``name`` of generator ``gen`` (raise it)."""
    return GeometryError(f"geometry generator {gen!r}: parameter '{name}' must be {allowed}, got {value!r}")


def _range(lo, hi, lo_open, hi_open, unit) -> str:
    u = f" {unit}" if unit else ""
    if lo is not None and hi is not None:
        return f"in {'(' if lo_open else '['}{lo:g}, {hi:g}{')' if hi_open else ']'}{u}"
    if lo is not None:
        return f"{'>' if lo_open else '>='} {lo:g}{u}"
    if hi is not None:
        return f"{'<' if hi_open else '<='} {hi:g}{u}"
    return f"finite{u}"


def number(gen: str, name: str, value, lo=None, hi=None, lo_open=False, hi_open=False, unit=""):
    """A finite number within [lo, hi] (bounds open where asked; None: no bound)."""
    ok = is_number(value) and (lo is None or (value > lo if lo_open else value >= lo)) \
        and (hi is None or (value < hi if hi_open else value <= hi))
    if not ok:
        raise fail(gen, name, "a number " + _range(lo, hi, lo_open, hi_open, unit), value)
    return value


def positive(gen: str, name: str, value, unit=""):
    """A finite number > 0."""
    return number(gen, name, value, lo=0, lo_open=True, unit=unit)


def integer(gen: str, name: str, value, lo=None, hi=None):
    """An integer (not a float such as 2.0, not a bool) within [lo, hi]."""
    if not is_int(value) or (lo is not None and value < lo) or (hi is not None and value > hi):
        raise fail(gen, name, "an integer " + _range(lo, hi, False, False, ""), value)
    return value


def choice(gen: str, name: str, value, allowed):
    """One of ``allowed`` (compared with ==, so None may be one)."""
    if not any(value == a and type(value) is type(a) for a in allowed):
        raise fail(gen, name, f"one of {list(allowed)}", value)
    return value


def numbers(gen: str, name: str, value, n: int, lo=None, lo_open=False, unit=""):
    """A list of ``n`` finite numbers, each >= lo (> lo if lo_open)."""
    if not isinstance(value, (list, tuple)) or len(value) != n or not all(
            is_number(x) and (lo is None or (x > lo if lo_open else x >= lo)) for x in value):
        each = "" if lo is None else ", each " + _range(lo, None, lo_open, False, "")
        raise fail(gen, name, f"a list of {n} finite numbers{each}{' (' + unit + ')' if unit else ''}", value)
    return value


def material(gen: str, density, kn, kt, damping, mu=None, friction_angle_deg=None) -> None:
    """The material parameters every generator takes: density (kg/m^3, DENSITY_RANGE), kn
    and kt (N/m^3, > 0), damping (fraction of critical, >= 0), mu (>= 0) or
    friction_angle_deg (in [0, 90))."""
    number(gen, "density", density, *DENSITY_RANGE, unit="kg/m^3")
    positive(gen, "kn", kn, "N/m^3")
    positive(gen, "kt", kt, "N/m^3")
    number(gen, "damping", damping, lo=0)
    if friction_angle_deg is not None:
        number(gen, "friction_angle_deg", friction_angle_deg, 0, 90, hi_open=True, unit="deg")
    else:
        number(gen, "mu", mu, lo=0)
