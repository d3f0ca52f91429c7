"""Impact law (2), validation, virtual restitution (12)."""
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hybridpd.model import (
    Case,
    ImpactPair,
    PDGains,
    Reference,
    check_odd_order,
    virtual_restitution,
)

finite = dict(allow_nan=False, allow_infinity=False)


@settings(max_examples=200, deadline=None)
@given(mu=st.floats(1e-3, 1e3), e=st.floats(0, 1), m2=st.floats(1e-2, 1e2),
       y1=st.floats(-10, 10), y2=st.floats(-10, 10))
def test_impact_law_momentum_restitution_energy(mu, e, m2, y1, y2):
    pair = ImpactPair(mu=mu, e=e, L=0.5, m2=m2)
    pre = np.array([0.5, y1, 0.0, y2])
    post = pair.impact(pre, wall=+1)
    # positions unchanged
    assert post[0] == pre[0] and post[2] == pre[2]
    # momentum conserved
    p_pre = pair.m1 * y1 + pair.m2 * y2
    p_post = pair.m1 * post[1] + pair.m2 * post[3]
    assert p_post == pytest.approx(p_pre, rel=1e-12, abs=1e-12 * (abs(p_pre) + pair.m1 + pair.m2))
    # relative velocity reversed and scaled by e
    scale = 1e-12 * (1 + abs(y1) + abs(y2))
    assert post[1] - post[3] == pytest.approx(-e * (y1 - y2), abs=scale * (1 + mu + 1 / mu))
    # energy loss formula
    dE = pair.kinetic_energy(pre) - pair.kinetic_energy(post)
    assert dE == pytest.approx(pair.energy_loss(y1 - y2), rel=1e-9, abs=1e-9 * (pair.m1 + pair.m2) * (1 + y1**2 + y2**2))


def test_impact_matrix_matches_paper_eq2():
    mu, e = 0.1, 0.5
    E = ImpactPair(mu, e, 1.0).impact_matrix()
    # paper's order is (x1, x2, y1, y2); ours (x1, y1, x2, y2)
    assert E[1, 1] == pytest.approx((mu - e) / (1 + mu))
    assert E[1, 3] == pytest.approx((1 + e) / (1 + mu))
    assert E[3, 1] == pytest.approx((1 + e) * mu / (1 + mu))
    assert E[3, 3] == pytest.approx((1 - mu * e) / (1 + mu))


@given(mu=st.floats(1e-3, 1e2), e=st.floats(0, 1), v=st.floats(0.1, 10))
def test_virtual_restitution_against_impact_law(mu, e, v):
    """(10)-(12): on the symmetric orbit m1 enters with +v and leaves with -v."""
    y20 = (e - 2 * mu - 1) / (1 + e) * v
    post = ImpactPair(mu, e, 1.0).impact([1.0, v, 0.0, y20])
    assert post[1] == pytest.approx(-v, rel=1e-12, abs=1e-12)
    assert post[3] == pytest.approx((e + 2 * e * mu - 1) / (1 + e) * v, rel=1e-10, abs=1e-12)
    assert post[3] == pytest.approx(float(virtual_restitution(mu, e)) * y20, rel=1e-10, abs=1e-12)


@pytest.mark.parametrize("kwargs, name", [
    (dict(mu=0.1, e=1.5, L=1), "e"), (dict(mu=0.1, e=-0.1, L=1), "e"),
    (dict(mu=0, e=0.5, L=1), "mu"), (dict(mu=-1, e=0.5, L=1), "mu"),
    (dict(mu=0.1, e=0.5, L=0), "L"), (dict(mu=0.1, e=0.5, L=1, m2=-2), "m2"),
    (dict(mu=float("nan"), e=0.5, L=1), "mu"), (dict(mu=0.1, e=0.5, L=math.inf), "L"),
])
def test_bad_parameters_name_themselves(kwargs, name):
    with pytest.raises(ValueError, match=rf"^{name} must"):
        ImpactPair(**kwargs)


def test_other_validation():
    with pytest.raises(ValueError, match="kp"):
        PDGains(0, 1)
    with pytest.raises(ValueError, match="kv"):
        PDGains(1, float("nan"))
    with pytest.raises(ValueError, match="omega"):
        Reference(1, 0)
    with pytest.raises(ValueError, match="xm"):
        Reference(-1, 1)
    for n in (0, 2, -1, 1.5, "a"):
        with pytest.raises(ValueError, match="odd"):
            check_odd_order(n)
    assert check_odd_order(3) == 3
    assert Case.parse("non-collocated") is Case.NONCOLLOCATED
    with pytest.raises(ValueError, match="case"):
        Case.parse("both")
    with pytest.raises(ValueError, match="wall"):
        ImpactPair(0.1, 0.5, 1).impact([0, 0, 0, 0], wall=0)
