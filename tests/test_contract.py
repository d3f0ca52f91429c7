"""The API contract: wrong types and values raise ValueError naming the parameter.

Hypothesis drives the public entry points with one parameter replaced by a wrong value of
the kind that parameter must not accept (strings, mappings, None, bools, non-finite or
out-of-range numbers, arrays of the wrong shape); the only exception allowed to escape is a
``ValueError`` whose message names the parameter. Result reprs are one line.
"""
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hybridpd import ImpactPair, PDGains, Reference
from hybridpd._results import compact_repr, short_repr
from hybridpd.loop import closed_loop
from hybridpd.model import as_gains
from hybridpd.pair import symbolic
from hybridpd.pair.impactmap import ImpactMap
from hybridpd.pair.impactpair import ControlledImpactPair
from hybridpd.pair.orbits import symmetric_orbit, symmetric_orbits

PAIR = ImpactPair(0.1, 0.5, 0.75)
GAINS = PDGains(10, 20)
REF = Reference(0.4, 5.0)

# values no numeric parameter accepts
_NOT_NUMBERS = [None, "1", "0.5", "abc", b"1", {"a": 1}, {}, [], [1.0, 2.0], (1, 2, 3),
                True, False, object(), 1j, np.array([1.0, 2.0]), np.array(["1"])]
_NON_FINITE = [math.nan, math.inf, -math.inf]

# values no array-of-numbers parameter accepts (arrays broadcast, so shapes are free)
_NOT_ARRAYS = [None, "1", "abc", b"1", {"a": 1}, {}, True, False, object(), 1j,
               np.array(["1"]), [1.0, "2"], [None, 1.0], np.array([True, False])]

BAD = {
    "positive[]": _NOT_ARRAYS + _NON_FINITE + [0, -1, [1.0, -1.0], np.array([[0.5], [0.0]])],
    "unit[]": _NOT_ARRAYS + _NON_FINITE + [-0.1, 1.5, [0.5, 1.01]],
    "odd[]": _NOT_ARRAYS + _NON_FINITE + [0, 2, -1, 1.5, [1, 2]],
    "real": _NOT_NUMBERS + _NON_FINITE,
    "positive": _NOT_NUMBERS + _NON_FINITE + [0, 0.0, -1, -1e-300, -np.inf],
    "nonneg": _NOT_NUMBERS + _NON_FINITE + [-1, -1e-9],
    "unit": _NOT_NUMBERS + _NON_FINITE + [-0.1, 1.5, 2],
    "odd": _NOT_NUMBERS + _NON_FINITE + [0, 2, -1, 1.5, 4.0],
    "count": _NOT_NUMBERS + _NON_FINITE + [0, -3, 2.5],
    "vec4": [None, "abcd", {"a": 1}, 3.0, True, [1, 2, 3], [1, 2, 3, 4, 5], np.zeros((2, 4)),
             [0, 0, "x", 0], [0, 0, math.nan, 0], [0, math.inf, 0, 0], np.zeros((4, 1))],
    "pair": [None, 10, 10.0, "ab", {"a": 1, "b": 2}, True, [1.0], (0, 1, 2), ("0", "1"),
             (0, math.nan), (math.inf, 1), (None, 1), (2.0, 1.0), (1.0, 1.0)],
    "gains": [None, 10, "kp", {"kp": 10, "kv": 20, "extra": 1}, {"kp": 10}, {"k": 1, "v": 2},
              (10,), (10, 20, 30), ("10", 20), (10, None), (0, 20), (10, -1), [True, 1],
              {"kp": "10", "kv": 20}],
    "axis": [None, 3, "0,1,2", {"a": 1}, (0, 1), (0, 1, 2, 3), ("0", 1, 2), (0, None, 2),
             (1, 0, 2), (0, math.inf, 2), (0, 1, 0), (0, 1, 2.5), (0, 1, True), (0, 1, "2")],
    "named_axis": [None, "kp", ("kp", 1, 2), ("zz", 1, 2, 3), ("kp", "1", 2, 3),
                   ("kp", 2, 1, 3), ("kp", 1, 2, 1), ("kp", 1, 2, 2.5), ("kp", 1, 2, True),
                   ("kp", -1, 2, 3), ("kp", math.nan, 2, 3), {"kp": 1}, ("kp", 1, 2, 3, 4)],
    "range": [None, 5, "1,2", {"lo": 1}, (1,), (1, 2, 3), ("1", 2), (2, 1), (0, 1), (-1, 2),
              (1, math.inf), (None, 2), (True, 2)],
    "grid": [None, 4, "4x4", {"a": 4}, (4,), (4, 4, 4), (1, 4), (4, 2.5), ("4", 4),
             (True, 4), (4, None), (4, -4)],
    "map_obj": [None, 1, "P", {"a": 1}, PAIR, (1, 2)],
    "case": [None, 1, "colocated", "", {"case": 1}, True, 2.5],
    "pair_obj": [None, 1, "pair", {"mu": 0.1}, (0.1, 0.5, 0.75), GAINS],
    "ref_obj": [None, 1, "ref", {"xm": 1}, (1, 5), PAIR],
}


