"""The limit analysis on the settled wall (a YADE settling run) against the wall as built."""
from __future__ import annotations

import json

import pytest

import tolerances as tol
from conftest import requires_yade
from drystone.analyses import limit as lim
from drystone.mechanics import limit_analysis as la

B, H = 0.1, 0.2  # each stacked stone: depth along the load (y), height; lambda = B / (2 H) as built


def _stack_case(tmp_path, stones: int):
    blocks = [{"id": 0, "role": "platform", "material": "stone",
               "vertices": [[x, y, z] for z in (-0.05, 0.0) for x, y in ((-0.5, -0.5), (0.5, -0.5), (0.5, 0.5),
                                                                         (-0.5, 0.5))]}]
    for k in range(stones):
        z0, z1 = k * H, (k + 1) * H
        blocks.append({"id": k + 1, "role": "free", "material": "stone",
                       "vertices": [[x, y, z] for z in (z0, z1) for x, y in ((-0.1, -B / 2), (0.1, -B / 2),
                                                                             (0.1, B / 2), (-0.1, B / 2))]})
    geo = {"format": "drystone.blocks", "version": 1, "name": f"stack{stones}",
           "units": {"length": "m", "mass": "kg"},
           "materials": {"stone": {"density": 2300, "kn": 2e8, "kt": 1e8, "mu": 0.6, "damping": 0.8}},
           "blocks": blocks}
    (tmp_path / "stack.json").write_text(json.dumps(geo))
    case = tmp_path / "stack.toml"
    case.write_text(f'[case]\nname = "stack{stones}"\ngeometry = "stack.json"\n\n'
                    '[[stages]]\ntype = "gravity"\nduration = 0.5\nramp = 0.25\n')
    return case


@requires_yade
@pytest.mark.yade
@pytest.mark.slow
@pytest.mark.parametrize("stones", [1, 2])
def test_settled_and_as_built_give_the_same_multiplier(tmp_path, stones):
    """A slender stone (lambda = b/h = 0.5) and two stacked (b/(2h) = 0.25), settled under
    gravity in YADE and as built: the same interfaces, lambda within the settlement's share of
    the stones' size (``LIMIT_SETTLED_PER_SETTLEMENT``); through the CLI's function."""
    case = _stack_case(tmp_path, stones)
    built = lim.load_wall(case)
    settled = lim.settled_wall(case, root=tmp_path / "out", log=lambda *a: None)
    assert 0 < settled.settlement_m < 0.01 * B
    assert len(settled.ifaces) == len(built.ifaces) == stones
    exact = B / (stones * H)
    lb = la.solve(built.bodies, built.ifaces, built.mu, lim.TOWARDS["+y"], (0, 0, -built.gravity))
    ls = la.solve(settled.bodies, settled.ifaces, settled.mu, lim.TOWARDS["+y"], (0, 0, -settled.gravity))
    assert lb.multiplier == pytest.approx(exact, rel=tol.LIMIT_LP_REL)
    rel = tol.LIMIT_SETTLED_PER_SETTLEMENT * settled.settlement_m / B + tol.LIMIT_LP_REL
    assert ls.multiplier == pytest.approx(lb.multiplier, rel=rel)
    d = lim.limit(case, ["+y"], ["associative"], out=tmp_path / "out", settled=True)
    assert d["geometry"] == "settled" and d["settlement_m"] == pytest.approx(settled.settlement_m)
    assert d["directions"]["+y"]["multiplier"] == pytest.approx(ls.multiplier, rel=tol.LIMIT_LP_REL)
