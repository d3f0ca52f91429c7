"""Simultaneous impacts (the multi-contact LCP law) against hand-solved cases, its
complementarity, energy and momentum properties, and the run that carries on after them."""
import numpy as np
import pytest

from hybridpd.mechanics import (
    Contact,
    MechanicalSystem,
    Reference,
    build_automaton,
    mechanical_loop,
    simulate,
)
from hybridpd.mechanics.impact import multi_impact, solve_lcp


def _free_chain(M, contacts, B=None):
    n = np.asarray(M).shape[0]
    s = MechanicalSystem([f"m{i}" for i in range(n)], M=M,
                         B=np.eye(n)[0] if B is None else B)
    loop = mechanical_loop(s, (0.0, 0.0), Reference.constant(0.0), "m0")
    return build_automaton(loop, contacts)


def _x0(q, v):
    x = np.empty(2 * len(q))
    x[0::2], x[1::2] = q, v
    return x


def _joint(tr, k):
    """The ``k`` impact records sharing the first impact time; checks they share pre/post."""
    assert tr.n_impacts >= k
    t = tr.impact_times[:k]
    np.testing.assert_allclose(t, t[0], rtol=0, atol=0, err_msg="one instant")
    for i in range(1, k):
        np.testing.assert_allclose(tr.post[i], tr.post[0], rtol=0, atol=0)
        np.testing.assert_allclose(tr.pre[i], tr.pre[0], rtol=0, atol=0)
    return t[0], tr.pre[0][1::2], tr.post[0][1::2]


def test_two_coupled_stops_hit_together():
    """Two masses coupled through M = [[1, .2], [.2, 1]] reach their stops at t = 0.5 with
    v = [1, 1], e = 0.5. By hand: A = M^-1, q = -1.5 [1, 1], lambda = 1.5 M [1, 1] = [1.8, 1.8]
    > 0, v+ = v - M^-1 lambda = [-0.5, -0.5]."""
    ma = _free_chain([[1.0, 0.2], [0.2, 1.0]], [Contact([1, 0], hi=0.5, restitution=0.5),
                                               Contact([0, 1], hi=0.5, restitution=0.5)])
    tr = simulate(ma, _x0([0, 0], [1, 1]), (0.0, 1.0))
    assert tr.termination == "end_time"
    t, _, v1 = _joint(tr, 2)
    assert sorted(tr.contacts[:2]) == [0, 1]
    np.testing.assert_allclose(t, 0.5, atol=1e-14)
    np.testing.assert_allclose(v1, [-0.5, -0.5], atol=1e-13)


def test_three_masses_middle_moving_closes_both_clearances():
    """Three unit masses, the middle one at speed 1 closes both clearances at t = 0.1
    (e = 0.5). By hand: A = [[2, 1], [1, 2]], q = [-1.5, -1.5], lambda = [0.5, 0.5],
    v+ = [0.5, 0, 0.5] (the joint answer; sequential impacts would differ)."""
    ma = _free_chain(np.eye(3), [Contact([-1, 1, 0], hi=0.1, restitution=0.5),
                                 Contact([0, 1, -1], hi=0.1, restitution=0.5)])
    tr = simulate(ma, _x0([0, 0, 0], [0, 1, 0]), (0.0, 0.5))
    assert tr.termination == "end_time"
    t, _, v1 = _joint(tr, 2)
    np.testing.assert_allclose(t, 0.1, atol=1e-14)
    np.testing.assert_allclose(v1, [0.5, 0.0, 0.5], atol=1e-13)
    assert tr.n_impacts == 2                      # and nothing else happens before 0.5


@pytest.mark.parametrize("e", [0.0, 0.5])
def test_four_clearances_of_a_converging_chain(e):
    """Five unit masses at v = [2, 1, 0, -1, -2], four clearances closing at t = 0.1. By hand:
    A = tridiag(-1, 2, -1), q = -(1 + e) [1, 1, 1, 1], lambda = (1 + e) [2, 3, 3, 2] > 0,
    v+ = -e v (all four leave at e times their closing speed; e = 0: all held, at rest)."""
    n = 5
    cs = [Contact(np.eye(n)[i] - np.eye(n)[i + 1], hi=0.1, restitution=e) for i in range(4)]
    ma = _free_chain(np.eye(n), cs)
    v = np.array([2.0, 1.0, 0.0, -1.0, -2.0])
    tr = simulate(ma, _x0([0] * n, v), (0.0, 0.3))
    t, _, v1 = _joint(tr, 4)
    np.testing.assert_allclose(t, 0.1, atol=1e-14)
    np.testing.assert_allclose(v1, -e * v, atol=1e-13)
    out = multi_impact(np.eye(n), -np.array([c.normal for c in cs]), v, [e] * 4)
    np.testing.assert_allclose(out.impulses, (1 + e) * np.array([2, 3, 3, 2]), rtol=1e-13)
    if e == 0.0:
        assert tr.hybrid.segments.mode[-1] == "stick0+1+2+3+"
        assert {k for *_, k in tr.sticking} == {0, 1, 2, 3}
        np.testing.assert_allclose(tr.mechanical(0.3)[1::2], 0.0, atol=1e-13)


