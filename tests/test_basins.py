"""Basin mapper and attractor-labelled basins: labels against direct long simulations, early
exits change no label, cycles are fixed points of P^k, windows grow, measures are formatted."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hybridpd import ImpactPair, PDGains
from hybridpd._format import format_percent
from hybridpd.analysis.basins import NO_CONVERGENCE, OFF_SECTION_LABEL, load_basin
from hybridpd.analysis.labels import LABELS
from hybridpd.analysis.mappers import Catalogue, Growth, Mapper, mapper
from hybridpd.pair.basins import PaperMetric, paper_distance2, section_grid
from hybridpd.pair.impactmap import ImpactMap
from hybridpd.pair.orbits import symmetric_orbit
from hybridpd.reproduce.basins import orbit_mapper
from hybridpd.sweeps.basins import basin_of_attraction

CASES = [("collocated", 0.5, 10.0, 20.0), ("collocated", 0.1, 10.0, 20.0),
         ("noncollocated", 0.1, 5.4, 2.5), ("noncollocated", 0.5, 10.0, 20.0)]


def mapper_for(case, e, kp, kv, **kw):
    o = symmetric_orbit(ImpactPair(0.1, e, 0.75), PDGains(kp, kv), 5.0, case=case)
    assert o.exists
    return o, mapper(ImpactMap(o.pair, o.gains, o.reference(), case), o.fixed_point, **kw)


def paper_basin(m, x1, y1, **options):
    """The paper's labels alone: the basin of the pair's mapper without attractor search."""
    return basin_of_attraction(m, x1, y1, max_period=0, **options)


def attractor_basin(m, x1, y1, *, extend=True, max_extensions=3, max_points=None, **options):
    """The basin by attractor, its window grown (``extend``) or kept."""
    grow = Growth(max_extensions if extend else 0, max_points)
    return basin_of_attraction(m, x1, y1, grow=grow, **options)


@pytest.mark.parametrize("case,e,kp,kv", CASES)
def test_early_exits_give_identical_labels(case, e, kp, kv):
    _o, fast = mapper_for(case, e, kp, kv)
    _, slow = mapper_for(case, e, kp, kv, early_exit=False)
    b1 = paper_basin(fast, (-3, 5, 13), (-2, 10, 13))
    b2 = paper_basin(slow, (-3, 5, 13), (-2, 10, 13))
    np.testing.assert_array_equal(b1.labels, b2.labels)
    assert b2.iterations.max() <= 1500


@pytest.mark.parametrize("case,e,kp,kv", CASES[:3])
def test_labels_agree_with_direct_long_simulation(case, e, kp, kv):
    """Sampled grid points: iterate P 1500 times directly and apply the paper's criterion."""
    o, m = mapper_for(case, e, kp, kv)
    P = m.map
    xs, ys = np.linspace(-3, 5, 7), np.linspace(-2, 10, 7)
    grid = section_grid(o.fixed_point, 0.75, xs, ys).reshape(-1, 4)
    lab, _ = m.labels(grid)
    T = P.period
    rng = np.random.default_rng(0)
    for i in rng.choice(len(grid), 12, replace=False):
        s = grid[i]
        if s[3] <= 0:
            assert LABELS[lab[i]] == "off_section"
            continue
        traj = P.iterate(s, 1500)
        last = traj[-1]
        if not np.all(np.isfinite(last)):
            assert LABELS[lab[i]] in ("diverged", "zeno_sticking", "unresolved")
            continue
        dphi = (last[0] - o.fixed_point[0] + T / 2) % T - T / 2
        d = np.array([last[1] - o.fixed_point[1],
                      last[2] + last[3] - o.fixed_point[2] - o.fixed_point[3],
                      last[2] - o.fixed_point[2], dphi])
        expect = "converged" if d @ d < 1e-3 else "not_converged"
        assert LABELS[lab[i]] == expect


def test_certified_ball_is_invariant_under_iteration():
    o, m = mapper_for("collocated", 0.5, 10.0, 20.0)
    assert m.certified_radius > 0
    Q, r2 = m.cert_Q[0], m.cert_r2[0]
    Lq = np.linalg.cholesky(Q)
    rng = np.random.default_rng(3)
    for _ in range(20):
        u = rng.normal(size=4)
        u /= np.linalg.norm(u)
        d = np.linalg.solve(Lq.T, u) * m.certified_radius * 0.99
        traj = m.map.iterate(o.fixed_point + d, 30)
        dev = traj - o.fixed_point
        q = np.einsum("ij,jk,ik->i", dev, Q, dev)
        assert np.all(q <= r2 * 1.0001)


