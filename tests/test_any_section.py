"""Sections of a model file that the motion crosses: the mode where it crosses them, the
number of crossings per period found automatically, charts that keep slices on the section.

The period-2 orbit below is checked by an independent ``scipy.integrate.solve_ivp`` loop of
the impact pair written here from its equations (terminal events at the walls, Newton's law
of restitution with conservation of momentum): nothing of the package runs in it.
"""
import math
from pathlib import Path

import numpy as np
import pytest
from _basins import model_basin
from _regions import model_region_map
from scipy.integrate import solve_ivp

import hybridpd as hp
from hybridpd.analysis.model_orbits import SectionSpec, orbit_from_model, simulated_returns
from hybridpd.mechanics.modelfile import model_from_dict

MODELS = Path(__file__).resolve().parents[1] / "examples" / "models"
OMEGA, L, E, MU = 5.0, 0.75, 0.1, 0.1
T = 2 * math.pi / OMEGA
XM = 0.690560625045185     # the collocated symmetric orbit's xm at kp = 10, kv = 20, e = 0.1


def _pair(kv, kp=10.0):
    return {"system": {"dofs": ["x1", "x2"], "masses": [MU, 1.0], "input": [0.0, 1.0]},
            "contact": [{"between": ["x1", "x2"], "lo": -L, "hi": L, "restitution": E}],
            "controller": {"type": "pd", "kp": kp, "kv": kv, "measure": "x2"},
            "reference": {"type": "sine", "amplitude": XM, "omega": OMEGA,
                          "feedforward_mass": 1.0},
            "initial": {"q": [0.3, 0.0], "v": [0.5, 0.0]}}


def _solve_ivp_pair(x, t0, t1, kv, kp=10.0):
    """The collocated pair from ``x = [x1, y1, x2, y2]`` at ``t0`` (pre-impact on the ``+L``
    wall) to ``t1``: returns the impacts ``(t, wall, pre-state)``."""
    def rhs(t, y):
        xd, vd, ad = XM * math.cos(OMEGA * t), -XM * OMEGA * math.sin(OMEGA * t), \
            -XM * OMEGA ** 2 * math.cos(OMEGA * t)
        u = ad + kp * (xd - y[2]) + kv * (vd - y[3])
        return [y[1], 0.0, y[3], u]

    def hit(wall):
        ev = lambda t, y: wall * (y[0] - y[2]) - L
        ev.terminal, ev.direction = True, 1
        return ev

    def impact(y):
        rel = y[1] - y[3]
        y = np.array(y, float)
        y[1] -= (1 + E) * rel / (1 + MU)          # momentum conserved, z4+ = -e z4-
        y[3] += (1 + E) * rel * MU / (1 + MU)
        return y

    out, t, y = [(t0, 1, np.array(x, float))], t0, impact(x)
    for _ in range(200):
        sol = solve_ivp(rhs, (t, t1), y, method="DOP853", rtol=1e-12, atol=1e-13,
                        events=[hit(1), hit(-1)])
        if sol.status == 0:
            return out
        wall = 1 if sol.t_events[0].size else -1
        t = float(sol.t_events[0 if wall == 1 else 1][0])
        pre = sol.y_events[0 if wall == 1 else 1][0]
        out.append((t, wall, pre.copy()))
        y = impact(pre)
    raise AssertionError("more than 200 impacts")


