"""Hunt-and-fill for incremental dynamic analysis (pure Python, no runs).

One search is one record scaled to a sequence of intensities (PGA, g). Its state is the
set of intensities run so far and whether the wall collapsed at each (``observed``:
{pga_g: collapsed}); ``step`` says what they give and which intensity to run next, so a
search is replayed from the runs on disk and continues after an interruption (the same
observations give the same next intensity). After Vamvatsikos & Cornell (2002, 2004:
"hunt & fill") as the ooida package does it, in three phases:

1. **hunt up** (no collapse yet): ``start``, then each level ``factor`` times the highest
   run so far, at most ``cap``; a wall standing at ``cap`` ends the search, censored (its
   intensity at collapse is above the cap).
2. **bracket**: hi = the lowest intensity seen to collapse the wall, lo = the highest seen
   standing below it (0 g, gravity alone, is assumed to stand and is not run); the middle
   of (lo, hi) is run until hi - lo <= ``tolerance``: the intensity at collapse is in
   (lo, hi].
3. **fill in** below the collapse: the widest gap between consecutive intensities run
   below hi (from 0 g) wider than ``fill`` x hi gets a run at its middle, until no gap is;
   ``fill`` = 0 (or None) skips this phase. A collapse found there, below a level that
   stood, is a **non-monotonic** response ("resurrection": the wall stands at a higher
   intensity than one that collapses it): hi moves down to the lowest collapse (the lowest
   is kept) and the bracket is refined below it again.

Every intensity standing above hi is listed in ``non_monotonic``. Intensities are rounded
to ``DIGITS`` decimals (stable run names). ``max_runs`` bounds a search (``status``
"budget" when it stops there, with what it has).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field

DIGITS = 4  # intensities are rounded to 1e-4 g
MIN_TOLERANCE = 2 * 10.0 ** -DIGITS


@dataclass(frozen=True)
class Params:
    """The rules of one search (intensities in g)."""

    start: float = 0.1
    factor: float = 2.0
    cap: float = 3.0
    tolerance: float = 0.05
    fill: float | None = 0.25
    max_runs: int = 30

    def check(self) -> "Params":
        if not self.start > 0 or not self.cap > 0:
            raise ValueError(f"start ({self.start!r} g) and cap ({self.cap!r} g) must be positive")
        if not self.factor > 1:
            raise ValueError(f"the hunt's factor must be > 1, got {self.factor!r}")
        if not self.tolerance >= MIN_TOLERANCE:
            raise ValueError(f"tolerance must be >= {MIN_TOLERANCE:g} g, got {self.tolerance!r}")
        if self.fill is not None and self.fill < 0:
            raise ValueError(f"fill must be >= 0, got {self.fill!r}")
        if self.max_runs < 1:
            raise ValueError(f"max_runs must be >= 1, got {self.max_runs!r}")
        return self


@dataclass(frozen=True)
class State:
    """What a search's observations say (intensities in g)."""

    phase: str                      # hunt, bracket, fill, done
    status: str                     # open, bracketed, censored, budget
    next_g: float | None            # the intensity to run next (None when done)
    low_g: float | None             # highest standing below the lowest collapse (0: assumed)
    high_g: float | None            # lowest collapse (None if none seen)
    censored_at_g: float | None     # the cap, when the wall stood there and never collapsed
    runs: int
    non_monotonic: list = field(default_factory=list)  # standing intensities above the lowest collapse

    @property
    def done(self) -> bool:
        return self.next_g is None

    @property
    def bracket(self) -> list | None:
        """[lo, hi] of the intensity at collapse, when bracketed."""
        return None if self.high_g is None or self.status == "open" else [self.low_g, self.high_g]

    def as_dict(self) -> dict:
        return dict(asdict(self), done=self.done, bracket=self.bracket)


def level(x: float) -> float:
    return round(float(x), DIGITS)


