"""Robustness on a user's own model: a robot joint with a shaft spring, a light gear node
and backlash (sampled PID or continuous PD), the pid controller type against an independent
solve_ivp integration, and the diverged termination."""
import copy
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from hybridpd.mechanics import model_from_dict

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

MODELS = Path(__file__).parents[1] / "examples" / "models"


def _joint():
    return tomllib.loads((MODELS / "robot_joint.toml").read_text())


@pytest.mark.parametrize("gear_inertia", [1e-4, 1e-3, 5e-3])
@pytest.mark.parametrize("ctrl", ["pid_sampled", "pd_continuous"])
def test_robot_joint_runs_to_the_end_without_empty_sticking(gear_inertia, ctrl):
    d = _joint()
    d["system"]["masses"][1] = gear_inertia
    if ctrl == "pd_continuous":
        d["controller"] = {"type": "pd", "kp": 20.0, "kv": 1.0, "measure": "motor"}
    tr = model_from_dict(d).simulate(10.0)
    assert tr.termination == "end_time"
    assert tr.sticking and all(b > a for a, b, _ in tr.sticking), "a sticking interval of zero length"
    # a held contact is released at most once per sticking interval (no release/re-hit loop)
    rel = sum(1 for g in tr.hybrid.jumps.guard if g.startswith("release"))
    assert rel <= len(tr.sticking)
    q = tr.mechanical(np.linspace(0.0, 10.0, 4001))[:, 0::2]
    gap = q[:, 1] - q[:, 2]
    assert gap.max() <= 0.01 + 1e-9 and gap.min() >= -0.01 - 1e-9


def test_pid_type_against_solve_ivp():
    """A unit mass under a filtered PID towards 0.3 (a stop far away): the model file's pid
    against the ODE integrated directly: x'' = kp e + ki I + kd d, I' = e, d' = (e' - d) / Tf,
    e = 0.3 - x."""
    kp, ki, kd, tf = 4.0, 2.0, 1.5, 0.05
    d = {"system": {"dofs": ["x"], "masses": [1.0], "input": [1.0]},
         "contact": [{"dof": "x", "hi": 10.0, "restitution": 0.5}],
         "controller": {"type": "pid", "kp": kp, "ki": ki, "kd": kd, "filter_time": tf,
                        "measure": "x"},
         "reference": {"type": "constant", "value": 0.3}}
    tr = model_from_dict(d).simulate(5.0)
    assert tr.termination == "end_time" and tr.n_impacts == 0

    def rhs(t, y):
        x, v, integ, dd = y
        e, edot = 0.3 - x, -v
        return [v, kp * e + ki * integ + kd * dd, e, (edot - dd) / tf]
    ts = np.linspace(0.0, 5.0, 51)
    sol = solve_ivp(rhs, (0, 5), [0, 0, 0, 0], t_eval=ts, rtol=1e-12, atol=1e-13,
                    method="DOP853")
    np.testing.assert_allclose(tr.mechanical(ts)[:, 0], sol.y[0], atol=1e-9)
    # sampled at 1 kHz with a zero-order hold: close to the continuous loop (first order)
    d2 = copy.deepcopy(d)
    d2["controller"]["dt"] = 1e-3
    tr2 = model_from_dict(d2).simulate(5.0)
    err = np.abs(tr2.mechanical(ts)[:, 0] - sol.y[0]).max()
    assert 1e-6 < err < 5e-3


@pytest.mark.parametrize("edit,key", [
    (lambda c: c.update(filter_time=-1.0), "controller.filter_time"),
    (lambda c: c.pop("kp"), "controller.kp"),
    (lambda c: c.update(kv=1.0), "controller.kv"),
])
def test_pid_bad_keys_are_named(edit, key):
    d = _joint()
    edit(d["controller"])
    with pytest.raises(ValueError, match=key.replace(".", r"\.")):
        model_from_dict(d)


def test_a_growing_motion_stops_as_diverged():
    """A destabilising loop (negative damping gain) on two masses rattling in a clearance:
    the amplitude grows without bound; the run stops at the documented bound."""
    d = {"system": {"dofs": ["a", "b"], "masses": [0.2, 1.0], "input": [0.0, 1.0],
                    "stiffness": [[5.0, -5.0], [-5.0, 5.0]]},
         "contact": [{"between": ["a", "b"], "lo": -0.1, "hi": 0.1, "restitution": 0.9}],
         "controller": {"type": "pd", "kp": 10.0, "kv": -2.0, "measure": "b"},
         "initial": {"q": [0.05, 0.0]}}
    m = model_from_dict(d)
    tr = m.simulate(100.0, max_state=1e6)
    assert tr.termination == "diverged"
    assert np.abs(tr.hybrid.x_final).max() > 1e6 and tr.t_final < 100.0


DIVERGING = """
[system]
dofs = ["a", "b"]
masses = [0.2, 1.0]
input = [0.0, 1.0]
stiffness = [[5.0, -5.0], [-5.0, 5.0]]
[[contact]]
between = ["a", "b"]
lo = -0.1
hi = 0.1
restitution = 0.9
[controller]
type = "pd"
kp = 10.0
kv = -5.0
measure = "b"
[initial]
q = [0.05, 0.0]
"""


def test_cli_exit_status_and_summary(tmp_path, capsys):
    from hybridpd.cli import main

    f = tmp_path / "diverging.toml"
    f.write_text(DIVERGING)
    assert main(["simulate", "--model", str(f), "--t-end", "100"]) == 4
    out, err = capsys.readouterr()
    assert "stopped: diverged" in out and "diverged" in err
    # long event lists are summarised, not printed one by one
    assert "more (use --json for all)" in out and len(out.splitlines()) < 40
    assert main(["simulate", "--model", str(MODELS / "robot_joint.toml"), "--t-end",
                 "10"]) == 0
    out, _ = capsys.readouterr()
    assert "accumulation of impacts on contact 0" in out