def test_basin_save_load_and_executors_agree(tmp_path):
    _o, m = mapper_for("collocated", 0.5, 10.0, 20.0)
    b1 = paper_basin(m, (-3, 5, 9), (-2, 10, 8))
    b2 = paper_basin(m, (-3, 5, 9), (-2, 10, 8), executor="processes", max_workers=2,
                             chunk_size=10)
    np.testing.assert_array_equal(b1.labels, b2.labels)
    b1.save(tmp_path / "b.npz")
    b3 = load_basin(tmp_path / "b.npz")
    np.testing.assert_array_equal(b3.labels, b1.labels)
    assert b3.metadata["kp"] == 10.0 and b3.converged_fraction == b1.converged_fraction


def test_bad_grids_and_mapper_input():
    o, m = mapper_for("collocated", 0.5, 10.0, 20.0)
    for bad in ((1, 0, 5), (0, 1, 0), (0, float("nan"), 3), (0, 1, 2.5)):
        with pytest.raises(ValueError, match="x1"):
            paper_basin(m, bad, (0, 1, 3))
    with pytest.raises(ValueError, match="fixed_point"):
        mapper(m.map, [0, 1, 2])
    with pytest.raises(ValueError, match="n_iter"):
        mapper(m.map, o.fixed_point, n_iter=0)


# ----------------------------------------------------------------------------------------
# Attractor-labelled basins
# ----------------------------------------------------------------------------------------

_AB_CACHE = {}


def fig6_e01(num=30, extend=False):
    """Collocated e = 0.1, kp = 10, kv = 20 on the Fig. 6 window (period-2 attractor)."""
    key = (num, extend)
    if key not in _AB_CACHE:
        o = symmetric_orbit(ImpactPair(0.1, 0.1, 0.75), PDGains(10, 20), 5.0)
        _AB_CACHE[key] = (o, attractor_basin(orbit_mapper(o), (-3, 5, num),
                                             (-2, 10, num), extend=extend))
    return _AB_CACHE[key]


def _power(P, s, k):
    return P.iterate(s, k)[-1]


def _wrapped_sup(a, b, T):
    d = np.asarray(a, float) - b
    d[0] = (d[0] + T / 2) % T - T / 2
    return np.max(np.abs(d))


def test_period2_attractor_is_a_fixed_point_of_P2_not_of_P():
    o, ab = fig6_e01()
    P = ImpactMap(o.pair, o.gains, o.reference())
    (a,) = [a for a in ab.attractors if a.label > 0]
    assert a.name == "period-2 orbit" and a.period == 2 and a.stable
    for s in a.points:
        assert _wrapped_sup(_power(P, s, 2), s, P.period) < 1e-10
        assert _wrapped_sup(_power(P, s, 1), s, P.period) > 1e-2
    # the points are one cycle: P maps the first to the second
    assert _wrapped_sup(_power(P, a.points[0], 1), a.points[1], P.period) < 1e-10
    # the hybrid-automaton simulator (event location, python-control loop), started just
    # after the impact at points[0], meets the +L wall at points[1], then at points[0]
    T, L = P.period, o.pair.L
    s0 = a.points[0]
    post = o.pair.impact(np.array([s0[1] + L, s0[2] + s0[3], s0[1], s0[2]]), +1)
    tr = o.system().simulate(post, (s0[0], s0[0] + 2.6 * T))
    plus = np.flatnonzero(tr.walls == 1)[:2]
    assert len(plus) == 2
    for j, i in enumerate(plus):
        _x1, y1, x2, y2 = tr.pre[i]
        s_sim = np.array([tr.impact_times[i] % T, x2, y2, y1 - y2])
        assert _wrapped_sup(s_sim, a.points[(j + 1) % 2], T) < 1e-9
    # multipliers against finite differences of the simulated map (chain rule over the cycle)
    J = P.jacobian_fd(a.points[1]) @ P.jacobian_fd(a.points[0])
    ev = np.sort(np.abs(np.linalg.eigvals(J)))[::-1]
    np.testing.assert_allclose(ev[:2], np.abs(a.multipliers[:2]), rtol=1e-4, atol=1e-6)
    assert abs(a.spectral_radius - ev[0]) < 1e-5 * ev[0]
    # the paper's slice at e = 0.1 is almost all period-2 motion
    m = ab.measure(a.label)
    assert 0.9 < m.fraction < 1.0 and m.percent.endswith(" %")
    sym = ab.measure(0)
    assert sym.count > 0 and sym.count + m.count == (ab.labels != OFF_SECTION_LABEL).sum()


