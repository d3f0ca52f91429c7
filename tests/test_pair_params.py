"""The impact pair's parameters by name: validation, the packed array and its named indices."""
import math
import pathlib
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

import hybridpd
from hybridpd.pair import batch
from hybridpd.pair import params as P
from hybridpd.pair.params import NAMES, PairParams

_POSITIVE = ("kp", "kv", "mu", "gamma", "omega", "m2", "x10")
_positive = st.floats(min_value=1e-6, max_value=1e6, allow_nan=False)
_unit = st.floats(min_value=0.0, max_value=1.0)


def _valid():
    return st.fixed_dictionaries({**{k: _positive for k in _POSITIVE}, "e": _unit,
                                  "xm": st.floats(min_value=-1e3, max_value=1e3)})


@settings(max_examples=200, deadline=None)
@given(_valid())
def test_every_value_in_range_is_kept_by_name(values):
    p = PairParams(**values)
    d = p.as_dict()
    assert set(d) == set(NAMES)
    for k, v in values.items():
        np.testing.assert_allclose(d[k], v, rtol=0, atol=0)
    np.testing.assert_allclose(p.L, values["gamma"] * values["x10"], rtol=1e-15, atol=0)
    np.testing.assert_allclose(p.m1, values["mu"] * values["m2"], rtol=1e-15, atol=0)


_outside_positive = st.sampled_from([0.0, -0.0, -1e-300, -1.0, math.inf, -math.inf, math.nan])


@settings(max_examples=200, deadline=None)
@given(_valid(), st.sampled_from(_POSITIVE), _outside_positive)
def test_a_positive_parameter_out_of_range_is_named_with_its_range(values, name, bad):
    values[name] = bad
    with pytest.raises(ValueError, match=rf"^{name} must .*\(0, inf\)"):
        PairParams(**values)


@settings(max_examples=100, deadline=None)
@given(_valid(), st.one_of(st.floats(max_value=-1e-12, allow_infinity=False),
                           st.floats(min_value=1.0 + 1e-12, allow_infinity=False),
                           st.just(math.nan)))
def test_a_restitution_out_of_unit_interval_is_named_with_its_range(values, bad):
    values["e"] = bad
    with pytest.raises(ValueError, match=r"^e must .*\[0, 1\]"):
        PairParams(**values)


@pytest.mark.parametrize("bad", ["1", None, True, [1.0], np.array([1.0, 2.0])])
def test_a_value_that_is_no_real_number_is_refused(bad):
    with pytest.raises(ValueError, match="^kv must be a"):
        PairParams(kp=1, kv=bad, mu=0.1, gamma=0.75, omega=5, e=0.5)


def test_the_product_gamma_x10_must_be_finite():
    with pytest.raises(ValueError, match="gamma \\* x10"):
        PairParams(kp=1, kv=1, mu=0.1, gamma=1e200, omega=5, e=0.5, x10=1e200)


@settings(max_examples=200, deadline=None)
@given(_valid())
def test_the_packed_array_round_trips(values):
    p = PairParams(**values)
    a = p.packed()
    assert a.shape == (P.N_PACKED,) and a.dtype == np.float64
    # each entry at its named index, checked against the fields (not the packer's table)
    expect = {P.KP: values["kp"], P.KV: values["kv"], P.M2: values["m2"],
              P.MU: values["mu"], P.E: values["e"], P.L: values["gamma"] * values["x10"],
              P.OMEGA: values["omega"], P.XM: values["xm"]}
    assert sorted(expect) == list(range(P.N_PACKED))
    for i, v in expect.items():
        np.testing.assert_allclose(a[i], v, rtol=1e-15, atol=0)
    q = PairParams.from_packed(a, x10=values["x10"])
    for k in NAMES:
        np.testing.assert_allclose(getattr(q, k), getattr(p, k), rtol=4e-16, atol=0)
    # the unvalidated packer of the kernels lays the array out the same way
    b = batch.pack_params(kp=p.kp, kv=p.kv, m2=p.m2, mu=p.mu, e=p.e, L=p.L, w=p.omega,
                          xm=p.xm)
    np.testing.assert_allclose(b, a, rtol=0, atol=0)


def test_packing_needs_the_reference_amplitude_and_a_whole_array():
    p = PairParams(kp=10, kv=20, mu=0.1, gamma=0.75, omega=5, e=0.5)
    with pytest.raises(ValueError, match="^xm must"):
        p.packed()
    with pytest.raises(ValueError, match=r"shape \(8,\)"):
        PairParams.from_packed(np.ones(7))


def test_replace_validates_and_knows_the_clearance():
    p = PairParams(kp=10, kv=20, mu=0.1, gamma=0.75, omega=5, e=0.5, x10=2.0)
    np.testing.assert_allclose(p.replace(L=3.0).gamma, 1.5, rtol=1e-15, atol=0)
    q = p.replace(x10=3.0, L=p.L)
    np.testing.assert_allclose(q.L, 1.5, rtol=1e-15, atol=0)
    np.testing.assert_allclose(p.replace(x10=3.0).L, 2.25, rtol=1e-15, atol=0)
    with pytest.raises(ValueError, match="^e must"):
        p.replace(e=2.0)
    with pytest.raises(ValueError, match="unknown parameter"):
        p.replace(Kp=1.0)
    with pytest.raises(ValueError, match="L or gamma"):
        p.replace(L=1.0, gamma=1.0)
    with pytest.raises(AttributeError):
        p.kp = 1.0     # frozen


def _flight_reference(p: PairParams, case, t0, state, tau):
    """The closed loop between impacts integrated by solve_ivp from CONVENTIONS.md:
    ``m2 x2'' = m2 xd'' + kp (xd - x) + kv (xd' - x')`` with ``x = x2`` (collocated) or
    ``x1`` (non-collocated), ``x1'' = 0``, ``xd = xm cos(omega t)``."""
    def rhs(t, z):
        x1, y1, x2, y2 = z
        xd = p.xm * math.cos(p.omega * t)
        vd = -p.xm * p.omega * math.sin(p.omega * t)
        ad = -p.omega ** 2 * xd
        x, v = (x2, y2) if case == 0 else (x1, y1)
        return [y1, 0.0, y2, ad + (p.kp * (xd - x) + p.kv * (vd - v)) / p.m2]

    sol = solve_ivp(rhs, (t0, t0 + tau), state, method="DOP853", rtol=1e-12, atol=1e-12)
    return sol.y[:, -1]


@pytest.mark.parametrize("case", [0, 1])
def test_the_kernels_read_every_parameter_by_its_name(case):
    # distinct values for every entry: a kernel reading the wrong index would see another
    p = PairParams(kp=7.0, kv=3.0, mu=0.3, gamma=0.6, omega=2.5, e=0.4, m2=1.7, x10=1.3,
                   xm=0.9)
    state = [0.2, 0.5, -0.1, 0.3]
    t0, tau = 0.37, 0.8
    got = batch._eval.interpret(p.packed(), case, batch.Flight(t0, *state), tau, 0.0)[:4]
    want = _flight_reference(p, case, t0, state, tau)
    np.testing.assert_allclose(got, want, rtol=1e-8, atol=1e-9)


def test_no_parameter_is_read_by_a_bare_index():
    root = pathlib.Path(hybridpd.__file__).parent / "pair"
    bare = re.compile(r"\bparams\[\s*\d+\s*\]")
    for path in (root / "batch.py", root / "impactmap.py", root / "testfunctions.py"):
        hits = bare.findall(path.read_text())
        assert not hits, (path.name, hits)
