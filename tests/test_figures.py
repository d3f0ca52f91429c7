"""Every figure of the reproduction and of the CLI, rendered at its saved size: print width,
smallest font, legends that never tell entries apart by colour alone, nothing cut off."""
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from _regions import pair_region_map
from _reproduce_run import small_run
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from hybridpd.plotting.regions import plot_region_panels, plot_regions
from hybridpd.plotting.style import DOUBLE, MAX_HEIGHT, MIN_FONT, SINGLE

#: Figures whose legends are built by this package from the drawn artists.
OWN = ("fig3_orbit", "fig4_regions", "fig5_regions", "m2_study", "mu_study", "gamma_study",
       "scaled_regions")


def _draw(fig):
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    return canvas.get_renderer()


def _texts(fig):
    """Every drawn, non-empty text of the figure (tick labels, legends, titles included)."""
    out = list(fig.texts)
    if fig._suptitle is not None:
        out.append(fig._suptitle)
    for lg in fig.legends:
        out += [*lg.get_texts(), lg.get_title()]
    for ax in fig.axes:
        if not ax.get_visible():
            continue
        out += [ax.title, ax._left_title, ax._right_title, *ax.texts]
        if ax.axison:
            for axis in (ax.xaxis, ax.yaxis):
                out.append(axis.label)
                for tick in axis._update_ticks():     # the ticks that are drawn
                    out += [tick.label1, tick.label2]
        lg = ax.get_legend()
        if lg is not None:
            out += [*lg.get_texts(), lg.get_title()]
    return [t for t in out if t.get_visible() and t.get_text().strip()]


def _assert_print_ready(fig, name):
    w, h = fig.get_size_inches()
    assert min(abs(w - SINGLE), abs(w - DOUBLE)) < 0.01, f"{name}: width {w} in"
    assert h <= MAX_HEIGHT + 1e-9, f"{name}: height {h} in"
    r = _draw(fig)
    W, H = fig.bbox.width, fig.bbox.height
    inside = lambda b: b.x0 >= -1 and b.y0 >= -1 and b.x1 <= W + 1 and b.y1 <= H + 1
    for t in _texts(fig):
        assert t.get_fontsize() >= MIN_FONT - 1e-9, \
            f"{name}: {t.get_text()!r} at {t.get_fontsize()} pt"
        if t.get_clip_on() and t.axes is not None and t in t.axes.texts:
            continue      # annotations clipped to their axes
        assert inside(t.get_window_extent(r)), f"{name}: text {t.get_text()!r} is cut off"
    for ax in fig.axes:
        if ax.get_visible() and ax.axison:
            assert inside(ax.get_tightbbox(r)), f"{name}: axes labels are cut off"


def _is_hollow(c):
    from matplotlib.colors import to_rgba

    if isinstance(c, str) and c.lower() == "none":
        return True
    rgba = to_rgba(c)
    return rgba[3] == 0 or rgba[:3] == (1.0, 1.0, 1.0)


def _signature(h):
    """What tells a legend entry apart besides its colour."""
    if isinstance(h, Line2D):
        ls = h.get_linestyle() if h.get_linestyle() in ("None", "none", "") else \
            tuple(h._unscaled_dash_pattern[1] or ())
        marker = h.get_marker() if h.get_marker() not in (None, "None", "none", "") else None
        return ("line", ls, marker, marker is not None and _is_hollow(h.get_markerfacecolor()))
    if isinstance(h, Patch):
        return ("patch", h.get_hatch() or "", _is_hollow(h.get_facecolor()),
                tuple(h._unscaled_dash_pattern[1] or ()))
    return (type(h).__name__,)


def _legends(fig):
    return [lg for lg in [*fig.legends, *(ax.get_legend() for ax in fig.axes)]
            if lg is not None]


def _assert_legends_differ_by_more_than_colour(fig, name):
    for lg in _legends(fig):
        seen = {}
        for h, t in zip(lg.legend_handles, lg.get_texts()):
            sig = _signature(h)
            assert sig not in seen, (f"{name}: legend entries {seen[sig]!r} and "
                                     f"{t.get_text()!r} differ by colour alone")
            seen[sig] = t.get_text()


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
    for lg in _legends(fig):
        labels |= {t.get_text() for t in lg.get_texts()}
    return labels


