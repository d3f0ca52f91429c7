"""General mechanical systems: the impact pair as a model file, drivetrains and gear trains
against an independent solve_ivp loop, impact bookkeeping, simultaneous contacts."""
import copy
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from hybridpd import ImpactPair, PDGains
from hybridpd import Reference as PairReference
from hybridpd.mechanics import (
    Contact,
    MechanicalSystem,
    Reference,
    build_automaton,
    mechanical_loop,
)
from hybridpd.mechanics.modelfile import load_model, model_from_dict
from hybridpd.mechanics.naive import naive_mechanical
from hybridpd.mechanics.simulate import simulate, simulate_state
from hybridpd.pair.impactpair import ControlledImpactPair

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "examples" / "models"


def pair_model(case="collocated", xm=1.0, e=0.5):
    d = tomllib.loads((MODELS / "impact_pair.toml").read_text())
    d["controller"]["measure"] = "x2" if case == "collocated" else "x1"
    d["reference"]["amplitude"] = xm
    d["contact"][0]["restitution"] = e
    return model_from_dict(d)


@pytest.mark.parametrize("case,xm,n_imp", [
    ("collocated", 1.0, 30),        # the default, chaotic case: the first 30 impacts
    ("noncollocated", 1.0, 30),
    ("collocated", 2.0, 200),       # a stable period-4 impact orbit
    ("noncollocated", 1.0, 200),    # a stable (non-chaotic) motion
])
def test_pair_model_file_reproduces_the_specialised_path(case, xm, n_imp):
    model = pair_model(case, xm)
    pair = ControlledImpactPair(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20),
                                PairReference(xm, 5.0), case)
    tp = pair.simulate([0.3, 0.5, 0.0, 0.0], (0.0, 1e4), max_impacts=n_imp)
    tm = model.simulate(1e4, max_impacts=n_imp)
    assert tp.n_impacts == tm.n_impacts == n_imp
    np.testing.assert_array_equal(tm.walls, tp.walls)
    assert np.max(np.abs(tm.impact_times - tp.impact_times)) < 1e-10
    scale = 1.0 + np.abs(tp.pre).max()
    assert np.max(np.abs(tm.pre - tp.pre)) < 1e-8 * scale
    dm, dp = tm.to_dict(), tp.to_dict()
    assert dm.keys() == dp.keys()
    assert [list(i) for i in dm["impacts"][:1]] == [list(i) for i in dp["impacts"][:1]]
    assert dm["termination"] == dp["termination"] == "jump_limit"


def test_pair_json_identical_in_format_through_the_cli():
    pair = subprocess.run(
        [sys.executable, "-m", "hybridpd", "simulate", "--case", "collocated", "--mu", "0.1",
         "--e", "0.5", "--L", "0.75", "--omega", "5", "--kp", "10", "--kv", "20", "--xm", "1",
         "--x0", "0.3", "0.5", "0", "0", "--t-end", "4", "--json"],
        capture_output=True, text=True, cwd=ROOT, check=True)
    model = subprocess.run(
        [sys.executable, "-m", "hybridpd", "simulate", "--model",
         str(MODELS / "impact_pair.toml"), "--t-end", "4", "--json"],
        capture_output=True, text=True, cwd=ROOT, check=True)
    a, b = json.loads(pair.stdout), json.loads(model.stdout)
    assert a.keys() == b.keys() == {"impacts", "sticking", "termination", "t_final"}
    assert len(a["impacts"]) == len(b["impacts"]) > 3
    for x, y in zip(a["impacts"], b["impacts"]):
        assert list(x) == list(y) == ["t", "contact", "wall", "pre", "post", "grazing"]
        assert abs(x["t"] - y["t"]) < 1e-12 and x["wall"] == y["wall"] and y["contact"] == 0
    assert (a["termination"], a["t_final"]) == (b["termination"], b["t_final"])


def _raw(model):
    s = model.system
    cons = [(c.normal, c.lo, c.hi, c.restitution) for c in model.contacts]
    return s, cons


def rattling_drivetrain():
    """Motor - flexible shaft - gear - backlash - light load: the load rattles, never sticks."""
    ks = 50.0
    s = MechanicalSystem(["load", "gear", "motor"], M=np.diag([0.3, 0.2, 1.0]),
                         C=[[0, 0, 0], [0, 0.2, -0.2], [0, -0.2, 0.2]],
                         K=[[0, 0, 0], [0, ks, -ks], [0, -ks, ks]], B=[0, 0, 1.0])
    loop = mechanical_loop(s, (10.0, 20.0), Reference.sine(1.0, 5.0, 1.3), "motor")
    return build_automaton(loop, [Contact([1, -1, 0], -0.75, 0.75, restitution=0.8)])


