"""Bisection of the PGA at collapse on a grid of ``resolution`` g (pure Python, no runs).

The searches' one home is drystone/analyses/: ``ida.py`` (hunt-and-fill, what the
``collapse`` analysis runs on any case) and this fixed-grid bisection, which the shape and
site studies ran (drystone/studies/rounds.py) and keep, so that their stored runs replay.

One search is one wall, seed and record. Its state is the set of PGAs run so far and
whether the wall collapsed at each (``observed``: {pga_g: collapsed}); ``bracket`` gives
what they say and which PGA to run next, so a search can be replayed from the runs on
disk and continued after an interruption (the same observations give the same next PGA).

Rules, with PGAs as integer multiples k of ``resolution`` (a PGA off the grid is refused):

* ``low`` (default 0 g) is assumed to leave the wall standing (not run: gravity alone);
  ``cap`` is the highest PGA run.
* hi = the lowest PGA seen to collapse the wall (None if none), lo = the highest PGA below
  it seen standing, or ``low``. A standing wall above hi (non-monotonic: a record can
  topple a wall at one PGA and not at a higher one) is listed in ``non_monotonic`` and does
  not move the bracket (collapse is assumed monotonic in PGA, the bisection's premise).
* done when hi - lo <= one grid step: the PGA at collapse is in (lo, hi]; or when the wall
  stood at ``cap``: censored, above cap.
* otherwise the next PGA is the grid point in the middle, floor((lo + up) / 2) with up = hi,
  or ``cap`` when no collapse has been seen (the cap itself is run last, when lo is one
  step below it).

From ``low`` = 0 to ``cap`` = 2^n steps this runs n PGAs to a bracket one step wide (n + 1
for a wall whose bracket is the last step below the cap, or that stands at the cap); 3.2 g
at 0.1 g: 5 runs (6 for a wall standing at 3.1 g).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field

#: a PGA is on the grid when k x resolution matches it within this x resolution
GRID_TOL = 1e-6


@dataclass(frozen=True)
class Bracket:
    """What a search's observations say (PGAs in g)."""

    low_g: float                 # highest PGA standing (or the assumed ``low``)
    high_g: float | None         # lowest PGA collapsing, None if no collapse seen
    done: bool
    next_g: float | None         # the PGA to run next (None when done)
    censored: bool               # done without a collapse: the wall stood at the cap
    runs: int                    # observations used
    non_monotonic: list = field(default_factory=list)  # PGAs standing above a collapsing one

    @property
    def estimate_g(self) -> float | None:
        """The middle of the final bracket (None while open or censored)."""
        if not self.done or self.censored or self.high_g is None:
            return None
        return 0.5 * (self.low_g + self.high_g)

    def as_dict(self) -> dict:
        return dict(asdict(self), estimate_g=self.estimate_g)


def grid(pga_g: float, resolution_g: float) -> int:
    """The grid index of ``pga_g`` (ValueError if it is not on the grid)."""
    k = round(pga_g / resolution_g)
    if abs(k * resolution_g - pga_g) > GRID_TOL * resolution_g:
        raise ValueError(f"PGA {pga_g!r} g is not on the {resolution_g:g} g grid")
    return int(k)


def value(k: int, resolution_g: float) -> float:
    """The PGA (g) of grid index ``k``, rounded to 6 decimals (so that names are stable)."""
    return round(k * resolution_g, 6)


def bracket(observed: dict, low_g: float = 0.0, cap_g: float = 3.2, resolution_g: float = 0.1) -> Bracket:
    """The bracket and next PGA of a search from ``observed`` ({pga_g: collapsed})."""
    if not resolution_g > 0:
        raise ValueError(f"resolution must be > 0 g, got {resolution_g!r}")
    lo0, cap = grid(low_g, resolution_g), grid(cap_g, resolution_g)
    if cap <= lo0:
        raise ValueError(f"the cap ({cap_g:g} g) must be above the assumed-safe PGA ({low_g:g} g)")
    obs = {}
    for p, c in observed.items():
        k = grid(float(p), resolution_g)
        if not lo0 < k <= cap:
            raise ValueError(f"observed PGA {p!r} g is outside ({low_g:g}, {cap_g:g}] g")
        obs[k] = bool(c)
    collapsed = [k for k, c in obs.items() if c]
    hi = min(collapsed) if collapsed else None
    standing = [k for k, c in obs.items() if not c]
    lo = max([lo0] + [k for k in standing if hi is None or k < hi])
    odd = sorted(value(k, resolution_g) for k in standing if hi is not None and k > hi)
    v = lambda k: None if k is None else value(k, resolution_g)  # noqa: E731
    if hi is not None and hi - lo <= 1:
        return Bracket(v(lo), v(hi), True, None, False, len(obs), odd)
    if hi is None and lo >= cap:
        return Bracket(v(lo), None, True, None, True, len(obs), odd)
    up = hi if hi is not None else cap
    nxt = cap if up - lo <= 1 else (lo + up) // 2
    return Bracket(v(lo), v(hi), False, v(nxt), False, len(obs), odd)


def search(collapses, low_g: float = 0.0, cap_g: float = 3.2, resolution_g: float = 0.1,
           max_runs: int = 100) -> tuple[Bracket, list[float]]:
    """Run one search to the end with ``collapses(pga_g) -> bool`` (a model or a fake);
    returns the final bracket and the PGAs run, in order."""
    observed, order = {}, []
    for _ in range(max_runs):
        b = bracket(observed, low_g, cap_g, resolution_g)
        if b.done:
            return b, order
        observed[b.next_g] = bool(collapses(b.next_g))
        order.append(b.next_g)
    raise RuntimeError(f"no bracket after {max_runs} runs")
