"""What a print reviewer found in the reproduction's figures, checked on figures drawn from
small synthetic or quick data: one denominator for the basin shares (the titles' and
summary.md's), mathematics rendered (no raw caret), the fixed point's and the paper's-gains
stars on top and inside their axes, an empty basin figure that says why, coinciding curves
that stay distinguishable on one shared m2 range, legends in the colours drawn, no empty
decades, non-collocated regions that show."""
import math
import re
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import LineCollection, PolyCollection
from matplotlib.colors import to_rgba
from matplotlib.lines import Line2D
from matplotlib.text import Text

from hybridpd import ImpactPair, PDGains
from hybridpd._format import pct
from hybridpd.analysis.basins import OFF_SECTION_LABEL
from hybridpd.analysis.mappers import Growth
from hybridpd.pair.orbits import symmetric_orbit
from hybridpd.plotting.basins import plot_basin
from hybridpd.plotting.regions import plot_region_panels
from hybridpd.plotting.studies import (
    CERT_LABEL,
    CERT_PLAIN,
    plot_m2_study,
    plot_param_study,
    plot_scaled_regions,
)
from hybridpd.reproduce.basins import orbit_mapper
from hybridpd.reproduce.figures import _basin_figure, _plain_figure, basin_share
from hybridpd.reproduce.settings import PAPER
from hybridpd.sweeps.basins import basin_of_attraction

_MATH = re.compile(r"\$[^$]*\$")
_PAR = dict(mu=0.1, gamma=0.75, omega=5.0, n=1, m2=1.0, x10=1.0)
_VERMILLION = to_rgba("#D55E00")


def _draw(fig):
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    return canvas.get_renderer()


def _texts(fig):
    """Every visible, non-empty text drawn (titles, labels, ticks, legends, annotations)."""
    _draw(fig)
    return [t for t in fig.findobj(Text) if t.get_visible() and t.get_text().strip()]


def _assert_no_raw_caret(fig, name):
    for t in _texts(fig):
        outside = _MATH.sub("", t.get_text())
        assert "^" not in outside, f"{name}: raw caret in {t.get_text()!r}"


def _stars(ax):
    return [ln for ln in ax.lines if ln.get_marker() == "*"]


def _assert_star_on_top_and_inside(ax, name):
    """The star is drawn above every other artist of the axes and lies, whole, inside the
    axes (its marker's extent within the axes' box)."""
    stars = _stars(ax)
    assert stars, f"{name}: no star"
    r = _draw(ax.figure)
    others = [a for a in ax.get_children() if a not in stars and a.get_visible()
              and a not in (ax.patch, ax.title, ax._left_title, ax._right_title)
              and not isinstance(a, Text) and a not in ax.spines.values()
              and a not in (ax.xaxis, ax.yaxis)]
    top = max(a.get_zorder() for a in others)
    box = ax.get_window_extent(r)
    for s in stars:
        assert s.get_zorder() > top, f"{name}: star at zorder {s.get_zorder()} under {top}"
        rad = s.get_markersize() / 2 * ax.figure.dpi / 72
        for x, y in ax.transData.transform(np.column_stack([s.get_xdata(), s.get_ydata()])):
            assert (box.x0 <= x - rad and x + rad <= box.x1 and box.y0 <= y - rad
                    and y + rad <= box.y1), f"{name}: star at {(x, y)} leaves {box}"


# ---- a small basin with off-section points and a period-2 orbit beside the fixed point --

@pytest.fixture(scope="module")
def basin():
    o = symmetric_orbit(ImpactPair(0.1, 0.1, 0.75), PDGains(10, 20), 5.0)
    b = basin_of_attraction(orbit_mapper(o, n_iter=300), (-3, 5, 7), (-6, 10, 7),
                            grow=Growth(0))
    assert (b.labels == OFF_SECTION_LABEL).any() and (b.labels == 1).any()
    return b


def _orbit(kind):
    if kind == "stable":
        return SimpleNamespace(exists=True, stable=True, spectral_radius=0.5, reason="")
    if kind == "unstable":
        return SimpleNamespace(exists=True, stable=False, spectral_radius=880.8, reason="")
    return SimpleNamespace(exists=False, stable=False, spectral_radius=math.nan,
                           reason="viability violated: extra contact between the impacts "
                                  "(contact on wall -1 at t0 + 0.28)")


def _run(basins, kinds):
    keys = [("collocated", e) for e in PAPER["e"]]
    return SimpleNamespace(m2=1.0, basins=dict(zip(keys, basins)),
                           orbits={k: _orbit(kind) for k, kind in zip(keys, kinds)})


def _title_share(title):
    m = re.search(r"symmetric orbit (\S+%)", title)
    assert m, title
    return m.group(1)


