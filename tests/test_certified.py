"""Certified classification: the interval layer against arb, the proofs against point
evaluations and an independent implementation of the paper's orbit.

The independent implementation (``Paper``, ``tests/_paper_orbit.py``) is written from the
paper's equations only: the closed loop between impacts as a 6 x 6 linear system flowed
with ``scipy.linalg.expm``, Newton's impact law, the symmetry conditions (13)-(14) solved as a linear system for
``(C, S) = xm (cos w t0, sin w t0)``, viability by dense sampling of the gap, and the
multipliers from central finite differences of the impact map (contacts located with
``brentq``).
"""
import math

import numpy as np
import pytest
from _paper_orbit import Paper
from _regions import pair_region_map
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import hybridpd as hp
from hybridpd.pair import flowintervals as fi
from hybridpd.pair import intervals as iv
from hybridpd.pair import proofs
from hybridpd.pair.centred import INTERVAL_OPS, Box
from hybridpd.pair.certified import (
    FLAG_MEANINGS,
    FLAG_VALUES,
    cell_edges,
    certified_map,
    certify_box,
    certify_cells,
    certify_orbit,
    class_shares,
)
from hybridpd.pair.flowintervals import FLOAT_OPS, arb_ops
from hybridpd.pair.interval_kernels import KERNEL_ARGS, interval_kernel
from hybridpd.pair.intervals import Interval

flint = pytest.importorskip("flint")
arb = flint.arb

FIXED = dict(mu=0.1, gamma=0.75, omega=5.0)
HSET = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])


# ---------------------------------------------------------------------------------------------
# the interval layer against arb

def _inside(x_arb, lo, hi):
    """The ball ``x_arb`` lies in ``[lo, hi]``, up to a slack of 1e-60 relative (far below
    a float's last place, so a bound off by one ulp still fails; at 256 bits the balls are
    narrower than the slack)."""
    lo, hi = float(lo), float(hi)
    a = arb(lo) - arb(1e-60) * (1 + abs(lo))
    b = arb(hi) + arb(1e-60) * (1 + abs(hi))
    return bool(a <= x_arb) and bool(x_arb <= b)


def _points(lo, hi, extra=()):
    pts = [lo, hi, 0.5 * (lo + hi)] + [p for p in extra if lo <= p <= hi]
    rng = np.random.default_rng(abs(hash((lo, hi))) % 2**32)
    return pts + list(rng.uniform(lo, hi, 5))


_ARB_FUNCS = {
    "exp": (iv.exp, lambda x: x.exp()),
    "sin": (iv.sin, lambda x: x.sin()),
    "cos": (iv.cos, lambda x: x.cos()),
    "cu": (fi.cu, lambda x: arb_ops().DCH(arb(0), x, arb(1))),
    "su": (fi.su, lambda x: arb_ops().DSH(arb(0), x, arb(1))),
    "emq": (fi.emq, lambda x: -(-x).expm1() / x if x != 0 else arb(1)),
}


@HSET
@given(lo=st.floats(-40, 40), width=st.floats(0, 8),
       name=st.sampled_from(sorted(_ARB_FUNCS)))
def test_functions_enclose_arb_values(lo, width, name):
    hi = lo + width
    f, ref = _ARB_FUNCS[name]
    if name == "emq" and (lo <= 0 <= hi):
        lo, hi = abs(lo) + 1e-3, abs(lo) + 1e-3 + width
    out = f(Interval(lo, hi))
    extra = [k * math.pi / 2 for k in range(-30, 31)]
    for p in _points(lo, hi, extra):
        with flint.ctx.workprec(256):  # balls far narrower than the float enclosures
            assert _inside(ref(arb(p)), out.lo, out.hi), (name, lo, hi, p, out)


@HSET
@given(a=st.floats(-1e3, 1e3), wa=st.floats(0, 10), b=st.floats(-1e3, 1e3),
       wb=st.floats(0, 10), op=st.sampled_from(["+", "-", "*", "/", "pow2", "pow3", "sqrt"]))