def _check_label_by_simulation(P, ab, label, s, n_iter, criterion=1e-3):
    traj = P.iterate(s, n_iter + 10)
    last = traj[n_iter]
    if label in (-2, -3, -4):   # diverged, sticking, unresolved: the flight fails
        assert not np.all(np.isfinite(traj)) or np.max(np.abs(traj[:, 1:])) > 1e3
        return
    assert np.all(np.isfinite(traj))
    to_fp = paper_distance2(last, ab.fixed_point, P.period)
    if label == 0:
        assert to_fp < criterion
        return
    cycles = [a for a in ab.attractors if a.label > 0]
    near = {a.label: np.all(paper_distance2(traj[n_iter:, None, :], a.points[None],
                                            P.period).min(axis=1) < criterion)
            for a in cycles}
    if label == NO_CONVERGENCE:
        assert to_fp >= criterion and not any(near.values())
    else:
        assert near[label] and to_fp >= criterion


@pytest.mark.parametrize("case,e,kp,kv,n_iter,periods", [
    ("collocated", 0.1, 10.0, 20.0, 1500, [2]),        # symmetric orbit, period-2 motion
    ("collocated", 0.9, 2.0, 1.0, 1500, [3]),          # symmetric orbit, a period-3 orbit
    ("noncollocated", 0.1, 10.0, 20.0, 300, []),       # unstable symmetric orbit
    ("noncollocated", 0.5, 20.0, 2.0, 600, [1, 1, 2, 3]),  # four other cycles coexist
])
def test_attractor_labels_agree_with_direct_simulation(case, e, kp, kv, n_iter, periods):
    o = symmetric_orbit(ImpactPair(0.1, e, 0.75), PDGains(kp, kv), 5.0, case=case)
    mapper = orbit_mapper(o, n_iter=n_iter)
    ab = attractor_basin(mapper, (-3, 5, 16), (-2, 10, 16), extend=False)
    P = mapper.map
    grid = section_grid(o.fixed_point, 0.75, ab.x1, ab.y1)
    rng = np.random.default_rng(1)
    seen = set()
    for a in ab.attractors:
        iy, ix = np.nonzero(ab.labels == a.label)
        seen.add(a.label)
        for j in rng.choice(len(iy), min(4, len(iy)), replace=False):
            s = grid[iy[j], ix[j]]
            if a.label == OFF_SECTION_LABEL:
                assert s[3] <= 0
                continue
            _check_label_by_simulation(P, ab, a.label, s, n_iter)
    assert seen >= set(np.unique(ab.labels).tolist())
    cycles = [a for a in ab.attractors if a.label > 0]
    assert sorted(a.period for a in cycles) == periods
    assert len({a.name for a in ab.attractors}) == len(ab.attractors)
    for a in cycles:   # every listed cycle is a stable fixed point of P^k with a basin
        assert a.stable and a.residual < 1e-10 and ab.measure(a.label).count > 0
    if o.stable is False:
        assert ab.measure(0).count == 0


def test_cycles_are_deduplicated_up_to_a_cyclic_shift():
    o, ab = fig6_e01()
    P = ImpactMap(o.pair, o.gains, o.reference())
    cyc = next(a for a in ab.attractors if a.label > 0)
    cat = mapper(P, o.fixed_point).catalogue(8)
    assert isinstance(cat.metric, PaperMetric)
    t0 = P.iterate(cyc.points[0], 10)
    t1 = P.iterate(cyc.points[1], 10)
    # entered at either point of the cycle, each on its own catalogue call
    assert cat.assign(t1[None]).tolist() == [1]
    assert cat.assign(t0[None]).tolist() == [1]
    assert len(cat.attractors) == 2
    # a tail that is not periodic (first iterates of a transient) is not labelled
    far = P.iterate(o.fixed_point + [0, 1.5, 0.5, 2.0], 10)
    assert cat.assign(far[None]).tolist() == [NO_CONVERGENCE]
    with pytest.raises(ValueError, match="tails"):
        cat.assign(t0)
    with pytest.raises(ValueError, match="max_period"):
        Catalogue(P, PaperMetric(P), max_period=0)