def test_basin_titles_count_every_point_of_the_slice(basin):
    fig = _basin_figure(_run([basin] * 3, ["stable"] * 3), "collocated", "Fig. 6", _PAR, None)
    _plain_figure(fig)
    n = basin.labels.size
    on = int((basin.labels != OFF_SECTION_LABEL).sum())
    want = pct((basin.labels == 0).sum() / n)
    assert basin_share(basin) == (basin.labels == 0).sum() / n
    assert want != pct((basin.labels == 0).sum() / on)      # the denominators differ here
    for ax in fig.axes:
        assert _title_share(ax.get_title()) == want
    assert f"all {n} points" in fig.get_suptitle() and "off-section" in fig.get_suptitle()


def test_fixed_point_star_is_above_the_other_section_points(basin):
    fig = _basin_figure(_run([basin] * 3, ["stable"] * 3), "collocated", "Fig. 6", _PAR, None)
    for ax in fig.axes:
        assert any(ln.get_marker() == "D" for ln in ax.lines)     # the period-2 orbit's
        _assert_star_on_top_and_inside(ax, "fig6 panel")
    _assert_star_on_top_and_inside(plot_basin(basin).axes[0], "basin.png")


def test_a_basin_figure_without_stable_orbits_says_why(basin):
    run = _run([None] * 3, ["unstable", "unstable", "none"])
    grid = np.logspace(-1, 3, 40)
    study = SimpleNamespace(rho_grid=grid, rho={("collocated", e): 1 + 900 / grid
                                                for e in PAPER["e"]})
    for st in (None, study):
        fig = _basin_figure(run, "collocated", "Fig. 7", _PAR, st)
        _plain_figure(fig)
        said = [" ".join(t.get_text().split()) for ax in fig.axes for t in ax.texts]
        assert said[0].startswith("no stable orbit at these gains: spectral radius 880.8")
        assert said[1].startswith("no stable orbit at these gains: spectral radius 880.8")
        assert said[2].startswith("no orbit at these gains: extra contact between the impacts")
        assert "no basins" in fig.get_suptitle()
        for ax in fig.axes:
            assert ax.axison and "no basin" in ax.get_title()
        _assert_no_raw_caret(fig, "fig7 without basins")


# ---- synthetic studies ---------------------------------------------------------------

def _m2_study():
    g = np.logspace(-1, 3, 120)
    rho = {}
    for k, e in enumerate(PAPER["e"]):
        # collocated: apart below m2 = 20, one curve above it
        rho[("collocated", e)] = np.where(g < 20, 0.5 + 0.1 * k * np.exp(-g / 5),
                                          1 - 5 / (g + 5))
        # non-collocated: no orbit below m2 ~ 0.7 (the data's own x range is shorter)
        rho[("noncollocated", e)] = np.where(g < 0.7, np.nan, 1 + (k + 1) / g)
    iv = {c: {e: [] for e in PAPER["e"]} for c in ("collocated", "noncollocated")}
    readings = {"1": [{"verdict": "agrees", "computed": [1.0, 10.0]}],
                "2": [{"verdict": "contradicted", "computed": [100.0]}]}
    return SimpleNamespace(rho_grid=g, rho=rho, intervals=iv), readings


def test_m2_study_shares_its_range_and_tells_coinciding_curves_apart():
    study, readings = _m2_study()
    fig = plot_m2_study(study, readings=readings, m2_range=(0.1, 1000), runs=[1.0, 100.0])
    _plain_figure(fig)
    logx = [ax for ax in fig.axes if ax.get_visible() and ax.axison
            and ax.get_xscale() == "log"]
    assert len(logx) == 3
    lims = {tuple(np.round(ax.get_xlim(), 9)) for ax in logx}
    assert len(lims) == 1, lims
    col = next(ax for ax in logx if ax.get_title().startswith("collocated"))
    assert "coincide" in col.get_title() and "20" in col.get_title()
    lines = [ln for ln in col.lines if ln.get_gid() and ln.get_gid().startswith("e = ")]
    assert len(lines) == 3
    styles = {(tuple(ln._unscaled_dash_pattern[1] or ()), ln.get_marker(),
               ln.get_linewidth()) for ln in lines}
    assert len(styles) == 3
    starts = {ln.get_markevery()[0] for ln in lines}
    assert len(starts) == 3, "markers of coinciding curves sit on one another"
    # the widest is drawn first (under the others)
    widths = [ln.get_linewidth() for ln in lines]
    assert widths == sorted(widths, reverse=True)
    assert "coinciding" in fig.get_suptitle()
    _assert_no_raw_caret(fig, "m2_study")


