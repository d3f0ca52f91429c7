"""General LTI controllers between impacts: orbits, impact map and DP against independent checks."""
import doctest
import importlib
import pkgutil

import control as ct
import numpy as np
import pytest

import hybridpd.pair.lti as lti_mod
from hybridpd import ImpactPair, PDGains
from hybridpd.loop import pd_controller
from hybridpd.pair.impactmap import ImpactMap
from hybridpd.pair.lti import (
    _chain_jacobian,
    filtered_pd,
    filtered_pid,
    lead_lag,
    lti_symmetric_orbit,
)
from hybridpd.pair.lti.flight import _FreeFlight, _full_state, _impact_full
from hybridpd.pair.orbits import symmetric_orbit, symmetric_orbits

CASES = ("collocated", "noncollocated")
PAIR = ImpactPair(mu=0.1, e=0.5, L=0.75)
W = 5.0


def pid2(kp, ki, kv):
    """Unfiltered PID on ``[err, err_dot]``: a 2-input controller with one (integrator) state."""
    return ct.ss([[0.0]], [[1.0, 0.0]], [[ki]], [[kp, kv]])


CONTROLLERS = {
    "filtered_pd": filtered_pd(10, 20, 0.01),
    "filtered_pid": filtered_pid(10, 2, 20, 0.01),
    "lead": lead_lag(10, 2.0, 0.05),
    "lead_lag": lead_lag(10, 1.0, 0.1, 1.0, 5.0),
    "pid_2input": pid2(10, 2, 20),
}


def phase_diff(a, b, T):
    d = np.asarray(a, float) - np.asarray(b, float)
    d[0] = (d[0] + 0.5 * T) % T - 0.5 * T
    return d


# ------------------------------------------------------------------------------------------
# PD through the general path = symbolic fast path
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("e,n", [(0.1, 1), (0.5, 1), (0.9, 1), (0.5, 3)])
def test_pd_as_python_control_system_matches_symbolic(case, e, n):
    pair = ImpactPair(0.1, e, 0.75)
    b = symmetric_orbit(pair, PDGains(10, 20), W, n=n, case=case)
    a = lti_symmetric_orbit(pair, pd_controller(10, 20), W, n=n, case=case)
    assert a.n_controller_states == 0
    assert a.code == (0 if b.exists else next(k for k, v in lti_mod.LTI_REASONS.items()
                                              if b.reason.startswith(v)))
    assert abs(a.xm - b.xm) <= 1e-9 * b.xm
    assert abs(phase_diff([a.phi0], [b.phi0], a.T)[0]) <= 1e-9 * a.T
    np.testing.assert_allclose(a.fixed_point, b.fixed_point, rtol=0, atol=1e-9)
    assert a.exists == b.exists
    if not b.exists:
        return
    scale = np.abs(b.DP).max()
    assert np.abs(a.DP - b.DP).max() <= 1e-9 * scale
    for k in ("DP10", "DP21", "DP32", "DP43"):
        assert np.abs(a.blocks[k] - b.blocks[k]).max() <= 1e-9 * max(1.0, np.abs(b.blocks[k]).max())
    assert np.abs(a.multipliers - b.multipliers).max() <= 1e-9 * b.spectral_radius
    assert a.spectral_radius == pytest.approx(b.spectral_radius, rel=1e-9)
    assert a.stable == b.stable and a.hyperbolic == b.hyperbolic
    assert a.viability_margin == pytest.approx(b.viability_margin, abs=1e-9)
    assert a.residual < 1e-12


@pytest.mark.parametrize("case", CASES)
def test_pd_existence_decisions_match_symbolic_over_gain_grid(case):
    kp = np.geomspace(0.5, 200, 5)
    kv = np.geomspace(0.5, 200, 5)
    for e in (0.0, 0.1, 0.9):
        r = symmetric_orbits(kp[None, :], kv[:, None], mu=0.1, e=e, L=0.75, omega=W, case=case)
        for i in range(kv.size):
            for j in range(kp.size):
                a = lti_symmetric_orbit(ImpactPair(0.1, e, 0.75), pd_controller(kp[j], kv[i]), W,
                                        case=case, margin=False)
                assert a.code == r.reason[i, j], (e, kp[j], kv[i], a.reason)
                if a.code == 3:   # where and when of the extra contact
                    assert a.violation["t"] == pytest.approx(r.violation_time[i, j], rel=1e-9)
                    assert a.violation["wall"] == r.violation_wall[i, j]
                    assert "wall" in a.reason and a.stable is None
                if a.exists:
                    assert a.spectral_radius == pytest.approx(r.spectral_radius[i, j], rel=1e-9)