def test_three_clearances_of_a_converging_chain():
    """Four unit masses at v = [1.5, 0.5, -0.5, -1.5] (e = 0.5), three clearances closing at
    t = 0.1. By hand: A = tridiag(-1, 2, -1) (3 x 3), q = -1.5 [1, 1, 1],
    lambda = 1.5 [1.5, 2, 1.5] > 0, v+ = -e v."""
    cs = [Contact(np.eye(4)[i] - np.eye(4)[i + 1], hi=0.1, restitution=0.5) for i in range(3)]
    v = np.array([1.5, 0.5, -0.5, -1.5])
    tr = simulate(_free_chain(np.eye(4), cs), _x0([0] * 4, v), (0.0, 0.15))
    t, _, v1 = _joint(tr, 3)
    np.testing.assert_allclose(t, 0.1, atol=1e-14)
    np.testing.assert_allclose(v1, -0.5 * v, atol=1e-13)
    out = multi_impact(np.eye(4), -np.array([c.normal for c in cs]), v, [0.5] * 3)
    np.testing.assert_allclose(out.impulses, 1.5 * np.array([1.5, 2.0, 1.5]), rtol=1e-13)


def test_one_contact_of_the_set_inactive():
    """Mass 0 touches mass 1 (clearance at lo, zero relative speed) while mass 1 hits mass 2
    (e = 0.5), v = [1, 1, 0]. By hand: both active would need lambda = [-0.5, 1] (< 0), so
    only the closing one pushes: lambda = [0, 0.75], v+ = [1, 0.25, 0.75], and the touching
    contact opens at 0.75."""
    ma = _free_chain(np.eye(3), [Contact([1, -1, 0], lo=-0.2, hi=0.2, restitution=0.5),
                                 Contact([0, 1, -1], hi=0.1, restitution=0.5)])
    tr = simulate(ma, _x0([-0.2, 0, 0], [1, 1, 0]), (0.0, 0.2))
    assert tr.termination == "end_time"
    np.testing.assert_allclose(tr.impact_times[0], 0.1, atol=1e-14)
    np.testing.assert_allclose(tr.post[0][1::2], [1.0, 0.25, 0.75], atol=1e-13)
    W = np.array([[1.0, -1.0, 0.0], [0.0, -1.0, 1.0]])
    out = multi_impact(np.eye(3), W, [1.0, 1.0, 0.0], [0.5, 0.5])
    np.testing.assert_allclose(out.impulses, [0.0, 0.75], atol=1e-14)
    np.testing.assert_allclose(out.u_post, [0.75, 0.5], atol=1e-14)


def test_random_lcps_complementarity_energy_and_momentum():
    """Random SPD M, random independent normals, every contact closing or touching (the
    active set: separating contacts take no part): the LCP answer satisfies the
    complementarity conditions, never adds kinetic energy, and changes the generalised
    momentum only along the contact normals."""
    rng = np.random.default_rng(7)
    worst = -np.inf
    for _ in range(400):
        n = int(rng.integers(2, 7))
        k = int(rng.integers(1, n + 1))
        L = rng.normal(size=(n, n))
        M = L @ L.T + n * np.eye(n)
        W = rng.normal(size=(k, n))
        u = -rng.uniform(0, 1, size=k) * (rng.uniform(size=k) > 0.2)   # some touching
        null = np.linalg.svd(W)[2][k:].T
        v = np.linalg.lstsq(W, u, rcond=None)[0] + null @ rng.normal(size=null.shape[1])
        e = rng.uniform(0, 1, size=k) if rng.uniform() < 0.5 else np.full(k, rng.uniform())
        Minv = np.linalg.inv(M)
        out = multi_impact(Minv, W, v, e)
        assert out is not None
        lam, u0, u1 = out.impulses, out.u_pre, out.u_post
        b = e * np.maximum(-u0, 0)
        scale = 1 + np.abs(u0).max()
        assert np.all(lam >= 0) and np.all(u1 - b >= -1e-10 * scale)
        np.testing.assert_allclose(lam * (u1 - b), 0, atol=1e-10 * scale * (1 + lam.max()))
        T0, T1 = 0.5 * v @ M @ v, 0.5 * out.v @ M @ out.v
        worst = max(worst, (T1 - T0) / max(T0, 1e-300))
        dp = M @ (out.v - v)
        np.testing.assert_allclose(dp, W.T @ lam, atol=1e-10 * (1 + np.abs(dp).max()))
    assert worst <= 1e-12, f"kinetic energy grew by {worst:.3g} (relative)"


