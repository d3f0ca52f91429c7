"""Brute-force bifurcation diagrams against continued orbits.

Where the map has a stable period-k orbit (found and continued by Newton's method, not by
iteration), the diagram must show exactly k points equal to the orbit's section points, and
its Lyapunov exponent (QR product of finite-difference Jacobians along the iterates) must
equal log(rho(DP^k)) / k with DP^k from the continuation (symbolic Jacobian chain).
"""
import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hybridpd import ImpactPair, PDGains
from hybridpd.analysis.diagrams import CLASSES, load_diagram
from hybridpd.analysis.diagrams import bifurcation_diagram as any_diagram
from hybridpd.analysis.maps import detect_period
from hybridpd.pair.bifdiagram import PAIR_SETTINGS, ImpactMapFamily, section_coordinate
from hybridpd.pair.continuation import branch_map, continue_symmetric, switch_branch

W = 5.0
PAIR01 = ImpactPair(0.1, 0.1, 0.75)
BASIN_POINT = [0.3, -2.1, -2.3, 0.5]      # a grid point of the kv = 20 basin slice


def bifurcation_diagram(pair, gains, omega, parameter, values, *, case="collocated",
                        x10=1.0, n=1, xm=None, initial=None, **kw):
    """The impact pair's family through the one diagram, with the pair's settings."""
    fam = ImpactMapFamily(pair, gains, omega, parameter, case, x10, n, xm)
    return any_diagram(fam, values, s0=initial, **dict(PAIR_SETTINGS, **kw))


def _d(a, b, T):
    d = np.asarray(a, float) - np.asarray(b, float)
    d[..., 0] = (d[..., 0] + T / 2) % T - T / 2
    return np.max(np.abs(d))


def _matches(cycle, orbit_points, T, tol):
    """Every cycle point is one of the orbit points and vice versa."""
    return (all(min(_d(c, o, T) for o in orbit_points) < tol for c in cycle)
            and all(min(_d(o, c, T) for c in cycle) < tol for o in orbit_points))


@pytest.fixture(scope="module")
def period2_branch():
    """The e = 0.1 double-impact 2-cycle on the design path, reached from the symmetric
    orbit's grazing point and continued down to kv = 20."""
    br = continue_symmetric(PAIR01, PDGains(10, 20), W, "kv", 23.0)
    sw = switch_branch(br, br.events_of("grazing")[0], 20.0)
    return sw.branches[0]


