"""Newton on P^k and parameter continuation, checked against independent computations.

Every detected event is verified by something other than the test function that found it:
the closed-form symmetric orbits on both sides, a fine parameter grid, or brute-force
iteration of the simulated impact map (square-root scaling of the bifurcating orbits).
"""
import json

import numpy as np
import pytest

from hybridpd import ImpactPair, PDGains, Reference
from hybridpd.analysis.continuation import continue_orbit
from hybridpd.analysis.periodic import find_orbit
from hybridpd.pair.continuation import (
    EVENT_KINDS,
    Branch,
    continue_symmetric,
    trace_map,
)
from hybridpd.pair.impactmap import ImpactMap
from hybridpd.pair.orbits import symmetric_orbit, symmetric_orbits
from hybridpd.plotting.branches import plot_branch

PAPER = dict(mu=0.1, L=0.75)
W = 5.0


def sym(kp=10.0, kv=20.0, e=0.5, case="collocated", x10=1.0):
    return symmetric_orbit(ImpactPair(PAPER["mu"], e, PAPER["L"]), PDGains(kp, kv), W,
                           case=case, x10=x10)


def pmap(kp, kv, e, xm, case="collocated"):
    return ImpactMap(ImpactPair(PAPER["mu"], e, PAPER["L"]), PDGains(kp, kv), Reference(xm, W),
                     case)


@pytest.fixture(scope="module")
def period2():
    """The period-2 attractor at the paper's parameters (collocated, e = 0.1)."""
    xm = sym(e=0.1).xm
    P = pmap(10, 20, 0.1, xm)
    s0 = P.iterate(np.array([0.3, -2.1, -2.3, 0.5]), 200)[-1]
    return P, find_orbit(P, s0, period=2)


@pytest.fixture(scope="module")
def asym60():
    """A non-symmetric period-1 orbit: collocated, e = 0.5, kv = 0.5, kp = 60, xm fixed."""
    o = sym(kp=60, kv=0.5, e=0.5)
    P = ImpactMap(o.pair, o.gains, o.reference())
    s0 = P.iterate(o.fixed_point + np.array([0, 1e-3, 0, 0]), 3000)[-1]
    return o, P, find_orbit(P, s0)


# ---------------------------------------------------------------------------------------
# Newton on P^k
# ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("case,e", [("collocated", 0.5), ("collocated", 0.1),
                                    ("noncollocated", 0.5)])
def test_newton_finds_symmetric_fixed_point(case, e):
    o = sym(e=e, case=case)
    assert o.exists
    P = ImpactMap(o.pair, o.gains, o.reference(), case)
    start = o.fixed_point + np.array([0.01, 0.02, -0.05, 0.05]) * (0.01 if o.spectral_radius > 10
                                                                   else 1)
    r = find_orbit(P, start)
    assert r.converged, r.reason
    assert np.max(np.abs(r.s - o.fixed_point)) < 1e-10
    assert r.walls == ((-1, 1),) and r.symbolic_dp
    # multipliers by decreasing modulus; relative agreement (the non-collocated one is ~5e3)
    assert np.max(np.abs(r.multipliers - o.multipliers) / np.maximum(1, np.abs(o.multipliers))) \
        < 1e-8
    assert r.stable == o.stable
    assert abs(r.margin - o.viability_margin) < 1e-6
    assert r.iterations >= 1 and r.residual < 1e-10


def test_newton_with_finite_difference_jacobian_agrees():
    o = sym(e=0.5)
    P = ImpactMap(o.pair, o.gains, o.reference())
    r = find_orbit(P, o.fixed_point + 0.01, jacobian="fd")
    assert r.converged
    assert np.max(np.abs(r.s - o.fixed_point)) < 1e-10
    assert np.max(np.abs(r.DP - o.DP)) < 1e-6 * np.max(np.abs(o.DP))


