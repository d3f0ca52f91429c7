"""Sampled-data orbits: Floquet multipliers against an independent stroboscopic period map.

The reference below is written here from the model's equations, with nothing of the package:
the impact pair's plant (a free mass in the slot of a mass pushed by the force) flows in
closed form between the sampling instants ``t_k = k dt`` under the held force ``u_k``; impacts on the
clearance are located by bracketing and ``scipy.optimize.brentq`` and apply Newton's law in the
metric of ``M``; at every sample the controller reads the tracking error and updates its
states (PD: none; PID: the integral and the filtered derivative, discretised exactly). The
stroboscopic period map takes the plant and controller state just before the sample at
``t = 0 (mod T)`` to the state just before the sample one period later; its fixed point is
found by Newton's method with central differences, and its multipliers are the eigenvalues of
the central-difference Jacobian there.
"""
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from hybridpd.analysis.model_orbits import orbit_from_model
from hybridpd.mechanics.modelfile import model_from_dict
from hybridpd.mechanics.sections import mechanical_section

OMEGA = 5.0
T = 2 * math.pi / OMEGA
XM = 0.3985841681159091          # the continuous loop's symmetric orbit at kp = 10, kv = 20
MASSES = (0.1, 1.0)
L, E = 0.75, 0.5


def _model(controller, dt=None):
    ctrl = dict(controller, measure="x2")
    if dt:
        ctrl["dt"] = dt
    return model_from_dict({
        "system": {"dofs": ["x1", "x2"], "masses": list(MASSES), "input": [0.0, 1.0]},
        "contact": [{"between": ["x1", "x2"], "lo": -L, "hi": L, "restitution": E}],
        "controller": ctrl,
        "reference": {"type": "sine", "amplitude": XM, "omega": OMEGA, "feedforward_mass": 1.0},
        "initial": {"q": [0.3, 0.0], "v": [0.5, 0.0]}})


class _StroboscopicMap:
    """The sampled loop of the impact pair written from its equations (module docstring)."""

    def __init__(self, controller, n_samples):
        self.g = {k: float(controller.get(k, 0.0)) for k in ("kp", "kv", "ki", "kd",
                                                            "filter_time")}
        self.pid = controller["type"] == "pid"
        self.N = n_samples
        self.dt = T / n_samples
        m1, m2 = MASSES
        # state [x1, y1, x2, y2, 1]: the last entry carries the held force
        self.minv_w = np.array([1 / m1, -1 / m2])          # M^-1 w, w = [1, -1]
        self.w_minv_w = 1 / m1 + 1 / m2

    def _flow(self, x, u, tau):
        # the free mass flies, the secondary mass moves under the held force u
        a = u / MASSES[1]
        return np.array([x[0] + x[1] * tau, x[1], x[2] + x[3] * tau + 0.5 * a * tau * tau,
                         x[3] + a * tau])

    def _interval(self, x, u, t_len):
        """Flow over ``t_len`` under the held force ``u``, with every impact on the way."""
        t = 0.0
        for _ in range(1000):
            def gap(tau, x=x):
                y = self._flow(x, u, tau)
                return y[0] - y[2]

            grid = np.linspace(t, t_len, 33)
            vals = [gap(tau - t) for tau in grid]
            hit = None
            for i in range(1, len(grid)):
                for bound in (L, -L):
                    # from inside (|gap| < L) to the wall or beyond: a state that starts on
                    # the wall after an impact moves inward and is no crossing
                    if bound * (vals[i - 1] - bound) < 0 <= bound * (vals[i] - bound):
                        tau = brentq(lambda s, b=bound, g=gap, t0=t: g(s - t0) - b,
                                     grid[i - 1], grid[i],
                                     xtol=1e-15, rtol=1e-15)
                        hit = tau if hit is None else min(hit, tau)
                if hit is not None:
                    break
            if hit is None:
                return self._flow(x, u, t_len - t)
            x = self._impact(self._flow(x, u, hit - t))
            t = hit
        raise RuntimeError("more than 1000 impacts in one sampling interval")

    def _control(self, x, c, t):
        xd = XM * math.cos(OMEGA * t)
        vd = -XM * OMEGA * math.sin(OMEGA * t)
        ad = -XM * OMEGA ** 2 * math.cos(OMEGA * t)
        err, derr = xd - x[2], vd - x[3]
        g = self.g
        if not self.pid:
            return MASSES[1] * ad + g["kp"] * err + g["kv"] * derr, c
        a = math.exp(-self.dt / g["filter_time"])
        u = MASSES[1] * ad + g["kp"] * err + g["ki"] * c[0] + g["kd"] * c[1]
        return u, np.array([c[0] + self.dt * err, a * c[1] + (1 - a) * derr])

    def __call__(self, X):
        x, c = X[:4], X[4:]
        for k in range(self.N):
            u, c = self._control(x, c, k * self.dt)
            x = self._interval(x, u, self.dt)
        return np.concatenate([x, c])

    def _impact(self, x):
        x = x.copy()
        x[[1, 3]] -= (1 + E) * (x[1] - x[3]) * self.minv_w / self.w_minv_w
        return x

    def from_section(self, z, t, u, c):
        """The pre-sample state at the next sample ``t = T`` from a pre-impact state on the
        wall at ``t`` in ``[0, T)`` with held force ``u`` (to seed Newton from the package's
        section point)."""
        k = math.floor(t / self.dt) + 1
        x = self._interval(self._impact(z), u, k * self.dt - t)
        for j in range(k, self.N):
            u, c = self._control(x, c, j * self.dt)
            x = self._interval(x, u, self.dt)
        return np.concatenate([x, c])

    def fixed_point(self, X0, tol=1e-11):
        X = np.array(X0, float)
        for _ in range(30):
            F = self(X) - X
            if np.max(np.abs(F)) < tol * max(1.0, np.max(np.abs(X))):
                return X
            X = X - np.linalg.solve(self.jacobian(X) - np.eye(X.size), F)
        raise AssertionError(f"no fixed point of the period map (residual {np.abs(F).max()})")

    def jacobian(self, X, h=1e-6):
        J = np.empty((X.size, X.size))
        for j in range(X.size):
            d = np.zeros(X.size)
            d[j] = h * max(1.0, abs(X[j]))
            J[:, j] = (self(X + d) - self(X - d)) / (2 * d[j])
        return J


