"""Soundness of the interval layer and of what the certifier makes of its failures.

Each test closes one hole a review found in :mod:`hybridpd.pair.intervals` and
:mod:`hybridpd.pair.centred`: real exponents, NaN (one rule: the whole line), empty
intersections (a failure the certifier leaves undecided), integers beyond 2^53, and the
error bound assumed of NumPy's elementary functions (checked by a self-test before
certification runs). python-flint's ``arb`` is the reference for containment.
"""
import math
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hybridpd.pair import centred, proofs, selftest
from hybridpd.pair import flowintervals as fi
from hybridpd.pair import intervals as iv
from hybridpd.pair.centred import Box
from hybridpd.pair.certified import certify_box, certify_cells, certify_orbit
from hybridpd.pair.intervals import EmptyIntersectionError, Interval

flint = pytest.importorskip("flint")
arb = flint.arb

HSET = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
CELL = dict(kp=(9.5, 10.0), kv=(19.5, 20.0), mu=0.1, e=0.5, gamma=0.75, omega=5.0)


def _encloses(out, exact, index=()):
    """``out[index]`` contains the arb ball ``exact`` (exactly: no slack)."""
    lo, hi = float(np.asarray(out.lo)[index]), float(np.asarray(out.hi)[index])
    return bool(arb(lo) <= exact) and bool(exact <= arb(hi))


def _whole(x):
    return bool(np.all(x.lo == -np.inf)) and bool(np.all(x.hi == np.inf))


# ---------------------------------------------------------------------------------------------
# real exponents: refused (never truncated)

def test_a_real_exponent_is_refused_not_truncated():
    # was [4, 9]: 2.5 truncated to 2, not enclosing [2^2.5, 3^2.5] = [5.66, 15.59]
    with pytest.raises(ValueError, match="2.5"):
        Interval(2.0, 3.0) ** 2.5
    with pytest.raises(ValueError, match="2.5"):
        iv.ipow(Interval(2.0, 3.0), 2.5)


@HSET
@given(k=st.floats(-10, 10).filter(lambda k: not float(k).is_integer()),
       order=st.sampled_from([0, 1, 2]))
def test_every_non_integral_exponent_is_refused(k, order):
    if order == 0:
        x = Interval(2.0, 3.0)
    else:
        box, (c,) = Box.from_bounds([(2.0, 3.0)])
        x = box.variable(0, 2.0, 3.0, c, order=order)
    with pytest.raises(ValueError, match="exponent"):
        x.pow(k) if order else x ** k


@HSET
@given(lo=st.floats(-30, 30), width=st.floats(0, 5), k=st.integers(1, 7),
       as_float=st.booleans())
def test_integral_exponents_enclose_arb(lo, width, k, as_float):
    hi = lo + width
    out = Interval(lo, hi) ** (float(k) if as_float else k)
    with flint.ctx.workprec(256):
        for p in (lo, hi, 0.5 * (lo + hi), 0.0 if lo <= 0 <= hi else lo):
            assert _encloses(out, arb(p) ** k), (lo, hi, k, out)


# ---------------------------------------------------------------------------------------------
# NaN: one rule, the whole line

_FUNCTIONS = {
    "exp": iv.exp, "sqrt": iv.sqrt, "sin": iv.sin, "cos": iv.cos, "cu": fi.cu, "su": fi.su,
    "su1": fi.su1, "su2": fi.su2, "emq": fi.emq, "emq1": fi.emq1, "emq2": fi.emq2,
    "pow1": lambda x: iv.ipow(x, 1), "pow2": lambda x: iv.ipow(x, 2),
    "pow3": lambda x: iv.ipow(x, 3), "neg": lambda x: -x,
    "add": lambda x: x + Interval(1.0, 2.0), "sub": lambda x: x - Interval(1.0, 2.0),
    "mul": lambda x: x * Interval(1.0, 2.0), "div": lambda x: x / Interval(1.0, 2.0),
    "rdiv": lambda x: 1.0 / x, "add_point": lambda x: x + 1.0, "rsub_point": lambda x: 1.0 - x,
    "mul_point": lambda x: x * 3.0, "hull": lambda x: Interval.hull_of(x, Interval(0.0)),
    "intersect": lambda x: x.intersect(Interval(-1e300, 1e300)),
}
_NAN_BOUNDS = [(math.nan, math.nan), (math.nan, 3.0), (-3.0, math.nan)]