# ------------------------------------------------------------------------------------------
# Filtered PD -> PD as tf -> 0
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("case", CASES)
def test_filtered_pd_converges_to_pd_linearly_in_tf(case):
    pd = symmetric_orbit(PAIR, PDGains(10, 20), W, case=case)
    tfs = (1e-3, 5e-4, 2.5e-4)
    orbs = [lti_symmetric_orbit(PAIR, filtered_pd(10, 20, tf), W, case=case, margin=False)
            for tf in tfs]
    assert all(o.exists and o.n_controller_states == 1 for o in orbs)
    err_xm = np.array([o.xm - pd.xm for o in orbs])
    err_rho = np.array([o.spectral_radius - pd.spectral_radius for o in orbs])
    err_phi = np.array([phase_diff([o.phi0], [pd.phi0], pd.T)[0] for o in orbs])
    for err in (err_xm, err_rho, err_phi):
        # O(tf): halving tf halves the error (observed order log2(ratio) = 1). The O(tf^2)
        # term makes the ratio 2 (1 + c tf): its distance to 2 shrinks with tf.
        ratios = err[:-1] / err[1:]
        assert np.all(np.abs(np.log2(ratios) - 1.0) < 0.03), ratios
        assert abs(ratios[1] - 2.0) <= abs(ratios[0] - 2.0) + 1e-3, ratios
    # the limit: error constants are modest compared with the quantities themselves
    assert abs(err_xm[-1]) < 1e-2 * pd.xm
    assert abs(err_rho[-1]) < 1e-2 * pd.spectral_radius
    assert all(o.stable == pd.stable for o in orbs)


# ------------------------------------------------------------------------------------------
# DP by implicit differentiation against finite differences of the simulated map
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("name", sorted(CONTROLLERS))
def test_DP_against_finite_differences_of_simulated_map(case, name):
    o = lti_symmetric_orbit(PAIR, CONTROLLERS[name], W, case=case, fd_check=True)
    assert o.exists
    assert o.DP.shape == (4 + o.n_controller_states,) * 2
    assert o.DP_fd_error < 1e-6, o.DP_fd_error
    # the general map's saltation Jacobian agrees with the orbit's (implicit differentiation)
    J = o.section_map().jacobian(o.fixed_point)
    sc = o.coordinate_scale()
    scaled = lambda M: M * sc[None, :] / sc[:, None]
    assert np.abs(scaled(J - o.DP)).max() <= 1e-7 * np.abs(scaled(o.DP)).max()


@pytest.mark.parametrize("case", CASES)
def test_DP_off_the_orbit_against_finite_differences(case):
    """Implicit differentiation at a general section point (flight times != n T / 2), along
    the contacts the general map locates, against finite differences of that map."""
    o = lti_symmetric_orbit(PAIR, filtered_pd(10, 20, 0.05), W, case=case)
    P = o.section_map()
    sc = o.coordinate_scale()
    rng = np.random.default_rng(3)
    s = o.fixed_point + 0.02 * sc * rng.normal(size=sc.size)
    r = P.apply(s)
    assert r.ok and r.signature == (("wall+", "crossing"), ("wall-", "crossing"))
    taus = np.diff([r.jumps[0][0], r.jumps[1][0], r.t_hit])
    assert not np.allclose(taus, o.tau)
    z0 = _full_state(s, 1, PAIR.L, o.xm, o.omega)
    flight = _FreeFlight(o.loop, 10_000)
    J = _chain_jacobian(o.loop.A, _impact_full(PAIR, o.loop.n_states), flight.gap, z0, (-1, 1),
                        taus, o.omega).DP
    Jfd = P.jacobian_fd(s, h=1e-5, scale=sc, richardson=True)
    scaled = lambda M: M * sc[None, :] / sc[:, None]
    assert np.abs(scaled(J - Jfd)).max() <= 1e-6 * np.abs(scaled(J)).max()


