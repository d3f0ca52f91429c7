"""Gain design: designed gains re-checked independently (fresh orbit, simulated impact map)."""
import json
import math

import numpy as np
import pytest

from hybridpd import ImpactPair, PDGains, Reference
from hybridpd.pair.design import (
    InfeasibleDesignError,
    design,
    design_objective,
    robustness,
    robustness_comparison,
    shifted_amplitude,
    shifted_orbit,
)
from hybridpd.pair.impactmap import ImpactMap
from hybridpd.pair.orbits import symmetric_orbit, symmetric_orbits

CASES = ("collocated", "noncollocated")
PAPER = dict(mu=0.1, e=0.5, gamma=0.75, omega=5.0)
BOX = dict(e_range=(0.3, 0.7), mu_range=(0.08, 0.12))
L = 0.75


def wrap_phase(d, T):
    d = np.array(d, float)
    d[..., 0] = (d[..., 0] + 0.5 * T) % T - 0.5 * T
    return d


@pytest.fixture(scope="module", params=CASES)
def nominal(request):
    return design(request.param, grid=(32, 32), **PAPER)


@pytest.fixture(scope="module", params=CASES)
def robust(request):
    return design(request.param, grid=(32, 32), **PAPER, **BOX)


# --------------------------------------------------------------------------- nominal design


def test_nominal_design_recomputed_independently(nominal):
    d = nominal
    pair = ImpactPair(0.1, 0.5, L)
    o = symmetric_orbit(pair, PDGains(d.kp, d.kv), 5.0, x10=1.0, n=1, case=d.case)
    assert o.exists and o.stable and o.hyperbolic
    assert o.spectral_radius == pytest.approx(d.spectral_radius, rel=1e-10)
    assert d.stability_margin == pytest.approx(1 - o.spectral_radius, rel=1e-10)
    assert o.viability_margin == pytest.approx(d.viability_margin, abs=1e-12)
    assert o.xm == pytest.approx(d.xm, rel=1e-12)
    assert o.phi0 == pytest.approx(d.phi0, rel=1e-12)
    # the objective (min of the two margins) is what was reported
    assert d.objective == pytest.approx(min(1 - o.spectral_radius, o.viability_margin))
    # inside the gain box
    assert 0.1 <= d.kp <= 100 and 0.1 <= d.kv <= 100


def test_nominal_design_converges_in_the_simulated_map(nominal):
    d = nominal
    o = d.orbit
    P = ImpactMap(o.pair, o.gains, Reference(d.xm, 5.0), d.case)
    assert np.abs(wrap_phase(P(o.fixed_point) - o.fixed_point, P.period)).max() < 1e-10
    s0 = o.fixed_point + np.array([1e-3, -1e-3, 2e-3, 1e-3])
    traj = P.iterate(s0, 200)
    assert np.all(np.isfinite(traj))
    dist = np.abs(wrap_phase(traj - o.fixed_point, P.period)).max(axis=1)
    assert dist[-1] < 1e-10
    # the contraction is not slower than the spectral radius says (asymptotically)
    k = int(np.argmax(dist < 1e-9)) or len(dist) - 1
    rate = (dist[k] / dist[0]) ** (1 / k)
    assert rate <= d.spectral_radius * 1.5 + 0.05


def test_design_is_at_least_as_good_as_the_searched_grid(nominal):
    d = nominal
    m = d.design_map
    assert m.objective.shape == (32, 32)
    assert d.objective >= np.nanmax(m.objective) - 1e-12
    # the optimiser report: refined seeds, best first, each not worse than its seed
    assert len(d.optimizer) >= 1
    assert d.optimizer[0].objective == pytest.approx(d.objective, rel=1e-9)
    for run in d.optimizer:
        assert run.objective >= run.start_objective - 1e-12
        assert run.nfev > 0
    # the map agrees with the vectorised orbit solver
    r = symmetric_orbits(m.kp[None, :], m.kv[:, None], mu=0.1, e=0.5, L=L, omega=5.0,
                         case=d.case)
    assert np.array_equal(r.stable, m.stable)


def test_noncollocated_stability_margin_is_capped_by_restitution():
    # det DP = e^4 for the non-collocated loop (the flow has zero trace), so rho >= e
    for e in (0.3, 0.5):
        d = design("noncollocated", mu=0.1, e=e, gamma=0.75, omega=5.0, grid=(24, 24),
                   n_starts=1)
        assert np.linalg.det(d.orbit.DP) == pytest.approx(e**4, rel=1e-8)
        assert d.spectral_radius >= e - 1e-9
        assert d.spectral_radius == pytest.approx(e, abs=5e-3)