def test_trace_map_reproduces_the_compiled_map(period2):
    P, orb = period2
    rng = np.random.default_rng(3)
    pts = np.vstack([orb.orbit, orb.orbit + rng.normal(scale=0.05, size=(2, 4))])
    pts[:, 3] = np.abs(pts[:, 3]) + 0.1
    for s in pts:
        tr = trace_map(P, s)
        r = P.apply_batch(s)
        assert tr.ok == bool(r.ok[0])
        if tr.ok:
            assert np.array_equal(tr.s, r.s[0])
            assert len(tr.steps) == int(r.n_impacts[0])


def test_period2_cycle_of_the_paper_parameters(period2):
    P, orb = period2
    assert orb.converged and orb.minimal_period == 2
    expected = np.array([[0.2216, 0.2934, -3.0818, 6.4529], [0.3300, -0.0407, -3.3711, 0.2893]])
    for row in expected:
        assert np.min(np.max(np.abs(orb.orbit - row), axis=1)) < 1e-4
    # a double impact on the right wall: the flight after the big impact ends on +L again
    assert sorted(orb.walls) == [(-1, -1, 1), (1,)]
    assert orb.n_impacts == 4 and not orb.grazing
    # the jacobian of P^2 against finite differences of P^2
    J = P.jacobian_fd(orb.s, 2, h=1e-7, scale=np.maximum(1.0, np.abs(orb.s)), one_sided=True)
    assert np.max(np.abs(J - orb.DP)) < 1e-5 * np.max(np.abs(orb.DP))
    # multipliers against the measured contraction of a perturbation iterated by P
    rho = orb.spectral_radius
    assert 0.5 < rho < 0.55 and orb.stable
    tr = P.iterate(orb.s + np.array([0.0, 1e-5, 0.0, 0.0]), 40)[::2]   # every P^2
    d = np.array([np.linalg.norm(_phase_diff(x, orb.s, P.period)) for x in tr])
    measured = (d[14] / d[4]) ** (1 / 10)
    assert abs(measured - rho) < 1e-3 * rho


def _phase_diff(a, b, T):
    d = np.asarray(a, float) - b
    d[0] = (d[0] + T / 2) % T - T / 2
    return d


def test_nonsymmetric_period1_orbit(asym60):
    o, P, r = asym60
    assert o.exists and o.multipliers[0].real > 1         # symmetric orbit unstable here
    assert r.converged and r.walls == ((-1, 1),) and r.minimal_period == 1
    # not the symmetric orbit: x2 at the impact differs from x10 - L = 0.25
    assert abs(r.s[1] - 0.25) > 0.01
    assert r.stable and r.spectral_radius < 1
    # the fixed point against a long simulation started on it
    assert np.max(np.abs(P.iterate(r.s, 500)[-1] - r.s)) < 1e-9


def test_newton_reports_non_convergence():
    o = sym(e=0.5)
    P = ImpactMap(o.pair, o.gains, o.reference())
    r = find_orbit(P, o.fixed_point + 0.05, max_iter=1)
    assert not r.converged and "max_iter" in r.reason
    assert r.iterations == 1


# ---------------------------------------------------------------------------------------
# Continuation of the symmetric family (closed form)
# ---------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def colloc_kv():
    return continue_symmetric(ImpactPair(0.1, 0.1, 0.75), PDGains(10, 15), W, "kv", 25.0)