def test_jacobian_blocks_compose():
    o = lti_symmetric_orbit(PAIR, CONTROLLERS["filtered_pid"], W)
    B = o.blocks
    np.testing.assert_allclose(B["DP43"] @ B["DP32"] @ B["DP21"] @ B["DP10"], o.DP,
                               rtol=0, atol=1e-12 * np.abs(o.DP).max())
    # the impact blocks keep phase, positions and controller states; reverse z4 by -e
    D = B["DP10"]
    assert D[3, 3] == pytest.approx(-PAIR.e)
    assert np.allclose(D[np.ix_([0, 1, 4, 5], [0, 1, 4, 5])], np.eye(4))


# ------------------------------------------------------------------------------------------
# Fixed point, simulation and measured contraction
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("name", sorted(CONTROLLERS))
def test_fixed_point_returns_under_simulated_map(case, name):
    o = lti_symmetric_orbit(PAIR, CONTROLLERS[name], W, case=case)
    P = o.section_map()
    r = P.apply(o.fixed_point)
    assert r.ok and r.signature == (("wall+", "crossing"), ("wall-", "crossing"))
    assert not r.grazing
    # rounding of the fixed point (~1e-16) is amplified by the unstable non-collocated
    # multipliers (~3e3) before the second flight ends
    np.testing.assert_allclose(np.diff([r.jumps[0][0], r.jumps[1][0], r.t_hit]),
                               [o.tau, o.tau], rtol=1e-10)
    d = phase_diff(r.s, o.fixed_point, o.T) / np.maximum(1.0, np.abs(o.fixed_point))
    assert np.abs(d).max() < 1e-10
    # the state at the return is the +L pre-impact state: the orbit closes (incl. controller)
    np.testing.assert_allclose(r.z_hit, o.state_plus, rtol=0, atol=1e-9)


def test_pd_fixed_point_agrees_with_batch_impact_map():
    o = lti_symmetric_orbit(PAIR, pd_controller(10, 20), W)
    Pb = ImpactMap(PAIR, PDGains(10, 20), o.reference())
    s = o.fixed_point + np.array([1e-3, 2e-3, -1e-2, 3e-2])
    np.testing.assert_allclose(o.section_map()(s), Pb(s), rtol=0, atol=1e-11)


def test_simulation_with_controlled_impact_pair_stays_on_stable_orbit():
    o = lti_symmetric_orbit(PAIR, CONTROLLERS["filtered_pid"], W)
    assert o.exists and o.stable
    sysm = o.system()
    tr = sysm.simulate(o.pre_plus, (o.t0, o.t0 + 40 * o.tau + 0.5 * o.tau),
                       controller_state=o.controller_state)
    assert tr.termination.name == "END_TIME" and tr.n_impacts == 41
    k = np.arange(tr.n_impacts)
    sign = np.where(k % 2 == 0, 1.0, -1.0)
    np.testing.assert_array_equal(tr.walls, sign.astype(int))
    np.testing.assert_allclose(tr.impact_times, o.t0 + k * o.tau, rtol=0, atol=1e-10)
    np.testing.assert_allclose(tr.pre, sign[:, None] * o.pre_plus, rtol=0, atol=1e-10)
    # controller state at the last impact
    c_last = tr(tr.impact_times[-1])[6:]
    np.testing.assert_allclose(c_last, sign[-1] * o.controller_state, rtol=0,
                               atol=1e-10 * max(1.0, np.abs(o.controller_state).max()))


def test_spectral_radius_against_iterated_perturbations():
    o = lti_symmetric_orbit(PAIR, CONTROLLERS["filtered_pd"], W)
    assert o.stable and abs(o.multipliers[0].imag) == 0      # a real dominant multiplier
    sc = o.coordinate_scale()
    P = o.section_map()
    rng = np.random.default_rng(5)
    traj = P.iterate(o.fixed_point + 1e-4 * sc * rng.normal(size=sc.size), 20)
    d = traj - o.fixed_point
    d[:, 0] = (d[:, 0] + 0.5 * o.T) % o.T - 0.5 * o.T
    dist = np.linalg.norm(d / sc, axis=1)
    # the second multiplier is |.| ~ 0.14: after 6 iterations the dominant one rules
    rate = (dist[20] / dist[8]) ** (1 / 12)
    assert rate == pytest.approx(o.spectral_radius, rel=2e-3)