def test_linear_spacing_sum_objective_and_other_spec():
    d = design("collocated", mu=0.2, e=0.8, L=0.5, x10=0.8, m2=2.0, omega=3.0, n=1,
               kp_range=(1, 30), kv_range=(1, 30), grid=(16, 16), spacing="linear",
               objective="sum", viability_weight=0.1, n_starts=2)
    o = symmetric_orbit(ImpactPair(0.2, 0.8, 0.5, 2.0), d.gains, 3.0, x10=0.8, n=1,
                        case="collocated")
    assert o.exists and o.stable
    assert d.objective == pytest.approx((1 - o.spectral_radius) + 0.1 * o.viability_margin)
    assert np.allclose(np.diff(d.design_map.kp), np.diff(d.design_map.kp)[0])
    assert 1 <= d.kp <= 30 and 1 <= d.kv <= 30
    assert d.spec["gamma"] == pytest.approx(0.5 / 0.8)


def test_viability_margin_enters_the_objective():
    # mu = 1: every stable orbit has a turning point of z3 near the wall (nu < 1)
    spec = dict(mu=1.0, e=0.5, gamma=0.75, omega=5.0, grid=(24, 24), n_starts=2)
    d = design("collocated", **spec)
    assert d.viability_margin < 1
    # the min objective balances the two margins at the optimum
    assert d.stability_margin == pytest.approx(d.viability_margin, abs=0.02)
    # ignoring grazing drives the design to the existence boundary
    g = design("collocated", objective="sum", viability_weight=0.0, **spec)
    assert g.viability_margin < 0.05 < d.viability_margin
    assert g.stability_margin > d.stability_margin
    o = symmetric_orbit(ImpactPair(1.0, 0.5, L), d.gains, 5.0, case="collocated")
    assert o.viability_margin == pytest.approx(d.viability_margin, abs=1e-12)


# --------------------------------------------------------------------------- JSON


def test_to_dict_nominal_and_robust(nominal, robust):
    dn = nominal.to_dict()
    json.dumps(dn)
    for k in ("kp", "kv", "xm", "phi0", "spectral_radius", "viability_margin"):
        assert isinstance(dn[k], float)
    assert dn["robust"] is False and "worst_case" not in dn
    dr = robust.to_dict()
    json.dumps(dr)
    assert dr["robust"] is True
    assert set(dr["worst_case"]) == {"e", "mu"}
    assert dr["worst_spectral_radius"] == pytest.approx(robust.robust.worst_spectral_radius)
    assert dr["e_range"] == [0.3, 0.7] and dr["mu_range"] == [0.08, 0.12]


# --------------------------------------------------------------------------- robust design


def test_shifted_amplitude_at_the_nominal_plant():
    xm = float(symmetric_orbits(10, 20, mu=0.1, e=0.5, L=L, omega=5.0).xm)
    x, alt = shifted_amplitude(10, 20, xm, mu=0.1, e=0.5, L=L, omega=5.0)
    assert x == pytest.approx(1.0, abs=1e-10)
    # the other root realises the same xm
    if np.isfinite(alt):
        assert float(symmetric_orbits(10, 20, mu=0.1, e=0.5, L=L, omega=5.0, x10=alt).xm) == \
            pytest.approx(xm, rel=1e-9)


def _check_plant(d, e, mu):
    """Independent check of one plant: simulate with the designed gains and xm."""
    pair = ImpactPair(mu, e, L)
    pred = shifted_orbit(pair, d.gains, d.xm, 5.0, x10_nominal=1.0, case=d.case)
    assert pred is not None and pred.exists and pred.stable
    P = ImpactMap(pair, d.gains, Reference(d.xm, 5.0), d.case)
    T = P.period
    # from near the predicted fixed point ...
    traj = P.iterate(pred.fixed_point + np.array([2e-3, 1e-3, -2e-3, 1e-3]), 400)
    end = traj[-1]
    assert np.abs(wrap_phase(end - pred.fixed_point, T)).max() < 1e-8
    # ... and from the nominal orbit's fixed point: the plant settles on the predicted orbit
    traj = P.iterate(d.orbit.fixed_point, 400)
    assert np.abs(wrap_phase(traj[-1] - pred.fixed_point, T)).max() < 1e-8
    # the primary mass hits at x1 = x2 + L: its amplitude, from the simulation
    x10_sim = end[1] + L
    assert abs(x10_sim - 1.0) <= d.robust.x10_tol + 1e-7
    assert pred.xm == pytest.approx(d.xm, rel=1e-9)
    return pred