def test_format_percent_never_rounds_to_the_ends():
    assert format_percent(9999, 10000) == "99.99 %"
    assert format_percent(99999, 100000) == ">99.99 %"
    assert format_percent(1, 100000) == "<0.01 %"
    assert format_percent(0, 7) == "0 %" and format_percent(7, 7) == "100 %"
    assert format_percent(1 - 1e-9) == ">99.99 %" and format_percent(1e-9) == "<0.01 %"
    assert format_percent(1, 3, digits=1) == "33.3 %"
    for bad in ((5, 4), (-1, 4), (1, 0)):
        with pytest.raises(ValueError):
            format_percent(*bad)
    with pytest.raises(ValueError, match="fraction"):
        format_percent(1.5)


def test_window_extends_until_the_basin_boundary_is_inside():
    # e = 0.1: the symmetric orbit's basin is a thin streak; a window around the fixed point
    # cuts it, so the window grows until no basin point is on its edge
    o = symmetric_orbit(ImpactPair(0.1, 0.1, 0.75), PDGains(10, 20), 5.0)
    mapper = orbit_mapper(o)
    ab = attractor_basin(mapper, (0.5, 1.5, 12), (2.5, 4.0, 12), max_extensions=6)
    assert len(ab.windows) > 1 and not ab.reaches_edge and ab.edges == ()
    for w0, w1 in zip(ab.windows, ab.windows[1:]):
        assert w1[0] <= w0[0] and w1[1] >= w0[1] and w1[2] <= w0[2] and w1[3] >= w0[3]
        assert w1 != w0
    on_edge = np.concatenate([ab.labels[0], ab.labels[-1], ab.labels[:, 0], ab.labels[:, -1]])
    assert not np.any(on_edge == 0)
    # without extension the same first window reports the edge instead
    ab0 = attractor_basin(mapper, (0.5, 1.5, 12), (2.5, 4.0, 12), extend=False)
    assert ab0.reaches_edge and len(ab0.windows) == 1
    assert set(ab0.edges) <= {"x1 min", "x1 max", "y1 min", "y1 max"}
    # e = 0.5: the basin fills every window; the bound on extensions stops it and says so
    o5 = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0)
    ab5 = attractor_basin(orbit_mapper(o5), (-3, 5, 10), (-2, 10, 10),
                          max_extensions=2)
    assert len(ab5.windows) == 3 and ab5.reaches_edge
    assert any("reaches the window edge" in line for line in ab5.summary())
    # finer extended grids keep the first cell size up to max_points per axis
    abf = attractor_basin(mapper, (0.5, 1.5, 12), (2.5, 4.0, 12), max_extensions=2,
                          max_points=30)
    assert 12 < max(len(abf.x1), len(abf.y1)) <= 30
    ab7 = attractor_basin(mapper, (0.5, 1.5, 7), (2.5, 4.0, 9), max_extensions=1)
    assert ab7.labels.shape == (9, 7) and len(ab7.windows) == 2
    with pytest.raises(ValueError, match="max_points"):
        attractor_basin(mapper, (0, 1, 5), (3, 4, 5), max_points=3)
    with pytest.raises(ValueError, match="max_extensions"):
        attractor_basin(mapper, (0, 1, 3), (3, 4, 3), max_extensions=-1)


def test_attractor_basin_save_load_and_executors(tmp_path):
    o, ab = fig6_e01(num=12)
    ab2 = attractor_basin(orbit_mapper(o), (-3, 5, 12), (-2, 10, 12), extend=False,
                          executor="processes", max_workers=2, chunk_size=40)
    np.testing.assert_array_equal(ab.labels, ab2.labels)
    ab.save(tmp_path / "ab.npz")
    ab3 = load_basin(tmp_path / "ab.npz")
    np.testing.assert_array_equal(ab3.labels, ab.labels)
    assert [a.name for a in ab3.attractors] == [a.name for a in ab.attractors]
    np.testing.assert_allclose(ab3.attractors[1].points, ab.attractors[1].points)
    assert ab3.to_dict() == ab.to_dict()
    assert ab3.metadata["gamma"] == 0.75 and ab3.metadata["kp"] == 10.0
    np.savez(tmp_path / "other.npz", x=np.zeros(2))
    with pytest.raises(ValueError, match="basin"):
        load_basin(tmp_path / "other.npz")