def gear_train():
    d = tomllib.loads((MODELS / "gear_train.toml").read_text())
    for c in d["contact"]:
        c["restitution"] = 0.9
    d["reference"]["omega"] = 8.0
    d["system"]["stiffness"][2][2] = 40.0
    return model_from_dict(d)


def test_drivetrain_against_independent_solve_ivp_loop():
    ma = rattling_drivetrain()
    x0 = [0.3, 0.5, 0.0, 0.0, 0.0, 0.0]
    tr = simulate(ma, x0, (0.0, 100.0), max_impacts=60)
    s = ma.loop.system
    ref = naive_mechanical(s.M, s.C, s.K, s.B, [([1, -1, 0], -0.75, 0.75, 0.8)], 10, 20,
                           [0, 0, 1], 1.0, 5.0, 1.3, x0, (0.0, 100.0), max_impacts=60,
                           rtol=1e-13, atol=1e-14)
    assert tr.n_impacts == len(ref.impact_times) == 60 and not tr.sticking
    np.testing.assert_array_equal(tr.walls, ref.walls)
    assert np.max(np.abs(tr.impact_times - ref.impact_times)) < 1e-8
    assert np.max(np.abs(tr.post - ref.post)) < 1e-6


def test_gear_train_with_coupled_mass_matrix_against_solve_ivp_loop():
    m = gear_train()
    s, cons = _raw(m)
    assert np.count_nonzero(s.M - np.diag(np.diag(s.M))) > 0
    # the rattle is chaotic: two correct solvers part by ~x3 per impact after ~20 impacts
    tr = m.simulate(100.0, max_impacts=40)
    ref = naive_mechanical(s.M, s.C, s.K, s.B, cons, 30, 6, [1, 0, 0], 1.0, 8.0, 0.0, m.x0,
                           (0.0, 100.0), max_impacts=40, rtol=1e-13, atol=1e-14)
    assert tr.n_impacts == len(ref.impact_times) == 40 and not tr.sticking
    assert set(tr.contacts) == {0, 1}
    np.testing.assert_array_equal(tr.contacts, ref.contacts)
    np.testing.assert_array_equal(tr.walls, ref.walls)
    assert np.max(np.abs(tr.impact_times - ref.impact_times)) < 1e-8


@pytest.mark.parametrize("which", ["drivetrain", "gear_train"])
def test_momentum_and_energy_bookkeeping_at_impacts(which):
    if which == "drivetrain":
        ma = rattling_drivetrain()
        tr = simulate(ma, [0.3, 0.5, 0, 0, 0, 0], (0.0, 20.0), max_impacts=40)
        contacts, s = ma.contacts, ma.loop.system
    else:
        m = gear_train()
        tr = m.simulate(20.0, max_impacts=40)
        contacts, s = m.contacts, m.system
    assert tr.n_impacts == 40
    Minv = np.linalg.inv(s.M)
    for k, pre, post in zip(tr.contacts, tr.pre, tr.post):
        c = contacts[k]
        w = c.normal
        v0, v1 = pre[1::2], post[1::2]
        np.testing.assert_array_equal(pre[0::2], post[0::2])        # positions do not jump
        # Newton's law on the normal velocity
        assert abs(w @ v1 + c.restitution * (w @ v0)) < 1e-12 * (1 + abs(w @ v0))
        # the generalised momentum changes only along the normal: M dv = P w
        dp = s.M @ (v1 - v0)
        P = (w @ dp) / (w @ w)
        np.testing.assert_allclose(dp, P * w, atol=1e-12 * (1 + np.abs(dp).max()))
        assert abs(P + (1 + c.restitution) * (w @ v0) / (w @ Minv @ w)) < 1e-11 * (1 + abs(P))
        # kinetic energy lost: (1 - e^2) (w.v)^2 / (2 w.M^-1 w)
        dT = s.kinetic_energy(pre) - s.kinetic_energy(post)
        expect = (1 - c.restitution ** 2) * (w @ v0) ** 2 / (2 * w @ Minv @ w)
        assert abs(dT - expect) < 1e-11 * (1 + expect)
    if which == "gear_train":
        # stage 2 (mid-load) impacts move the motor too, through the coupled M
        k2 = np.flatnonzero(tr.contacts == 1)
        assert k2.size and np.all(np.abs(tr.post[k2, 1] - tr.pre[k2, 1]) > 0)