def test_symmetric_family_grazes_near_kv_21_9(colloc_kv):
    br = colloc_kv
    assert br.termination == "reached stop" and br.family == "symmetric"
    ev = br.events_of("grazing")
    assert len(ev) == 1 and ev[0].located
    kv_g = ev[0].parameter
    assert 21.0 < kv_g < 22.0
    # independent: where `exists` flips on a fine grid, and the margin sign change
    kv = np.linspace(21.0, 23.0, 4001)
    r = symmetric_orbits(10.0, kv, e=0.1, margin=True, omega=W, **PAPER)
    flip = np.flatnonzero(np.diff(r.exists.astype(int)))
    assert flip.size == 1
    assert kv[flip[0]] <= kv_g <= kv[flip[0] + 1]
    before, after = sym(kv=kv_g * (1 - 1e-7), e=0.1), sym(kv=kv_g * (1 + 1e-7), e=0.1)
    assert before.exists and before.viability_margin > 0
    assert not after.exists and after.viability_margin < 0
    # stable up to the end: no stability change, only the loss of existence
    assert br.stable[br.parameter < kv_g].all() and not br.viable[br.parameter > kv_g].any()
    assert not br.events_of("stability_change")


def test_map_continuation_agrees_with_the_symmetric_family(colloc_kv):
    """Same branch two ways: the closed-form family (x10 = 1, xm follows) and Newton on P.

    Along the family xm changes, so Newton on P at a fixed xm meets it where xm matches: at
    every family point Newton at that point's xm returns the family's fixed point, and the
    map continuation in kv at the grazing point's xm grazes exactly where the family does.
    """
    br = colloc_kv
    ok = np.flatnonzero(br.viable & (br.margin > 1e-3))     # away from grazing
    assert ok.size > 5
    for i in ok[[0, ok.size // 2, -1]]:
        P = pmap(10, br.parameter[i], 0.1, br.xm[i])
        r = find_orbit(P, br.points[i] + np.array([0.001, 0.01, -0.01, 0.02]))
        assert r.converged
        assert np.max(np.abs(r.s - br.points[i])) < 1e-10
        assert np.max(np.abs(r.multipliers - br.multipliers[i])) < 1e-8
    g = br.events_of("grazing")[0]
    P = pmap(10, 21.5, 0.1, g.xm)
    mb = continue_orbit(P.family("kv"), 21.5, 23.0, sym(kv=21.5, e=0.1).fixed_point)
    assert "ends at grazing" in mb.termination
    ge = mb.events_of("grazing")[-1]
    assert abs(ge.parameter - g.parameter) < 1e-6
    assert np.max(np.abs(ge.point - g.point)) < 1e-7
    # on the map branch, xm is fixed and the points are symmetric orbits of other x10
    assert np.all(mb.xm == g.xm) and np.all(np.diff(mb.parameter) > 0)


def test_map_continuation_in_xm_meets_the_symmetric_orbit_of_another_x10():
    o1, o2 = sym(e=0.5), sym(e=0.5, x10=1.2)
    assert o2.exists
    P = ImpactMap(o1.pair, o1.gains, o1.reference())
    br = continue_orbit(P.family("xm"), o1.xm, o2.xm, o1.fixed_point)
    assert br.termination == "reached stop"
    assert br.parameter[-1] == o2.xm
    assert np.max(np.abs(br.points[-1] - o2.fixed_point)) < 1e-10
    assert np.max(np.abs(br.multipliers[-1] - o2.multipliers)) < 1e-8


@pytest.mark.parametrize("e,expected", [
    (0.1, {"neimark_sacker": 2, "stability_change": 2, "grazing": 1}),
    (0.5, {"neimark_sacker": 1, "stability_change": 1, "grazing": 1}),
])
def test_noncollocated_events_verified_by_the_closed_form(e, expected):
    br = continue_symmetric(ImpactPair(0.1, e, 0.75), PDGains(10, 0.5), W, "kv", 35.0,
                            case="noncollocated")
    assert br.termination == "reached stop"
    counts = {k: len(br.events_of(k)) for k in EVENT_KINDS}
    for k, n in expected.items():
        assert counts[k] == n, (k, counts)
    assert counts["fold"] == counts["period_doubling"] == 0
    for ev in br.events:
        assert ev.located and ev.viable
        lo = sym(kv=ev.parameter * (1 - 1e-6), e=e, case="noncollocated")
        hi = sym(kv=ev.parameter * (1 + 1e-6), e=e, case="noncollocated")
        if ev.kind == "grazing":
            assert lo.viability_margin > 0 > hi.viability_margin
            assert lo.exists and not hi.exists
        else:
            # spectral radius on both sides of the event straddles the unit circle
            assert (lo.spectral_radius - 1) * (hi.spectral_radius - 1) < 0
            assert abs(np.max(np.abs(ev.multipliers)) - 1) < 1e-9
            if ev.kind == "neimark_sacker":
                crit = ev.multipliers[np.argmin(np.abs(np.abs(ev.multipliers) - 1))]
                assert abs(crit.imag) > 0.1
    # the paper's gains (kv = 20) lie on the unstable part of the branch
    i = np.argmin(np.abs(br.parameter - 20.0))
    assert br.viable[i] and not br.stable[i]


# ---------------------------------------------------------------------------------------
# Bifurcations located and verified by brute force
# ---------------------------------------------------------------------------------------


def test_symmetry_breaking_pitchfork_on_the_symmetric_family():
    """A real multiplier crosses +1 on the symmetric family (collocated, kv = 0.5): beyond it
    iterating P lands on a non-symmetric orbit at a distance ~ sqrt(kp - kp_c)."""
    br = continue_symmetric(ImpactPair(0.1, 0.5, 0.75), PDGains(55, 0.5), W, "kp", 62.0)
    folds = br.events_of("fold")
    assert len(folds) == 1 and folds[0].located and "branch point" in folds[0].detail
    kc = folds[0].parameter
    assert 58.0 < kc < 59.0
    assert np.min(np.abs(folds[0].multipliers - 1)) < 1e-9
    ratios = []
    for d in (0.01, 0.04):
        o = sym(kp=kc + d, kv=0.5)
        P = ImpactMap(o.pair, o.gains, o.reference())
        tr = P.iterate(o.fixed_point + np.array([0, 1e-3, 0, 0]), 20000)
        assert np.linalg.norm(tr[-1] - tr[-2]) < 1e-10            # a fixed point of P
        ratios.append(np.linalg.norm(tr[-1] - o.fixed_point) / np.sqrt(d))
    assert ratios[0] > 0.05 and abs(ratios[1] / ratios[0] - 1) < 0.01
    o = sym(kp=kc - 0.5, kv=0.5)                                    # before: symmetric
    P = ImpactMap(o.pair, o.gains, o.reference())
    assert np.linalg.norm(P.iterate(o.fixed_point + 1e-4, 5000)[-1] - o.fixed_point) < 1e-8


def test_period_doubling_located_and_verified_by_iteration(asym60):
    """On the non-symmetric branch, a multiplier crosses -1 near kp = 99.24; below it
    (where the fixed point is unstable) iterating P settles on a 2-cycle whose squared size
    is linear in the distance to the located point (supercritical flip)."""
    o, P, r = asym60
    br = continue_orbit(P.family("kp"), 60.0, 99.3, r)
    pds = br.events_of("period_doubling")
    assert len(pds) >= 2 and all(ev.located for ev in pds)
    pd = min(pds, key=lambda ev: abs(ev.parameter - 99.24))
    kc = pd.parameter
    assert 99.0 < kc < 99.5
    crit = pd.multipliers[np.argmin(np.abs(pd.multipliers + 1))]
    assert abs(crit + 1) < 1e-7
    amps = {}
    for d in (0.001, 0.004):
        Q = ImpactMap(o.pair, PDGains(kc - d, 0.5), o.reference())
        f = find_orbit(Q, pd.point)
        assert f.converged and f.multipliers[0].real < -1            # unstable, flip
        tr = Q.iterate(f.s + np.array([0, 1e-4, 0, 0]), 20000)
        a, b = tr[-1], tr[-2]
        assert np.linalg.norm(tr[-1] - tr[-3]) < 1e-9                # period 2
        amps[d] = np.linalg.norm(a - b)
        c = find_orbit(Q, a, period=2)
        assert c.converged and c.minimal_period == 2 and c.stable
    # amplitude^2 = c (kc - kp): extrapolate the brute-force amplitudes to zero
    c = (amps[0.004] ** 2 - amps[0.001] ** 2) / 0.003
    kc_brute = (kc - 0.001) + amps[0.001] ** 2 / c
    assert abs(kc_brute - kc) < 2e-4
    Q = ImpactMap(o.pair, PDGains(kc + 0.004, 0.5), o.reference())  # above: a stable point
    f = find_orbit(Q, pd.point)
    assert f.stable
    tr = Q.iterate(f.s + np.array([0, 1e-4, 0, 0]), 20000)
    assert np.linalg.norm(tr[-1] - f.s) < 1e-8


def test_fold_of_the_period2_cycle(period2):
    """Continuing the paper's 2-cycle down in kv, the branch turns back at a fold; above the
    fold iterating P settles on a 2-cycle at a distance ~ sqrt(kv - kv_f) from the fold point,
    below it the same start goes to the period-1 symmetric orbit."""
    P, orb = period2
    br = continue_orbit(P.family("kv"), 20.0, 5.0, orb, period=2)
    assert "turned back" in br.termination
    folds = br.events_of("fold")
    assert len(folds) == 1 and "turns back" in folds[0].detail and folds[0].located
    f = folds[0]
    assert 17.0 < f.parameter < 18.0
    assert np.min(np.abs(f.multipliers - 1)) < 1e-6
    assert np.min(br.parameter) >= f.parameter - 1e-7                # never below the fold
    dist = {}
    for d in (1e-3, 1e-2):
        Q = ImpactMap(P.pair, PDGains(10, f.parameter + d), P.reference)
        tr = Q.iterate(f.point, 30000)
        assert np.linalg.norm(tr[-1] - tr[-3]) < 1e-9
        dist[d] = min(np.linalg.norm(tr[-1] - f.point), np.linalg.norm(tr[-2] - f.point))
    assert abs(dist[1e-2] / dist[1e-3] - np.sqrt(10)) < 0.1
    Q = ImpactMap(P.pair, PDGains(10, f.parameter - 1e-3), P.reference)
    tr = Q.iterate(f.point, 30000)
    assert np.linalg.norm(tr[-1] - tr[-2]) < 1e-9                    # period 1 now
    assert np.linalg.norm(tr[-1] - f.point) > 1.0


def test_natural_continuation_stops_at_the_fold_and_agrees_before_it(period2):
    P, orb = period2
    nat = continue_orbit(P.family("kv"), 20.0, 5.0, orb, period=2, method="natural",
                         step=0.5)
    arc = continue_orbit(P.family("kv"), 20.0, 5.0, orb, period=2)
    kf = arc.events_of("fold")[0].parameter
    assert "min_step" in nat.termination
    assert abs(nat.parameter[-1] - kf) < 1e-3
    # the same orbits on the common stretch
    for p, s in zip(nat.parameter[1:4], nat.points[1:4]):
        Q = ImpactMap(P.pair, PDGains(10, p), P.reference)
        r = find_orbit(Q, s, period=2)
        assert np.max(np.abs(r.s - s)) < 1e-9


# ---------------------------------------------------------------------------------------
# Results, plotting, bounds and validation
# ---------------------------------------------------------------------------------------


def test_branch_to_dict_and_plot(colloc_kv):
    br = colloc_kv
    assert isinstance(br, Branch) and len(br) == br.points.shape[0]
    d = json.loads(json.dumps(br.to_dict()))
    assert d["parameter_name"] == "kv" and len(d["events"]) == len(br.events)
    assert d["events"][0]["kind"] == "grazing"
    from matplotlib.figure import Figure

    for q in ("spectral_radius", "margin", "multipliers", 0):
        fig = plot_branch(br, quantity=q)
        assert isinstance(fig, Figure) and fig.axes[0].get_xlabel() == "kv"
    with pytest.raises(ValueError, match="quantity"):
        plot_branch(br, quantity="nope")


def test_loops_are_bounded_and_report_why(period2):
    P, orb = period2
    br = continue_orbit(P.family("kv"), 20.0, 25.0, orb, period=2, max_steps=3)
    assert len(br) == 3 and br.termination.startswith("max_steps")
    br = continue_symmetric(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), W, "e", 0.9,
                            max_steps=2)
    assert len(br) == 3 and "max_steps" in br.termination
    bad = continue_orbit(P.family("kv"), 20.0, 25.0, np.array([0.1, 50.0, 0.0, 1e-3]),
                         period=2, max_iter=2)
    assert len(bad) == 0 and "initial Newton failed" in bad.termination


def test_bad_input_names_the_culprit(period2):
    P, orb = period2
    with pytest.raises(ValueError, match="parameter"):
        continue_orbit(P.family("kd"), 20.0, 25.0, orb.s)
    with pytest.raises(ValueError, match="parameter"):
        continue_symmetric(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), W, "xm", 1.0)
    with pytest.raises(ValueError, match="step"):
        continue_orbit(P.family("kv"), 20.0, 25.0, orb.s, step=0.0)
    with pytest.raises(ValueError, match="step"):
        continue_symmetric(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), W, "kv", 25.0,
                           step=0.0)
    with pytest.raises(ValueError, match="p_end"):
        continue_orbit(P.family("kv"), 20.0, float("nan"), orb.s)
    with pytest.raises(ValueError, match="p_end"):
        continue_orbit(P.family("e"), 0.1, 1.5, orb.s)
    with pytest.raises(ValueError, match="p_end"):
        continue_orbit(P.family("kv"), 20.0, 20.0, orb.s)
    with pytest.raises(ValueError, match="finite"):
        find_orbit(P, [np.nan, 0, 0, 1])
    with pytest.raises(ValueError, match="z4"):
        find_orbit(P, [0.1, 0, 0, -1])
    with pytest.raises(ValueError, match="period"):
        find_orbit(P, orb.s, period=0)
    with pytest.raises(ValueError, match="tol"):
        find_orbit(P, orb.s, tol=float("nan"))
    with pytest.raises(ValueError, match="jacobian"):
        find_orbit(P, orb.s, jacobian="symbolic")
    with pytest.raises(ValueError, match="method"):
        continue_orbit(P.family("kv"), 20.0, 25.0, orb.s, method="newton")
    with pytest.raises(ValueError, match="events"):
        continue_orbit(P.family("kv"), 20.0, 25.0, orb.s, events=("hopf",))


