"""The stroboscopic section of model files: its DP, its multipliers against the event sections
and an independent period map, its phase, and the default of the commands."""
import json
import math

import numpy as np
import pytest
from test_sampled_orbits import PD, PID, T, _model, _StroboscopicMap

from hybridpd.analysis.model_orbits import orbit_from_model
from hybridpd.analysis.model_sections import SectionSpec, choose_phase, fix_section
from hybridpd.cli import main
from hybridpd.mechanics.modelfile import load_model, model_from_dict
from hybridpd.mechanics.simulate import simulate_state

MODELS = __import__("pathlib").Path(__file__).parents[1] / "examples" / "models"

#: A motor driving a link through a gear backlash; the backlash sticks for part of each
#: period, and with a sampled controller the contact releases at a sample instant.
JOINT = {
    "system": {"dofs": ["motor", "link"], "masses": [0.02, 0.10],
               "damping": [[0.01, 0.0], [0.0, 0.05]], "input": [1.0, 0.0]},
    "contact": [{"name": "backlash", "between": ["motor", "link"], "lo": -0.02, "hi": 0.02,
                 "restitution": 0.5}],
    "controller": {"type": "pid", "kp": 8.0, "ki": 2.0, "kd": 0.4, "filter_time": 0.005,
                   "measure": "motor"},
    "reference": {"type": "sine", "amplitude": 0.3, "omega": 2 * math.pi},
    "initial": {"q": [0.0, 0.0], "v": [0.0, 0.0]},
}


def _joint(dt=None, **controller):
    d = json.loads(json.dumps(JOINT))
    d["controller"].update(controller)
    if dt:
        d["controller"]["dt"] = dt
    return d


def _compliant():
    """A drivetrain with a compliant end stop on one side and a rigid one on the other."""
    d = _joint(None, type="pd", kp=8.0, kv=0.4)
    for k in ("ki", "kd", "filter_time"):
        d["controller"].pop(k)
    d["contact"] += [{"name": "soft stop", "dof": "link", "hi": 0.25, "stiffness": 400.0,
                      "damping": 0.5},
                     {"name": "hard stop", "dof": "link", "lo": -0.26, "restitution": 0.6}]
    return d


def _two_controllers():
    """The joint with a second, sampled controller on the link (its own dt)."""
    d = _joint(0.01)
    d["controller"] = [d["controller"],
                       {"type": "pd", "kp": 0.5, "kv": 0.05, "measure": "link",
                        "actuate": "link", "dt": 0.02}]
    return d


CASES = {"continuous": lambda: _joint(), "sampled": lambda: _joint(0.005),
         "compliant": _compliant, "two controllers": _two_controllers}


@pytest.mark.parametrize("case", list(CASES))
def test_stroboscopic_dp_is_the_derivative_of_the_simulated_period_map(case):
    model = model_from_dict(CASES[case]())
    po, P = orbit_from_model(model)
    assert po.converged, (po.reason, po.detail)
    assert P.names and "phi" not in P.names and po.n_periods >= 1
    # the exact chain against central differences of the simulated map
    fd = P.jacobian_fd(po.s, po.period)
    scale = max(1.0, float(np.max(np.abs(po.DP))))
    assert np.max(np.abs(fd - po.DP)) < 1e-5 * scale, (case, np.max(np.abs(fd - po.DP)))
    # the non-zero multipliers are those of the differences
    ours = np.sort(np.abs(po.multipliers))[::-1]
    theirs = np.sort(np.abs(np.linalg.eigvals(fd)))[::-1][:ours.size]
    np.testing.assert_allclose(ours, theirs, rtol=1e-4, atol=1e-6)
    # the structural zeros are left out: no multiplier at rounding level is reported
    assert np.all(np.abs(po.multipliers) > 1e-12), po.multipliers


def test_the_orbit_agrees_with_a_simulation_of_the_model():
    model = model_from_dict(_joint(0.005))
    po, P = orbit_from_model(model)
    assert po.converged
    z0, t0 = P.section.to_state(po.s)
    tr = simulate_state(model.automaton, z0, (t0, t0 + 3 * P.common_period), P.mode).hybrid
    assert tr.mode_final == P.mode
    assert np.max(np.abs(tr.x_final - z0)) < 1e-8 * max(1.0, np.max(np.abs(z0)))
    # the motion sticks within the period and releases at a sample instant
    sig = po.signature
    assert any(k == "zeno" for _, k in sig) and any(g.startswith("release") for g, _ in sig)
    times = [j[0] for j in P.apply(po.s).jumps if j[2].startswith("release")]
    assert any(abs(t / 0.005 - round(t / 0.005)) < 1e-9 for t in times)