def test_period2_diagram_equals_the_continued_cycle(period2_branch):
    b = period2_branch
    idx = [len(b) - 1, len(b) // 2, 1]
    vals = b.parameter[idx]
    d = bifurcation_diagram(PAIR01, PDGains(10, 20), W, "kv", vals, iterations=1500, keep=64,
                            initial=BASIN_POINT)
    T = 2 * np.pi / W
    for j, i in enumerate(idx):
        assert d.classification[j] == "periodic" and d.period[j] == 2
        cyc = d.cycle(j)
        assert cyc.shape == (2, 4)
        # exactly two distinct points among all kept iterates
        kept = d.points[j]
        assert all(min(_d(x, c, T) for c in cyc) < 1e-10 for x in kept)
        s = b.points[i]
        P = branch_map(b, b.parameter[i])
        assert abs(P.reference.xm - d.xm[j]) < 1e-12
        assert _matches(cyc, [s, P(s)], T, 1e-8)
        # the exponent against the continuation's multipliers
        lam = np.log(b.spectral_radius[i]) / 2
        assert d.lyapunov[j] < 0
        assert abs(d.lyapunov[j] - lam) < 1e-6


@pytest.mark.parametrize("case,e,kv", [("collocated", 0.5, 20.0), ("noncollocated", 0.5, 1.0)])
def test_period1_diagram_equals_the_symmetric_orbit(case, e, kv):
    br = continue_symmetric(ImpactPair(0.1, e, 0.75), PDGains(10, kv), W, "kv", kv + 0.5,
                            case=case, step=0.25, max_step=0.25)
    assert br.stable.all()
    d = bifurcation_diagram(ImpactPair(0.1, e, 0.75), PDGains(10, kv), W, "kv", br.parameter,
                            case=case, iterations=2000, keep=64)
    T = 2 * np.pi / W
    for j in range(len(br)):
        assert d.period[j] == 1
        assert _d(d.cycle(j)[0], br.points[j], T) < 1e-8
        # a real dominant multiplier: the QR estimate converges geometrically; a complex
        # dominant pair rotates the vector and the average converges like 1/N (N = 48 here)
        m = br.multipliers[j][np.argmax(np.abs(br.multipliers[j]))]
        tol = 1e-6 if abs(m.imag) < 1e-9 else 1.0 / 48
        assert abs(d.lyapunov[j] - np.log(br.spectral_radius[j])) < tol


def test_following_shows_the_hysteresis_of_the_two_attractors():
    """kv = 20 and 21: from the symmetric orbit the diagram stays on it (period 1); following
    down from kv = 23 (past the grazing at 21.938) it stays on the 2-cycle."""
    up = bifurcation_diagram(PAIR01, PDGains(10, 20), W, "kv", [20.0, 21.0, 23.0],
                             iterations=800, keep=32, follow=True)
    assert list(up.period) == [1, 1, 2]
    down = bifurcation_diagram(PAIR01, PDGains(10, 20), W, "kv", [23.0, 21.0, 20.0],
                               iterations=800, keep=32, follow=True,
                               initial=up.final[-1])
    assert list(down.period) == [2, 2, 2]
    # without following every value starts from the same point (the symmetric one)
    fresh = bifurcation_diagram(PAIR01, PDGains(10, 20), W, "kv", [23.0, 21.0, 20.0],
                                iterations=800, keep=32, initial=up.initial)
    assert list(fresh.period) == [2, 1, 1]


def test_no_impact_class_and_fixed_xm():
    """A tiny fixed reference amplitude: the masses settle inside the clearance."""
    d = bifurcation_diagram(PAIR01, PDGains(10, 20), W, "kp", [5.0, 10.0], xm=0.01,
                            iterations=200, keep=10, initial=[0.1, 0.0, 0.0, 1.0])
    assert d.classification == ["no_impact", "no_impact"]
    assert not d.design and d.fixed["xm"] == 0.01 and np.all(d.xm == 0.01)


def test_save_load_roundtrip_and_dict(tmp_path):
    d = bifurcation_diagram(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), W, "e",
                            [0.4, 0.5], iterations=100, keep=16)
    for path in (tmp_path / "d.nc", tmp_path / "d.zarr"):
        d.save(path)
        r = load_diagram(path)
        for f in ("values", "points", "code", "periods", "lyapunov", "xm", "L", "final"):
            np.testing.assert_array_equal(getattr(r, f), getattr(d, f))
        assert r.fixed == d.fixed and r.parameter_name == "e" and r.case == d.case
        assert r.status == d.status and r.names == d.names
    out = json.loads(json.dumps(d.to_dict()))
    assert out["counts"]["periodic"] == 2 and set(out["counts"]) == set(CLASSES)
    assert np.allclose(section_coordinate(d.points, "x1", d.L[:, None]),
                       d.points[..., 1] + 0.75)
    assert np.allclose(section_coordinate(d.points, "y1", 0.75),
                       d.points[..., 2] + d.points[..., 3])


def test_gamma_sweep_moves_the_clearance():
    d = bifurcation_diagram(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), W, "gamma",
                            [0.6, 0.75], x10=2.0, iterations=200, keep=16)
    assert np.allclose(d.L, [1.2, 1.5]) and "L" not in d.fixed and d.fixed["x10"] == 2.0


@pytest.mark.parametrize("kw,match", [
    (dict(parameter="L"), "parameter must be one of"),
    (dict(values=[1.0]), "at least 2"),
    (dict(values=[-1.0, 2.0]), "must be > 0"),
    (dict(keep=50, iterations=10), "keep must be in"),
    (dict(keep=4), "keep must be in"),
    (dict(initial=[0, 0, 0, -1]), "z4 must be > 0"),
    (dict(parameter="xm"), "fixed-xm"),
    (dict(n=2), "odd"),
])
def test_bad_input_names_the_culprit(kw, match):
    args = dict(parameter="kv", values=[1.0, 2.0])
    args.update(kw)
    with pytest.raises(ValueError, match=match):
        bifurcation_diagram(PAIR01, PDGains(10, 20), W, args.pop("parameter"),
                            args.pop("values"), **args)