def test_early_exits_give_identical_attractor_labels():
    o = symmetric_orbit(ImpactPair(0.1, 0.1, 0.75), PDGains(10, 20), 5.0)
    fast = attractor_basin(orbit_mapper(o), (-3, 5, 10), (-2, 10, 10), extend=False)
    slow = attractor_basin(orbit_mapper(o, early_exit=False), (-3, 5, 10),
                           (-2, 10, 10), extend=False)
    np.testing.assert_array_equal(fast.labels, slow.labels)
    assert [a.name for a in fast.attractors] == [a.name for a in slow.attractors]
    assert fast.iterations.mean() < 0.5 * slow.iterations.mean()


def _rendered(fig):
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig)
    fig.canvas.draw()
    return fig.canvas.get_renderer()


def _assert_no_text_clipped(fig):
    from matplotlib.text import Text

    r = _rendered(fig)
    fb = fig.bbox
    # tick labels exist for ticks beyond the view limits, but only those inside are drawn
    hidden = set()
    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            lo, hi = sorted(axis.get_view_interval())
            for tick in axis.get_major_ticks() + axis.get_minor_ticks():
                if not lo - 1e-9 * (hi - lo) <= tick.get_loc() <= hi + 1e-9 * (hi - lo):
                    hidden.update({id(tick.label1), id(tick.label2)})
    n = 0
    for t in fig.findobj(Text):
        if not (t.get_visible() and t.get_text().strip()) or id(t) in hidden:
            continue
        bb = t.get_window_extent(r)
        assert (bb.x0 >= fb.x0 - 0.5 and bb.x1 <= fb.x1 + 0.5 and bb.y0 >= fb.y0 - 0.5
                and bb.y1 <= fb.y1 + 0.5), f"text {t.get_text()!r} outside the figure: {bb}"
        n += 1
    return n


def _assert_legend_matches_drawing(ax, basin):
    from matplotlib.colors import to_rgba
    from matplotlib.patches import Rectangle

    leg = ax.get_legend()
    handles = leg.legend_handles
    texts = [t.get_text() for t in leg.get_texts()]
    img = ax.images[0]
    arr = img.get_array()
    lab = basin.labels if hasattr(basin, "attractors") else None
    drawn_lines = {ln.get_label() for ln in ax.lines}
    drawn_bands = {p.get_label() for p in ax.patches if isinstance(p, Rectangle)
                   and p.get_hatch()}
    n_patch = 0
    for h, txt in zip(handles, texts):
        if txt in drawn_lines or txt in drawn_bands:
            continue
        # a colour entry: some grid cell is drawn in exactly that colour
        fc = to_rgba(h.get_facecolor())
        cells = img.to_rgba(arr.compressed())
        assert np.any(np.all(np.isclose(cells, fc, atol=1e-6), axis=1)), txt
        n_patch += 1
    # every colour drawn has an entry, every marker line and hatched band is in the legend
    colours = {tuple(np.round(c, 6)) for c in img.to_rgba(arr.compressed())}
    assert len(colours) == n_patch
    assert drawn_lines <= set(texts) and drawn_bands <= set(texts)
    if lab is not None:
        for a in basin.attractors:
            m = basin.measure(a.label)
            if m.count and a.label != OFF_SECTION_LABEL:
                assert f"{a.name}: {m.percent}" in texts