def _entry_points():
    """name -> (callable(**kwargs), valid kwargs, {parameter: kind})."""
    def orbit(pair, gains, omega, x10, n, case, tol):
        return symmetric_orbit(pair, gains, omega, x10=x10, n=n, case=case, tol=tol)

    def orbits(kp, kv, mu, e, L, omega, m2, x10, n, case, margin_samples, tol):
        return symmetric_orbits(kp, kv, mu=mu, e=e, L=L, omega=omega, m2=m2, x10=x10, n=n,
                                case=case, margin_samples=margin_samples, tol=tol, margin=True)

    def sym_orbit(kp, kv, m2, mu, e, L, w, x10, n, case):
        return symbolic.solve_symmetric_orbit(kp=kp, kv=kv, m2=m2, mu=mu, e=e, L=L, w=w, x10=x10,
                                        n=n, case=case)

    def simulate(x0, t_span, max_impacts):
        sysm = ControlledImpactPair(PAIR, GAINS, REF)
        return sysm.simulate(x0, t_span, max_impacts=max_impacts)

    def system(plant, controller, reference, case):
        return ControlledImpactPair(plant, controller, reference, case)

    def impact_map(pair, gains, reference, case, tol, max_impacts):
        return ImpactMap(pair, gains, reference, case, tol=tol, max_impacts=max_impacts)

    def map_call(s):
        return ImpactMap(PAIR, GAINS, REF)(s)

    def loop(pair, controller, reference, case):
        return closed_loop(pair, controller, reference, case)

    def regions(case, x, y, e, mu, omega, L, m2, n):
        from hybridpd.pair.regions import SymmetricFamily
        from hybridpd.sweeps.regions import region_map

        return region_map(SymmetricFamily(case, e=e, mu=mu, omega=omega, L=L, m2=m2, n=n),
                          x=x, y=y)

    def mapper_(P, fixed_point, n_iter, criterion, escape):
        return mapper(P, fixed_point, n_iter=n_iter, criterion=criterion, escape=escape,
                      early_exit=False)

    def basin(mapper_or_map, x, y):
        from hybridpd.sweeps.basins import basin_of_attraction

        return basin_of_attraction(mapper_or_map, x, y, max_period=0)

    def design_(case, mu, e, omega, L, kp_range, kv_range, grid, n_starts, maxiter):
        from hybridpd.pair.design import design

        return design(case, mu=mu, e=e, omega=omega, L=L, kp_range=kp_range,
                      kv_range=kv_range, grid=grid, n_starts=n_starts, maxiter=maxiter,
                      validation_grid=(2, 2), uncertainty_grid=(2, 2))

    def periodic(P, s0, period, tol, max_iter):
        from hybridpd.analysis.periodic import find_orbit

        return find_orbit(P, s0, period, tol=tol, max_iter=max_iter)

    def lti_orbit(pair, controller, omega, x10, n, case, margin_samples):
        from hybridpd.pair.lti import lti_symmetric_orbit

        return lti_symmetric_orbit(pair, controller, omega, x10=x10, n=n, case=case,
                                   margin_samples=margin_samples)

    def continuation(pair, gains, omega, parameter, stop, x10, n, max_steps):
        from hybridpd.pair.continuation import continue_symmetric

        return continue_symmetric(pair, gains, omega, parameter, stop, x10=x10, n=n,
                                  max_steps=max_steps)

    def trace(impact_map_, s, margin_samples):
        from hybridpd.pair.continuation import trace_map

        return trace_map(impact_map_, s, margin_samples=margin_samples)

    def shifted(pair, gains, xm, omega, x10_nominal, n):
        from hybridpd.pair.design import shifted_orbit

        return shifted_orbit(pair, gains, xm, omega, x10_nominal=x10_nominal, n=n)

    def robust(case, kp, kv, xm, mu, e, omega, L, uncertainty_grid):
        from hybridpd.pair.design import robustness

        return robustness(case, kp, kv, xm, mu=mu, e=e, omega=omega, L=L,
                          e_range=(0.4, 0.6), uncertainty_grid=uncertainty_grid)

    from hybridpd.analysis.mappers import mapper

    orb = symmetric_orbit(PAIR, GAINS, 5.0)
    P = ImpactMap(PAIR, GAINS, orb.reference())
    fp = orb.fixed_point
    pos, arr = "positive", "positive[]"
    return {
        "region_map": (regions, dict(case="collocated", x=("kp", 1.0, 20.0, 2),
                                     y=("kv", 1.0, 20.0, 2), e=(0.5,), mu=0.1, omega=5.0,
                                     L=0.75, m2=1.0, n=1),
                       dict(case="case", x="named_axis", y="named_axis", e="unit[]", mu=pos,
                            omega=pos, L=pos, m2=pos, n="odd")),
        "mapper": (mapper_, dict(P=P, fixed_point=fp, n_iter=5, criterion=1e-3, escape=1e3),
                   dict(P="map_obj", fixed_point="vec4", n_iter="count", criterion=pos,
                        escape=pos)),
        "basin_of_attraction": (basin, dict(mapper_or_map=mapper(P, fp, n_iter=3,
                                                                 early_exit=False),
                                            x=(-0.5, 0.5, 2), y=(-0.5, 0.5, 2)),
                                dict(mapper_or_map="map_obj", x="axis", y="axis")),
        "design": (design_, dict(case="collocated", mu=0.1, e=0.5, omega=5.0, L=0.75,
                                 kp_range=(1.0, 50.0), kv_range=(1.0, 50.0), grid=(4, 4),
                                 n_starts=1, maxiter=2),
                   dict(case="case", mu=pos, e="unit", omega=pos, L=pos, kp_range="range",
                        kv_range="range", grid="grid", n_starts="count", maxiter="count")),
        "lti_symmetric_orbit": (lti_orbit, dict(pair=PAIR, controller=GAINS, omega=5.0,
                                                x10=1.0, n=1, case="collocated",
                                                margin_samples=16),
                                dict(pair="pair_obj", controller="gains", omega=pos, x10=pos,
                                     n="odd", case="case", margin_samples="count")),
        "continue_symmetric": (continuation, dict(pair=PAIR, gains=GAINS, omega=5.0,
                                                  parameter="kp", stop=10.5, x10=1.0, n=1,
                                                  max_steps=3),
                               dict(pair="pair_obj", gains="gains", omega=pos, parameter="case",
                                    stop="real", x10=pos, n="odd", max_steps="count")),
        "trace_map": (trace, dict(impact_map_=P, s=fp, margin_samples=16),
                      dict(impact_map_="map_obj", s="vec4", margin_samples="count")),
        "shifted_orbit": (shifted, dict(pair=PAIR, gains=GAINS, xm=orb.xm, omega=5.0,
                                        x10_nominal=1.0, n=1),
                          dict(pair="pair_obj", gains="gains", xm=pos, omega=pos,
                               x10_nominal=pos, n="odd")),
        "robustness": (robust, dict(case="collocated", kp=10.0, kv=20.0, xm=orb.xm, mu=0.1,
                                    e=0.5, omega=5.0, L=0.75, uncertainty_grid=(2, 2)),
                       dict(case="case", kp=pos, kv=pos, xm=pos, mu=pos, e="unit", omega=pos,
                            L=pos, uncertainty_grid="grid")),
        "find_orbit": (periodic, dict(P=P, s0=fp, period=1, tol=1e-12, max_iter=20),
                       dict(P="map_obj", s0="vec4", period="count", tol=pos,
                            max_iter="count")),
        "ImpactPair": (ImpactPair, dict(mu=0.1, e=0.5, L=0.75, m2=1.0),
                       dict(mu=pos, e="unit", L=pos, m2=pos)),
        "PDGains": (PDGains, dict(kp=10, kv=20), dict(kp=pos, kv=pos)),
        "Reference": (Reference, dict(xm=1.0, omega=5.0), dict(xm="nonneg", omega=pos)),
        "as_gains": (as_gains, dict(value=(10, 20)), dict(value="gains")),
        "symmetric_orbit": (orbit, dict(pair=PAIR, gains=GAINS, omega=5.0, x10=1.0, n=1,
                                        case="collocated", tol=1e-13),
                            dict(pair="pair_obj", gains="gains", omega=pos, x10=pos, n="odd",
                                 case="case", tol=pos)),
        "symmetric_orbits": (orbits, dict(kp=10.0, kv=20.0, mu=0.1, e=0.5, L=0.75, omega=5.0,
                                          m2=1.0, x10=1.0, n=1, case="collocated",
                                          margin_samples=16, tol=1e-13),
                             dict(kp=arr, kv=arr, mu=arr, e="unit[]", L=arr, omega=arr, m2=arr,
                                  x10=arr, n="odd", case="case", margin_samples="count",
                                  tol=pos)),
        "symbolic.solve_symmetric_orbit": (sym_orbit, dict(kp=10.0, kv=20.0, m2=1.0, mu=0.1, e=0.5,
                                                     L=0.75, w=5.0, x10=1.0, n=1,
                                                     case="collocated"),
                                     dict(kp=arr, kv=arr, m2=arr, mu=arr, e="unit[]", L=arr,
                                          w=arr, x10=arr, n="odd[]", case="case")),
        "ControlledImpactPair": (system, dict(plant=PAIR, controller=GAINS, reference=REF,
                                              case="collocated"),
                                 dict(plant="pair_obj", controller="gains",
                                      reference="ref_obj", case="case")),
        "simulate": (simulate, dict(x0=[0.1, 0.0, 0.0, 0.0], t_span=(0.0, 0.5), max_impacts=5),
                     dict(x0="vec4", t_span="pair", max_impacts="count")),
        "ImpactMap": (impact_map, dict(pair=PAIR, gains=GAINS, reference=REF,
                                       case="collocated", tol=1e-13, max_impacts=100),
                      dict(pair="pair_obj", gains="gains", reference="ref_obj", case="case",
                           tol=pos, max_impacts="count")),
        "ImpactMap.__call__": (map_call, dict(s=[0.2, 0.0, 0.0, 1.0]), dict(s="vec4")),
        "closed_loop": (loop, dict(pair=PAIR, controller=GAINS, reference=REF,
                                   case="collocated"),
                        dict(pair="pair_obj", controller="gains", reference="ref_obj",
                             case="case")),
    }