@pytest.mark.parametrize("name", sorted(_FUNCTIONS))
@pytest.mark.parametrize("bounds", _NAN_BOUNDS, ids=["both", "lo", "hi"])
@pytest.mark.parametrize("shape", ["scalar", "array"])
def test_a_nan_operand_gives_the_whole_line(name, bounds, shape):
    # was: NaN bounds, [-1, 1] (sin, cos), the empty [inf, -inf] (su1, su2) or [9, nan] (ipow)
    lo, hi = bounds
    if shape == "array":  # the 1-D compiled path, beside an ordinary element
        x = Interval(np.array([lo, 1.0]), np.array([hi, 1.5]))
        out = _FUNCTIONS[name](x)
        assert out.lo[0] == -np.inf and out.hi[0] == np.inf, (name, out.lo, out.hi)
        assert np.isfinite(out.lo[1]) and np.isfinite(out.hi[1])
    else:
        out = _FUNCTIONS[name](Interval(lo, hi))
        assert _whole(out), (name, out)


@pytest.mark.parametrize("shape", ["scalar", "array"])
def test_a_nan_result_gives_the_whole_line(shape):
    wrap = (lambda v: np.array([v])) if shape == "array" else (lambda v: v)
    I = lambda a, b=None: Interval(wrap(a), wrap(a if b is None else b))
    inf = math.inf
    cases = {
        "inf - inf": I(inf) - I(inf),
        "inf + -inf": I(inf) + I(-inf),
        "0 * inf": I(0.0) * I(inf),
        "inf / inf": I(inf) / I(inf, inf),
        "sqrt below 0": iv.sqrt(I(-1.0, 4.0)),
    }
    for what, out in cases.items():
        assert _whole(out), (what, out.lo, out.hi)


def test_overflow_never_gives_nan_bounds():
    big = Interval(np.array([1e308, 1.0]), np.array([1e308, 2.0]))
    for out in (big + big, big * big, big * 4.0, iv.exp(Interval(np.array([800.0]))),
                iv.ipow(Interval(-np.inf, -1.0), 2), iv.ipow(Interval(1e200, 1e300), 3)):
        assert not np.any(np.isnan(out.lo)) and not np.any(np.isnan(out.hi))
        assert np.all(out.lo <= out.hi)
    # an overflowed exp still encloses: exp(800) > half the largest float
    assert iv.exp(Interval(800.0)).lo > 1e307


def test_ipow_of_a_sqrt_reaching_below_zero():
    # was [4.0000000000000036, nan] and [9, nan]
    out = iv.ipow(iv.sqrt(Interval(-1.0, 4.0)), 2)
    assert not np.isnan(out.lo) and not np.isnan(out.hi)
    assert out.lo <= 0.0 and out.hi >= 4.0
    assert _whole(iv.ipow(Interval(np.nan, 3.0), 2))


@pytest.mark.parametrize("which", ["su1", "su2"])
def test_su1_su2_of_nan_never_prove_a_sign(which):
    out = getattr(fi, which)(Interval(np.nan))
    assert not bool(out.lo > 0) and not bool(out.hi < 0)
    assert _whole(out)


def test_whole_line_arguments_keep_their_bounded_images():
    # the whole line is a real interval (unlike NaN): sin of it is [-1, 1], a square >= 0
    w = Interval(-np.inf, np.inf)
    assert (float(iv.sin(w).lo), float(iv.sin(w).hi)) == (-1.0, 1.0)
    assert float(iv.ipow(w, 2).lo) == 0.0


@HSET
@given(lo=st.floats(-1e3, 1e3), width=st.floats(0, 50),
       name=st.sampled_from(["exp", "sin", "cos", "cu", "su", "su1", "su2", "sqrt"]))
def test_functions_never_return_nan_or_inverted_bounds(lo, width, name):
    out = _FUNCTIONS[name](Interval(lo, lo + width))
    assert not np.isnan(out.lo) and not np.isnan(out.hi) and out.lo <= out.hi


# ---------------------------------------------------------------------------------------------
# empty intersections: a failure, never a proof

def test_an_empty_intersection_raises():
    # was [3, 2], on which both lo > 0 and hi < 2 "hold"
    with pytest.raises(EmptyIntersectionError, match="do not meet"):
        Interval(1.0, 2.0).intersect(Interval(3.0, 4.0))
    a = Interval(np.array([0.0, 1.0, 5.0]), np.array([1.0, 2.0, 6.0]))
    b = Interval(np.array([0.5, 1.5, 0.0]), np.array([2.0, 3.0, 1.0]))
    with pytest.raises(EmptyIntersectionError, match="1 element"):
        a.intersect(b)
    # touching enclosures meet
    out = Interval(1.0, 2.0).intersect(Interval(2.0, 3.0))
    assert (float(out.lo), float(out.hi)) == (2.0, 2.0)


def test_an_inconsistent_centred_form_raises():
    # a centre value that is not in the naive range: the tightening must not give an empty range
    box, (_c,) = Box.from_bounds([(1.0, 1.1)])
    with pytest.raises(EmptyIntersectionError):
        centred.CForm(Interval(5.0), (Interval(1.0),), Interval(1.0, 1.1), box)