def two_masses_at_stops(M):
    s = MechanicalSystem(["a", "b"], M=M, B=[1.0, 0.0])
    loop = mechanical_loop(s, (0.0, 0.0), Reference.constant(0.0), "a")
    return build_automaton(loop, [Contact([1, 0], hi=0.5, restitution=0.5),
                                  Contact([0, 1], hi=0.5, restitution=0.5)])


def test_simultaneous_contacts_resolved_jointly():
    x0 = [0.0, 1.0, 0.0, 1.0]                     # both stops reached at t = 0.5
    for M in ([[1.0, 0.2], [0.2, 1.0]], np.eye(2)):
        tr = simulate(two_masses_at_stops(M), x0, (0.0, 2.0))
        assert tr.termination == "end_time"
        assert tr.n_impacts == 2 and sorted(tr.contacts) == [0, 1]
        np.testing.assert_allclose(tr.impact_times, 0.5, atol=1e-14)
        # both leave at e times their closing speed (hand-solved LCP, both impulses > 0)
        np.testing.assert_allclose(tr.post[-1][1::2], [-0.5, -0.5], atol=1e-13)


def test_gear_train_holds_both_meshes_at_once_and_respects_the_gaps():
    m = load_model(MODELS / "gear_train.toml")
    tr = m.simulate(30.0)
    assert tr.termination == "end_time"
    modes = set(tr.hybrid.segments.mode)
    assert any(md.startswith("stick0") and "1" in md[6:] for md in modes)   # both held
    ts = np.linspace(0.0, tr.t_final, 20001)
    assert tr.zeno_tails
    for a, b, _ in tr.zeno_tails:                 # unresolved tails: documented exception
        ts = ts[(ts < a) | (ts > b)]
    q = tr.mechanical(ts)[:, 0::2]
    for c in m.contacts:
        gap = q @ c.normal
        assert gap.max() <= c.hi + 1e-9 and gap.min() >= c.lo - 1e-9
    for a, b, k in tr.sticking:
        assert b >= a and k in (0, 1)