def test_lead_lag_stabilises_noncollocated_orbit_in_simulation():
    """The PD (10, 20) orbit is unstable non-collocated (rho ~ 5e3); this lead-lag's is stable:
    a perturbed start converges to it in the hybrid-automaton simulation."""
    o = lti_symmetric_orbit(PAIR, CONTROLLERS["lead_lag"], W, case="noncollocated")
    assert o.exists and o.stable and o.spectral_radius < 0.6
    x0 = o.pre_plus + np.array([0.0, 0.02, 0.01, -0.05])
    x0[0] = x0[2] + PAIR.L                          # start on the +L wall
    tr = o.system().simulate(x0, (o.t0, o.t0 + 60 * o.T), controller_state=o.controller_state)
    plus = np.flatnonzero(tr.walls == 1)
    dist = np.abs(tr.pre[plus] - o.pre_plus).max(axis=1)
    assert dist[0] > 1e-2 and dist[-1] < 1e-12
    np.testing.assert_allclose(np.diff(tr.impact_times[plus])[-5:], o.T, rtol=1e-12)


def test_unstable_noncollocated_multiplier_measured():
    o = lti_symmetric_orbit(PAIR, CONTROLLERS["lead"], W, case="noncollocated")
    assert o.exists and not o.stable
    P = o.section_map()
    sc = o.coordinate_scale()
    d0 = 1e-12 * sc
    traj = P.iterate(o.fixed_point + d0, 3)
    d = traj - o.fixed_point
    dist = np.linalg.norm(d / sc, axis=1)
    assert dist[3] / dist[2] == pytest.approx(o.spectral_radius, rel=1e-2)


# ------------------------------------------------------------------------------------------
# Controllers and validation
# ------------------------------------------------------------------------------------------
def test_controller_constructors():
    s = np.array([0.3j, 1j, 7j, 50j])
    C = filtered_pd(10, 20, 0.01)
    np.testing.assert_allclose(C(s), 10 + 20 * s / (0.01 * s + 1), rtol=1e-13)
    C = filtered_pid(10, 2, 20, 0.01)
    np.testing.assert_allclose(C(s), 10 + 2 / s + 20 * s / (0.01 * s + 1), rtol=1e-13)
    C = lead_lag(10, 2.0, 0.05, 0.5, 2.0)
    np.testing.assert_allclose(C(s), 10 * (2 * s + 1) / (0.05 * s + 1) * (0.5 * s + 1)
                               / (2 * s + 1), rtol=1e-13)
    np.testing.assert_allclose(lead_lag(10, 2.01, 0.01)(s), filtered_pd(10, 20, 0.01)(s),
                               rtol=1e-13)
    for sys in (filtered_pd(1, 1, 1), filtered_pid(1, 1, 1, 1), lead_lag(1, 2, 1)):
        assert sys.input_labels == ["err"] and sys.output_labels == ["u_fb"]
    # a filtered PD expressed as a lead gives the same orbit
    a = lti_symmetric_orbit(PAIR, lead_lag(10, 2.01, 0.01), W)
    b = lti_symmetric_orbit(PAIR, filtered_pd(10, 20, 0.01), W)
    assert a.xm == pytest.approx(b.xm, rel=1e-12)
    assert a.spectral_radius == pytest.approx(b.spectral_radius, rel=1e-9)


@pytest.mark.parametrize("make,match", [
    (lambda: lti_symmetric_orbit(PAIR, ct.tf([20.0, 10.0], [1.0]), W), "proper"),
    (lambda: lti_symmetric_orbit(PAIR, ct.tf([1.0, 1.0, 1.0], [1.0, 2.0]), W), "proper"),
    (lambda: lti_symmetric_orbit(PAIR, ct.tf([1.0], [1.0, 0.5], dt=0.1), W), "continuous"),
    (lambda: lti_symmetric_orbit(PAIR, ct.ss([[-1.0]], [[1.0]], [[1.0], [1.0]], [[0.0], [0.0]]),
                                 W), "output"),
    (lambda: lti_symmetric_orbit(PAIR, ct.ss([[-1.0]], [[1.0, 1.0, 1.0]], [[1.0]],
                                             [[0.0, 0.0, 0.0]]), W), "inputs"),
    (lambda: lti_symmetric_orbit(PAIR, np.eye(2), W), "controller"),
    (lambda: lti_symmetric_orbit(PAIR, filtered_pd(10, 20, 0.01), W, n=2), "odd"),
    (lambda: lti_symmetric_orbit(PAIR, filtered_pd(10, 20, 0.01), W, n=0), "odd"),
    (lambda: lti_symmetric_orbit(PAIR, filtered_pd(10, 20, 0.01), -1.0), "omega"),
    (lambda: lti_symmetric_orbit(PAIR, filtered_pd(10, 20, 0.01), W, x10=0.0), "x10"),
    (lambda: lti_symmetric_orbit("pair", filtered_pd(10, 20, 0.01), W), "pair"),
    (lambda: filtered_pd(10, 20, 0.0), "tf"),
    (lambda: filtered_pd(-1, 20, 0.1), "kp"),
    (lambda: filtered_pid(10, 0.0, 20, 0.1), "ki"),
    (lambda: lead_lag(10, 0.1, 0.2), "lead"),
    (lambda: lead_lag(10, 2.0, 0.1, 1.0, 0.5), "lag"),
    (lambda: lead_lag(10, 2.0, 0.1, 1.0), "together"),
])
def test_bad_input_raises_value_error_naming_it(make, match):
    with pytest.raises(ValueError, match=match):
        make()