def test_robust_design_holds_at_corners_and_random_points(robust):
    d = robust
    assert d.robust.ok and d.orbit.stable
    rng = np.random.default_rng(7)
    points = [(e, mu) for e in (0.3, 0.7) for mu in (0.08, 0.12)]
    points += [(rng.uniform(0.3, 0.7), rng.uniform(0.08, 0.12)) for _ in range(4)]
    worst = 0.0
    for e, mu in points:
        worst = max(worst, _check_plant(d, e, mu).spectral_radius)
    assert worst <= d.robust.worst_spectral_radius + 1e-9
    # the reported worst case is where the reported worst objective happens
    wc = d.robust.worst_case
    o = shifted_orbit(ImpactPair(wc["mu"], wc["e"], L), d.gains, d.xm, 5.0, case=d.case)
    assert d.robust.worst_objective == pytest.approx(
        min(1 - o.spectral_radius, o.viability_margin), rel=1e-9)
    assert d.objective == pytest.approx(d.robust.worst_objective)
    assert d.validation is not None and d.validation.ok


def test_robust_report_grid_and_robustness_function(robust):
    d = robust
    rep = robustness(d.case, d.kp, d.kv, d.xm, **PAPER, **BOX)
    assert rep.ok
    assert rep.e_values.tolist() == pytest.approx([0.3, 0.4, 0.5, 0.6, 0.7])
    assert rep.spectral_radius.shape == (5, 5)
    assert np.all(rep.x10_error <= rep.x10_tol)
    assert rep.worst_spectral_radius == pytest.approx(np.max(rep.spectral_radius))
    json.dumps(rep.to_dict())


def test_nominal_gains_are_not_robust_to_the_box(nominal):
    # what the paper's closing remark is about: gains tuned on the nominal plant
    rep = robustness(nominal.case, nominal.kp, nominal.kv, nominal.xm, **PAPER, **BOX)
    assert not rep.ok
    assert rep.failures()


# --------------------------------------------------------------------------- failures


def test_infeasible_box_raises_with_closest_miss():
    # around the paper's (kp, kv) = (10, 20) the non-collocated orbit exists (mostly) but is
    # unstable: nothing to choose from
    box = dict(kp_range=(10, 20), kv_range=(15, 25))
    r = symmetric_orbits(np.geomspace(10, 20, 8)[None, :], np.geomspace(15, 25, 8)[:, None],
                         mu=0.1, e=0.5, L=L, omega=5.0, case="noncollocated")
    assert np.any(r.exists) and not np.any(r.stable)
    with pytest.raises(InfeasibleDesignError) as info:
        design("noncollocated", grid=(8, 8), **PAPER, **box)
    err = info.value
    assert isinstance(err, RuntimeError)
    assert "no existing, stable" in str(err)
    assert sum(err.reason_counts.values()) == 64
    assert err.reason_counts["exists but unstable"] == int(r.exists.sum())
    assert err.closest["spectral_radius"] >= 1
    assert err.closest["spectral_radius"] == pytest.approx(
        np.nanmin(np.where(r.exists, r.spectral_radius, np.nan)))
    assert err.design_map.objective.shape == (8, 8)
    assert np.all(err.design_map.objective <= 0)


def test_infeasible_nothing_exists():
    # e = 0.9, high gains: viability fails everywhere (extra contact between the impacts)
    with pytest.raises(InfeasibleDesignError) as info:
        design("noncollocated", mu=0.1, e=0.9, gamma=0.75, omega=5.0, kp_range=(50, 100),
               kv_range=(50, 100), grid=(6, 6))
    err = info.value
    assert err.closest is None
    assert list(err.reason_counts.values()) == [36]
    assert "viability" in str(err)


def test_robust_infeasible_raises_with_worst_case():
    with pytest.raises(InfeasibleDesignError) as info:
        design("collocated", grid=(12, 12), n_starts=1, x10_tol=0.001, **PAPER, **BOX)
    err = info.value
    assert "x10_tol" in str(err)
    assert err.closest is not None and "worst_case" in err.closest
    assert any(k.startswith("robust:") for k in err.reason_counts)