PD = {"type": "pd", "kp": 10.0, "kv": 20.0}
PID = {"type": "pid", "kp": 10.0, "ki": 2.0, "kd": 20.0, "filter_time": 0.02}


def _package_orbit(controller, n_samples, guess=None):
    po, P = orbit_from_model(_model(controller, T / n_samples), 0, 1, transient=40.0,
                             guess=guess, event="impact")
    return po, P


def _compare(controller, n_samples, guess=None):
    po, P = _package_orbit(controller, n_samples, guess)
    assert po.converged, (po.reason, po.detail)
    sec = P.section
    lay = P.section.automaton.state_names
    z = po.z
    strobe = _StroboscopicMap(controller, n_samples)
    mech = z[[lay.index(n) for n in ("x1", "x1_dot", "x2", "x2_dot")]]
    ctrl = z[[i for i, n in enumerate(lay) if n.startswith("c")]]
    X0 = strobe.from_section(mech, float(po.s[0]), float(z[lay.index("h0")]), ctrl)
    X = strobe.fixed_point(X0)
    mult = np.linalg.eigvals(strobe.jacobian(X))
    # the plant's 2n = 4 states plus the controller's: no clock, no held force
    assert po.multipliers.size == X.size == 4 + ctrl.size, (po.multipliers, sec.names)
    ours = np.sort(np.abs(po.multipliers))
    theirs = np.sort(np.abs(mult))
    np.testing.assert_allclose(ours, theirs, rtol=1e-5, atol=1e-6,
                               err_msg="multiplier moduli against the period map")
    return po, theirs


@pytest.mark.parametrize("n_samples", [200, 16])
def test_sampled_pd_multipliers_match_the_period_map(n_samples):
    po, theirs = _compare(PD, n_samples)
    assert po.stable and theirs.max() < 1
    assert not np.any(np.abs(np.abs(po.multipliers) - 1.0) < 1e-6), \
        "no spurious multiplier 1 from the sampling clock"


def test_coarse_sampling_destabilises_an_orbit_the_continuous_loop_keeps():
    cont, _ = orbit_from_model(_model(PD), 0, 1, transient=40.0)
    assert cont.converged and cont.stable
    # follow the family from fine to coarse sampling
    guess = None
    for n in (20, 16, 15):
        po, _ = _package_orbit(PD, n, guess)
        guess = po.s
    po, theirs = _compare(PD, 13, guess)
    assert not po.stable and theirs.max() > 1.05, theirs


@pytest.mark.parametrize("n_samples", [200, 40])
def test_sampled_pid_multipliers_match_the_period_map(n_samples):
    po, _ = _compare(PID, n_samples)
    assert po.n_periods == 1


def test_sampling_clock_is_no_section_coordinate():
    model = _model(PD, T / 50)
    sec = mechanical_section(model.automaton, 0, 1)
    assert sec.names == ("phi", "x1_dot", "x2", "x2_dot", "h0")
    assert sec.period == pytest.approx(T) and sec.clocks
    z, _ = sec.to_state(np.array([0.3 * sec.period, 3.0, 0.25, -1.5, -7.0]))
    np.testing.assert_allclose(z[-1], (0.3 * T) % (T / 50), rtol=1e-12, atol=1e-15)


def test_common_period_of_reference_and_sampling():
    # dt = 3 T / 100: the sampling instants return with the phase after 3 periods
    model = _model(PD, 3 * T / 100)
    sec = mechanical_section(model.automaton, 0, 1)
    assert sec.period == pytest.approx(3 * T, rel=1e-12)
    assert sec.reference_period == pytest.approx(T, rel=1e-12)


def test_incommensurate_sampling_names_the_nearest_dividing_period():
    dt = T / (200 + math.sqrt(2) / 7)
    po, _ = orbit_from_model(_model(PD, dt), 0, 1, transient=5.0)
    assert po.reason == "sampling_incommensurate"
    assert f"{T / 200:.10g}" in po.detail, po.detail