def test_basin_figures_keep_text_inside_and_legend_matches_drawing():
    from matplotlib.figure import Figure

    from hybridpd.plotting import plot_basin

    o, ab = fig6_e01(num=20)
    paper = paper_basin(orbit_mapper(o), (-3, 5, 20), (-2, 10, 20))
    o5 = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0)
    ab5 = attractor_basin(orbit_mapper(o5), (-3, 5, 10), (-2, 10, 10),
                          max_extensions=1)
    for b in (ab, paper, ab5):
        fig = plot_basin(b)
        assert _assert_no_text_clipped(fig) >= 5
        ax = fig.axes[0]
        _assert_legend_matches_drawing(ax, b)
        assert ax.get_xlabel().startswith("$x_1$") and ax.get_ylabel().startswith("$y_1$")
        title = ax.get_title()
        for p in ("Collocated", "$e$ = ", "$k_p$ = 10", "$k_v$ = 20", "$\\mu$ = 0.1",
                  "$\\gamma$ = 0.75", "$\\omega$ = 5", "$n$ = 1", "$m_2$ = 1"):
            assert p in title
        legend_title = ax.get_legend().get_title().get_text()
        assert "\\phi^*" in legend_title and "y_2^*" in legend_title
    assert "reaches the window's edge" in plot_basin(ab5).axes[0].get_legend().get_title() \
        .get_text()
    # panels of a multi-panel figure, as the reproduction draws them
    fig = Figure(figsize=(12, 6.5))
    for i, b in enumerate((ab, ab5)):
        plot_basin(b, ax=fig.add_subplot(1, 2, i + 1))
    fig.tight_layout()
    _assert_no_text_clipped(fig)
    with pytest.raises(ValueError, match="basin"):
        plot_basin(np.zeros((3, 3)))