@pytest.mark.parametrize("kwargs, name", [
    (dict(mu=-1), "mu"),
    (dict(e=1.5), "e"),
    (dict(omega=0), "omega"),
    (dict(gamma=-0.5), "gamma"),
    (dict(L=0.75), "gamma"),               # both L and gamma
    (dict(x10=0), "x10"),
    (dict(m2=-2), "m2"),
    (dict(n=2), "n"),
    (dict(case="sideways"), "case"),
    (dict(kp_range=(10, 1)), "kp_range"),
    (dict(kv_range=(0, 1)), "kv_range"),
    (dict(kp_range=5), "kp_range"),
    (dict(grid=(1, 5)), "grid"),
    (dict(spacing="cubic"), "spacing"),
    (dict(viability_weight=-1), "viability_weight"),
    (dict(viability_weight=0), "viability_weight"),
    (dict(objective="max"), "objective"),
    (dict(e_range=(0.6, 0.7)), "e_range"),
    (dict(e_range=(0.3, 1.2)), "e_range"),
    (dict(mu_range=(-1, 0.2)), "mu_range"),
    (dict(mu_range=(0.05, 0.2), uncertainty_grid=(5, 1)), "uncertainty_grid"),
    (dict(mu_range=(0.05, 0.2), x10_tol=0), "x10_tol"),
    (dict(n_starts=0), "n_starts"),
    (dict(maxiter=1.5), "maxiter"),
])
def test_bad_input_names_the_parameter(kwargs, name):
    spec = dict(case="collocated", grid=(4, 4), **PAPER)
    spec.update(kwargs)
    case = spec.pop("case")
    with pytest.raises(ValueError, match=name):
        design(case, **spec)


def test_robustness_bad_input():
    with pytest.raises(ValueError, match="e_range"):
        robustness("collocated", 10, 20, 0.4, **PAPER)
    with pytest.raises(ValueError, match="xm"):
        robustness("collocated", 10, 20, -0.4, **PAPER, **BOX)
    with pytest.raises(ValueError, match="kp"):
        robustness("collocated", 0, 20, 0.4, **PAPER, **BOX)


def test_design_objective_sign_is_feasibility():
    assert design_objective(True, True, 0.3, 0.9) == pytest.approx(0.7)
    assert design_objective(True, True, 0.3, 0.2) == pytest.approx(0.2)
    assert design_objective(True, True, 0.3, 0.2, viability_weight=2) == pytest.approx(0.4)
    assert design_objective(True, True, 0.3, 0.2, objective="sum") == pytest.approx(0.9)
    assert design_objective(True, False, 1.5, 1.0) == pytest.approx(-0.5)
    assert design_objective(False, False, np.nan, -0.2) == pytest.approx(-1.2)
    assert design_objective(False, False, np.nan, np.nan) == pytest.approx(-3)
    J = design_objective([True, False], [True, False], [0.5, np.nan], [1.0, -0.1])
    assert J.shape == (2,) and J[0] > 0 > J[1]
    with pytest.raises(ValueError, match="objective"):
        design_objective(True, True, 0.5, 1.0, objective="max")


# --------------------------------------------------------------------------- slow


@pytest.mark.slow
def test_robustness_comparison_table():
    cmp = robustness_comparison(grid=(32, 32))
    rows = {r.case: r for r in cmp.rows}
    col, non = rows["collocated"], rows["noncollocated"]
    # existence and stability alone: the collocated region is much larger and more robust
    assert col.nominal_fraction > 2 * non.nominal_fraction
    assert col.robust_stable_fraction > 2 * non.robust_stable_fraction
    for r in cmp.rows:
        assert r.robust_fraction <= r.robust_stable_fraction <= r.nominal_fraction + 1e-12
        if r.robust is not None:
            assert r.robust.robust.ok
    text = cmp.to_text()
    assert "collocated" in text and "noncollocated" in text
    json.dumps(cmp.to_dict())


@pytest.mark.slow
@pytest.mark.parametrize("case", CASES)
def test_robust_design_dense_check(case):
    d = design(case, **PAPER, **BOX)
    for e in np.linspace(0.3, 0.7, 7):
        for mu in np.linspace(0.08, 0.12, 4):
            _check_plant(d, e, mu)


@pytest.mark.slow
@pytest.mark.parametrize("case", CASES)
def test_other_orders_and_frequencies(case):
    for n, omega in ((3, 5.0), (1, 2.0)):
        try:
            d = design(case, mu=0.1, e=0.5, gamma=0.75, omega=omega, n=n, grid=(24, 24))
        except InfeasibleDesignError:
            continue
        o = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), d.gains, omega, n=n, case=case)
        assert o.exists and o.stable
        assert math.isclose(o.spectral_radius, d.spectral_radius, rel_tol=1e-10)