def _shifted_centres(monkeypatch):
    """Make exp wrong by +5 on narrow arguments (the centre values) in the centred forms."""
    good = centred._FUNCS["exp"]

    def bad(x):
        r = iv.exp(x)
        narrow = (x.hi - x.lo) <= 1e-9 * (1 + np.abs(x.lo))
        return Interval(np.where(narrow, r.lo + 5, r.lo), np.where(narrow, r.hi + 5, r.hi))

    monkeypatch.setitem(centred._FUNCS, "exp", (bad,) + good[1:])


def test_the_certifier_leaves_inconsistent_boxes_undecided(monkeypatch):
    before = certify_cells("collocated", depth=0, **CELL)
    assert int(before.flags) == 1     # proved stable with the right exp
    _shifted_centres(monkeypatch)
    r = certify_cells("collocated", depth=2, **CELL)
    assert int(r.flags) == 0, r
    assert proofs.REASONS[int(r.reasons)].startswith("undecided: two enclosures")
    c = certify_box("collocated", depth=1, **CELL)
    assert c.verdict == "undecided" and "did not meet" in c.reason


def test_classify_isolates_the_failing_boxes(monkeypatch):
    kp = np.linspace(9.0, 11.0, 7)
    boxes, _ = proofs.scaled_boxes(kp=(kp, kp + 0.1), kv=(19.5, 19.6), mu=0.1, e=0.5,
                                   gamma=0.75, omega=5.0, m2=1.0)
    cls0, why0 = proofs.classify("collocated", 1, boxes)
    poison = boxes.lo["kpt"][3]
    real = proofs._classify
    calls = []

    def failing(case, n, b, pieces, depth):
        calls.append(b.size)
        if np.any(b.lo["kpt"] == poison):
            raise EmptyIntersectionError("injected")
        return real(case, n, b, pieces, depth)

    monkeypatch.setattr(proofs, "_classify", failing)
    cls, why, parts = proofs.classify("collocated", 1, boxes, details=True)
    assert cls[3] == proofs.UNDECIDED and why[3] == proofs.R_EMPTY
    assert not parts["exists"][3] and parts["viable"][3] == 0
    keep = np.arange(7) != 3
    np.testing.assert_array_equal(cls[keep], cls0[keep])
    np.testing.assert_array_equal(why[keep], why0[keep])
    assert len(calls) <= 1 + 2 * math.ceil(math.log2(7))    # halving, not box by box


# ---------------------------------------------------------------------------------------------
# integers beyond 2^53

def test_an_integer_beyond_2_53_is_not_taken_as_exact():
    # was [0, 2^-1022]-ish: 2^53 + 1 rounded to 2^53, and the difference lost
    k = 2**53 + 1
    with flint.ctx.workprec(256):
        assert _encloses(Interval(2.0**53) - k, arb(-1))
        assert _encloses(Interval(k), arb(k))
        assert _encloses(Interval([k, 3]), arb(k), (0,))
        assert _encloses(Interval(np.array([k], dtype=np.int64)), arb(k), (0,))
        assert _encloses(Interval(10**400), arb(10**400))


# integers of 54 to 80 significant bits (no float holds them), and any others
_BIG_INTS = st.one_of(
    st.builds(lambda m, e, s: s * (m * 2**e + 1), st.integers(2**52, 2**53),
              st.integers(1, 27), st.sampled_from([1, -1])),
    st.integers(-2**80, 2**80))


@HSET
@given(k=_BIG_INTS, offset=st.floats(-1e20, 1e20), near=st.booleans(),
       width=st.floats(0, 1e6), op=st.sampled_from(["+", "-", "r-", "*", "/", "r/", "point"]))
def test_integers_are_enclosed_in_every_operation(k, offset, near, width, op):
    # near: x next to k, so that x - k cancels and the conversion error of k is all there is
    lo = float(k) + (offset * 1e-19 if near else offset)
    x = Interval(lo, lo + width * (1e-19 if near else 1.0))
    width = float(x.hi) - lo
    fn = {"+": lambda a, b: a + b, "-": lambda a, b: a - b, "r-": lambda a, b: b - a,
          "*": lambda a, b: a * b, "/": lambda a, b: a / b, "r/": lambda a, b: b / a,
          "point": lambda a, b: Interval(b)}[op]
    if op == "/" and k == 0:
        return
    out = fn(x, k)
    with flint.ctx.workprec(512):
        for p in (lo, lo + width, 0.5 * lo + 0.5 * (lo + width)):
            if op == "r/" and p == 0:
                continue
            exact = fn(arb(p), arb(k)) if op != "point" else arb(k)
            assert _encloses(out, exact), (op, k, p, out)