def step(observed: dict, p: Params = Params()) -> State:
    """The state and next intensity of a search from ``observed`` ({pga_g: collapsed})."""
    p.check()
    cap = level(p.cap)
    obs = {level(x): bool(c) for x, c in observed.items()}
    n = len(obs)
    coll = sorted(x for x, c in obs.items() if c)
    stand = sorted(x for x, c in obs.items() if not c)
    hi = coll[0] if coll else None
    odd = [x for x in stand if hi is not None and x > hi]
    lo = max([0.0] + [x for x in stand if hi is None or x < hi])

    def state(phase, status, nxt):
        if nxt is not None and n >= p.max_runs:
            phase, status, nxt = "done", "budget", None
        return State(phase, status, nxt, lo, hi, cap if status == "censored" else None, n, odd)

    if hi is None:  # hunt up
        if stand and stand[-1] >= cap:
            return state("done", "censored", None)
        nxt = level(min(cap, p.start if not stand else stand[-1] * p.factor))
        if nxt in obs:  # the start above the cap, or rounding: the cap is next
            nxt = cap
        return state("hunt", "open", nxt)
    if hi - lo > p.tolerance + 1e-12:  # bracket
        mid = level(0.5 * (lo + hi))
        if mid in obs or mid <= lo or mid >= hi:  # below the rounding: done
            return state("done", "bracketed", None)
        return state("bracket", "open", mid)
    if p.fill:  # fill in below the lowest collapse
        levels = [0.0] + [x for x in stand if x < hi] + [hi]
        gaps = [(b - a, a, b) for a, b in zip(levels, levels[1:]) if b - a > p.fill * hi + 1e-12]
        if gaps:
            _, a, b = max(gaps)
            mid = level(0.5 * (a + b))
            if mid not in obs and a < mid < b:
                return state("fill", "bracketed", mid)
    return state("done", "bracketed", None)


def search(collapses, p: Params = Params()) -> tuple[State, list[float]]:
    """Run one search to its end with ``collapses(pga_g) -> bool`` (a model or a fake);
    returns the final state and the intensities run, in order."""
    observed, order = {}, []
    while True:
        s = step(observed, p)
        if s.done:
            return s, order
        observed[s.next_g] = bool(collapses(s.next_g))
        order.append(s.next_g)


def plan(observed: dict, p: Params = Params(), probes: int = 1) -> list[float]:
    """Up to ``probes`` intensities to run at once (one round on several cores), in the
    phase ``step`` is in: hunting, the next ``probes`` levels up (as if the wall stood at
    each); bracketing, the points dividing (lo, hi) into ``probes`` + 1 equal parts; filling,
    the middles of the ``probes`` widest gaps. ``probes`` = 1 is ``step``'s next intensity;
    the search's end (``step`` with every observation) is the same rule whatever ``probes``,
    only the intensities visited differ."""
    s = step(observed, p)
    if s.done:
        return []
    if probes <= 1:
        return [s.next_g]
    obs = {level(x): bool(c) for x, c in observed.items()}
    room = max(0, p.max_runs - len(obs))
    if s.phase == "hunt":
        out, spec = [], dict(obs)
        for _ in range(probes):
            t = step(spec, p)
            if t.done or t.phase != "hunt":
                break
            out.append(t.next_g)
            spec[t.next_g] = False
    elif s.phase == "bracket":
        lo, hi = s.low_g, s.high_g
        out = [level(lo + (hi - lo) * i / (probes + 1)) for i in range(1, probes + 1)]
        out = [x for x in out if lo < x < hi and x not in obs]
    else:  # fill
        hi = s.high_g
        levels = [0.0] + sorted(x for x, c in obs.items() if not c and x < hi) + [hi]
        gaps = sorted(((b - a, a, b) for a, b in zip(levels, levels[1:]) if b - a > p.fill * hi + 1e-12),
                      reverse=True)
        out = [level(0.5 * (a + b)) for _, a, b in gaps[:probes]]
        out = [x for x in out if x not in obs]
    out = sorted(set(out))[:room] or [s.next_g]
    return out
