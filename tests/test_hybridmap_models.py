"""The general map on mechanical models: the pair as a model file, the drivetrain, the CLI."""
import json
from pathlib import Path

import numpy as np
import pytest

from hybridpd import ImpactPair, PDGains
from hybridpd.analysis.model_orbits import orbit_from_model
from hybridpd.analysis.periodic import measured_contraction
from hybridpd.cli import main
from hybridpd.mechanics.modelfile import load_model, model_from_dict
from hybridpd.mechanics.sections import mechanical_section
from hybridpd.pair.orbits import symmetric_orbit

MODELS = Path(__file__).resolve().parents[1] / "examples" / "models"


def _pair_model(case, xm, e=0.5):
    return model_from_dict({
        "system": {"dofs": ["x1", "x2"], "masses": [0.1, 1.0], "input": [0.0, 1.0]},
        "contact": [{"between": ["x1", "x2"], "lo": -0.75, "hi": 0.75, "restitution": e}],
        "controller": {"type": "pd", "kp": 10.0, "kv": 20.0,
                       "measure": "x2" if case == "collocated" else "x1"},
        "reference": {"type": "sine", "amplitude": xm, "omega": 5.0, "feedforward_mass": 1.0},
        "initial": {"q": [0.3, 0.0], "v": [0.5, 0.0]}})


@pytest.mark.parametrize("case", ["collocated", "noncollocated"])
def test_pair_model_file_orbit_matches_symmetric_orbit(case):
    orb = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0, case=case)
    model = _pair_model(case, orb.xm)
    sec = mechanical_section(model.automaton, 0, 1)
    assert sec.names == ("phi", "x1_dot", "x2", "x2_dot")
    phi, z1, z2, z4 = orb.fixed_point
    guess = np.array([phi, z2 + z4, z1, z2])          # (phi, y1, x2, y2)
    eps = 1e-3 if orb.stable else 1e-7
    po, _ = orbit_from_model(model, 0, 1, guess=guess + eps, event="impact")
    assert po.converged, po.reason
    s = po.s
    assert np.max(np.abs(np.array([s[0], s[2], s[3], s[1] - s[3]]) - orb.fixed_point)) < 1e-9
    rho = orb.spectral_radius
    assert np.max(np.abs(np.sort_complex(po.multipliers) - np.sort_complex(orb.multipliers))) \
        < 1e-9 * max(1.0, rho)


def _impacts_per_period(orbit, guard="contact0+"):
    """How often `guard` fires (resolved crossings) in one period of `orbit`: the returns
    of its impact section per period. The resolved part of a burst ending in an accumulation
    is set by the automaton's accumulation rule (``ZenoOptions.tail_tol``), not by the orbit
    alone, so it is read from the orbit found on the release section."""
    return sum(1 for g, kind in orbit.signature if g == guard and kind == "crossing")


def test_drivetrain_dp_through_chatter_and_sticking_matches_finite_differences():
    model = load_model(MODELS / "drivetrain.toml")
    pr, _ = orbit_from_model(model, 0, 1, 1, event="release")
    assert pr.converged
    k = _impacts_per_period(pr)
    assert k >= 4, pr.signature
    po, P = orbit_from_model(model, 0, 1, k, event="impact")
    assert po.converged and po.stable
    kinds = [kd for _, kd in po.signature]
    assert kinds.count("zeno") == 2 and len(po.signature) == len(pr.signature)
    np.testing.assert_allclose(po.t_period, np.pi, rtol=1e-9, err_msg="one reference period")
    fd = P.jacobian_fd(po.s, k, h=1e-6)
    assert np.max(np.abs(fd - po.DP)) < 1e-6 * max(1.0, np.max(np.abs(po.DP)))
    # the release section sees the same orbit: the same multipliers
    assert np.max(np.abs(pr.multipliers[:3] - po.multipliers[:3])) < 1e-8
    rho = measured_contraction(P, po.s, k, n_iter=40, eps=1e-6, n_dirs=1)
    assert abs(rho - po.spectral_radius) < 3e-2 * po.spectral_radius