def test_plot_overlays_branches_with_a_legend_of_the_drawn_artists(period2_branch):
    from hybridpd.plotting.bifurcation import plot_bifurcation

    b = period2_branch
    sym = continue_symmetric(PAIR01, PDGains(10, 20), W, "kv", 23.0)
    d = bifurcation_diagram(PAIR01, PDGains(10, 20), W, "kv", np.linspace(20, 23, 4),
                            iterations=200, keep=16, follow=True)
    fig = plot_bifurcation(d, coordinate="phi", branches=[(sym, "symmetric"), (b, "2-cycle")])
    ax = fig.axes[0]
    drawn = {ln.get_label() for ln in ax.get_lines() if not ln.get_label().startswith("_")}
    legend = {t.get_text() for t in ax.get_legend().get_texts()}
    assert legend == drawn
    assert {"iterates of $P$", "symmetric, stable", "2-cycle, stable", "grazing"} <= legend
    # the 2-cycle is drawn through both of its points: one solid curve per cycle point
    c2 = next(ln.get_color() for ln in ax.get_lines() if ln.get_label() == "2-cycle, stable")
    solid = [ln for ln in ax.get_lines() if ln.get_linestyle() == "-" and ln.get_color() == c2]
    assert len(solid) >= 2
    ys = np.concatenate([ln.get_ydata() for ln in solid])
    T = 2 * np.pi / W
    s0, s1 = b.points[-1], branch_map(b, b.parameter[-1])(b.points[-1])
    assert np.nanmin(np.abs(ys - s0[0])) < 1e-12 and np.nanmin(np.abs(ys - s1[0] % T)) < 1e-12
    assert ax.get_xlabel().startswith("$k_v$") and "mod" in ax.get_ylabel()
    with pytest.raises(ValueError, match="coordinate"):
        plot_bifurcation(d, coordinate="x3")


@settings(max_examples=60, deadline=None)
@given(k=st.integers(1, 9), n=st.integers(20, 80), seed=st.integers(0, 2**32 - 1),
       shift=st.floats(0, 1))
def test_period_detection_finds_the_minimal_period(k, n, seed, shift):
    """Synthetic cycles (phases wrapped across T, noise far below the tolerance)."""
    T = 1.2566
    rng = np.random.default_rng(seed)
    cyc = rng.uniform(-3, 3, (k, 4))
    cyc[:, 0] = (np.arange(k) * 0.37 + shift) % T          # distinct phases mod T
    X = cyc[np.arange(n) % k] + rng.normal(0, 1e-12, (n, 4))
    X[:, 0] %= T
    want = k if n >= 2 * k else 0
    def wrap(d):
        d = np.array(d, float)
        d[:, 0] = (d[:, 0] + T / 2) % T - T / 2
        return d

    assert detect_period(X, wrap, min(16, n // 2), 1e-8)[0] == want


def test_the_npz_file_reads_as_the_same_diagram_and_the_earlier_layout_is_refused(tmp_path):
    """``.npz`` is one suffix of the one result writer; the 0.2.0 layout is not read."""
    d = bifurcation_diagram(PAIR01, PDGains(10, 20), W, "kv", [20.0, 23.0], iterations=100,
                            keep=16)
    r = load_diagram(d.save(tmp_path / "d.npz"))
    for k in ("values", "points", "code", "periods", "spectrum", "final", "xm", "L"):
        a, b = np.asarray(getattr(r, k)), np.asarray(getattr(d, k))
        assert a.dtype == b.dtype and np.array_equal(a, b, equal_nan=True), k
    assert r.status == d.status and r.fixed == d.fixed and r.names == d.names
    assert r.to_dict() == d.to_dict()
    # the 0.2.0 .npz layout (arrays and a JSON "meta"), written here by hand
    meta = {"parameter_name": "kv", "iterations": 100, "keep": 16, "classes": list(CLASSES)}
    np.savez_compressed(tmp_path / "old.npz", values=d.values, points=d.points,
                        meta=np.array(json.dumps(meta)))
    with pytest.raises(ValueError, match="old.npz.*not a result archive"):
        load_diagram(tmp_path / "old.npz")
