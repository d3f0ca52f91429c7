"""The convention study: m2 intervals, their end points, the rule for the second m2, verdicts."""
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hybridpd._format import pct as _pct
from hybridpd.analysis.orbits import symmetric_orbit, symmetric_orbits
from hybridpd.model import ImpactPair, PDGains
from hybridpd.reproduce import PAPER, Settings
from hybridpd.reproduce import conclusions as C
from hybridpd.reproduce.pipeline import _basin_step
from hybridpd.reproduce.study import candidate_stability, choose_m2, intersect, stable_intervals

COMMON = dict(kp=10.0, kv=20.0, mu=0.1, L=0.75, omega=5.0)


@pytest.fixture(scope="module")
def intervals():
    return {case: {e: stable_intervals(case, e, num=801, **COMMON) for e in PAPER["e"]}
            for case in ("collocated", "noncollocated")}


def _orbit(case, e, m2):
    return symmetric_orbit(ImpactPair(0.1, e, 0.75, m2), PDGains(10.0, 20.0), 5.0, case=case)


def test_interval_ends_are_bifurcation_points(intervals):
    ends = 0
    for case, per_e in intervals.items():
        for e, ivs in per_e.items():
            assert ivs, (case, e)
            for iv in ivs:
                assert iv.lo.m2 < iv.hi.m2
                for end, inside in ((iv.lo, +1), (iv.hi, -1)):
                    if end.kind == "window":
                        continue
                    ends += 1
                    assert end.verified
                    # independent recomputation through the scalar path
                    o = _orbit(case, e, end.m2)
                    if end.kind == "stability":
                        assert abs(o.spectral_radius - 1) <= 1e-6
                    else:
                        assert end.kind == "viability"
                        assert abs(o.viability_margin) <= 1e-6
                    # stable just inside, not just outside
                    assert _orbit(case, e, end.m2 * (1 + inside * 1e-4)).stable
                    assert not _orbit(case, e, end.m2 * (1 - inside * 1e-4)).stable
    assert ends == 4     # three stability losses (non-collocated) and one grazing (collocated)


def test_interval_ends_do_not_depend_on_the_bracketing_grid(intervals):
    for e in PAPER["e"]:
        fine = stable_intervals("noncollocated", e, num=4001, **COMMON)
        coarse = intervals["noncollocated"][e]
        assert [i.lo.m2 for i in fine] == pytest.approx([i.lo.m2 for i in coarse], rel=1e-9)


def test_the_chosen_m2_follows_the_documented_rule(intervals):
    m2 = choose_m2(intervals["noncollocated"])
    (lo, hi), = intersect(intervals["noncollocated"].values())
    assert lo == pytest.approx(max(i[0].lo.m2 for i in intervals["noncollocated"].values()))
    assert m2 == float(f"{math.sqrt(lo * hi):.3g}") and lo < m2 < hi
    r = symmetric_orbits(10.0, 20.0, mu=0.1, e=np.array(PAPER["e"]), L=0.75, omega=5.0, m2=m2,
                         case="noncollocated")
    assert r.stable.all()
    assert choose_m2({0.5: []}) is None


@pytest.mark.parametrize("e", PAPER["e"])
def test_chosen_m2_gives_every_fig7_panel_a_nonempty_basin(intervals, e):
    m2 = choose_m2(intervals["noncollocated"])
    orb = _orbit("noncollocated", e, m2)
    s = Settings.quick(basin=(9, 9))
    b = _basin_step(orb, s, executor="serial", max_workers=None, progress=False)
    assert b is not None and b.basin.converged_fraction > 0 and b.measure(0).count > 0
    # and the paper's m2 = 1 has none (unstable or no orbit)
    assert _basin_step(_orbit("noncollocated", e, 1.0), s, executor="serial",
                       max_workers=None, progress=False) is None


def test_candidate_stability_is_the_orbits_where_the_orbit_exists():
    kp, kv = np.meshgrid(np.linspace(0.5, 30, 15), np.linspace(0.5, 30, 13))
    for case in ("collocated", "noncollocated"):
        r = symmetric_orbits(kp, kv, mu=0.1, e=0.5, L=0.75, omega=5.0, case=case)
        rho = candidate_stability(case, kp, kv, mu=0.1, e=0.5, L=0.75, omega=5.0, m2=1.0)
        assert r.exists.any()
        np.testing.assert_allclose(rho[r.exists], r.spectral_radius[r.exists], rtol=1e-12)
        # stability alone is defined beyond existence (viability ignored)
        assert np.isfinite(rho[~r.exists & (r.reason == 3)]).all()


def test_conclusion_checks():
    big = {"exists": [0.5, 0.8, 1.0], "stability": [1.0, 1.0, 1.0], "both": [0.5, 0.8, 1.0]}
    small = {"exists": [0.3, 0.2, 0.1], "stability": [0.05, 0.03, 0.01],
             "both": [0.05, 0.03, 0.01]}
    c1 = C.check_1(big, small)
    assert c1["verdict"] == "agrees" and c1["by_quantity"]["exists"]["verdict"] == "contradicted"
    assert C.check_1(small, big)["verdict"] == "contradicted"
    assert C.check_2(big, small)["verdict"] == "agrees"
    assert C.check_2(small, big)["verdict"] == "contradicted"
    assert C.check_3(big)["verdict"] == "agrees" and C.check_3(small)["verdict"] == "contradicted"
    assert C.check_4([0.5, 0.5, 0.5], [0.4, 0.6, 0.3])["verdict"] == "agrees"
    assert C.check_4([0.5, 0.5, 0.5], [None, 0.6, 0.3])["verdict"] == "contradicted"
    assert C.check_4_necessary([True] * 3, [True, False, True]) == "contradicted"
    assert C.check_4_necessary([True] * 3, [True] * 3) == "not measured"
    assert C.combine(["agrees", "agrees", "not measured"]) == "agrees"
    assert C.combine(["agrees", "contradicted"]) == "depends"
    assert C.combine(["contradicted"]) == "contradicted"


@given(st.floats(0.0, 1.0))
def test_percentages_never_round_to_0_or_100_when_they_are_not(f):
    s = _pct(f)
    if 0 < f < 1:
        assert s not in ("0.0%", "100.0%")
    if f == 1:
        assert s == "100.0%"


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.floats(0.1, 10), st.floats(0.1, 10)), min_size=1, max_size=3),
       st.lists(st.tuples(st.floats(0.1, 10), st.floats(0.1, 10)), min_size=1, max_size=3))
def test_intersect_is_the_common_part(a, b):
    a = [sorted(p) for p in a if p[0] != p[1]]
    b = [sorted(p) for p in b if p[0] != p[1]]
    common = intersect([a, b])
    for x in np.linspace(0.1, 10, 97):
        inside = lambda ivs, x=x: any(lo < x < hi for lo, hi in ivs)
        assert inside(common) == (inside(a) and inside(b))