def _param_study(name="mu", n_cells=None):
    vals = np.logspace(-2, 1, 6)
    es = np.array(PAPER["e"], float)
    kv = np.linspace(0.1, 50, 8)
    rng = np.random.default_rng(1)
    fr = {c: {"exists": rng.uniform(0, 1, (3, vals.size)),
              "both": rng.uniform(0, 0.1, (3, vals.size))}
          for c in ("collocated", "noncollocated")}
    col = np.zeros((3, kv.size, vals.size), bool)
    col[:, :, :3] = True
    non = np.zeros_like(col)
    non[:, 0, 3] = True          # one grid point: a region as small as the maps hold
    fixed = {"gamma": 0.75, "omega": 5.0, "n": 1, "m2": 1.0, "x10": 1.0, "mu": 0.1}
    fixed.pop(name)
    return SimpleNamespace(name=name, values=vals, e=es, fractions=fr,
                           box={"kp": [0.1, 50.0, 21], "kv": [0.1, 50.0, 21]},
                           maps={"collocated": {"stable": col}, "noncollocated": {"stable": non}},
                           map_kv=kv, map_kp=10.0, fixed=fixed)


def _certified():
    iv = [(0.3, 0.4), (0.5, 0.6), (0.7, 0.8)]
    return {"exists": {c: {0.1: iv} for c in ("collocated", "noncollocated")},
            "exists_stable": {c: {0.1: iv, 1e-4: iv} for c in ("collocated", "noncollocated")}}


def _legend_entries(lg):
    """``{text: [artists of its handle]}`` of a legend."""
    out = {}
    for column in lg._legend_handle_box.get_children():
        for item in column.get_children():
            handlebox, textbox = item.get_children()
            out[textbox._text.get_text()] = list(handlebox.get_children())
    return out


def test_mu_study_legend_shows_the_bars_colours_and_no_empty_decades():
    fig = plot_param_study(_param_study("mu"), certified=_certified())
    _plain_figure(fig)
    _draw(fig)
    bars = {to_rgba(ln.get_color()) for ax in fig.axes for ln in ax.lines
            if ln.get_gid() == CERT_LABEL}
    assert len(bars) == 3
    (lg,) = fig.legends
    entry = _legend_entries(lg)[CERT_LABEL]
    shown = {to_rgba(a.get_color()) for a in entry if isinstance(a, Line2D)}
    assert shown == bars
    # the sampled values span 0.01..10: the share axes hold no empty decade; the limit
    # mu -> 0 (1e-4) is drawn on a narrow axis of its own
    share_axes = [ax for ax in fig.axes if ax.get_ylabel().endswith("(%)")
                  or ax.get_gid() is None and ax.get_xscale() == "log"
                  and ax.get_ylim()[0] == 0]
    main = [ax for ax in share_axes if ax.get_xlim()[0] > 1e-3]
    limit = [ax for ax in share_axes if ax.get_xlim()[1] < 1e-3]
    assert len(main) == 4 and len(limit) == 4
    for ax in main:
        lo, hi = ax.get_xlim()
        assert math.log10(hi / lo) < math.log10(10 / 0.01) + 0.6
    for ax in limit:
        lo, hi = ax.get_xlim()
        assert lo < 1e-4 < hi
    _assert_no_raw_caret(fig, "mu_study")


def test_gamma_study_draws_a_one_point_non_collocated_region_visibly():
    fig = plot_param_study(_param_study("gamma"))
    _plain_figure(fig)
    r = _draw(fig)
    maps = [ax for ax in fig.axes if ax.get_title().startswith("e = ")]
    assert len(maps) == 3
    for ax in maps:
        gid = "non-collocated: exists and stable (hatched)"
        fills = [c for c in ax.collections if isinstance(c, PolyCollection)
                 and c.get_gid() == gid]
        assert fills and fills[0].get_hatch()
        # the cell of one grid point, a few percent of the axes at least
        xy = ax.transData.transform(np.concatenate([q.vertices for q in fills[0].get_paths()]))
        box = ax.get_window_extent(r)
        assert np.ptp(xy[:, 0]) > 0.04 * box.width and np.ptp(xy[:, 1]) > 0.04 * box.height
        (outline,) = [c for c in ax.collections if isinstance(c, LineCollection)
                      and c.get_gid() == gid]
        assert len(outline.get_segments()) == 4
        assert np.allclose(outline.get_colors()[0], _VERMILLION)
        assert outline.get_linewidths()[0] >= 1.0
    _assert_no_raw_caret(fig, "gamma_study")