@pytest.fixture(scope="module")
def figures():
    return small_run()[1]


def test_every_figure_of_the_reproduction_is_checked(figures):
    names = {p.name for p in figures}
    assert {"fig3_orbit.png", "fig4_regions_collocated.png", "fig5_regions_noncollocated.png",
            "fig6_basins_collocated.png", "fig7_basins_noncollocated.png", "m2_study.png",
            "mu_study.png", "gamma_study.png", "scaled_regions_collocated.png",
            "scaled_regions_noncollocated.png"} <= names
    assert len(figures) == 5 * 2 + 5
    for p in figures:       # PNG and PDF of each
        assert p.exists() and p.with_suffix(".pdf").exists(), p


def test_reproduction_figures_are_print_ready(figures):
    for path, fig in figures.items():
        name = f"{path.parent.name}/{path.name}"
        _assert_print_ready(fig, name)
        _assert_legends_differ_by_more_than_colour(fig, name)
        if path.name.startswith(OWN):
            assert _legend_labels(fig) == _gids(fig), path


def test_a_basin_panel_without_a_stable_orbit_shows_why(figures):
    fig = next(f for p, f in figures.items() if p.parent.name == "m2=1"
               and p.name.startswith("fig7"))
    # no stable non-collocated orbit at m2 = 1: every panel is the spectral radius along m2
    for ax in fig.axes:
        assert ax.axison and ax.get_yscale() == "log" and ax.lines
        assert "spectral radius" in ax.get_ylabel()


def test_every_axis_has_units(figures):
    for path, fig in figures.items():
        for ax in fig.axes:
            for lab in (ax.get_xlabel(), ax.get_ylabel()):
                if lab:
                    assert "(" in lab and ")" in lab, (path.name, lab)


def test_figures_state_the_parameters(figures):
    # the reproduction's figures are plain text (no sub- or superscripts under 7 pt): each
    # symbol as mathtext or as its plain spelling
    plain = {r"$\mu$": "μ", r"$\gamma$": "γ", r"$\omega$": "ω", "$n$": "n = ",
             "$m_2$": "m2"}
    for path, fig in figures.items():
        head = fig.get_suptitle()
        for sym in (r"$\mu$", r"$\gamma$", r"$\omega$", "$n$"):
            if path.name.startswith(("mu_study", "gamma_study")) and sym.strip("$\\") in \
                    path.name.split("_")[0]:
                continue      # the swept parameter is an axis there
            assert sym in head or plain[sym] in head, (path.name, sym, head)
        if path.name.startswith("fig"):
            assert "$m_2$" in head or "m2 = " in head, (path.name, head)


def _cli_figures(tmp_path, monkeypatch):
    """Run every command that draws, capturing each figure as it is saved."""
    from hybridpd.cli import main

    seen = {}
    orig = Figure.savefig

    def spy(self, fname, *a, **kw):
        seen[Path(fname)] = self
        return orig(self, fname, *a, **kw)

    monkeypatch.setattr(Figure, "savefig", spy)
    plant = ["--mu", "0.1", "--gamma", "0.75", "--omega", "5"]
    t = tmp_path
    cmds = [
        ["regions", "--case", "noncollocated", *plant, "--e", "0.1", "0.5", "0.9",
         "--kp", "0.1", "20", "15", "--kv", "0.1", "6", "15", "--out", str(t / "r.nc"),
         "--plot", str(t / "regions.png")],
        ["basin", "--case", "collocated", *plant, "--e", "0.1", "--kp", "10", "--kv", "20",
         "--x", "x1", "-3", "5", "8", "--y", "y1", "-2", "10", "8", "--iterations", "200",
         "--max-extensions", "0", "--executor", "serial", "--out", str(t / "b.nc"),
         "--plot", str(t / "basin.png")],
        ["bifurcation", "--case", "collocated", *plant, "--e", "0.5", "--kp", "10",
         "--param", "kv", "15", "25", "6", "--iterations", "60", "--keep", "8",
         "--follow", "--out", str(t / "d.nc"), "--plot", str(t / "diagram.png")],
        ["simulate", "--case", "collocated", *plant[:2], "--e", "0.5", "--L", "0.75",
         "--omega", "5", "--kp", "10", "--kv", "20", "--xm", "1", "--x0", "0.3", "0.5", "0",
         "0", "--t-end", "3", "--out", str(t / "run.json"), "--plot", str(t / "run.png")],
    ]
    for argv in cmds:
        assert main(argv) == 0, argv
    for f in ("r.nc", "b.nc", "d.nc", "run.json"):
        assert main(["plot", str(t / f), "--out", str(t / f"plot_{f}.png")]) == 0, f
    return seen