@pytest.mark.parametrize("name,stop", [("kp", 11.0), ("kv", 19.0), ("e", 0.6), ("mu", 0.12),
                                       ("xm", 0.42), ("omega", 5.2), ("L", 0.7)])
def test_every_parameter_can_be_continued(name, stop):
    """Short continuation in each parameter from the e = 0.5 symmetric orbit; the end point
    is a fixed point of the simulated map built independently at the stop value."""
    o = sym(e=0.5)
    P = ImpactMap(o.pair, o.gains, o.reference())
    fam = P.family(name)
    br = continue_orbit(fam, fam.value, stop, o.fixed_point)
    assert br.termination == "reached stop" and br.parameter[-1] == stop
    v = {"kp": 10.0, "kv": 20.0, "e": 0.5, "mu": 0.1, "xm": o.xm, "omega": W, "L": 0.75}
    v[name] = stop
    Q = ImpactMap(ImpactPair(v["mu"], v["e"], v["L"]), PDGains(v["kp"], v["kv"]),
                  Reference(v["xm"], v["omega"]))
    s = br.points[-1]
    assert 0 <= s[0] < Q.period
    assert np.max(np.abs(_phase_diff(Q(s), s, Q.period))) < 1e-9


@pytest.mark.parametrize("name,stop", [("kp", 12.0), ("kv", 18.0), ("e", 0.7), ("mu", 0.15),
                                       ("omega", 4.5), ("L", 0.6), ("x10", 1.3)])
