"""The section map hands the runs its compiled loop cannot finish alone (contacts that keep
refiring at one instant; a joint jump, with ``joint="resolve"``) to the section's resolver, as
a simulation does.

Reference: two identical, uncoupled forced oscillators against their own stops, started in
step. Their impacts are simultaneous, so the compiled run reports a joint jump; the resolver
reflects both velocities at once. Uncoupled, each oscillator moves as the single oscillator
of :func:`impact_oscillator` does, so the map of the pair is the single map twice, and its
multipliers are the single orbit's, each twice.
"""
import numpy as np
import pytest

from hybridpd.analysis.hybridmap import Section, SectionMap
from hybridpd.analysis.labels import LABELS
from hybridpd.analysis.mappers import mapper
from hybridpd.analysis.periodic import find_orbit
from hybridpd.hybrid.automaton import Guard, HybridAutomaton, Mode
from hybridpd.hybrid.modes import ZenoOptions
from hybridpd.hybrid.samples import impact_oscillator, oscillator_initial_state

W, E, STOP = 0.8, 0.8, 1.0


def _twins():
    """States ``x1, v1, x2, v2, f_c, f_s``: two oscillators, one forcing."""
    exo = np.array([[0.0, -W], [W, 0.0]])
    A = np.zeros((6, 6))
    for i in (0, 2):
        A[i, i + 1] = 1.0
        A[i + 1, i:i + 2] = [-1.0, -0.2]           # omega0 = 1, zeta = 0.1
        A[i + 1, 4] = 1.0
    A[4:, 4:] = exo
    guards = []
    for i, name in ((0, "impact1"), (2, "impact2")):
        R = np.eye(6)
        R[i + 1, i + 1] = -E
        c = np.zeros(6)
        c[i] = -1.0
        guards.append(Guard(name, c=c, d=STOP, direction=-1, reset=(R, np.zeros(6)),
                            target="free", group=1))
    return HybridAutomaton([Mode("free", A, guards=tuple(guards))],
                           state_names=("x1", "v1", "x2", "v2", "f_c", "f_s"))


def _resolver(mode, guard, t, z, refire=0):
    """Both oscillators at their stops reflect together."""
    z = np.array(z, float)
    names = []
    for i, name in ((0, "impact1"), (2, "impact2")):
        if abs(z[i] - STOP) <= 1e-9 * (1 + STOP):
            z[i + 1] *= -E
            names.append(name)
    return z, "free", tuple(names)


def _single():
    ha = impact_oscillator(omega0=1.0, zeta=0.1, omega=W, stop=STOP, e=E, sticking=False)
    ref = (oscillator_initial_state(0, 0, omega=W), 0.0)
    return SectionMap(Section(ha, "free", "impact", reference=ref))


def _pair(resolver, joint="resolve"):
    z = oscillator_initial_state(0, 0, omega=W)
    ref = (np.array([z[0], z[1], z[0], z[1], z[2], z[3]]), 0.0)
    return SectionMap(Section(_twins(), "free", "impact1", reference=ref, resolver=resolver),
                      joint=joint)


def _in_step(P2, z1, t):
    """The pair's section point of both oscillators in the single one's state ``z1``."""
    return P2.section.from_state(np.array([z1[0], z1[1], z1[0], z1[1], z1[2], z1[3]]), t)


def test_a_joint_jump_goes_to_the_resolver_and_gives_the_uncoupled_answer():
    P1 = _single()
    orb = find_orbit(P1, [7.7, 1.66])
    assert orb.converged
    P2 = _pair(_resolver)
    for ds in ([0.0, 0.0], [0.05, -0.02], [-0.1, 0.03]):
        s1 = orb.s + np.array(ds)
        r1 = P1.apply(s1)
        z1, t1 = P1.section.to_state(s1)
        r2 = P2.apply(_in_step(P2, z1, t1))
        assert r2.ok and r2.status == "returned"
        assert any(j[4] == "simultaneous" for j in r2.jumps)
        zh = r1.z_hit
        np.testing.assert_allclose(r2.z_hit, [zh[0], zh[1], zh[0], zh[1], zh[2], zh[3]],
                                   rtol=1e-10, atol=1e-10)
        assert r2.t_hit == pytest.approx(r1.t_hit, rel=1e-12, abs=1e-12)
    # without a resolver, or by default, the same run is refused
    z1, t1 = P1.section.to_state(orb.s)
    for P in (_pair(None), _pair(_resolver, joint="refuse")):
        r0 = P.apply(_in_step(P2, z1, t1))
        assert not r0.ok and r0.status == "simultaneous"
    with pytest.raises(ValueError, match="joint"):
        _pair(_resolver, joint="maybe")