def test_orbit_cli_with_a_model_file(capsys):
    f = MODELS / "drivetrain.toml"
    assert main(["orbit", "--model", str(f), "--event", "release", "--json"]) == 0
    d2 = json.loads(capsys.readouterr().out)
    k = sum(1 for g, kind in d2["impact_sequence"] if g == "contact0+" and kind == "crossing")
    assert main(["orbit", "--model", str(f), "--contact", "0", "--period", str(k),
                 "--event", "impact", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["exists"] and d["stable"] and d["contact"] == 0 and d["wall"] == 1
    assert len(d["multipliers"]) == len(d["fixed_point"]) == 6 and len(d["pre"]) == 6
    assert abs(d["t_period"] - np.pi) < 1e-9 and d["T"] == pytest.approx(np.pi)
    pre, post = np.array(d["pre"]), np.array(d["post"])     # [q_load, v_load, q_gear, ...]
    assert np.array_equal(post[[0, 2, 4, 5]], pre[[0, 2, 4, 5]])  # Newton's law: load, gear
    assert post[1] != pre[1] and post[3] != pre[3] and d["phi0"] == d["fixed_point"][0]
    g = [str(v) for v in d["fixed_point"]]
    assert main(["orbit", "--model", str(f), "--period", str(k), "--event", "impact",
                 "--guess", *g]) == 0
    assert "converged" in capsys.readouterr().out
    assert abs(d2["spectral_radius"] - d["spectral_radius"]) < 1e-8


def test_orbit_cli_bad_input(capsys):
    f = str(MODELS / "drivetrain.toml")
    assert main(["orbit", "--model", f, "--contact", "5"]) == 2
    assert "contact" in capsys.readouterr().err
    assert main(["orbit", "--model", f, "--guess", "1", "2"]) == 2
    assert "guess" in capsys.readouterr().err
    assert main(["orbit", "--model", f, "--period", "0"]) == 2
    assert main(["orbit", "--mu", "0.1"]) == 2
    assert "--model" in capsys.readouterr().err
    assert main(["orbit", "--case", "collocated", "--mu", "0.1", "--omega", "5", "--L", "0.75",
                 "--e", "0.5", "--kp", "10", "--kv", "20", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["exists"]


def test_sampled_data_orbit_dp(tmp_path):
    """A discrete PD (ZOH, dt = T / 200) on the pair: the sampling instants are jumps of the
    map; DP through them matches finite differences."""
    model = model_from_dict({
        "system": {"dofs": ["x1", "x2"], "masses": [0.1, 1.0], "input": [0.0, 1.0]},
        "contact": [{"between": ["x1", "x2"], "lo": -0.75, "hi": 0.75, "restitution": 0.5}],
        "controller": {"type": "pd", "kp": 10.0, "kv": 20.0, "measure": "x2",
                       "dt": 2 * np.pi / 5.0 / 200},
        "reference": {"type": "sine", "amplitude": 1.0, "omega": 5.0, "feedforward_mass": 1.0},
        "initial": {"q": [0.3, 0.0], "v": [0.5, 0.0]}})
    from hybridpd.analysis.hybridmap import SectionMap
    from hybridpd.analysis.model_orbits import _guess_from_simulation

    sec = mechanical_section(model.automaton, 0, 1)
    P = SectionMap(sec)
    s = _guess_from_simulation(model, sec, 20.0)
    names = sec.names
    assert "s" not in names and "h0" in names  # the clock is set from the phase
    r = P.apply(s, jacobian=True)
    assert r.ok and sum(1 for j in r.jumps if j[2] == "sample") > 20
    fd = P.jacobian_fd(s, h=1e-7)
    assert np.max(np.abs(fd - r.DP)) < 1e-6 * max(1.0, np.max(np.abs(r.DP))), names


@pytest.mark.slow
def test_pid_backlash_example_runs_and_writes_its_figure(tmp_path):
    import os
    import subprocess
    import sys

    root = Path(__file__).resolve().parents[1]
    env = dict(os.environ, PYTHONPATH=str(root), OPENBLAS_NUM_THREADS="1")
    r = subprocess.run([sys.executable, str(root / "examples" / "mechanical" /
                                            "plot_pid_backlash_describing_function.py"),
                        "--out", str(tmp_path), "--quick"], capture_output=True, text=True,
                       env=env, timeout=900, check=False)
    assert r.returncode == 0, r.stderr
    assert "describing function: A =" in r.stdout and "exact cycle" in r.stdout
    assert (tmp_path / "pid_backlash_describing_function.png").stat().st_size > 10_000


@pytest.mark.slow
def test_drivetrain_basin_early_exit_does_not_change_labels():
    from hybridpd.analysis.mappers import mapper
    from hybridpd.sweeps.basins import basin_of_attraction

    model = load_model(MODELS / "drivetrain.toml")
    po, P = orbit_from_model(model, 0, 1, 1, event="release")
    assert po.converged
    names = P.section.names
    i, j = names.index("motor"), names.index("motor_dot")
    x = (po.s[i] - 2.0, po.s[i] + 2.0, 6)
    y = (po.s[j] - 8.0, po.s[j] + 8.0, 6)
    axes = ("motor", "motor_dot")
    fast = basin_of_attraction(mapper(P, po.s, n_iter=60), x, y, axes=axes, max_period=0)
    full = basin_of_attraction(mapper(P, po.s, n_iter=60, early_exit=False), x, y, axes=axes,
                               max_period=0)
    assert np.array_equal(fast.labels, full.labels)
    assert fast.iterations.sum() < full.iterations.sum()
    par = basin_of_attraction(mapper(P, po.s, n_iter=60), x, y, axes=axes, max_period=0,
                              executor="processes", max_workers=2, chunk_size=9)
    assert np.array_equal(par.labels, fast.labels)


def test_section_map_and_simulation_end_an_accumulation_alike():
    """A burst of impacts ending in sticking (the robot joint's backlash): the release
    section's map and the mechanics simulation resolve it by the automaton's one rule, so a
    map step and the simulated run reach the next release at the same time and state; the
    plain ratio rule (no tail tolerance) stops resolving earlier and lands measurably
    elsewhere (its extrapolated accumulation time is off)."""
    from hybridpd.analysis.hybridmap import SectionMap
    from hybridpd.analysis.model_orbits import SectionSpec, _guess_from_simulation
    from hybridpd.hybrid.automaton import ZenoOptions
    from hybridpd.mechanics.params import ModelTemplate
    from hybridpd.mechanics.simulate import simulate_state

    model = ModelTemplate.load(MODELS / "robot_joint_pd.toml").model(
        {"controller.kp": 20.0, "controller.kv": 4.0})
    P = SectionSpec(event="release").section_map(model)
    sec = P.section
    assert P.zeno is model.automaton.automaton.zeno and P.zeno.tail_tol is not None
    s = _guess_from_simulation(model, sec, 3 * sec.period)      # a point on no orbit
    r = P.apply(s, jacobian=True)
    assert r.ok and not r.grazing and np.all(np.isfinite(r.DP))
    assert sum(j[4] == "zeno" for j in r.jumps) >= 1, r.jumps
    z, t0 = sec.to_state(s)
    tr = simulate_state(model.automaton, z, (t0, r.t_hit + 1e-3), mode=sec.mode)
    J = tr.hybrid.jumps
    hits = [i for i in range(len(J)) if J.source[i] == sec.mode and J.guard[i] == sec.guard]
    assert len(hits) >= 2
    np.testing.assert_allclose(J.t[hits[1]], r.t_hit, rtol=0, atol=1e-12 * (1 + r.t_hit),
                               err_msg="map and simulation release at other times")
    np.testing.assert_allclose(J.pre[hits[1]], r.z_hit, rtol=1e-10, atol=1e-12,
                               err_msg="map and simulation release at other states")
    # the saltation chain through the tiny late impacts of the burst is well conditioned:
    # a longer unresolved tail (fewer of them) gives the same DP
    coarse = SectionMap(sec, t_max=P.t_max, zeno=ZenoOptions(tail_tol=1e-9)).apply(
        s, jacobian=True)
    assert len(coarse.jumps) < len(r.jumps)
    np.testing.assert_allclose(coarse.DP, r.DP, rtol=0, atol=1e-9 * np.max(np.abs(r.DP)),
                               err_msg="DP depends on how many tail impacts are resolved")
    plain = SectionMap(sec, t_max=P.t_max, zeno=ZenoOptions()).apply(s)
    assert len(plain.jumps) < len(coarse.jumps)
    assert np.max(np.abs(plain.z_hit - r.z_hit)) > 1e-9 * np.max(np.abs(r.z_hit))
