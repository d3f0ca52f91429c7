"""Every figure of the reproduction renders with no text cut off and honest legends."""
from types import SimpleNamespace

import numpy as np
import pytest
from _reproduce_run import small_run
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from hybridpd.plotting.regions import plot_region_panels, plot_regions
from hybridpd.sweeps.regions import region_map

#: Figures whose legends are built by this package (the basin panels' are not).
OWN = ("fig3_orbit", "fig4_regions", "fig5_regions", "m2_study", "mu_study", "gamma_study")


def _texts(fig):
    """Text artists that are drawn, with the axes (tick labels included) as boxes."""
    out = [t for t in fig.texts if t.get_visible() and t.get_text()]
    for lg in fig.legends:
        out += [t for t in lg.get_texts()]
    for ax in fig.axes:
        out += [t for t in (ax.title, ax._left_title, ax._right_title) if t.get_text()]
        out += [t for t in ax.texts if t.get_visible() and t.get_text()]
        lg = ax.get_legend()
        if lg is not None:
            out += list(lg.get_texts())
    return out


def _assert_nothing_clipped(fig, name):
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    r = canvas.get_renderer()
    W, H = fig.bbox.width, fig.bbox.height
    inside = lambda b: b.x0 >= -1 and b.y0 >= -1 and b.x1 <= W + 1 and b.y1 <= H + 1
    for t in _texts(fig):
        assert inside(t.get_window_extent(r)), f"{name}: text {t.get_text()!r} is cut off"
    for ax in fig.axes:
        if ax.get_visible() and ax.axison:
            assert inside(ax.get_tightbbox(r)), f"{name}: axes labels are cut off"


def _gids(fig):
    gids = set()
    for ax in fig.axes:
        for a in ax.get_children():
            g = a.get_gid() if hasattr(a, "get_gid") else None
            if g:
                gids.add(g)
    return gids


def _legend_labels(fig):
    labels = set()
    for lg in [*fig.legends, *(ax.get_legend() for ax in fig.axes)]:
        if lg is not None:
            labels |= {t.get_text() for t in lg.get_texts()}
    return labels


@pytest.fixture(scope="module")
def figures():
    return small_run()[1]


def test_every_figure_is_checked(figures):
    names = {p.name for p in figures}
    assert {"fig3_orbit.png", "fig4_regions_collocated.png", "fig5_regions_noncollocated.png",
            "fig6_basins_collocated.png", "fig7_basins_noncollocated.png", "m2_study.png",
            "mu_study.png", "gamma_study.png"} <= names
    assert len(figures) == 5 * 2 + 3


def test_no_text_is_cut_off_and_legends_equal_the_drawn_artists(figures):
    for path, fig in figures.items():
        _assert_nothing_clipped(fig, f"{path.parent.name}/{path.name}")
        if path.name.startswith(OWN):
            assert _legend_labels(fig) == _gids(fig), path


def test_figures_state_the_parameters(figures):
    for path, fig in figures.items():
        head = fig.get_suptitle()
        for sym in (r"$\mu$", r"$\gamma$", r"$\omega$", "$n$", "$m_2$"):
            if path.name.startswith(("mu_study", "gamma_study")) and sym.strip("$\\") in \
                    path.name.split("_")[0]:
                continue      # the swept parameter is an axis there
            assert sym in head, (path.name, sym, head)


def test_region_figures_use_maths_labels(figures):
    for path, fig in figures.items():
        if path.name.startswith(("fig4", "fig5")):
            assert {ax.get_xlabel() for ax in fig.axes} == {"$k_p$"}
            assert {ax.get_ylabel() for ax in fig.axes} == {"$k_v$"}


def test_region_plots_accept_traced_curves(tmp_path):
    rm = region_map("noncollocated", x=("kp", 0.1, 20, 9), y=("kv", 0.1, 6, 9), e=[0.1, 0.5],
                    mu=0.1, omega=5.0, gamma=0.75)
    t = np.linspace(0, 1, 20)
    curves = [SimpleNamespace(kind="stability", x=2 + 10 * t, y=1 + 4 * t),
              SimpleNamespace(kind="existence", x=1 + 15 * t, y=5 - t)]
    fig = plot_region_panels(rm, curves=curves, mark=(10, 2))
    _assert_nothing_clipped(fig, "panels with curves")
    assert _legend_labels(fig) == _gids(fig)
    drawn = [ln for ax in fig.axes for ln in ax.lines if ln.get_gid() and "boundary" in
             ln.get_gid()]
    assert len(drawn) == 2 * len(curves)
    assert any(np.allclose(ln.get_xdata(), curves[0].x) for ln in drawn)
    # other kinds of traced boundaries get their own legend entries
    more = [SimpleNamespace(kind="grazing", x=t, y=t), SimpleNamespace(kind="neimark_sacker",
                                                                       x=t, y=2 * t)]
    fig = plot_region_panels(rm, curves={0.1: more, 0.5: []})
    labels = _legend_labels(fig)
    assert {"grazing: the orbit stops existing (traced)",
            "Neimark-Sacker: a complex pair crosses the unit circle (traced)"} <= labels
    assert labels == _gids(fig)
    fig.savefig(tmp_path / "curves.png", dpi=80)
    # the compact variant: all e on one axes, hatched, legend beside the axes
    fig = Figure(figsize=(8, 4), layout="constrained")
    plot_regions(rm, ax=fig.add_subplot(1, 1, 1), curves=curves)
    _assert_nothing_clipped(fig, "compact")
    assert _legend_labels(fig) == _gids(fig)