ENTRY = _entry_points()


@st.composite
def _bad_call(draw):
    name = draw(st.sampled_from(sorted(ENTRY)))
    kinds = ENTRY[name][2]
    param = draw(st.sampled_from(sorted(kinds)))
    value = draw(st.sampled_from(BAD[kinds[param]]))
    return name, param, value


def _message_names(msg: str, param: str) -> bool:
    aliases = {"plant": ("plant", "pair"), "value": ("gains",), "controller": ("controller",)}
    return any(a in msg for a in aliases.get(param, (param,)))


@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(_bad_call())
def test_wrong_inputs_raise_value_error_naming_the_parameter(call):
    name, param, value = call
    func, valid, _ = ENTRY[name]
    with pytest.raises(ValueError) as info:
        func(**{**valid, param: value})
    assert _message_names(str(info.value), param), (name, param, value, str(info.value))


@pytest.mark.parametrize("name", sorted(ENTRY))
def test_valid_inputs_are_accepted(name):
    func, valid, _ = ENTRY[name]
    func(**valid)


def test_issue_examples():
    with pytest.raises(ValueError, match="mu"):
        ImpactPair(mu="0.1", e=0.5, L=0.75)
    with pytest.raises(ValueError, match="kp"):
        PDGains(kp="10", kv=20)
    with pytest.raises(ValueError, match="omega"):
        symmetric_orbit(PAIR, GAINS, omega="5")
    with pytest.raises(ValueError, match="xm"):
        Reference(xm="1", omega=5)
    with pytest.raises(ValueError, match="exactly the keys kp, kv"):
        symmetric_orbit(PAIR, {"kp": 10, "kv": 20, "extra": 1}, 5)
    with pytest.raises(ValueError, match="t_span"):
        ControlledImpactPair(PAIR, GAINS, REF).simulate([0, 0, 0, 0], 10)
    # a mapping with exactly kp, kv is fine
    assert symmetric_orbit(PAIR, {"kp": 10, "kv": 20}, 5).exists