def test_arithmetic_encloses_arb_values(a, wa, b, wb, op):
    x, y = Interval(a, a + wa), Interval(b, b + wb)
    if op == "/" and b <= 0 <= b + wb:
        b, y = b + wb + 1.0, Interval(b + wb + 1.0, b + 2 * wb + 1.0)
    if op == "sqrt":
        a, x = abs(a), Interval(abs(a), abs(a) + wa)
    fn = {"+": lambda p, q: p + q, "-": lambda p, q: p - q, "*": lambda p, q: p * q,
          "/": lambda p, q: p / q, "pow2": lambda p, q: p**2, "pow3": lambda p, q: p**3,
          "sqrt": lambda p, q: p.sqrt() if isinstance(p, arb) else iv.sqrt(p)}[op]
    out = fn(x, y)
    for p in _points(a, a + wa if op != "sqrt" else abs(a) + wa):
        for q in _points(y.lo.item(), y.hi.item())[:4]:
            with flint.ctx.workprec(256):
                assert _inside(fn(arb(p), arb(q)), out.lo, out.hi), (op, p, q, out)


@HSET
@given(lo=st.floats(-60, 60), width=st.floats(0, 5), which=st.sampled_from([1, 2]))
def test_series_derivatives_enclose_finite_differences(lo, width, which):
    # su' and su'' against arb's derivative of sinh(sqrt(u))/sqrt(u) by a tiny-step quotient
    hi = lo + width
    out = (fi.su1 if which == 1 else fi.su2)(Interval(lo, hi))
    for p in _points(lo, hi)[:4]:
        h = arb(2) ** -30
        with flint.ctx.workprec(200):
            s = lambda u: arb_ops().DSH(arb(0), u, arb(1))
            if which == 1:
                val = (s(arb(p) + h) - s(arb(p) - h)) / (2 * h)
            else:
                val = (s(arb(p) + h) - 2 * s(arb(p)) + s(arb(p) - h)) / (h * h)
        assert out.lo - 1e-6 * (1 + abs(out.lo)) <= float(val.mid()) <= \
            out.hi + 1e-6 * (1 + abs(out.hi)), (which, p, out)


def test_vectorised_compiled_path_matches_numpy_path():
    rng = np.random.default_rng(3)
    a = Interval(rng.normal(size=500), None)
    a = Interval(a.lo, a.lo + rng.uniform(0, 1, 500))
    b = Interval(rng.normal(size=500) * 1e3, None)
    b = Interval(b.lo, b.lo + rng.uniform(0, 1, 500))
    for op in ("__add__", "__sub__", "__mul__"):
        fast = getattr(a, op)(b)
        slow = getattr(Interval(a.lo[:, None], a.hi[:, None]), op)(
            Interval(b.lo[:, None], b.hi[:, None]))  # 2-D: the NumPy path
        np.testing.assert_allclose(fast.lo, slow.lo[:, 0], rtol=1e-14, atol=1e-300)
        np.testing.assert_allclose(fast.hi, slow.hi[:, 0], rtol=1e-14, atol=1e-300)
        assert np.all(fast.lo <= slow.lo[:, 0] + 1e-12) and np.all(fast.hi >= slow.hi[:, 0] - 1e-12)


# ---------------------------------------------------------------------------------------------
# the kernels and the centred forms: enclosures of point values inside the box

def _box_forms(lo, hi, order):
    names = ["kpt", "kvt"]
    box, centres = Box.from_bounds([(np.array([lo[k]]), np.array([hi[k]])) for k in names])
    P = {k: box.variable(i, np.array([lo[k]]), np.array([hi[k]]), centres[i], order=order)
         for i, k in enumerate(names)}
    for k in ("mu", "e", "gam", "w"):
        P[k] = box.constant(Interval(lo[k]), order=order)
    return P


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(kp=st.floats(0.5, 50), kv=st.floats(0.5, 50), h=st.floats(0.01, 0.5),
       e=st.sampled_from([0.1, 0.5, 0.9]), case=st.sampled_from(["collocated", "noncollocated"]),
       order=st.sampled_from([0, 1, 2]))
def test_kernels_enclose_arb_point_values(kp, kv, h, e, case, order):
    lo = dict(kpt=kp, kvt=kv, mu=0.1, e=e, gam=0.75, w=5.0)
    hi = dict(lo, kpt=kp + h, kvt=kv + h)
    if order == 0:
        P = {k: Interval(lo[k], hi[k]) for k in lo}
    else:
        P = _box_forms(lo, hi, order)
    args = [P[k] for k in proofs.SCALED]
    nI = Interval(1.0)
    C, S, det = interval_kernel("existence", case)(INTERVAL_OPS, *args, nI)
    M = interval_kernel("halfmap", case)(INTERVAL_OPS, C, S, *args, nI)
    s = Interval(0.25, 0.375)
    G = interval_kernel("gap", case)(INTERVAL_OPS, s, C, S, *args, nI)
    rng = lambda x: x if isinstance(x, Interval) else x.r
    with flint.ctx.workprec(256):
        _check_kernel_points(case, e, kp, kv, h, C, S, det, M, G, rng)