@pytest.mark.parametrize("e,d", [(0.5, 1.0), (0.8, 1.0), (0.3, 0.1), (0.9, 3.0)])
def test_sticking_on_a_stop_under_a_pressing_force(e, d):
    """A unit mass under P control towards a set-point a distance d beyond a stop at 1:
    x'' = 4 (1 + d - x). From the stop with rebound speed v the flight lasts
    atan(v / (2 d)) exactly (harmonic flight), so the bounces accumulate at the closed-form
    sum of all flights; then the mass rests on the stop while the controller pushes."""
    s = MechanicalSystem(["x"], M=[[1.0]], B=[1.0])
    loop = mechanical_loop(s, (4.0, 0.0), Reference.constant(1.0 + d), "x")
    ma = build_automaton(loop, [Contact([1.0], hi=1.0, restitution=e)])
    tr = simulate(ma, [1.0, 1.0], (0.0, 10.0))
    assert tr.termination == "end_time"
    assert len(tr.sticking) == 1 and tr.sticking[0][2] == 0 and tr.sticking[0][1] == 10.0
    flights = np.arctan(e ** np.arange(1, 5000) / (2.0 * d))
    k = tr.n_impacts
    np.testing.assert_allclose(tr.impact_times, np.r_[0.0, np.cumsum(flights)][:k],
                               atol=1e-12)
    # the sticking phase starts at the accumulation point (closed form) to 1e-9
    assert len(tr.accumulations) == 1
    t_inf, contact, wall, n_resolved = tr.accumulations[0]
    assert (contact, wall, n_resolved) == (0, 1, k)
    np.testing.assert_allclose(t_inf, flights.sum(), rtol=0, atol=1e-9)
    np.testing.assert_allclose(tr.sticking[0][0], t_inf, rtol=0, atol=0)
    # ... with the state on the contact: gap at the bound, zero velocity
    np.testing.assert_allclose(tr.mechanical(t_inf), [1.0, 0.0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(tr.mechanical(9.0), [1.0, 0.0], atol=1e-12)


BAD = [
    (lambda d: d["system"].update(massx=1), "system.massx"),
    (lambda d: d.update(extra={}), "extra"),
    (lambda d: d["system"].update(mass=[[1, 0], [0, 1]]), "system.masses"),
    (lambda d: d["system"].update(masses=[0.1]), "system.masses"),
    (lambda d: (d["system"].pop("masses"), d["system"].update(mass=[[1, 2], [2, 1]])),
     "system.mass"),
    (lambda d: (d["system"].pop("masses"), d["system"].update(mass=[[1, 0.5], [0, 1]])),
     "system.mass"),
    (lambda d: d["system"].update(dofs=["x1", "x1"]), "system.dofs"),
    (lambda d: d["contact"][0].update(lo=1.0), "contact[0].lo"),
    (lambda d: d["contact"][0].update(restitution=1.5), "contact[0].restitution"),
    (lambda d: d["contact"][0].update(stiffness=1e4), "contact[0].restitution"),
    (lambda d: d["contact"][0].update(dof="x1"), "contact[0].between"),
    (lambda d: d["contact"][0].pop("between"), "contact[0].between"),
    (lambda d: d["contact"][0].update(between=["x1", "x9"]), "contact[0].between"),
    (lambda d: d["contact"][0].update(normal=[1.0]) or d["contact"][0].pop("between"),
     "contact[0].normal"),
    (lambda d: (d["contact"][0].pop("lo"), d["contact"][0].pop("hi")), "contact[0].hi"),
    (lambda d: d["initial"].update(q=[2.0, 0.0]), "initial"),
    (lambda d: d["initial"].update(q=[0.0]), "initial.q"),
    (lambda d: d["controller"].update(type="tf", num=[1, 2, 3], den=[1, 1]) or
     [d["controller"].pop(k) for k in ("kp", "kv")], "controller.num"),
    (lambda d: d["controller"].update(type="lqr"), "controller.type"),
    (lambda d: d["controller"].update(measure="x3"), "controller.measure"),
    (lambda d: d["controller"].update(num=[1.0]), "controller.num"),
    (lambda d: d["controller"].update(dt=-0.1), "controller.dt"),
    (lambda d: d["reference"].update(omega=-5.0), "reference.omega"),
    (lambda d: d["reference"].update(amplitude="big"), "reference.amplitude"),
    (lambda d: d["system"].update(input=[0.0, 1.0, 2.0]), "system.input"),
]


@pytest.mark.parametrize("edit,key", BAD)
def test_bad_model_names_the_key(edit, key):
    d = tomllib.loads((MODELS / "impact_pair.toml").read_text())
    edit(d)
    with pytest.raises(ValueError, match=r"^" + key.replace("[", r"\[").replace("]", r"\]")
                       .replace(".", r"\.")):
        model_from_dict(d)


def test_cli_bad_model_file_one_line_exit_2(tmp_path):
    text = (MODELS / "impact_pair.toml").read_text().replace("restitution = 0.5",
                                                            "restitution = 1.5")
    f = tmp_path / "bad.toml"
    f.write_text(text)
    r = subprocess.run([sys.executable, "-m", "hybridpd", "simulate", "--model", str(f),
                        "--t-end", "1", "--json"], capture_output=True, text=True, cwd=ROOT,
                       check=False)
    assert r.returncode == 2 and r.stdout == ""
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "contact[0].restitution" in lines[0]
    r = subprocess.run([sys.executable, "-m", "hybridpd", "simulate", "--model",
                        str(MODELS / "impact_pair.toml"), "--t-end", "1", "--kp", "3"],
                       capture_output=True, text=True, cwd=ROOT, check=False)
    assert r.returncode == 2 and "--kp" in r.stderr


@pytest.mark.parametrize("name", ["impact_pair", "drivetrain", "gear_train"])
def test_shipped_models_load_and_run(name):
    m = load_model(MODELS / f"{name}.toml")
    tr = m.simulate(m.t0 + 5.0, max_impacts=5000)
    assert tr.termination == "end_time" and tr.n_impacts > 0
    d = tr.to_dict()
    json.dumps(d)
    assert all(len(i["pre"]) == 2 * m.system.n for i in d["impacts"])


def test_reference_and_measurement_semantics():
    """u = m_ff xd'' + kp (xd - q_m) + kv (xd' - v_m) along B, checked on the loop's force row."""
    d = tomllib.loads((MODELS / "drivetrain.toml").read_text())
    m = model_from_dict(copy.deepcopy(d))
    loop = m.automaton.loop
    rng = np.random.default_rng(1)
    q, v, t = rng.normal(size=3), rng.normal(size=3), 0.7
    z = loop.initial_state(q, v, t)
    xd, vd, ad = loop.reference(t)
    assert xd == pytest.approx(np.cos(2.0 * t))
    u = 3.2 * ad + 20.0 * (xd - q[2]) + 5.0 * (vd - v[2])
    assert loop.force @ z == pytest.approx(u, rel=1e-12)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["drivetrain", "sampled_drivetrain", "compliant_contact"])
def test_examples_run_and_write_their_figure(name, tmp_path):
    import os

    env = dict(os.environ, PYTHONPATH=str(ROOT))
    r = subprocess.run([sys.executable, str(ROOT / "examples" / "mechanical" / f"plot_{name}.py"), "--out",
                        str(tmp_path)], capture_output=True, text=True, env=env, check=False)
    assert r.returncode == 0, r.stderr
    png = tmp_path / f"{name}.png"
    assert png.exists() and png.stat().st_size > 10_000


def _pair_dict():
    return tomllib.loads((MODELS / "impact_pair.toml").read_text())


def test_model_file_transfer_function_controller_poles():
    """tf from err: closed-loop poles of x2 are the roots of m2 s^2 den + num (independent of
    python-control's interconnection), plus the free x1 (0, 0) and the exosystem (+-5i)."""
    d = _pair_dict()
    d["controller"] = {"type": "tf", "num": [20.0, 10.0], "den": [1.0, 10.0], "measure": "x2"}
    loop = model_from_dict(d).automaton.loop
    expect = np.r_[np.roots(np.polyadd(np.polymul([1.0, 0.0, 0.0], [1.0, 10.0]),
                                       [20.0, 10.0])), 0.0, 0.0, 5j, -5j]
    got = np.linalg.eigvals(loop.A)
    for lam in expect:
        assert np.min(np.abs(got - lam)) < 1e-6
    assert loop.state_names[-1] == "c1"


def test_model_file_state_space_discrete_delay_and_sensors():
    d = _pair_dict()
    d["controller"] = {"type": "ss", "A": [[0.5]], "B": [[1.0, 0.0]], "C": [[2.0]],
                       "D": [[10.0, 3.0]], "measure": "x2", "measure_velocity": "x1",
                       "dt": 0.01, "delay": 1}
    d["reference"] = {"type": "sum_of_sines", "amplitudes": [1.0, 0.5], "omegas": [5.0, 7.0],
                      "feedforward_mass": 1.0}
    m = model_from_dict(d)
    loop = m.automaton.loop
    assert loop.dt == 0.01 and loop.delay == 1
    assert loop.state_names == ("x1", "x1_dot", "x2", "x2_dot", "pc1", "ps1", "pc2", "ps2",
                                "c1", "h0", "h1", "s")
    R, r = loop.sample_reset
    z = np.arange(1.0, 13.0)
    zp = R @ z + r
    xd = z[4] + z[6]
    vd = -5.0 * z[5] - 7.0 * z[7]
    ad = -25.0 * z[4] - 49.0 * z[6]
    err, err_dot = xd - z[2], vd - z[1]                 # position of x2, velocity of x1
    assert zp[8] == pytest.approx(0.5 * z[8] + err)     # x+ = A x + B [err, err_dot]
    assert zp[9] == pytest.approx(ad + 2.0 * z[8] + 10.0 * err + 3.0 * err_dot)
    assert zp[10] == z[9] and zp[11] == z[11] - 0.01    # shift register, clock
    tr = m.simulate(1.0)
    assert tr.termination == "end_time" and tr.samples.size >= 99


def test_restart_from_a_full_state_reproduces_the_run():
    """simulate_state from the state at t = 1 (sampled-data loop: clock and held force
    included) continues the same trajectory: impact times and sampling instants."""
    d = _pair_dict()
    d["controller"]["dt"] = 0.01
    m = model_from_dict(d)
    ma = m.automaton
    full = m.simulate(3.0)
    t_mid = 1.0005                               # between two samples
    part = simulate_state(ma, full(t_mid), (t_mid, 3.0))
    later = full.impact_times[full.impact_times > t_mid]
    assert later.size >= 2
    np.testing.assert_allclose(part.impact_times, later, atol=1e-12)
    np.testing.assert_allclose(part.samples, full.samples[full.samples > t_mid], atol=1e-12)
    assert ma.guard_name(0, -1) == "contact0-"
    with pytest.raises(ValueError, match="no guard"):
        ma.guard_name(1, 1)


def test_both_meshes_held_against_an_independent_constrained_solve():
    """A phase of the gear train with both meshes held: the state and the release time
    against solve_ivp on the Lagrange (KKT) formulation, M a = f + W lambda, W^T a = 0, with
    the force written from the raw model, released when a multiplier changes sign."""
    from scipy.integrate import solve_ivp

    m = load_model(MODELS / "gear_train.toml")
    s = m.system
    tr = m.simulate(3.0)
    seg = tr.hybrid.segments
    i = next(j for j in range(len(seg)) if seg.mode[j] in ("stick0+1+", "stick0-1-")
             and seg.t_end[j] - seg.t_start[j] > 0.3)
    t0, t1 = seg.t_start[i], seg.t_end[i]
    walls = (1, 1) if seg.mode[i] == "stick0+1+" else (-1, -1)
    W = np.array([c.normal for c in m.contacts]).T
    n = s.n

    def kkt(t, x):
        q, v = x[0::2], x[1::2]
        xd, vd = np.cos(3.0 * t), -3.0 * np.sin(3.0 * t)
        u = 30.0 * (xd - q[0]) + 6.0 * (vd - v[0])
        f = -s.C @ v - s.K @ q + s.B * u
        KKT = np.block([[s.M, -W], [W.T, np.zeros((2, 2))]])
        sol = np.linalg.solve(KKT, np.r_[f, 0.0, 0.0])
        return sol[:n], sol[n:]

    def rhs(t, x):
        out = np.empty(2 * n)
        out[0::2], out[1::2] = x[1::2], kkt(t, x)[0]
        return out

    events = []
    for k in range(2):
        def ev(t, x, k=k):
            return -walls[k] * kkt(t, x)[1][k]          # > 0 while the mesh pushes
        ev.terminal, ev.direction = True, -1
        events.append(ev)
    x0 = tr.mechanical(t0 + 1e-9)
    sol = solve_ivp(rhs, (t0 + 1e-9, t1 + 1.0), x0, method="DOP853", rtol=1e-12, atol=1e-13,
                    events=events)
    t_rel = min(te[0] for te in sol.t_events if te.size)
    assert abs(t_rel - t1) < 1e-7
    mid = 0.5 * (t0 + t1)
    ref_mid = solve_ivp(rhs, (t0 + 1e-9, mid), x0, method="DOP853", rtol=1e-12,
                        atol=1e-13).y[:, -1]
    np.testing.assert_allclose(tr.mechanical(mid), ref_mid, atol=1e-8)


@pytest.mark.parametrize("vb,expect_mode,expect_v", [
    # b pulls a away from the stop through the slot: the stop cannot hold, Newton's law free
    (-1.0, "free", [-0.75, -0.25]),
    # b pushes a into the stop: a stays held, b rebounds as from a wall
    (+1.0, "stick0+", [0.0, -0.5]),
])
def test_impact_on_a_held_mass_releases_it_only_if_the_stop_would_pull(vb, expect_mode,
                                                                     expect_v):
    """Mass a is pressed against a stop (a <= 0.5) by the controller; mass b (free) reaches
    the end of its slot |a - b| <= 0.4 on a (e = 0.5, unit masses)."""
    s = MechanicalSystem(["a", "b"], M=np.eye(2), B=[1.0, 0.0])
    loop = mechanical_loop(s, (1.0, 0.0), Reference.constant(2.0), "a")
    ma = build_automaton(loop, [Contact([1, 0], hi=0.5, restitution=0.5),
                                Contact([1, -1], -0.4, 0.4, restitution=0.5)])
    b0 = 0.3 if vb < 0 else 0.7                  # a - b = 0.2 or -0.2
    tr = simulate(ma, [0.5, 0.0, b0, vb], (0.0, 0.3))
    assert tr.sticking and tr.sticking[0][2] == 0 and tr.sticking[0][0] == 0.0
    k = int(np.flatnonzero(tr.contacts == 1)[0])
    assert tr.impact_times[k] == pytest.approx(0.2, abs=1e-12)
    np.testing.assert_allclose(tr.post[k][1::2], expect_v, atol=1e-12)
    jt = tr.hybrid.jumps
    i = int(np.flatnonzero(np.asarray(jt.guard) == "contact1" + ("+" if vb < 0 else "-"))[0])
    assert jt.target[i] == expect_mode