def test_auto_period_finds_the_double_impact_orbit_that_period_one_misses():
    model = model_from_dict(_pair(22.0))
    one, _ = orbit_from_model(model, 0, 1, period=1, event="impact")
    assert not one.converged
    po, P = orbit_from_model(model, 0, 1, event="impact")     # period="auto"
    assert po.converged and po.period == 2 and po.n_periods == 1, (po.reason, po.detail)
    lay = P.section.automaton.state_names
    x0 = po.z[[lay.index(n) for n in ("x1", "x1_dot", "x2", "x2_dot")]]
    phi = float(po.s[0])
    hits = _solve_ivp_pair(x0, phi, phi + T * (1 + 1e-9), 22.0)
    plus = [h for h in hits if h[1] == 1]
    assert len(plus) == 3, [(h[0], h[1]) for h in hits]     # start, 2nd, and one period later
    np.testing.assert_allclose(plus[2][0] - phi, T, rtol=1e-9, atol=0,
                               err_msg="the orbit repeats after one reference period")
    np.testing.assert_allclose(plus[2][2], x0, rtol=1e-7, atol=1e-8,
                               err_msg="the solve_ivp loop returns to the section point")
    np.testing.assert_allclose(plus[1][2][[1, 3]], P.section.to_state(
        P(po.s))[0][[lay.index("x1_dot"), lay.index("x2_dot")]], rtol=1e-7, atol=1e-8,
        err_msg="the second crossing is the map's image")


def test_region_map_labels_cells_by_the_returns_they_found():
    rm = model_region_map(_pair(22.0), ("controller.kp", 9.8, 10.2, 2),
                          ("controller.kv", 21.5, 22.5, 2), progress=False, event="impact")
    assert rm.exists.all(), rm.summary()
    assert (rm.period == 2).any() and set(np.unique(rm.period)) <= {1, 2}
    assert "k = 2" in rm.summary()
    back = type(rm).from_dataset(rm.to_dataset())
    np.testing.assert_array_equal(back.period, rm.period)


def test_release_section_in_the_mode_where_the_motion_crosses_it():
    model = hp.load_model(MODELS / "gear_train.toml")
    spec = SectionSpec(contact=0, event="release")
    assert spec.section_map(model).section.mode == "stick0+"     # the default never fires
    sim = simulated_returns(model, spec)
    assert sim.mode == "stick0+1+" and "stick0+1+" in sim.text
    po, P = orbit_from_model(model, 0, event="release")
    assert po.converged and po.mode == "stick0+1+" and po.period == 1, (po.reason, po.detail)
    # both contacts held at the section point: their gaps at the bounds, no relative motion
    z = po.z
    lay = model.automaton.layout
    for k, c in enumerate(model.automaton.contacts):
        np.testing.assert_allclose(model.automaton.gap_rows[k] @ z, c.hi, rtol=0, atol=1e-12)
        np.testing.assert_allclose(c.normal @ z[lay["v"]], 0.0, rtol=0, atol=1e-12)
    assert len(P.section.names) == 2          # phi and one velocity: the rest is fixed


def test_a_section_the_motion_never_crosses_says_what_it_does_cross():
    model = hp.load_model(MODELS / "gear_train.toml")
    with pytest.raises(ValueError, match=r"does not cross the section \(release1\+\).*"
                                         r"contact0\+ in free"):
        orbit_from_model(model, 1, event="release", transient=20.0)


def test_a_basin_axis_that_the_section_fixes_is_refused_naming_the_constraint():
    with pytest.raises(ValueError, match=r"'gear' is no coordinate of this section \(fixed by "
                                         r"release0\+ and contact 0 \(backlash\) held"):
        model_basin(MODELS / "drivetrain.toml", ("gear", -1, 1, 3), ("motor_dot", -6, 6, 3),
                    event="release", n_iter=5)


def test_inadmissible_states_are_labelled_counted_and_never_iterated():
    # the drivetrain's motor end stop: motor <= 2 rad; a slice across it on the release
    # section of the backlash
    b = model_basin(MODELS / "drivetrain.toml", ("motor", 1.0, 3.0, 5), ("motor_dot", -2, 2, 3),
                    n_iter=20, event="release")
    motor = np.broadcast_to(b.x, b.labels.shape)
    beyond = motor > 2.0 * (1 + 1e-9)
    assert beyond.any() and (b.labels[beyond] == -6).all()
    assert (b.labels[~beyond] != -6).all()
    assert (b.iterations[beyond] == 0).all()
    assert b.metadata["inadmissible"] == int(beyond.sum())
    assert any("inadmissible" in line and "not iterated" in line for line in b.summary())