def _check_kernel_points(case, e, kp, kv, h, C, S, det, M, G, rng):
    ops = arb_ops()
    for a, b in [(kp, kv), (kp + h, kv + h), (kp + h / 3, kv + 2 * h / 3)]:
        pa = [arb(a), arb(b), arb(0.1), arb(e), arb(0.75), arb(5.0), arb(1)]
        Ca, Sa, da = interval_kernel("existence", case)(ops, *pa)
        Ma = interval_kernel("halfmap", case)(ops, Ca, Sa, *pa)
        for x, ref in zip([C, S, det, *M], [Ca, Sa, da, *Ma]):
            r = rng(x)
            assert _inside(ref, r.lo[()] if r.lo.ndim == 0 else r.lo[0],
                           r.hi[()] if r.hi.ndim == 0 else r.hi[0])
        for sv in (0.25, 0.3, 0.375):
            Ga = interval_kernel("gap", case)(ops, arb(sv), Ca, Sa, *pa)
            for x, ref in zip(G, Ga):
                r = rng(x)
                assert _inside(ref, np.ravel(r.lo)[0], np.ravel(r.hi)[0])


def test_kernels_reproduce_the_float_path():
    from hybridpd.pair import symbolic

    for case in ("collocated", "noncollocated"):
        for kp, kv, e in [(10, 20, 0.5), (3, 1, 0.1), (40, 5, 0.9)]:
            orb = hp.symmetric_orbit(hp.ImpactPair(mu=0.1, e=e, L=0.75), hp.PDGains(kp, kv),
                                     omega=5.0, case=case)
            C, S, _ = interval_kernel("existence", case)(FLOAT_OPS, kp, kv, 0.1, e, 0.75, 5.0, 1)
            np.testing.assert_allclose(math.hypot(C, S), orb.xm, rtol=1e-12, atol=0)
            M = np.array(interval_kernel("halfmap", case)(FLOAT_OPS, C, S, kp, kv, 0.1, e, 0.75, 5.0,
                                                 1)).reshape(4, 4)
            cand = symbolic.solve_symmetric_orbit(kp=kp, kv=kv, mu=0.1, e=e, L=0.75, w=5.0, x10=1.0,
                                            case=case)
            DP = np.asarray(symbolic.orbit_jacobian(cand).DP).reshape(4, 4)
            np.testing.assert_allclose(M @ M, DP, rtol=1e-9, atol=1e-9 * np.abs(DP).max())
    assert set(KERNEL_ARGS) == {"existence", "gap", "halfmap"}


@HSET
@given(seed=st.integers(0, 2**31))
def test_stability_criteria_agree_with_eigenvalues(seed):
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(4, 4)) * rng.uniform(0.1, 0.8)
    entries = [Interval(v) for v in M.ravel()]
    rho = max(abs(np.linalg.eigvals(M)))
    J = proofs.hurwitz_quantities(entries)
    if all(j.lo > 0 for j in J):
        assert rho < 1
    if any(j.hi < 0 for j in J):
        assert rho > 1
    for x, bound in proofs.escape_quantities(entries):
        if x.lo > bound or x.hi < -bound:
            assert rho > 1
    if abs(rho - 1) > 1e-6:  # away from the circle, the bilinear test decides
        assert all(j.lo > 0 for j in J) or any(j.hi < 0 for j in J)


# ---------------------------------------------------------------------------------------------
# the paper, independently: expm flows, the symmetry conditions, finite-difference multipliers

def _corners_and_centre(b):
    (a0, a1), (b0, b1) = b["kp"], b["kv"]
    return [(0.5 * (a0 + a1), 0.5 * (b0 + b1)), (a0, b0), (a0, b1), (a1, b0), (a1, b1)]


def _samples(b, num=40, seed=0):
    rng = np.random.default_rng(seed)
    return rng.uniform(b["kp"][0], b["kp"][1], num), rng.uniform(b["kv"][0], b["kv"][1], num)


CELLS = [("collocated", 0.5, (9.8, 10.2), (19.8, 20.2), "proved_stable"),
         ("noncollocated", 0.5, (9.8, 10.2), (19.8, 20.2), "proved_unstable"),
         ("collocated", 0.1, (9.8, 10.2), (39.8, 40.2), "proved_no_orbit")]