def test_every_symmetric_parameter_matches_symmetric_orbit(name, stop):
    br = continue_symmetric(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), W, name, stop,
                            max_steps=200)
    assert br.termination == "reached stop"
    v = {"kp": 10.0, "kv": 20.0, "e": 0.5, "mu": 0.1, "omega": W, "L": 0.75, "x10": 1.0}
    v[name] = stop
    o = symmetric_orbit(ImpactPair(v["mu"], v["e"], v["L"]), PDGains(v["kp"], v["kv"]),
                        v["omega"], x10=v["x10"])
    assert np.max(np.abs(br.points[-1] - o.fixed_point)) < 1e-12
    assert abs(br.xm[-1] - o.xm) < 1e-12 and br.stable[-1] == o.stable


@pytest.mark.parametrize("case", ["collocated", "noncollocated"])
@pytest.mark.parametrize("e", [0.1, 0.5, 0.9])
def test_symmetric_events_against_a_fine_grid(case, e):
    """Every sign change of rho - 1 and of the margin on a fine kv grid is matched by a
    located event, and vice versa (paper parameters, kp = 10)."""
    br = continue_symmetric(ImpactPair(0.1, e, 0.75), PDGains(10, 0.5), W, "kv", 40.0,
                            case=case)
    kv = np.linspace(0.5, 40.0, 20001)
    r = symmetric_orbits(10.0, kv, e=e, margin=True, omega=W, case=case, **PAPER)
    rho = np.where(r.exists, r.spectral_radius, np.nan)
    st = np.flatnonzero(np.diff(np.sign(rho - 1)) != 0)
    st = st[np.isfinite(rho[st]) & np.isfinite(rho[st + 1])]
    ex = np.flatnonzero(np.diff(r.exists.astype(int)))
    sc = [ev.parameter for ev in br.events_of("stability_change") if ev.viable]
    gr = [ev.parameter for ev in br.events_of("grazing")]
    assert len(sc) == st.size and len(gr) == ex.size
    for p, i in zip(sorted(sc), st):
        assert kv[i] <= p <= kv[i + 1]
    for p, i in zip(sorted(gr), ex):
        assert kv[i] <= p <= kv[i + 1]


