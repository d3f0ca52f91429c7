"""Region maps of model files: dotted parameter paths, continuation across the grid, every
reported orbit confirmed by an independent simulation of one period, the pair's file format."""
import json
from pathlib import Path

import numpy as np
import pytest
from _pair_model import PAIR
from _regions import model_region_map

from hybridpd.analysis.model_orbits import OrbitSearch, SectionSpec
from hybridpd.cli import main
from hybridpd.mechanics.naive import naive_mechanical
from hybridpd.mechanics.params import ModelTemplate, check_path, numeric_paths, set_values
from hybridpd.mechanics.simulate import simulate_state
from hybridpd.sweeps.model_regions import _Cells, _Context
from hybridpd.sweeps.regions import load_region_map

MODELS = Path(__file__).resolve().parents[1] / "examples" / "models"

def _cell_orbits(rm, tpl):
    """Per cell of a (kp, kv) map: the gains, the model, its section and the reported orbit's
    state and time on the section."""
    spec = SectionSpec(**rm.spec)
    for iy, kv in enumerate(rm.y):
        for ix, kp in enumerate(rm.x):
            model = tpl.model({"controller.kp": kp, "controller.kv": kv})
            sec = spec.section_map(model).section
            z, t0 = sec.to_state(rm.section_point[0, iy, ix])
            yield kp, kv, model, sec, z, t0


def test_dotted_paths_address_every_number_and_refuse_the_rest():
    t = ModelTemplate.load(MODELS / "drivetrain.toml")
    paths = t.paths
    for p in ("controller.kp", "contact.0.restitution", "system.masses.2", "reference.omega",
              "system.stiffness.1.2", "contact.1.hi"):
        assert p in paths, p
    np.testing.assert_allclose(paths["system.masses.2"], 1.0, rtol=0, atol=0)
    d = set_values(t.data, {"contact.0.restitution": 0.25, "system.stiffness.1.2": -40.0})
    assert d["contact"][0]["restitution"] == pytest.approx(0.25)
    assert d["system"]["stiffness"][1][2] == pytest.approx(-40.0)
    assert t.data["contact"][0]["restitution"] == pytest.approx(0.5)     # never modified
    m = t.model({"reference.omega": 3.0})
    np.testing.assert_allclose(m.automaton.loop.reference.omegas[0], 3.0, rtol=1e-15)
    with pytest.raises(ValueError, match=r"'controller\.kd'.*did you mean controller\.kv.*"
                                         r"contact\.0\.restitution"):
        check_path(t.data, "controller.kd")
    with pytest.raises(ValueError, match="system.masses.7"):
        set_values(t.data, {"system.masses.7": 1.0})
    with pytest.raises(ValueError, match="contact.0.restitution: must be finite"):
        set_values(t.data, {"contact.0.restitution": float("nan")})
    with pytest.raises(ValueError, match="contact\\[0\\].restitution"):
        t.model({"contact.0.restitution": 2.0})        # the file's own check names the key
    assert "controller.type" not in numeric_paths(t.data)