def test_gamma_study_certified_at_every_value_draws_bands_not_bars():
    # 12 values certified (a full run certifies every value): bars that close would hide
    # each other, so each e is a band between the certified ends, hatched per e
    ps = _param_study("gamma")
    ps.values = np.logspace(np.log10(0.05), np.log10(2), 12)
    ps.fractions = {c: {q: np.full((3, 12), 0.02) for q in ("exists", "both")}
                    for c in ("collocated", "noncollocated")}
    ps.maps = {c: {"stable": np.zeros((3, ps.map_kv.size, 12), bool)}
               for c in ("collocated", "noncollocated")}
    iv = [(0.01, 0.05), (0.0, 0.08), (0.02, 0.03)]
    cert = {"exists_stable": {c: {float(g): iv for g in ps.values}
                              for c in ("collocated", "noncollocated")}}
    fig = plot_param_study(ps, certified=cert)
    _plain_figure(fig)
    _draw(fig)
    assert not [ln for ax in fig.axes for ln in ax.lines if ln.get_gid() in
                (CERT_PLAIN, CERT_LABEL)]
    for ax in [a for a in fig.axes if a.get_ylabel() == "exists and stable (%)"]:
        bands = [c for c in ax.collections if c.get_gid() == CERT_PLAIN]
        assert len(bands) == 3
        assert len({c.get_hatch() for c in bands}) == 3
        assert len({tuple(to_rgba(c.get_facecolor()[0])[:3]) for c in bands}) == 3
        assert ax.get_ylim()[1] >= 8.0          # the widest upper end is on the axis
    (lg,) = fig.legends
    entry = _legend_entries(lg)[CERT_PLAIN]
    assert len(entry) == 3


def test_scaled_regions_render_the_unit_power_as_mathematics():
    x, y = np.logspace(-2.5, 2.2, 6), np.logspace(-2, 2.5, 6)
    ex = np.ones((1, 6, 6), bool)
    st = np.zeros_like(ex)
    st[0, :3, :3] = True
    sm = SimpleNamespace(x=x, y=y, e=np.array([0.5]), exists=ex, stable=st, case="collocated")
    fig = plot_scaled_regions(sm, params=_PAR)
    _plain_figure(fig)
    assert "time$^{-2}$" in fig.axes[0].get_xlabel()
    _assert_no_raw_caret(fig, "scaled_regions")


def test_paper_gains_star_on_a_box_corner_is_whole_and_on_top():
    # the paper's gains (10, 20) at the lower corner of the box, as at m2 = 100
    from _regions import pair_region_map

    rm = pair_region_map("noncollocated", x=("kp", 10.0, 5000.0, 5),
                         y=("kv", 10.0, 5000.0, 5), e=[0.5], mu=0.1, omega=5.0, gamma=0.75,
                         m2=100.0)
    fig = plot_region_panels(rm, mark=(10.0, 20.0))
    ax = fig.axes[0]
    _assert_star_on_top_and_inside(ax, "fig5 at m2 = 100")
    assert "lies outside" not in fig.get_suptitle()
    labels = {t.get_text() for lg in fig.legends for t in lg.get_texts()}
    assert "not computed (grey, dotted)" in labels
    # a point outside the box is said to be so
    fig = plot_region_panels(rm, mark=(1.0, 2.0))
    assert not _stars(fig.axes[0]) and "lies outside the box" in fig.get_suptitle()


# ---- one quick reproduction: its figures against its summary.md -----------------------

def _summary_shares(text):
    """``{(m2, case, e): "95.1%"}`` from summary.md's basin table."""
    out = {}
    case = {"collocated": "collocated", "non-collocated": "noncollocated"}
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 6 and cells[1] in case and "(" in cells[3]:
            m = re.match(r"(\S+%)", cells[4])
            if m:
                out[(cells[0], case[cells[1]], cells[2])] = m.group(1)
    return out


@pytest.mark.slow
def test_basin_titles_agree_with_summary_md():
    from _reproduce_run import small_run

    path, figures = small_run()
    shares = _summary_shares(Path(path).read_text())
    assert shares
    seen = 0
    for p, fig in figures.items():
        if not p.name.startswith(("fig6", "fig7")):
            continue
        m2 = p.parent.name.split("=")[1]
        case = "collocated" if p.name.startswith("fig6") else "noncollocated"
        for ax in fig.axes:
            m = re.match(r"e = ([\d.]+): symmetric orbit (\S+%)", ax.get_title())
            if m:
                assert shares[(m2, case, m.group(1))] == m.group(2), (p, ax.get_title())
                seen += 1
    assert seen == sum(1 for k in shares)


@pytest.mark.slow
def test_quick_reproduction_figures_have_no_raw_caret_and_stars_on_top():
    from _reproduce_run import small_run

    _, figures = small_run()
    for p, fig in figures.items():
        name = f"{p.parent.name}/{p.name}"
        _assert_no_raw_caret(fig, name)
        for ax in fig.axes:
            if _stars(ax) and p.name.startswith(("fig4", "fig5", "fig6", "fig7")):
                _assert_star_on_top_and_inside(ax, name)