def _central_differences(P, s, h=1e-7):
    """Hand-written central differences of P at s (phase differences wrapped)."""
    J = np.empty((4, 4))
    for j in range(4):
        d = np.zeros(4)
        d[j] = h * max(1.0, abs(s[j]))
        J[:, j] = _phase_diff(P(s + d), P(s - d), P.period) / (2 * d[j])
    return J


def test_impact_map_jacobian_is_an_array_with_named_blocks(period2):
    o = sym(e=0.5)
    P = ImpactMap(o.pair, o.gains, o.reference())
    J = P.jacobian(o.fixed_point)
    assert isinstance(J, np.ndarray) and J.shape == (4, 4)
    B = P.blocks(o.fixed_point)
    np.testing.assert_allclose(J, B.DP43 @ B.DP32 @ B.DP21 @ B.DP10, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(J, _central_differences(P, o.fixed_point), rtol=1e-5, atol=1e-6)
    # a return with a double impact: no named blocks, the map's DP is still an array
    Q, orb = period2
    s = next(x for x, w in zip(orb.orbit, orb.walls) if w != (-1, 1))
    with pytest.raises(ValueError, match="pattern"):
        Q.blocks(s)
    np.testing.assert_allclose(Q.jacobian(s), _central_differences(Q, s), rtol=1e-4,
                               atol=1e-5)