def test_cli_figures_are_print_ready(tmp_path, monkeypatch, capsys):
    seen = _cli_figures(tmp_path, monkeypatch)
    capsys.readouterr()
    assert len({id(f) for f in seen.values()}) >= 8
    for path, fig in seen.items():
        _assert_print_ready(fig, path.name)
        _assert_legends_differ_by_more_than_colour(fig, path.name)


def test_region_plots_accept_traced_curves(tmp_path):
    rm = pair_region_map("noncollocated", x=("kp", 0.1, 20, 9), y=("kv", 0.1, 6, 9), e=[0.1, 0.5],
                    mu=0.1, omega=5.0, gamma=0.75)
    t = np.linspace(0, 1, 20)
    curves = [SimpleNamespace(kind="stability", x=2 + 10 * t, y=1 + 4 * t),
              SimpleNamespace(kind="existence", x=1 + 15 * t, y=5 - t)]
    fig = plot_region_panels(rm, curves=curves, mark=(10, 2))
    _assert_print_ready(fig, "panels with curves")
    _assert_legends_differ_by_more_than_colour(fig, "panels with curves")
    assert _legend_labels(fig) == _gids(fig)
    drawn = [ln for ax in fig.axes for ln in ax.lines if ln.get_gid() and "boundary" in
             ln.get_gid()]
    assert len(drawn) == 2 * len(curves)
    assert any(np.allclose(ln.get_xdata(), curves[0].x) for ln in drawn)
    # other kinds of traced boundaries get their own legend entries and dash patterns
    more = [SimpleNamespace(kind="grazing", x=t, y=t), SimpleNamespace(kind="neimark_sacker",
                                                                       x=t, y=2 * t),
            SimpleNamespace(kind="fold", x=t, y=3 * t)]
    fig = plot_region_panels(rm, curves={0.1: more, 0.5: []})
    labels = _legend_labels(fig)
    assert {"existence boundary (ticks on the existing side)",
            "Neimark-Sacker: a complex pair crosses the unit circle (traced)",
            "a multiplier crosses +1 (traced)"} <= labels
    assert labels == _gids(fig)
    _assert_legends_differ_by_more_than_colour(fig, "traced kinds")
    # the compact variant: all e on one axes, hatched, legend beside the axes
    fig = Figure(figsize=(DOUBLE, 3), layout="constrained")
    plot_regions(rm, ax=fig.add_subplot(1, 1, 1), curves=curves)
    _assert_print_ready(fig, "compact")
    _assert_legends_differ_by_more_than_colour(fig, "compact")
    assert _legend_labels(fig) == _gids(fig)


def test_exists_but_unstable_is_not_white():
    rm = pair_region_map("noncollocated", x=("kp", 0.1, 50, 21), y=("kv", 0.1, 50, 21), e=[0.5],
                    mu=0.1, omega=5.0, gamma=0.75)
    assert (rm.exists & ~rm.stable).any() and (~rm.exists).any()
    fig = plot_region_panels(rm)
    labels = _legend_labels(fig)
    assert {"exists and stable", "exists, unstable (hatched)", "no orbit (white)"} <= labels


def test_the_house_style_is_never_global():
    import matplotlib

    before = dict(matplotlib.rcParams)
    rm = pair_region_map("collocated", x=("kp", 0.1, 20, 5), y=("kv", 0.1, 6, 5), e=[0.5],
                    mu=0.1, omega=5.0, gamma=0.75)
    plot_region_panels(rm)
    after = dict(matplotlib.rcParams)
    assert {k for k in before if before[k] != after[k]} == set()