def test_section_map_validation():
    o = lti_symmetric_orbit(PAIR, filtered_pd(10, 20, 0.01), W)
    P = o.section_map()
    assert P.dim == 5
    with pytest.raises(ValueError, match="shape"):
        P(o.fixed_point[:4])
    with pytest.raises(ValueError, match="finite"):
        P(np.full(5, np.nan))
    with pytest.raises(ValueError, match="max_jumps"):
        o.section_map(max_jumps=0)
    with pytest.raises(ValueError, match="scale"):
        P.jacobian_fd(o.fixed_point, scale=np.ones(4))


def test_sticking_and_singular_reports():
    # e = 0 with the collocated PD: zero rebound and the force presses -> code 4
    a = lti_symmetric_orbit(ImpactPair(0.1, 0.0, 0.75), filtered_pd(10, 20, 0.01), W)
    assert not a.exists and a.code == 4 and "stick" in a.reason and a.DP is None
    assert a.to_dict()["exists"] is False


def test_result_helpers_and_json():
    o = lti_symmetric_orbit(PAIR, CONTROLLERS["lead_lag"], W, x10=0.8)
    assert o.exists and o.n_controller_states == 2
    z = o.flight(np.array([o.t0, o.t0 + o.tau]))
    assert z.shape == (2, 8)
    np.testing.assert_allclose(z[1], -o.state_plus, atol=1e-11)
    d = o.to_dict()
    assert d["n_controller_states"] == 2 and len(d["fixed_point"]) == 6
    assert d["multipliers"] is not None and d["stable"] is True
    assert o.reference().xm == o.xm


def test_module_doctests():
    mods = [lti_mod] + [importlib.import_module(f"{lti_mod.__name__}.{m.name}")
                        for m in pkgutil.iter_modules(lti_mod.__path__)]
    assert len(mods) >= 4
    res = [doctest.testmod(m, optionflags=doctest.ELLIPSIS) for m in mods]
    assert sum(r.failed for r in res) == 0 and sum(r.attempted for r in res) > 5


@pytest.mark.slow
@pytest.mark.parametrize("case", CASES)
def test_filtered_pd_rate_down_to_tiny_filters(case):
    pd = symmetric_orbit(PAIR, PDGains(10, 20), W, case=case)
    tfs = np.array([1e-3, 1e-4, 1e-5])
    err = np.array([lti_symmetric_orbit(PAIR, filtered_pd(10, 20, tf), W, case=case,
                                        margin=False).xm - pd.xm for tf in tfs])
    slope = np.diff(np.log(np.abs(err))) / np.diff(np.log(tfs))
    assert np.all(np.abs(slope - 1.0) < 0.01)


@pytest.mark.slow
def test_example_script(tmp_path):
    # the full (not --quick) run; the example imports _out from examples/, so it runs as a
    # script with this checkout first on PYTHONPATH, like tests/test_examples.py
    import os
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    path = os.pathsep.join(filter(None, [str(root), os.environ.get("PYTHONPATH")]))
    r = subprocess.run([sys.executable, str(root / "examples" / "design" / "plot_filtered_pd.py"),
                        "--out", str(tmp_path)], check=False, cwd=tmp_path, capture_output=True,
                       text=True, env=dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=path),
                       timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    out = tmp_path / "filtered_pd.png"
    assert out.exists() and out.stat().st_size > 10_000