@pytest.mark.parametrize("case, e, kp, kv, expected", CELLS, ids=[c[-1] for c in CELLS])
def test_proved_cell_against_points_and_the_paper(case, e, kp, kv, expected):
    cert = certify_box(case, kp=kp, kv=kv, e=e, depth=1, **FIXED)
    assert cert.verdict == expected, cert
    b = {"kp": kp, "kv": kv}
    kps, kvs = _samples(b)
    pts = hp.symmetric_orbits(kps, kvs, mu=0.1, e=e, L=0.75, omega=5.0, case=case)
    if expected == "proved_no_orbit":
        assert not pts.exists.any()
    else:
        assert pts.exists.all()
        assert (pts.stable if expected == "proved_stable" else ~pts.stable).all()
    for a, c in _corners_and_centre(b):
        paper = Paper(case, a, c, 0.1, e, 0.75, 5.0)
        gap = paper.gap_max()
        if expected == "proved_no_orbit":
            assert gap > 0.75
            continue
        assert gap < 0.75
        fp = paper.fixed_point()
        np.testing.assert_allclose(paper.section_map(fp), fp, rtol=1e-8, atol=1e-8)
        mods = paper.multipliers()
        assert (mods[0] < 1) if expected == "proved_stable" else (mods[0] > 1)


def test_point_certificate_encloses_the_float_path_and_the_paper():
    pair = hp.ImpactPair(mu=0.1, e=0.5, L=0.75)
    c = certify_orbit(pair, hp.PDGains(10, 20), 5.0)
    orb = hp.symmetric_orbit(pair, hp.PDGains(10, 20), 5.0)
    assert c.verdict == "proved_stable" and c.viable == 1
    lo, hi = c.xm
    assert lo <= orb.xm <= hi and hi - lo < 1e-10
    for name, v in zip(("phi0", "z1", "z2", "z4"), orb.fixed_point):
        lo, hi = c.section_point[name]
        assert lo - 1e-13 <= v <= hi + 1e-13 and hi - lo < 1e-9, name
    moduli = np.sort(np.abs(orb.multipliers))[::-1]
    for (lo, hi), m in zip(c.multiplier_moduli, moduli):
        assert lo - 1e-9 <= m <= hi + 1e-9
    paper = Paper("collocated", 10, 20, 0.1, 0.5, 0.75, 5.0)
    np.testing.assert_allclose(paper.xm, np.mean(c.xm), rtol=1e-9, atol=0)
    np.testing.assert_allclose(paper.multipliers(), [np.mean(m) for m in c.multiplier_moduli],
                               rtol=1e-4, atol=1e-6)
    d = c.to_dict()
    assert d["verdict"] == "proved_stable" and len(d["multiplier_moduli"]) == 4
    assert "\n" not in repr(c) and repr(c).startswith("OrbitCertificate(")


def test_point_certificates_of_other_classes():
    c = certify_orbit(hp.ImpactPair(mu=0.1, e=0.5, L=0.75), (10, 20), 5.0, case="noncollocated")
    assert c.verdict == "proved_unstable" and c.spectral_radius[0] > 1
    c = certify_orbit(hp.ImpactPair(mu=0.1, e=0.1, L=0.75, m2=2.0), (20, 80), 5.0, x10=1.0)
    assert c.verdict == "proved_no_orbit" and c.viable == -1
    # m2 enters only through kp/m2, kv/m2
    c2 = certify_orbit(hp.ImpactPair(mu=0.1, e=0.1, L=0.75), (10, 40), 5.0)
    assert c2.verdict == c.verdict


# ---------------------------------------------------------------------------------------------
# boxes across boundaries: undecided, or a class every point agrees with

def _grazing_kv(kp=10.0):
    """kv of the grazing boundary (collocated, e = 0.1) at kp, by bisection on the float path."""
    f = lambda kv: hp.symmetric_orbits(kp, kv, mu=0.1, e=0.1, L=0.75, omega=5.0).exists
    a, b = 20.0, 24.0
    assert f(a) and not f(b)
    for _ in range(40):
        m = 0.5 * (a + b)
        a, b = (m, b) if f(m) else (a, m)
    return a