def test_cli_basin_prints_attractors_and_measures(capsys):
    import json

    from hybridpd.cli import main

    base = ["basin", "--case", "collocated", "--mu", "0.1", "--gamma", "0.75", "--omega", "5",
            "--n", "1", "--e", "0.1", "--kp", "10", "--kv", "20", "--x", "x1", "-3", "5", "12",
            "--y", "y1", "-2", "10", "12", "--max-extensions", "0"]
    assert main(base) == 0
    out = capsys.readouterr().out
    assert "period-2 orbit: " in out and "symmetric orbit (period 1): " in out
    assert "multipliers" in out and "y2 = y2* = " in out
    assert main([*base, "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    names = [a["name"] for a in d["attractors"]]
    assert names[:2] == ["symmetric orbit (period 1)", "period-2 orbit"]
    lab = np.array(d["attractor_labels"])
    assert lab.shape == (12, 12)
    for a in d["attractors"]:
        assert a["count"] == int((lab == a["label"]).sum())
    assert d["attractors"][1]["period"] == 2 and len(d["attractors"][1]["points"]) == 2
    assert main([*base, "--max-period", "0"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "max-period" in err


@pytest.mark.slow
@pytest.mark.parametrize("case,e,kp,kv", [("collocated", 0.1, 10.0, 20.0),
                                          ("collocated", 0.9, 2.0, 1.0),
                                          ("noncollocated", 0.1, 10.0, 20.0),
                                          ("noncollocated", 0.5, 20.0, 2.0)])
def test_attractor_labels_agree_with_direct_simulation_many_points(case, e, kp, kv):
    o = symmetric_orbit(ImpactPair(0.1, e, 0.75), PDGains(kp, kv), 5.0, case=case)
    mapper = orbit_mapper(o)
    ab = attractor_basin(mapper, (-3, 5, 50), (-2, 10, 50))
    grid = section_grid(o.fixed_point, 0.75, ab.x1, ab.y1).reshape(-1, 4)
    lab = ab.labels.ravel()
    rng = np.random.default_rng(7)
    for i in rng.choice(len(grid), 150, replace=False):
        if lab[i] == OFF_SECTION_LABEL:
            assert grid[i, 3] <= 0
            continue
        _check_label_by_simulation(mapper.map, ab, int(lab[i]), grid[i], 1500)


@given(whole=st.integers(1, 10**9), data=st.data(), digits=st.integers(0, 4))
@settings(max_examples=200, deadline=None)
def test_format_percent_is_within_rounding_and_never_at_the_ends(whole, data, digits):
    part = data.draw(st.integers(0, whole))
    s = format_percent(part, whole, digits)
    assert s.endswith(" %")
    if part == 0:
        assert s == "0 %"
    elif part == whole:
        assert s == "100 %"
    else:
        assert s not in ("0 %", "100 %")
        body = s[:-2]
        step = 10.0 ** -digits
        p = 100.0 * part / whole
        if body.startswith(">"):
            assert float(body[1:]) == pytest.approx(100 - step) and p > 100 - step
        elif body.startswith("<"):
            assert float(body[1:]) == pytest.approx(step) and p < step
        else:
            assert abs(float(body) - p) <= 0.5 * step + 1e-9 and 0 < float(body) < 100


def test_attractor_basin_round_trips_through_every_format(tmp_path):
    orb = symmetric_orbit(ImpactPair(0.1, 0.1, 0.75), PDGains(10, 20), 5.0, case="collocated")
    ab = attractor_basin(orbit_mapper(orb, n_iter=300), (-3, 5, 10), (-2, 10, 9),
                         max_points=20, progress=False)
    ds = ab.to_dataset()
    assert ds.labels.dims == ("y1", "x1") and ds.attrs["kind"] == "basin"
    assert list(ds.labels.attrs["flag_values"]) == [a.label for a in ab.attractors]
    for suf in (".nc", ".zarr", ".npz"):
        r = load_basin(ab.save(tmp_path / f"b{suf}") or tmp_path / f"b{suf}")
        np.testing.assert_array_equal(r.labels, ab.labels)
        np.testing.assert_array_equal(r.criterion_labels, ab.criterion_labels)
        np.testing.assert_array_equal(r.x1, ab.x1)
        assert [a.name for a in r.attractors] == [a.name for a in ab.attractors]
        assert (r.windows, r.edges) == (ab.windows, ab.edges)
        assert [m.count for m in r.measures()] == [m.count for m in ab.measures()]


class _OnlyLabels(Mapper):
    """A mapper with only what the protocol requires: ``labels`` and its attributes."""

    def __init__(self, m):
        self.m, self.map, self.fixed_point = m, m.map, m.fixed_point
        self.n_iter, self.criterion = m.n_iter, m.criterion

    def labels(self, S):
        return self.m.labels(S)


def test_a_mapper_with_only_labels_labels_any_slice_and_matches_iterating_the_map():
    """The basin of a mapper that gives only ``labels`` (every other hook the protocol's
    default: the slice at its fixed point, tails by iterating the map, the general
    catalogue); checked point by point by iterating ``P``."""
    from hybridpd.analysis.hybridmap import SectionMap
    from hybridpd.pair.section import impact_pair_section

    o, m = mapper_for("collocated", 0.1, 10.0, 20.0, n_iter=300)
    P = SectionMap(impact_pair_section(o.system()))
    b = basin_of_attraction(_OnlyLabels(mapper(P, o.fixed_point, n_iter=300)), (-0.5, 0.5, 4),
                            (0.5, 3.0, 3), axes=("z1", "z4"), max_period=4)
    assert b.labels.shape == (3, 4) and b.axes == ("z1", "z4") and b.names == P.names
    assert b.criterion_labels is not None and set(np.unique(b.labels)) - {0} != set()
    T = P.period
    for (r, c), lab in np.ndenumerate(b.labels):
        s = o.fixed_point.copy()
        s[1], s[3] = b.x[c], b.y[r]
        traj = P.iterate(s, 320)
        d = traj[300] - o.fixed_point
        d[0] = (d[0] + T / 2) % T - T / 2
        dist2 = d[1] ** 2 + (d[2] + d[3]) ** 2 + d[2] ** 2 + d[0] ** 2
        if lab == 0:
            assert dist2 < 1e-3
        elif lab > 0:
            pts = b.attractor(lab).points
            gap = traj[300:, None, :] - pts[None]
            gap[..., 0] = (gap[..., 0] + T / 2) % T - T / 2
            np.testing.assert_allclose(np.abs(gap).max(axis=2).min(axis=1), 0.0, rtol=0,
                                       atol=1e-5)
        else:
            assert lab == NO_CONVERGENCE and dist2 >= 1e-3
    # the same slice by the section map's own mapper (compiled, with its hooks)
    same = basin_of_attraction(mapper(P, o.fixed_point, n_iter=300), (-0.5, 0.5, 4),
                               (0.5, 3.0, 3), axes=("z1", "z4"), max_period=4)
    np.testing.assert_array_equal(same.criterion_labels, b.criterion_labels)
    with pytest.raises(ValueError, match="mapper_or_map"):
        basin_of_attraction("m", (-3, 5, 5), (-2, 10, 4))
    with pytest.raises(ValueError, match="executor"):
        basin_of_attraction(P, (0, 1, 2), (0, 1, 2), base=o.fixed_point, executor="processes")
    with pytest.raises(ValueError, match="grow"):
        basin_of_attraction(m, (0, 1, 2), (0, 1, 2), grow=3)


def test_the_phase_wrap_and_its_kernel_twin_are_one_expression_bit_for_bit():
    import inspect

    from hybridpd._phase import wrap_phase, wrap_phase_kernel

    def expr(f):
        src = inspect.getsource(f.py_func if hasattr(f, "py_func") else f)
        return [ln.strip() for ln in src.splitlines() if ln.strip().startswith("return")]

    assert expr(wrap_phase) == expr(wrap_phase_kernel) == ["return (d + 0.5 * T) % T - 0.5 * T"]
    rng = np.random.default_rng(5)
    T = 2 * np.pi / 5.0
    d = np.concatenate([rng.normal(0, 10, 2000), rng.normal(0, 1e-7, 2000),
                        np.arange(-6, 7) * 0.5 * T, [0.0, -0.0, 1e-300, -1e-300]])
    py = wrap_phase(d, T)
    nb = np.array([wrap_phase_kernel(float(x), T) for x in d])
    np.testing.assert_array_equal(py, nb)
    # half-open [-T/2, T/2): +T/2 wraps to -T/2; the wrapped value differs from d by whole T
    assert np.all((py >= -0.5 * T) & (py < 0.5 * T))
    assert wrap_phase(0.5 * T, T) == -0.5 * T
    np.testing.assert_allclose((d - py) / T, np.round((d - py) / T), rtol=0, atol=1e-6)


def test_the_mapper_of_any_map_labels_by_its_iterations():
    """A map with no labeller of its own: labels read at iterate n_iter, checked in closed
    form (x -> a x converges to 0 for |a| < 1, diverges beyond ``escape`` for |a| > 1)."""
    import hybridpd as hp

    class Linear(hp.PoincareMap):
        names = ("x", "y")

        def __init__(self, a):
            self.a = a

        def apply(self, s, k=1, jacobian=False):
            return hp.MapResult(np.asarray(s, float) * self.a ** k)

    m = mapper(Linear(0.5), [0.0, 0.0], n_iter=30, criterion=1e-6)
    lab, its = m.labels(np.array([[1.0, -2.0], [1e3, 0.0], [0.0, 0.0]]))
    # 1e3 * 0.5**30 = 9.3e-7 > sqrt(1e-6)? no: its square 8.7e-13 < 1e-6: converged
    assert lab.tolist() == [0, 0, 0] and its.tolist() == [30, 30, 30]
    far = mapper(Linear(0.5), [0.0, 0.0], n_iter=5, criterion=1e-6)
    assert far.labels(np.array([[1.0, 0.0]]))[0].tolist() == [1]    # 1/32: not yet
    up = mapper(Linear(2.0), [0.0, 0.0], n_iter=20, escape=1e3)
    assert up.labels(np.array([[1.0, 0.0], [0.0, 0.0]]))[0].tolist() == [2, 0]
    b = basin_of_attraction(m, (-1, 1, 3), (-1, 1, 2), max_period=0)
    assert b.axes == ("x", "y") and (b.labels == 0).all() and b.attractors[0].period == 1


def test_a_section_maps_window_grows_in_its_own_coordinates():
    from hybridpd.analysis.hybridmap import SectionMap
    from hybridpd.pair.section import impact_pair_section

    o = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0)
    P = SectionMap(impact_pair_section(o.system()))
    m = mapper(P, o.fixed_point, n_iter=40)
    fp = o.fixed_point
    b = basin_of_attraction(m, (fp[1] - 0.05, fp[1] + 0.05, 3), (fp[3] - 0.05, fp[3] + 0.05, 3),
                            axes=("z1", "z4"), max_period=0, grow=Growth(1))
    assert len(b.windows) == 2 and b.metadata["max_extensions"] == 1
    w0, w1 = b.windows
    assert w1[0] < w0[0] and w1[1] > w0[1] and w1[2] < w0[2] and w1[3] > w0[3]
    assert set(b.edges) <= {"z1 min", "z1 max", "z4 min", "z4 max"}
    # the first window lies inside the orbit's basin: every side was pushed out
    assert (basin_of_attraction(m, b.windows[0][:2] + (3,), b.windows[0][2:] + (3,),
                                axes=("z1", "z4"), max_period=0).labels == 0).all()