@pytest.mark.slow
def test_the_stiff_lightly_damped_arm_has_its_orbit():
    """arm3.toml with kp = 60, kv = 4 on every joint: its contacts keep refiring at one
    instant, which only the resolver settles. The orbit returns after one period under the
    model's own simulator, and the finite-difference Jacobian whose eigenvalues are its
    multipliers predicts six iterates of a perturbation of the (resolved) map."""
    from pathlib import Path

    import hybridpd as hp
    from hybridpd.analysis.model_orbits import orbit_from_model
    from hybridpd.mechanics.params import ModelTemplate
    from hybridpd.mechanics.simulate import simulate_state

    models = Path(hp.__file__).parents[1] / "examples" / "models"
    model = ModelTemplate.load(models / "arm3.toml").model({"controller.*.kp": 60.0,
                                                            "controller.*.kv": 4.0})
    orb, P = orbit_from_model(model, 0, event="release")
    assert orb.converged and orb.period == 1 and orb.stable, orb.reason
    z0, t0 = P.section.to_state(orb.s)
    T = P.section.reference_period
    run = simulate_state(model.automaton, z0, (t0, t0 + T), mode=orb.mode).hybrid
    np.testing.assert_allclose(run(t0 + T), z0, rtol=0,
                               atol=1e-7 * max(1.0, float(np.abs(z0).max())))
    J = P.jacobian_fd(orb.s)
    np.testing.assert_allclose(np.sort(np.abs(np.linalg.eigvals(J)))[::-1][:6],
                               np.sort(np.abs(orb.multipliers))[::-1][:6], rtol=1e-3)
    ds = np.zeros(P.dim)
    ds[1:] = 1e-7 * np.maximum(1.0, np.abs(orb.s[1:]))
    s, lin = orb.s + ds, ds
    for _ in range(6):
        s, lin = P(s), J @ lin
        err = np.abs(P.wrap(s - orb.s) - lin).max()
        assert err <= 0.05 * np.abs(lin).max()
    # the basin labeller takes the same resolved applications (it labelled every point
    # zeno_sticking where its compiled run stopped): three iterations bring perturbations of
    # 1e-4 within the criterion, as the spectral radius 0.53 says
    ds = np.zeros((2, P.dim))
    ds[0, 1], ds[1, 2] = 1e-4, -1e-4
    lab, its = mapper(P, orb.s, n_iter=3, early_exit=False).labels(orb.s + ds)
    assert [LABELS[i] for i in lab] == ["converged"] * 2 and list(its) == [3, 3]


def test_basins_hand_runs_the_compiled_loop_cannot_finish_to_the_resolver():
    """With at most one jump per instant the twins' impacts in step stop the compiled run
    (contacts refiring at one instant); the map takes such an application to the resolver,
    and the basin labeller must too: started in step, the twins converge exactly when the
    single oscillator does."""
    P1 = _single()
    orb = find_orbit(P1, [7.7, 1.66])
    calls = []

    def counting(*a, **kw):
        calls.append(a[2])
        return _resolver(*a, **kw)

    def twins(resolver):
        z = oscillator_initial_state(0, 0, omega=W)
        ref = (np.array([z[0], z[1], z[0], z[1], z[2], z[3]]), 0.0)
        return SectionMap(Section(_twins(), "free", "impact1", reference=ref,
                                  resolver=resolver), joint="resolve",
                          zeno=ZenoOptions(max_instant_jumps=1))

    P2 = twins(counting)
    fp2 = _in_step(P2, *P1.section.to_state(orb.s))
    rng = np.random.default_rng(3)
    starts = orb.s + rng.uniform(-1, 1, (10, 2)) * [2.0, 1.0]
    starts = starts[[P1.section.fires(P1.section.to_state(s)[0]) > 0 for s in starts]]
    lab1, _ = mapper(P1, orb.s, n_iter=200).labels(starts)
    in_step = np.array([_in_step(P2, *P1.section.to_state(s)) for s in starts])
    lab2, its2 = mapper(P2, fp2, n_iter=200).labels(in_step)
    assert len(starts) >= 5 and np.any(lab1 == LABELS.index("converged"))
    np.testing.assert_array_equal(lab2, lab1)
    assert len(calls) >= np.sum(its2)       # every application went to the resolver
    # without a resolver the compiled run's answer stays: an accumulation at one instant
    lab0, _ = mapper(twins(None), fp2, n_iter=200, early_exit=False).labels(in_step)
    assert np.all(lab0 == LABELS.index("zeno_sticking"))