def test_integer_arrays_are_enclosed():
    ks = np.array([2**53 + 1, -(2**62) - 1, 7, 2**63 - 1], dtype=np.int64)
    out = Interval(ks)
    with flint.ctx.workprec(256):
        for i, k in enumerate(ks.tolist()):
            assert _encloses(out, arb(k), (i,))
    small = Interval(np.arange(5))
    assert np.array_equal(small.lo, small.hi)   # exact integers stay points


# ---------------------------------------------------------------------------------------------
# the self-test of NumPy's elementary functions

@pytest.fixture
def fresh_selftest():
    selftest.libm_check.cache_clear()
    yield
    selftest.libm_check.cache_clear()


def test_the_selftest_passes_here_and_covers_the_layer(fresh_selftest):
    r = selftest.libm_check()
    assert r.ok, r.failures
    # every NumPy function the interval layer calls is checked
    assert {"exp", "expm1", "cosh", "sinh", "sin", "cos", "sqrt"} <= set(r.worst)
    assert all(used < 1 for _, _, used, _ in r.worst.values())
    # hard arguments: next to multiples of pi/2, huge, tiny
    xs = selftest.hard_arguments("sin")
    assert 6381956970095103 * 2.0**797 in xs and 5e-324 in xs
    with flint.ctx.workprec(256):
        assert min(abs(float(arb(x).cos().mid())) for x in xs if 1 < x < 100) < 1e-15


def _perturbed(name, amount):
    """``_evaluate`` with one value of ``name`` off by ``amount`` (absolute for sin and cos,
    relative for the others), on the contiguous path only."""
    real = selftest._evaluate

    def evaluate(fn_name, args):
        values = real(fn_name, args)
        if fn_name == name:
            v = values[0] = values[0].copy()
            i = len(v) // 2
            v[i] = v[i] + amount if name in ("sin", "cos") else v[i] * (1 + amount)
        return values

    return evaluate


@pytest.mark.parametrize("name, amount", [("sin", 2.0**-40), ("exp", 1e-9), ("cosh", 1e-9)])
def test_certification_refuses_when_the_selftest_fails(fresh_selftest, monkeypatch, name,
                                                       amount):
    monkeypatch.setattr(selftest, "_evaluate", _perturbed(name, amount))
    r = selftest.libm_check()
    assert not r.ok and r.failures[0].startswith(f"{name}(")
    with pytest.raises(selftest.LibmSelfTestError, match=f"certification refused.*{name}"):
        certify_cells("collocated", depth=0, **CELL)
    with pytest.raises(selftest.LibmSelfTestError):
        certify_box("collocated", depth=0, **CELL)


def test_every_certifying_entry_point_refuses(fresh_selftest, monkeypatch):
    import hybridpd as hp
    from hybridpd.pair.regions import SymmetricFamily
    from hybridpd.reproduce.certified import ShareTarget, certified_shares

    monkeypatch.setattr(selftest, "_evaluate", _perturbed("cos", 1e-6))
    boxes, _ = proofs.scaled_boxes(kp=10.0, kv=20.0, mu=0.1, e=0.5, gamma=0.75, omega=5.0,
                                   m2=1.0)
    with pytest.raises(selftest.LibmSelfTestError):
        proofs.classify("collocated", 1, boxes)
    with pytest.raises(selftest.LibmSelfTestError):
        certify_orbit(hp.ImpactPair(mu=0.1, e=0.5, L=0.75), hp.PDGains(10, 20), omega=5.0)
    with pytest.raises(selftest.LibmSelfTestError):
        certified_shares([ShareTarget("collocated", e=0.5, box=(9.0, 11.0))], grid=2,
                         levels=0)
    fam = SymmetricFamily("collocated", e=[0.5], mu=0.1, omega=5.0, gamma=0.75)
    with pytest.raises(selftest.LibmSelfTestError):   # before any grid work
        fam.classify_grid(("kp", 9, 11, 2), ("kv", 19, 21, 2), certify=True)
    # the uncertified map does not need the self-test
    fam.classify_grid(("kp", 9, 11, 2), ("kv", 19, 21, 2))


def test_the_selftest_runs_once_per_process_and_lazily():
    code = (
        "import hybridpd.pair.certified as c, hybridpd.pair.selftest as s\n"
        "before = s.libm_check.cache_info().currsize\n"
        "c.certify_box('collocated', kp=(9.5, 10.0), kv=(19.5, 20.0), mu=0.1, e=0.5,"
        " gamma=0.75, omega=5.0, depth=1)\n"
        "c.certify_box('collocated', kp=(9.5, 10.0), kv=(19.5, 20.0), mu=0.1, e=0.5,"
        " gamma=0.75, omega=5.0, depth=1)\n"
        "i = s.libm_check.cache_info()\n"
        "print(before, i.misses, i.currsize)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=300).stdout.split()
    assert out == ["0", "1", "1"]