@pytest.mark.parametrize("path,event", [("gear_train.toml", "release"),
                                        ("drivetrain.toml", "release")])
def test_stroboscopic_multipliers_equal_the_event_section_ones(path, event):
    model = load_model(MODELS / path)
    po, _ = orbit_from_model(model)
    pe, _ = orbit_from_model(model, 0, event=event)
    assert po.converged and pe.converged
    a = np.sort(np.abs(po.multipliers))[::-1]
    b = np.sort(np.abs(pe.multipliers))[::-1]
    n = int(np.sum(b > 1e-8))
    np.testing.assert_allclose(a[:n], b[:n], rtol=1e-7)
    assert po.spectral_radius == pytest.approx(pe.spectral_radius, rel=1e-8)


@pytest.mark.parametrize("controller,n_samples", [(PD, 200), (PD, 16), (PID, 50)])
def test_sampled_pair_multipliers_match_an_independent_period_map(controller, n_samples):
    """The reference of tests/test_sampled_orbits.py (the pair's sampled loop written from its
    equations, on the samples at t = 0 mod T): the same multipliers on the stroboscopic
    section half a sample away from them."""
    model = _model(controller, T / n_samples)
    po, P = orbit_from_model(model, transient=40.0)
    assert po.converged, (po.reason, po.detail)
    lay = P.section.automaton.state_names
    z0, t0 = P.section.to_state(po.s)
    # the reference's section: simulate to the next sample at t = 0 (mod T)
    t1 = math.ceil(t0 / T) * T - 1e-12 * T
    z = simulate_state(model.automaton, z0, (t0, t1), P.mode).hybrid.x_final
    ref = _StroboscopicMap(controller, n_samples)
    mech = z[[lay.index(n) for n in ("x1", "x1_dot", "x2", "x2_dot")]]
    ctrl = z[[i for i, n in enumerate(lay) if n.startswith("c")]]
    X = ref.fixed_point(ref.from_section(mech, 0.0, float(z[lay.index("h0")]), ctrl))
    theirs = np.sort(np.abs(np.linalg.eigvals(ref.jacobian(X))))
    ours = np.sort(np.abs(po.multipliers))
    assert ours.size == theirs.size == 4 + ctrl.size
    np.testing.assert_allclose(ours, theirs, rtol=1e-5, atol=1e-6)


def test_the_phase_is_chosen_away_from_every_jump_but_the_samples():
    model = model_from_dict(_joint(0.005))
    spec, mode, text = fix_section(model, SectionSpec())
    assert spec.event == "stroboscopic" and "phase phi0" in text
    # half-way between two samples, and the other jumps of the period farther than a sample
    assert abs((spec.phase / 0.005) % 1.0 - 0.5) < 1e-9
    tr = model.simulate(model.t0 + 30.0).hybrid
    phase, margin = choose_phase(model, tr, model.t0 + 30.0)
    J = tr.jumps
    others = [J.t[i] % 1.0 for i in range(len(J)) if J.t[i] >= 29.0 and J.guard[i] != "sample"]
    d = min(min(abs(phase - t), 1.0 - abs(phase - t)) for t in others)
    assert d == pytest.approx(margin, abs=1e-9) and margin >= 0.0025 - 1e-9
    # no other candidate is farther from every jump by more than twice
    cand = (np.arange(200) + 0.5) * 0.005
    far = max(min(min(abs(c - t), 1.0 - abs(c - t)) for t in others) for c in cand)
    assert margin >= 0.5 * far - 1e-12
    assert mode == tr.segments.mode[int(np.searchsorted(tr.segments.t_start,
                                                         29.0 + phase, "right")) - 1]