def test_solve_lcp_degenerate_and_infeasible():
    # dependent normals: the same constraint twice, a singular A
    assert solve_lcp([[1.0, 1.0], [1.0, 1.0]], [-1.0, -1.0]) is not None
    # no solution: A = -1, q = -1
    assert solve_lcp([[-1.0]], [-1.0]) is None
    with pytest.raises(ValueError, match="A must have shape"):
        solve_lcp(np.eye(2), [1.0])


def test_three_masses_model_file_through_the_cli(capsys):
    """The same hand-solved case as a model file, through the command line: both contacts
    recorded at t = 0.1 with the joint post-impact velocities, exit status 0."""
    import json
    from pathlib import Path

    from hybridpd.cli import main

    f = Path(__file__).parents[1] / "examples" / "models" / "three_masses.toml"
    assert main(["simulate", "--model", str(f), "--t-end", "1", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["termination"] == "end_time" and len(d["impacts"]) == 2
    for imp in d["impacts"]:
        np.testing.assert_allclose(imp["t"], 0.1, atol=1e-14)
        np.testing.assert_allclose(imp["post"][1::2], [0.5, 0.0, 0.5], atol=1e-13)


def test_held_contact_takes_part_in_the_impact():
    """Masses 0 and 1 held together (contact 0 at its bound) move at 1 and hit mass 2
    through contact 1 (e = 0.5). By hand: A = [[2, -1], [-1, 2]], q = [0, -1.5],
    lambda = [0.5, 1.0] > 0 (the held contact pushes: it stays held), v+ = [0.5, 0.5, 1].
    Both the law compiled into the sticking mode and the run-time resolver give it."""
    from hybridpd.mechanics.simulate import simulate_state

    ma = _free_chain(np.eye(3), [Contact([1, -1, 0], lo=-0.3, hi=0.0, restitution=0.0),
                                 Contact([0, 1, -1], hi=0.1, restitution=0.5)])
    z0 = ma.initial_state([0.0, 0.0, 0.0], [1.0, 1.0, 0.0])
    tr = simulate_state(ma, z0, (0.0, 0.15), mode="stick0+")
    np.testing.assert_allclose(tr.impact_times[0], 0.1, atol=1e-14)
    np.testing.assert_allclose(tr.post[0][1::2], [0.5, 0.5, 1.0], atol=1e-13)
    assert tr.hybrid.jumps.target[0] == "stick0+"
    z = tr.hybrid.jumps.pre[0]
    z_post, target, names = ma.resolver()("stick0+", "contact1+", 0.1, z)
    np.testing.assert_allclose(z_post[ma.layout["v"]], [0.5, 0.5, 1.0], atol=1e-13)
    assert target == "stick0+" and names == ["contact1+"]


def test_section_map_reports_a_joint_impact_instead_of_a_sequential_one():
    """The section map's compiled run applies jumps one at a time; where the simulation would
    take a joint impact (two stops reached together) the map says so rather than give another
    answer, or (``joint="resolve"``) takes it with the model's resolver as the simulation
    does."""
    from hybridpd.analysis.hybridmap import SectionMap
    from hybridpd.mechanics.sections import mechanical_section

    ma = _free_chain([[1.0, 0.2], [0.2, 1.0]], [Contact([1, 0], hi=0.5, restitution=0.5),
                                               Contact([0, 1], hi=0.5, restitution=0.5)])
    sec = mechanical_section(ma, contact=0, wall=1)
    P = SectionMap(sec, t_max=5.0)
    z_at = np.r_[_x0([0.5, 0.5], [1.0, 1.0]), 0.0]      # both stops reached at once
    r = P.apply(sec.from_state(z_at, 0.0))
    assert not r.ok and r.status == "simultaneous"
    r = SectionMap(sec, t_max=5.0, joint="resolve").apply(sec.from_state(z_at, 0.0))
    assert [j[4] for j in r.jumps[:2]] == ["simultaneous", "simultaneous"]
    ref = ma.automaton.simulate(z_at, sec.mode, (0.0, 5.0), resolver=ma.resolver())
    assert [j[:2] for j in r.jumps] == [(float(t), m) for t, m in
                                        zip(ref.jumps.t, ref.jumps.source)][:len(r.jumps)]
    z_apart = np.r_[_x0([0.5, 0.3], [1.0, 1.0]), 0.0]   # the second one 0.2 later
    r = SectionMap(sec, t_max=5.0).apply(sec.from_state(z_apart, 0.0))
    assert r.status != "simultaneous"
    assert SectionMap(sec, t_max=5.0, simtol=None).apply(
        sec.from_state(z_at, 0.0)).status != "simultaneous"
    with pytest.raises(ValueError, match="simtol"):
        SectionMap(sec, simtol=-1.0)
