"""An orbit is an orbit: Newton's zero is reported as a periodic orbit only if it returns after
a whole number of reference periods, transversally, and a simulation of one period confirms it;
non-convergence and refusals are results, never exceptions."""
import json
from pathlib import Path

import numpy as np
import pytest

from hybridpd.analysis.hybridmap import SectionMap
from hybridpd.analysis.model_orbits import _guess_from_simulation, orbit_from_model
from hybridpd.analysis.periodic import PeriodicOrbit, find_orbit
from hybridpd.cli import main
from hybridpd.mechanics.modelfile import model_from_dict
from hybridpd.mechanics.sections import mechanical_section

MODELS = Path(__file__).resolve().parents[1] / "examples" / "models"


def _drivetrain(omega=5.0, **ctrl):
    """The example drivetrain (a 3-DOF model with a one-sided motor stop, so positions drift)
    driven at omega = 5 (T = 1.257): the kind of model where a grazing crossing returned to
    itself after 1e-14 s and was reported as a converged orbit."""
    return model_from_dict({
        "system": {"dofs": ["load", "gear", "motor"], "masses": [2.0, 0.2, 1.0],
                   "damping": [[0.5, 0, 0], [0, 0.2, -0.2], [0, -0.2, 0.2]],
                   "stiffness": [[0, 0, 0], [0, 50.0, -50.0], [0, -50.0, 50.0]],
                   "input": [0.0, 0.0, 1.0]},
        "contact": [{"between": ["load", "gear"], "lo": -0.1, "hi": 0.1, "restitution": 0.5},
                    {"dof": "motor", "hi": 2.0, "restitution": 0.8}],
        "controller": {"type": "pd", "kp": 20.0, "kv": 5.0, "measure": "motor", **ctrl},
        "reference": {"type": "sine", "amplitude": 1.0, "omega": omega,
                      "feedforward_mass": 3.2},
        "initial": {"q": [0.05, 0.0, 0.0]}})


def test_degenerate_return_is_no_orbit():
    model = _drivetrain()
    sec = mechanical_section(model.automaton, 0, 1)
    P = SectionMap(sec)
    guess = _guess_from_simulation(model, sec, None)
    po = find_orbit(P, guess, 1, min_return=0.0)      # the fast-return refusal switched off
    assert isinstance(po, PeriodicOrbit)
    assert not po.converged and not po.stable, po
    assert po.reason == "degenerate_return", (po.reason, po.detail)
    # the reported return time is no period of the reference (T = 1.257)
    assert po.t_period < 1e-9 * sec.period
    # independently: one reference period later the flow is nowhere near the point
    r = P.apply(po.s, 1)
    assert (not r.ok) or r.t_hit - r.t_start < 1e-9 or \
        np.max(np.abs(sec.wrap(r.s - po.s))) > 1e-6


def test_cli_refuses_rebounds_with_the_release_hint(capsys):
    f = str(MODELS / "robot_joint_pd.toml")
    assert main(["orbit", "--model", f, "--event", "impact", "--json"]) == 3     # no orbit
    d = json.loads(capsys.readouterr().out)
    assert d["exists"] is False and d["reason"] == "fast_return"
    assert "--event release" in d["detail"]
    assert main(["orbit", "--model", f, "--event", "release", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["exists"] and d["n_periods"] == 1, d
    np.testing.assert_allclose(d["t_period"], 2 * np.pi / 3.0, rtol=1e-9,
                               err_msg="the release orbit's period is the reference's")
    assert d["return_error"] < 1e-8


def test_newton_never_raises_from_finite_guesses():
    model = _drivetrain(omega=2.0)
    sec = mechanical_section(model.automaton, 0, 1)
    P = SectionMap(sec, t_max=20.0)
    rng = np.random.default_rng(3)
    base = _guess_from_simulation(model, sec, None)
    seen = set()
    for _ in range(6):
        g = base + rng.normal(scale=[0.5, 3, 1, 3, 1, 5])
        po = find_orbit(P, g, 1, max_iter=6, min_return=0.0)
        assert isinstance(po, PeriodicOrbit) and po.reason, po
        seen.add(po.reason.split(":")[0])
        if po.converged:        # every accepted orbit passed the checks
            assert po.n_periods >= 1 and po.return_error < 1e-6
    assert seen, "no result"
    # a guess where the flow does not fire the guard is a result too
    bad = base.copy()
    bad[sec.names.index("load_dot")] = -50.0
    po = find_orbit(P, bad, 1)
    assert not po.converged and po.reason.startswith("map undefined"), po.reason


def test_sampled_data_incommensurate_period_is_refused():
    T = 2 * np.pi / 5.0
    pair = {
        "system": {"dofs": ["x1", "x2"], "masses": [0.1, 1.0], "input": [0.0, 1.0]},
        "contact": [{"between": ["x1", "x2"], "lo": -0.75, "hi": 0.75, "restitution": 0.5}],
        "reference": {"type": "sine", "amplitude": 1.0, "omega": 5.0, "feedforward_mass": 1.0},
        "initial": {"q": [0.3, 0.0], "v": [0.5, 0.0]}}
    ctrl = {"type": "pd", "kp": 10.0, "kv": 20.0, "measure": "x2"}
    bad = model_from_dict({**pair, "controller": {**ctrl, "dt": T / (200 + np.sqrt(2) / 7)}})
    po, _ = orbit_from_model(bad, 0, 1, transient=5.0)
    assert not po.converged and po.reason == "sampling_incommensurate", po.reason
    assert "sampling period" in po.detail


def test_fast_return_refused_before_newton_with_hint():
    model = _drivetrain()
    sec = mechanical_section(model.automaton, 0, 1)
    P = SectionMap(sec)
    po = find_orbit(P, _guess_from_simulation(model, sec, None), 1)
    assert po.reason == "fast_return" and po.iterations == 0
    assert "release" in po.detail
    with pytest.raises(ValueError, match="min_return"):
        find_orbit(P, po.s, 1, min_return=-1.0)