def test_reprs_are_one_line_with_shapes():
    orb = symmetric_orbit(PAIR, GAINS, 5.0)
    grid = symmetric_orbits(np.linspace(1, 40, 30), np.linspace(1, 40, 20)[:, None], mu=0.1,
                            e=0.5, L=0.75, omega=5.0)
    traj = ControlledImpactPair(PAIR, GAINS, REF).simulate([0.1, 0, 0, 0], (0, 5))
    cand = symbolic.solve_symmetric_orbit(kp=np.linspace(1, 40, 30), kv=20.0, mu=0.1, e=0.5, L=0.75,
                                    w=5.0, x10=1.0)
    jac = symbolic.orbit_jacobian(cand)
    P = ImpactMap(PAIR, GAINS, orb.reference())
    objects = [orb, grid, cand, jac, traj, traj.hybrid, traj.hybrid.jumps,
               traj.hybrid.segments, P.apply_batch(np.tile(orb.fixed_point, (5, 1))),
               P.stability(orb.fixed_point), closed_loop(PAIR, GAINS, REF)]
    for obj in objects:
        r = repr(obj)
        assert "\n" not in r and len(r) < 2500, (type(obj).__name__, r)
        assert r.startswith(type(obj).__name__ + "(")
    assert "array(shape=(20, 30), dtype=float64)" in repr(grid)
    assert "DP=array(shape=(30, 4, 4), dtype=float64)" in repr(jac)
    assert "pre_plus=array(shape=(4,), dtype=float64)" in repr(orb)


def test_short_repr_of_values():
    assert short_repr(np.float64(0.1234567891)) == "0.123457"
    assert short_repr(np.zeros((2, 3))) == "array(shape=(2, 3), dtype=float64)"
    assert short_repr(np.array([2.5])) == "2.5"
    assert short_repr(None) == "None" and short_repr(True) == "True"
    assert short_repr(list(range(10))) == "list(len=10)"
    assert short_repr("x" * 100) == "str(len=100)"

    class Thing:
        def __init__(self):
            self.a = np.ones(5)
            self._hidden = 1

    assert compact_repr(Thing()) == "Thing(a=array(shape=(5,), dtype=float64))"