def test_orbit_command_defaults_to_the_stroboscopic_section(tmp_path, capsys):
    f = tmp_path / "joint.toml"
    f.write_text(_toml(_joint(0.005)))
    assert main(["orbit", "--model", str(f), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["event"] == "stroboscopic" and d["exists"] and d["stable"]
    assert d["contact"] is None and d["T"] == pytest.approx(1.0) and 0 <= d["phi0"] < 1.0
    assert d["structural_zeros"] >= 1 and d["jacobian"] == "saltation"
    assert len(d["multipliers"]) + d["structural_zeros"] == len(d["fixed_point"])
    assert main(["orbit", "--model", str(f)]) == 0
    out = capsys.readouterr().out
    assert "stroboscopic section" in out and "structural zero" in out
    # the event sections stay one option away
    assert main(["orbit", "--model", str(f), "--event", "release", "--json"]) in (0, 3)
    assert json.loads(capsys.readouterr().out)["event"] == "release"


def test_a_model_without_periodic_reference_gets_the_event_section_it_crosses(tmp_path,
                                                                             capsys):
    d = _joint(None, kp=2.0, ki=2.0, kd=0.5, filter_time=0.01, measure="link")
    d["system"]["masses"] = [0.05, 0.5]
    d["system"]["damping"] = [[0.02, 0.0], [0.0, 0.05]]
    d["contact"][0]["restitution"] = 0.3
    d["reference"] = {"type": "constant", "value": 0.1}
    f = tmp_path / "hunting.toml"
    f.write_text(_toml(d))
    assert main(["orbit", "--model", str(f), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["event"] == "release" and "no periodic reference" in out["section_choice"]
    with pytest.raises(ValueError, match="no periodic reference"):
        SectionSpec(event="stroboscopic").section_map(model_from_dict(d))


def _toml(d) -> str:
    """A model dict as TOML (the few shapes the model files use)."""
    def val(v):
        if isinstance(v, str):
            return json.dumps(v)
        if isinstance(v, list):
            return "[" + ", ".join(val(x) for x in v) + "]"
        return repr(float(v)) if isinstance(v, float) else str(v)

    out = []
    for key, table in d.items():
        rows = table if isinstance(table, list) else [table]
        for row in rows:
            out.append(f"[[{key}]]" if isinstance(table, list) else f"[{key}]")
            out += [f"{k} = {val(v)}" for k, v in row.items()]
    return "\n".join(out) + "\n"


def test_a_release_at_a_sample_instant_is_named_as_the_reason():
    # the sampled joint releases its backlash when the held input steps: the release section
    # has no map there, and the answer says so (the stroboscopic orbit exists)
    m = load_model(MODELS / "robot_joint_sampled.toml")
    po, _ = orbit_from_model(m, 0, event="release")
    assert not po.converged
    assert "at a sample instant" in po.detail
    assert orbit_from_model(m)[0].converged


def test_sections_in_words():
    from hybridpd.analysis.model_sections import section_words

    assert section_words("stroboscopic", phase=0.25) == "stroboscopic section at phi0 = 0.25"
    assert section_words("impact", 2, -1) == "impact section of contact 2 (lower bound)"
    assert "contact" not in section_words("stroboscopic")


def test_a_state_inside_a_compliant_stop_starts_engaged():
    # a mass on a PD loop starting 2 cm into a rubber stop: the stroboscopic map runs from
    # the engaged mode (the state is admissible), checked against solve_ivp of the
    # piecewise-linear equation m x'' = u - [x > hi] (k (x - hi) + c x') with the stop's
    # entry and exit located as events
    from scipy.integrate import solve_ivp

    from hybridpd.analysis.strobe import StroboscopicMap
    from hybridpd.mechanics.sections import stroboscopic_section

    m_, k, c, hi, kp, kv, A, w = 2.0, 2.0e4, 20.0, 0.05, 60.0, 8.0, 0.08, 2 * math.pi
    model = model_from_dict({
        "system": {"dofs": ["x"], "masses": [m_], "input": [1.0]},
        "contact": [{"dof": "x", "hi": hi, "stiffness": k, "damping": c}],
        "controller": {"type": "pd", "kp": kp, "kv": kv, "measure": "x"},
        "reference": {"type": "sine", "amplitude": A, "omega": w},
        "initial": {"q": [0.0], "v": [0.0]}})
    ha = model.automaton
    phi0 = 0.3
    sec = stroboscopic_section(ha, phi0)
    assert not sec.bounds            # a compliant gap beyond its bound is admissible
    P = StroboscopicMap(sec)
    s0 = np.array([hi + 0.02, -0.1])
    names = sec.names
    assert names[:2] == ("x", "x_dot"), names
    res = P.apply(s0)
    assert res.ok, res.status

    def rhs(t, y, engaged):
        x, v = y
        xd, vd = A * math.cos(w * t), -A * w * math.sin(w * t)
        u = kp * (xd - x) + kv * (vd - v)
        return [v, (u - (k * (x - hi) + c * v if engaged else 0.0)) / m_]

    def gap(t, y, engaged):
        return y[0] - hi

    gap.terminal = True
    t, y, engaged = phi0, s0.copy(), True
    T = 2 * math.pi / w
    for _ in range(100):           # each stretch ends where the stop is entered or left
        gap.direction = -1.0 if engaged else 1.0
        sol = solve_ivp(rhs, (t, phi0 + T), y, method="DOP853", rtol=1e-12, atol=1e-14,
                        events=gap, args=(engaged,))
        t, y = sol.t[-1], sol.y[:, -1]
        if sol.status == 0:
            break
        engaged = not engaged
    assert abs(t - (phi0 + T)) < 1e-12
    assert np.allclose(res.s, y, rtol=1e-7, atol=1e-9), (res.s, y)
