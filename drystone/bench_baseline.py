"""``python -m drystone bench --baseline COMMIT``: this tree's step against an earlier commit's,
measured back to back on one machine (a speed-up over a commit stated with both figures from
one run on one machine).

Each of ``--rounds`` rounds (2 by default) runs the bench's scale section (``bench --only scale``,
the walls and sizes asked) twice, each in a fresh process: first in a git worktree of COMMIT, then
in this tree. The worktree is made in a temporary folder and removed at the end; it keeps its own
numba cache, compiled in its first round before anything is timed (the scale section primes it).
Timings on a shared machine move 20-30 % run to run, so the rounds alternate and every round's
figure is kept. Per wall and size: both trees' ms per step (the scale section's steady rate, ms) and
us per contact-step in each round, and the speed-up of the fastest (the bench's convention, "fastest
of repeats") and of the medians. Each tree's own results/bench/bench.json gets its scale rows as a
``bench --only scale`` would write them; this tree's also gets the ``baseline`` section.
"""
from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path

from drystone import paths


class BaselineError(ValueError):
    """A baseline that cannot be measured (not a commit, not a git checkout, a failed run): one line."""


def _git(*args, cwd: Path | None = None) -> subprocess.CompletedProcess:
    return subprocess.run(["git", "-C", str(cwd or paths.ROOT), *args], capture_output=True, text=True)


def resolve(commit: str) -> str:
    """The full hash of ``commit`` in this checkout; BaselineError where it names none (before any run)."""
    try:
        r = _git("rev-parse", "--verify", "--quiet", f"{commit}^{{commit}}")
    except FileNotFoundError:
        raise BaselineError("bench --baseline: git is not installed") from None
    if r.returncode != 0 or not r.stdout.strip():
        raise BaselineError(f"bench --baseline: {commit!r} is not a commit of the checkout at {paths.ROOT}")
    return r.stdout.strip()


@contextmanager
def worktree(sha: str):
    """A git worktree of commit ``sha`` (detached) in a temporary folder, removed on exit."""
    with tempfile.TemporaryDirectory(prefix="drystone-baseline-") as tmp:
        tree = Path(tmp) / sha[:12]
        r = _git("worktree", "add", "--detach", "--quiet", str(tree), sha)
        if r.returncode != 0:
            raise BaselineError(f"bench --baseline: git worktree add {sha[:12]} failed: "
                                f"{(r.stderr.strip().splitlines() or ['no message'])[-1]}")
        try:
            yield tree
        finally:  # its own entry only (no ``git worktree prune``: other worktrees are not the bench's)
            _git("worktree", "remove", "--force", str(tree))


def scale_rows(tree: Path, sizes, walls) -> list[dict]:
    """Run ``python -m drystone bench --only scale`` of the tree at ``tree`` in a fresh process
    (its own package first on the path) and return its scale rows for ``walls`` x ``sizes``, as
    its bench.json holds them."""
    cmd = [sys.executable, "-m", "drystone", "bench", "--only", "scale", "--sizes", *map(str, sizes),
           "--walls", *walls]
    env = dict(os.environ, PYTHONPATH=str(tree) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    r = subprocess.run(cmd, cwd=tree, env=env, capture_output=True, text=True)
    if r.returncode != 0:
        last = (r.stderr.strip().splitlines() or r.stdout.strip().splitlines() or ["no message"])[-1]
        raise BaselineError(f"bench --baseline: the scale section failed in {tree}: {last}")
    rows = json.loads((tree / "results" / "bench" / "bench.json").read_text())["scale"]["rows"]
    return [r for r in rows if r["wall"] in walls and r["size"] in sizes]


def _key(row: dict) -> tuple:
    return row["wall"], row["size"]


def compare(theirs: list[list[dict]], ours: list[list[dict]]) -> list[dict]:
    """Per wall and size of this tree's rows: both trees' ms/step and us per contact-step in each
    round (``theirs``, ``ours``: one list of scale rows per round), the speed-up of the fastest
    (theirs' fastest over ours') and of the medians. A wall the baseline did not measure (a kind it
    does not have) keeps None there."""
    out = []
    for row in ours[0]:
        k = _key(row)
        ms = [next(r["ms_per_step"] for r in rnd if _key(r) == k) for rnd in ours]
        us = [next(r["us_per_contact_step"] for r in rnd if _key(r) == k) for rnd in ours]
        base = [next((r for r in rnd if _key(r) == k), None) for rnd in theirs]
        have = all(b is not None for b in base)
        b_ms = [b["ms_per_step"] for b in base] if have else None
        out.append(dict(wall=k[0], size=k[1], ms_per_step=ms, us_per_contact_step=us, baseline_ms_per_step=b_ms,
                        baseline_us_per_contact_step=[b["us_per_contact_step"] for b in base] if have else None,
                        speedup_fastest=min(b_ms) / min(ms) if have else None,
                        speedup_median=statistics.median(b_ms) / statistics.median(ms) if have else None))
    return out


def section(commit: str, sizes, walls, rounds: int = 2) -> dict:
    """The ``baseline`` section: COMMIT's scale section and this tree's in ``rounds`` alternating
    rounds (module docstring), printed as it goes and summed up per wall."""
    sha = resolve(commit)
    print(f"\nbaseline: the scale section of {commit} ({sha[:12]}) and of this tree, back to back, "
          f"{rounds} rounds:", flush=True)
    theirs, ours = [], []
    t0 = time.time()
    with worktree(sha) as tree:
        for k in range(rounds):
            for label, where, into in ((sha[:12], tree, theirs), ("this tree", paths.ROOT, ours)):
                t = time.time()
                into.append(scale_rows(where, sizes, walls))
                done = len(theirs) + len(ours)
                eta = (time.time() - t0) / done * (2 * rounds - done)  # (the first includes the baseline's compile)
                print(f"  round {k + 1}/{rounds}: {label} done in {time.time() - t:.0f} s ({done}/{2 * rounds} runs, "
                      f"{time.time() - t0:.0f} s so far, at most ~{eta:.0f} s to go)", flush=True)
    rows = compare(theirs, ours)
    for r in rows:
        mine = " ".join(f"{x:.2f}" for x in r["ms_per_step"])
        if r["baseline_ms_per_step"] is None:
            print(f"  {r['wall']:12s} {r['size']:5d} stones: this tree {mine} ms/step; {sha[:12]} has no such wall")
            continue
        base = " ".join(f"{x:.2f}" for x in r["baseline_ms_per_step"])
        print(f"  {r['wall']:12s} {r['size']:5d} stones: {sha[:12]} {base} ms/step, this tree {mine} ms/step: "
              f"{r['speedup_fastest']:.2f}x (fastest), {r['speedup_median']:.2f}x (medians)", flush=True)
    return {"commit": sha, "asked": commit, "rounds": rounds, "rows": rows}
