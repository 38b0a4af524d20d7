"""The limit-vs-DEM study's joint-compliance part without its DEM runs: the closed form of
one toppling stone read off a case's wall, the stiffness overrides, and the table built from
stored (fake) tilt results, with the runs not yet made marked "not run"."""
import pytest

import tolerances as tol
from drystone import paths
from drystone.analyses import limit as lim
from drystone.mechanics import analytic
from drystone.studies import limit_dem as ld

ONE_BLOCK = paths.ROOT / "cases" / "examples" / "one_block_tilt.toml"  # a 0.2 m cube, K_n 2e8, K_t 1e8


@pytest.fixture(scope="module")
def cube():
    return lim.load_wall(ONE_BLOCK)


@pytest.mark.parametrize("towards", ["+y", "-x"])
def test_closed_form_reads_the_stones_toe_and_centroid(cube, towards):
    # the cube's centroid 0.1 m from either toe and 0.1 m above its base, base 0.2 x 0.2 m
    w = 2300.0 * 0.2 ** 3 * cube.gravity
    for kn in (2e8, 2e10):
        assert ld.closed_form_deg(cube, towards, kn) == pytest.approx(
            analytic.stone_toppling_tilt_deg(0.1, 0.1, 0.2, 0.2, w, kn), rel=tol.NUMERICAL_REL)
    # stiffer joints: closer to the rigid atan(b/h) = 45 deg, from below
    soft, stiff = ld.closed_form_deg(cube, towards, 2e8), ld.closed_form_deg(cube, towards, 2e10)
    assert soft < stiff < 45.0


def test_stiffness_overrides_scale_both_stiffnesses():
    kn, kt = ld.base_stiffness(ONE_BLOCK)
    assert (kn, kt) == (2e8, 1e8)  # as written in cases/examples/one_block.json
    assert ld.stiffness_overrides(kn, kt, 100) == ["contact.kn=2e+10", "contact.kt=1e+10"]


def test_compliance_table_from_stored_results():
    w = ld.ComplianceWall("w", "a wall", "x.toml", "+y", (10.0, 2.0), 1.0, 1.0, closed_form=True)
    runs = {"w": {1: {"onset_deg": 15.0, "reaction_drop_deg": 16.0, "kn": 2e8},
                  10: {"onset_deg": 17.5, "reaction_drop_deg": 18.25, "kn": 2e9}}}  # x100 not run
    limits = {"w": {"associative": 19.0, "coulomb": 18.5, "cone": [19.0, 19.5],
                    "closed_form": {1: 14.9, 10: 17.4, 100: 18.6}}}
    rows = ld.compliance_table([w], runs, limits).splitlines()
    assert len(rows) == 2 + len(ld.K_FACTORS)
    cells = [[c.strip() for c in r.strip("|").split("|")] for r in rows[2:]]
    assert cells[0][1:5] == ["2e+08 (× 1)", "15.00", "16.00", "14.90"]
    assert cells[0][5] == "19.00 [19.00–19.50]" and cells[0][6] == "18.50"
    assert cells[0][7] == "3.00" and cells[1][7] == "0.75"  # the associative limit minus the reaction drop
    assert cells[2][2:4] == ["not run", "not run"] and cells[2][4] == "18.60"


def test_report_keeps_the_parts_not_recomputed():
    before = ("# old\n\nintro\n\n" + ld.HEADINGS["tilt"] + "\n\n| t |\n|---|\n| 1 |\n\n"
              + ld.HEADINGS["shape"] + "\n\n| s |\n|---|\n| 2 |\n")
    assert ld.sections(before)[ld.HEADINGS["shape"]] == "| s |\n|---|\n| 2 |"
    text = ld.report(parts=(), previous=before)
    assert ld.sections(text) == {h: b for h, b in ld.sections(before).items()}
    assert text.index(ld.HEADINGS["tilt"]) < text.index(ld.HEADINGS["shape"])
    assert ld.HEADINGS["compliance"] not in text  # never computed, not invented


def test_crosscheck_angles_read_the_generated_table():
    text = ("x\n<!-- begin:crosscheck -->\n| wall (seed) | LMGC90 (rigid) | package K_n 2e+08 | package K_n 2e+09 |\n"
            "|---|---|---|---|\n| 0 | 19.03 | 14.83 | 17.40 |\n| 1 | 19.27 | — | 17.48 |\n\nExperiment 14.33\n"
            "<!-- end:crosscheck -->\n")
    got = ld.crosscheck_angles(text)
    assert got[0] == {"lmgc90": 19.03, 2e8: 14.83, 2e9: 17.40}
    assert got[1] == {"lmgc90": 19.27, 2e9: 17.48}  # a dash is no angle
    assert ld.crosscheck_angles("no block") == {}


def test_crosscheck_angles_of_the_shipped_docs_are_onsets_of_the_varying_walls():
    """Its K_n 2e8 column is the tilt study's published onset of the same seed (the same
    runs' measure): the columns set beside each other measure the same thing."""
    xc, dem = ld.crosscheck_angles(), ld.tilt_dem_angles()
    common = [s for s in xc if 2e8 in xc[s] and s in dem.get("varying", {})]
    assert common
    for s in common:
        assert xc[s][2e8] == pytest.approx(dem["varying"][s][0], abs=tol.PRINTED_2_DECIMALS)