def test_cli_refuses_bad_paths_before_running(capsys):
    f = str(MODELS / "drivetrain.toml")
    assert main(["regions", "--model", f, "--x", "controller.kd", "1", "2", "3", "--y",
                 "controller.kv", "1", "2", "3"]) == 2
    err = capsys.readouterr().err
    assert "controller.kd" in err and "controller.kp" in err and err.count("\n") == 1
    assert main(["regions", "--model", f, "--x", "controller.kp", "1", "2", "3"]) == 2
    assert main(["regions", "--model", f, "--x", "controller.kp", "1", "2", "3", "--y",
                 "controller.kv", "1", "2", "3", "--mu", "0.1"]) == 2
    assert "--mu" in capsys.readouterr().err
    assert main(["orbit", "--model", f, "--set", "controller.kq", "3"]) == 2
    assert "controller.kq" in capsys.readouterr().err
    assert main(["orbit", "--model", f, "--event", "release", "--set", "controller.kp", "30",
                 "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["exists"] and d["n_periods"] == 1


def _naive_return(model, kp, kv, z, t0, T, wall):
    """State at the next impact on `wall` of contact 0 after one period, from the post-impact
    state at ``t0``: an independent solve_ivp run of the pair's equations."""
    x = z[:4].copy()
    w = np.array([1.0, -1.0])
    M = np.diag([0.1, 1.0])
    mw = np.linalg.solve(M, w)
    e = 0.5
    x[1::2] += -(1.0 + e) * (w @ x[1::2]) / (w @ mw) * mw     # Newton's law at the start
    ref = model.automaton.loop.reference
    r = naive_mechanical(M, np.zeros((2, 2)), np.zeros((2, 2)), [0.0, 1.0],
                         [(w, -0.75, 0.75, e)], kp, kv, [0, 1],
                         float(ref.amplitudes[0]), float(ref.omegas[0]), 1.0, x,
                         (t0, t0 + T * 1.001), rtol=1e-12, atol=1e-13)
    i = int(np.argmin(np.abs(r.impact_times - (t0 + T))))
    assert r.walls[i] == wall
    return r.impact_times[i], r.pre[i]


def test_pair_file_region_map_orbits_confirmed_by_solve_ivp(tmp_path):
    rm = model_region_map(PAIR, ("controller.kp", 6.0, 14.0, 3), ("controller.kv", 15.0, 25.0, 3),
                          progress=False, tile=2, event="impact")
    assert rm.status.shape == (1, 3, 3) and rm.exists.all(), rm.summary()
    assert set(np.unique(rm.status)) <= {0, 1}
    for kp, kv, model, sec, z, t0 in _cell_orbits(rm, ModelTemplate(PAIR)):
        t1, pre = _naive_return(model, kp, kv, z, t0, sec.period, 1)
        np.testing.assert_allclose(t1 - t0, sec.period, rtol=1e-8,
                                   err_msg=f"return time at kp={kp}, kv={kv}")
        np.testing.assert_allclose(pre, z[:4], rtol=1e-6, atol=1e-7,
                                   err_msg=f"solve_ivp does not return at kp={kp}, kv={kv}")
    # the pair's file format: the pair's reader and the plot command take it
    path = rm.save(tmp_path / "pair.nc")
    back = load_region_map(path)
    np.testing.assert_allclose(back.section_point, rm.section_point, rtol=0, atol=0)
    assert back.signature_of(1, 1) == rm.signature_of(1, 1) == (("contact0+", "crossing"),
                                                                ("contact0-", "crossing"))
    pr = load_region_map(path)
    assert pr.exists.shape == (1, 3, 3) and pr.x_name == "controller.kp"
    np.testing.assert_allclose(pr.e, [0.5], rtol=0)
    assert main(["plot", str(path), "--out", str(tmp_path / "pair.png")]) == 0
    assert (tmp_path / "pair.png").stat().st_size > 10_000


def test_robot_joint_release_map_every_orbit_returns_after_one_period(tmp_path, capsys):
    f = MODELS / "robot_joint_pd.toml"
    out = tmp_path / "rj.zarr"
    assert main(["regions", "--model", str(f), "--x", "controller.kp", "20", "40", "3",
                 "--y", "controller.kv", "4", "8", "2", "--event", "release", "--tile", "2",
                 "--out", str(out), "--json", "--quiet"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["counts"]["stable"] + d["counts"]["unstable"] == 6, d["counts"]
    # the section actually used is recorded: the releases of contact 0, no phase
    assert (d["fixed"]["section_event"], d["fixed"]["section_contact"],
            d["fixed"]["section_phase"]) == ("release", 0, None)
    rm = load_region_map(out)
    for kp, kv, model, sec, z, t0 in _cell_orbits(rm, ModelTemplate.load(f)):
        T = sec.period
        tr = simulate_state(model.automaton, z, (t0, t0 + T * (1 + 1e-6)), mode=sec.mode)
        J = tr.hybrid.jumps
        hits = [i for i in range(len(J)) if J.guard[i] == sec.guard
                and abs(J.t[i] - t0 - T) < 1e-6 * T]
        assert hits, f"no release one period later at kp={kp}, kv={kv}"
        np.testing.assert_allclose(J.pre[hits[0]], z, rtol=1e-7, atol=1e-8,
                                   err_msg=f"no return after one period at kp={kp}, kv={kv}")


def test_two_orbits_in_a_cell_are_both_kept():
    tpl = ModelTemplate(PAIR)
    spec = {k: getattr(SectionSpec(), k) for k in SectionSpec.__dataclass_fields__}
    ctx = _Context(tpl, spec, "")
    n = ctx.model.automaton.automaton.n_states

    class _O:      # the fields of PeriodicOrbit that the bookkeeping reads
        def __init__(self, z, stable, rho, sig):
            self.z = np.array(z, float)
            self.s = ctx.chart.from_state(self.z, 0.25)
            self.stable, self.spectral_radius, self.signature = stable, rho, sig
            self.period, self.mode = len(sig) // 2 or 1, "free"

    sig_a = (("contact0+", "crossing"), ("contact0-", "crossing"))
    sig_b = (("contact0+", "crossing"),) * 4
    za, zb = np.arange(n) + 1.0, np.arange(n) + 3.0
    cells = _Cells(1, ctx.chart.dim, n)
    cells.put(0, OrbitSearch(1, (_O(za, False, 1.5, sig_a),), 2), ctx)
    assert cells.a["n_orbits"][0] == 1 and cells.a["status"][0] == 1
    assert cells.add(0, OrbitSearch(0, (_O(zb, True, 0.5, sig_b),), 1), ctx)
    a = cells.a
    assert a["n_orbits"][0] == 2 and a["status"][0] == 0 and a["status2"][0] == 1
    np.testing.assert_allclose(a["z"][0], zb, rtol=0)
    np.testing.assert_allclose(a["z2"][0], za, rtol=0)
    np.testing.assert_allclose(a["s"][0], ctx.chart.from_state(zb, 0.25), rtol=0)
    np.testing.assert_allclose([a["rho"][0], a["rho2"][0]], [0.5, 1.5], rtol=0)
    assert [a["k"][0], a["k2"][0]] == [2, 1]
    seeds = cells.seeds_of(0, ctx)
    assert [sd.signature for sd in seeds] == [sig_b, sig_a]
    assert [sd.mode for sd in seeds] == ["free", "free"] and seeds[0].period == 2
    assert a["attempts"][0] == 3


def _returns(model, spec, s):
    """Relative distance of the section state to where a mechanics simulation of one period
    crosses the section again (independent of the map's kernel driver)."""
    sec = spec.section_map(model).section
    z, t0 = sec.to_state(s)
    T = sec.period
    tr = simulate_state(model.automaton, z, (t0, t0 + T * (1 + 1e-6)), mode=sec.mode)
    J = tr.hybrid.jumps
    hits = [i for i in range(len(J)) if J.guard[i] == sec.guard
            and abs(J.t[i] - t0 - T) < 1e-6 * T]
    assert hits, "no crossing one period later"
    return float(np.max(np.abs(J.pre[hits[0]] - z)) / max(1.0, np.max(np.abs(z))))


def test_two_orbits_of_the_undamped_drivetrain_both_reported_and_both_periodic():
    """Without damping in the PD (kv = 0) the drivetrain has mirror pairs of asymmetric
    orbits: the map reports every orbit found in a cell, and each returns after a period."""
    f = MODELS / "drivetrain.toml"
    rm = model_region_map(f, ("controller.kp", 0.5, 7.055, 2), ("controller.kv", 0.0, 0.4444, 2),
                          event="release", tile=1, progress=False)
    assert rm.n_orbits.max() >= 2, rm.summary()
    assert "two or more orbits" in rm.summary()
    tpl = ModelTemplate.load(f)
    spec = SectionSpec(**rm.spec)
    for iy, ix in np.argwhere(rm.n_orbits[0] >= 2):
        model = tpl.model({"controller.kp": rm.x[ix], "controller.kv": rm.y[iy]})
        a, b = rm.section_point[0, iy, ix], rm.section_point2[0, iy, ix]
        assert np.max(np.abs(a - b)) > 1e-3, "the two orbits are one"
        for s in (a, b):
            assert _returns(model, spec, s) < 1e-7
