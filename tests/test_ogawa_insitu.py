"""Ogawa et al. Tables 1-3 as data: the paper's averages are recomputed."""
from conftest import assert_figure
from drystone.studies.ogawa import insitu


def test_averages_match_the_paper():
    """35.34 and 32.53 um, 0.46 and 0.44: the recomputed means agree to one unit of the last
    printed digit (the paper truncates: 35.3467 um is printed 35.34)."""
    rows = insitu.check_averages()
    assert len(rows) == 4
    for q, site, mine, paper, ok in rows:
        assert ok, (q, site, mine, paper)


def test_figure(tmp_path):
    """Friction against roughness: a 6.5 x 4.5 in figure at 120 dpi with its points drawn."""
    assert_figure(insitu.figure(tmp_path / "friction_roughness.png"), (6.5, 4.5), dpi=120)