def _stability_kv(kp=5.0):
    """kv where the non-collocated orbit loses stability at kp (e = 0.5)."""
    f = lambda kv: hp.symmetric_orbits(kp, kv, mu=0.1, e=0.5, L=0.75, omega=5.0,
                                       case="noncollocated").stable
    a, b = 0.2, 6.0
    assert f(a) and not f(b)
    for _ in range(40):
        m = 0.5 * (a + b)
        a, b = (m, b) if f(m) else (a, m)
    return a


@pytest.mark.parametrize("which", ["grazing", "stability"])
def test_boxes_straddling_a_boundary(which):
    if which == "grazing":
        case, e, kp, kvb = "collocated", 0.1, 10.0, _grazing_kv()
    else:
        case, e, kp, kvb = "noncollocated", 0.5, 5.0, _stability_kv()
    kv = (kvb - 0.05, kvb + 0.05)
    c = certify_box(case, kp=(kp - 0.05, kp + 0.05), kv=kv, e=e, depth=1, **FIXED)
    kps, kvs = _samples({"kp": (kp - 0.05, kp + 0.05), "kv": kv}, num=60, seed=1)
    kvs[:2] = kv  # both sides of the boundary are among the points
    pts = hp.symmetric_orbits(kps, kvs, mu=0.1, e=e, L=0.75, omega=5.0, case=case)
    point_class = np.where(~pts.exists, 3, np.where(pts.stable, 1, 2))
    assert len(set(point_class.tolist())) == 2   # the box does straddle the boundary
    assert c.verdict == "undecided", c


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(kp=st.floats(0.3, 49.5), kv=st.floats(0.3, 49.5), e=st.sampled_from([0.1, 0.5, 0.9]),
       case=st.sampled_from(["collocated", "noncollocated"]))
def test_any_proved_box_agrees_with_its_points(kp, kv, e, case):
    b = {"kp": (kp, kp + 0.4), "kv": (kv, kv + 0.4)}
    flags = certify_cells(case, kp=b["kp"], kv=b["kv"], e=e, depth=0, **FIXED).flags
    kps, kvs = _samples(b, num=30, seed=int(kp * 1000))
    pts = hp.symmetric_orbits(kps, kvs, mu=0.1, e=e, L=0.75, omega=5.0, case=case)
    point_class = np.where(~pts.exists, 3, np.where(pts.stable, 1, 2))
    if int(flags) != 0:
        assert (point_class == int(flags)).all()


# ---------------------------------------------------------------------------------------------
# maps and files

def test_cell_edges_and_shares():
    np.testing.assert_allclose(cell_edges([0.0, 1.0, 3.0]), [0.0, 0.5, 2.0, 3.0], rtol=0,
                               atol=1e-15)
    np.testing.assert_allclose(cell_edges([1.0, 100.0], "log"), [1.0, 10.0, 100.0],
                               rtol=1e-15, atol=0)
    sh = class_shares(np.array([[0, 1], [1, 3]]))
    assert sh["proved_stable"] == {"proved": 2, "undecided": 1, "cells": 4, "share": (0.5, 0.75)}
    assert sh["undecided"]["proved"] == 1
    for bad in ([1.0], [2.0, 1.0], [[1.0, 2.0]]):
        with pytest.raises(ValueError, match="axis"):
            cell_edges(bad)
    with pytest.raises(ValueError, match="spacing"):
        cell_edges([1.0, 2.0], "cubic")


def test_certified_map_agrees_with_the_point_map():
    # across the existence boundary kv ~ 21.5: unstable cells below, no orbit above
    grid = dict(x=("kp", 10, 13, 4), y=("kv", 19.5, 23.5, 4), e=[0.5], mu=0.1, gamma=0.75,
                omega=5.0)
    cm = certified_map("noncollocated", depth=1, **grid)
    rm = pair_region_map("noncollocated", progress=False, **grid)
    point = np.where(~rm.exists, 3, np.where(rm.stable, 1, 2))
    proved = cm.flags != 0
    assert set(cm.flags[proved].tolist()) == {2, 3}
    assert (cm.flags[proved] == point[proved]).all()
    assert len(cm.summary()) == 1 and "undecided" in cm.summary()[0]
    assert cm.to_dict()["flag_meanings"] == FLAG_MEANINGS


def test_region_map_certified_round_trip(tmp_path):
    rm = pair_region_map("collocated", x=("kp", 9, 11, 3), y=("kv", 19, 21, 2), e=[0.5, 0.9],
                       mu=0.1, gamma=0.75, omega=5.0, certify=True, certify_depth=1,
                       progress=False, store=tmp_path / "run.zarr")
    assert (tmp_path / "run.certified.zarr").is_dir()   # the certification's own store
    assert rm.certified.shape == (2, 2, 3) and rm.certified.dtype == np.int8
    assert (rm.certified[rm.certified != 0] == 1).all()
    ds = rm.to_dataset()
    assert list(ds["certified"].attrs["flag_values"]) == list(FLAG_VALUES)
    assert ds["certified"].attrs["flag_meanings"] == FLAG_MEANINGS
    for suffix in (".nc", ".npz"):
        back = hp.load_region_map(rm.save(tmp_path / f"r{suffix}"))
        np.testing.assert_array_equal(back.certified, rm.certified)
    assert class_shares(rm.certified[0])["proved_stable"]["cells"] == 6
    plain = pair_region_map("collocated", x=("kp", 9, 11, 3), y=("kv", 19, 21, 2), e=[0.5],
                          mu=0.1, gamma=0.75, omega=5.0, progress=False)
    assert plain.certified is None and "certified" not in plain.to_dataset()
    back = hp.load_region_map(plain.save(tmp_path / "p.nc"))
    assert back.certified is None


def test_certified_figure(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    from hybridpd.plotting.regions import plot_certified_panels, plot_region_panels

    grid = dict(x=("kp", 10, 13, 3), y=("kv", 19.5, 23.5, 3), e=[0.5], mu=0.1, gamma=0.75,
                omega=5.0, progress=False)
    rm = pair_region_map("noncollocated", certify=True, certify_depth=1, **grid)
    assert {0, 2, 3} <= set(rm.certified.ravel().tolist())
    fig = plot_region_panels(rm)
    labels = [t.get_text() for leg in fig.legends for t in leg.get_texts()]
    assert {"proved unstable", "proved no orbit (white)", "undecided (hatched)"} <= set(labels)
    assert len(fig.axes) == 2
    fig.savefig(tmp_path / "c.png")
    assert len(plot_certified_panels(rm).axes) == 1
    plain = pair_region_map("noncollocated", **grid)
    with pytest.raises(ValueError, match="certify"):
        plot_certified_panels(plain)


# ---------------------------------------------------------------------------------------------
# input checks

@pytest.mark.parametrize("kw, match", [
    (dict(kp=(2.0, 1.0)), "kp"), (dict(e=1.5), "e must lie"), (dict(kv=-1.0), "kv"),
    (dict(depth=-1), "depth"), (dict(n=2), "odd"), (dict(kp="a"), "kp"),
])
def test_bad_input_names_the_parameter(kw, match):
    args = dict(kp=(9.0, 10.0), kv=(19.0, 20.0), e=0.5, **FIXED)
    args.update(kw)
    with pytest.raises(ValueError, match=match):
        certify_box("collocated", **args)


def test_bad_map_and_orbit_input():
    with pytest.raises(ValueError, match="gamma"):
        certified_map("collocated", x=("kp", 1, 2, 2), y=("kv", 1, 2, 2), e=[0.5], mu=0.1,
                      omega=5.0)
    with pytest.raises(ValueError, match="x axis name"):
        certified_map("collocated", x=("zeta", 1, 2, 2), y=("kv", 1, 2, 2), e=[0.5], mu=0.1,
                      omega=5.0, gamma=0.75)
    with pytest.raises(ValueError, match="pair"):
        certify_orbit((0.1, 0.5, 0.75), (10, 20), 5.0)
    with pytest.raises(ValueError, match="case"):
        certify_cells("sideways", kp=1.0, kv=1.0, mu=0.1, e=0.5, omega=5.0, gamma=0.75)


@pytest.mark.slow  # ~15 s per case
@pytest.mark.parametrize("case", ["collocated", "noncollocated"])
def test_certified_map_full_paper_box_is_consistent(case):
    cm = certified_map(case, x=("kp", 0.1, 50, 41), y=("kv", 0.1, 50, 41), e=[0.1, 0.5, 0.9],
                       mu=0.1, gamma=0.75, omega=5.0)
    rm = pair_region_map(case, x=("kp", 0.1, 50, 41), y=("kv", 0.1, 50, 41), e=[0.1, 0.5, 0.9],
                       mu=0.1, gamma=0.75, omega=5.0, progress=False)
    point = np.where(~rm.exists, 3, np.where(rm.stable, 1, 2))
    proved = cm.flags != 0
    assert (cm.flags[proved] == point[proved]).all()
    assert proved.mean() > 0.6
