"""The reproduction's figures, in the house style (:mod:`hybridpd.plotting.style`).

Each figure is saved at its print size as PNG (300 dpi) and PDF. Per convention: Fig. 3 (the
orbit's phase plane), Figs 4-5 (regions over the gain box scaled by ``m2``, the zoom window
outlined), Figs 6-7 (basins on the window shared by every panel and both cases; a panel
with no stable orbit shows the orbit's spectral radius along ``m2`` instead). Once: Figs 4-5
in the scaled gains ``(kp/m2, kv/m2)`` with the paper's gains as the ray ``(10/m2, 20/m2)``,
and the figures of the ``m2``, ``mu`` and ``gamma`` studies.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from hybridpd.reproduce.settings import PAPER

__all__ = ["ScaledMap", "basin_share", "convention_figures", "save", "scaled_map",
           "study_figures"]

CASES = ("collocated", "noncollocated")
#: Scaled-gain window of the m2-free figure (log10 of kp/m2 and kv/m2): the paper's gains
#: for every m2 in [0.1, 1000] lie inside it.
SCALED_WINDOW = ((-2.5, 2.2), (-2.0, 2.5))


@dataclass
class ScaledMap:
    """Existence and stability over log-spaced scaled gains (valid for every ``m2``).

    Attributes
    ----------
    x, y : ndarray
        ``kp/m2`` and ``kv/m2`` (per time squared and per time).
    e : ndarray
    exists, stable : ndarray of bool, shape (len(e), len(y), len(x))
    case : str
    """

    x: np.ndarray
    y: np.ndarray
    e: np.ndarray
    exists: np.ndarray
    stable: np.ndarray
    case: str


def scaled_map(case, settings, num) -> ScaledMap:
    """The regions in ``(kp/m2, kv/m2)``: computed at ``m2 = 1`` (only the ratios matter)."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.orbits import symmetric_orbits

    (xa, xb), (ya, yb) = SCALED_WINDOW
    x, y = np.logspace(xa, xb, num), np.logspace(ya, yb, num)
    es = np.asarray(PAPER["e"], float)
    E, Y, X = np.meshgrid(es, y, x, indexing="ij")
    r = symmetric_orbits(X, Y, mu=PAPER["mu"], e=E, L=settings.L, omega=PAPER["omega"],
                         m2=1.0, x10=settings.x10, n=PAPER["n"], case=case)
    return ScaledMap(x, y, es, np.asarray(r.exists, bool), np.asarray(r.stable, bool), case)


_MATH = re.compile(r"\$([^$]*)\$")
_GREEK = {r"\mu": "μ", r"\gamma": "γ", r"\omega": "ω", r"\phi": "φ", r"\cdot": "·",
          r"\lambda": "λ", r"\rho": "ρ", r"\tau": "τ", r"\infty": "∞", r"\to": "→",
          r"\times": "×", r"\leq": "≤", r"\geq": "≥", r"\pm": "±"}


def plain_text(text: str) -> str:
    """``text`` with its subscripted formulas spelled out: ``"$k_p/m_2$"`` becomes ``"kp/m2"``
    (the reproduction names its symbols plainly); a formula without scripts (a Greek letter)
    stays, and so does one with a superscript (``"$y_2^*$"``, ``"time$^{-2}$"``): it is drawn
    as mathematics, never as a raw caret.

    Examples
    --------
    >>> from hybridpd.reproduce.figures import plain_text
    >>> plain_text("$k_p$ (force/length), $x_{10}$ = 1, $m_1/m_2$ = 0.1, e = 0.5")
    'kp (force/length), x10 = 1, m1/m2 = 0.1, e = 0.5'
    >>> plain_text("$k_p/m_2$ (time$^{-2}$), $y_2 = y_2^*$")
    'kp/m2 (time$^{-2}$), $y_2 = y_2^*$'
    """
    def sub(m):
        body = m.group(1)
        if "_" not in body or "^" in body:
            return m.group(0)
        body = re.sub(r"\\mathdefault\{([^}]*)\}", r"\1", body)
        for cmd, ch in _GREEK.items():
            body = re.sub(re.escape(cmd) + r"(?![A-Za-z])", ch, body)
        body = re.sub(r"_\{([^}]*)\}|_(.)", lambda k: k.group(1) or k.group(2), body)
        body = body.replace("\\", "").replace("{", "").replace("}", "")
        return body
    return _MATH.sub(sub, text)


def _plain_figure(fig) -> None:
    """Every text of ``fig`` through :func:`plain_text` (the legend's gids too, so that a
    legend entry still names its artists), and plain numbers on log axes (no ``10^k``)."""
    from matplotlib.ticker import FuncFormatter, NullFormatter

    texts = list(fig.texts) + ([fig._suptitle] if fig._suptitle is not None else [])
    for lg in fig.legends:
        texts += list(lg.get_texts())
    for ax in fig.axes:
        texts += [ax.title, ax._left_title, ax._right_title, ax.xaxis.label, ax.yaxis.label,
                  *ax.texts]
        if ax.get_legend() is not None:
            texts += list(ax.get_legend().get_texts())
        for a in ax.get_children():
            g = a.get_gid() if hasattr(a, "get_gid") else None
            if g:
                a.set_gid(plain_text(g))
        for axis, scale in ((ax.xaxis, ax.get_xscale()), (ax.yaxis, ax.get_yscale())):
            if scale == "log":
                axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
                axis.set_minor_formatter(NullFormatter())
    for t in texts:
        t.set_text(plain_text(t.get_text()))


def save(fig, path, hook=None) -> None:
    """Make ``fig``'s text plain (:func:`_plain_figure`), show it to ``hook`` and write it as
    PNG (300 dpi) and PDF (the layout computed for the PNG is kept for the PDF)."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.plotting.style import house_style

    _plain_figure(fig)
    if hook is not None:
        hook(path, fig)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with house_style():
        fig.savefig(path.with_suffix(".png"), dpi=300)
        # the constrained layout is settled by the first draw: the PDF reuses it
        fig.set_layout_engine("none")
        fig.savefig(path.with_suffix(".pdf"))


def _params(run) -> dict:
    return dict(mu=PAPER["mu"], gamma=run.gamma, omega=PAPER["omega"], n=PAPER["n"], m2=run.m2,
                x10=run.x10)


def _ray_events(study) -> dict:
    """``{case: {e: [(m2, "exists" | "stable")]}}`` along the paper's gains: where each orbit
    starts to exist (first point of the study's m2 grid with an orbit) and to be stable
    (located interval ends)."""
    out = {}
    for case in CASES:
        for e in PAPER["e"]:
            ev = []
            for iv in study.intervals[case][e]:
                if iv.lo.kind != "window":
                    # a located stability end, or an existence end (grazing) where the orbit
                    # starts to exist already stable
                    ev.append((iv.lo.m2, "stable" if iv.lo.kind == "stability" else "exists"))
            rho = study.rho[(case, e)]
            ok = np.isfinite(rho)
            if ok.any() and not ok[0]:
                m = float(study.rho_grid[int(np.argmax(ok))])
                if not any(abs(np.log(m / m2)) < 0.1 for m2, _ in ev):
                    ev.append((m, "exists"))
            out.setdefault(case, {})[float(e)] = ev
    return out


def certified_points(shares) -> dict:
    """The certified intervals the remarks on ``mu`` rest on, for the ``mu`` study's figure:
    ``{"exists" | "exists_stable": {case: {mu: [(lo, hi) per e]}}}``."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.reproduce.certified import MU_LIMIT

    es = [float(e) for e in PAPER["e"]]
    out = {"exists": {}, "exists_stable": {}}
    for case in CASES:
        ex = out["exists"].setdefault(case, {})
        st = out["exists_stable"].setdefault(case, {})
        ex[PAPER["mu"]] = [shares["main"][(case, e)].interval("exists") for e in es]
        st[PAPER["mu"]] = [shares["main"][(case, e)].interval("exists_stable") for e in es]
        st[MU_LIMIT] = [shares["limit"][(case, e)].interval("exists_stable") for e in es]
        for g in ("mu_ends", "mu_moves", "mu_values"):
            for (c, e, mu), r in shares.get(g, {}).items():
                if c == case:
                    ex.setdefault(mu, [None] * len(es))[es.index(e)] = r.interval("exists")
    return out


def certified_gamma_points(shares) -> dict | None:
    """The ``gamma`` study's certified intervals for its figure, as :func:`certified_points`
    (``{"exists_stable": {case: {gamma: [(lo, hi) per e]}}}``), or None when the study is
    sampled only."""
    group = shares.get("gamma_values") or {}
    if not group:
        return None
    es = [float(e) for e in PAPER["e"]]
    out = {"exists_stable": {}}
    for (c, e, g), r in group.items():
        per = out["exists_stable"].setdefault(c, {})
        per.setdefault(g, [None] * len(es))[es.index(e)] = r.interval("exists_stable")
    return out


def study_figures(out, *, study, studies, settings, runs, table, shares, hook=None) -> None:
    """The m2-free scaled figures and the three study figures, into ``out``.

    ``table`` is the summary's lead table (its ``m2_readings`` are drawn in the ``m2``
    study), ``shares`` the certified shares (:func:`certified_points` in the ``mu`` study).
    """
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.plotting.studies import plot_m2_study, plot_param_study, plot_scaled_regions

    num = 241 if settings.gains[2] > 100 else 121
    events = _ray_events(study)
    lo, hi = settings.m2_range
    par = dict(mu=PAPER["mu"], gamma=PAPER["gamma"], omega=PAPER["omega"], n=PAPER["n"])
    zk, zv, _ = settings.zoom
    box = (0.1, settings.gains[0], 0.1, settings.gains[1])
    for case, label in (("collocated", "Fig. 4"), ("noncollocated", "Fig. 5")):
        sm = scaled_map(case, settings, num)
        ray = {"kp": PAPER["kp"], "kv": PAPER["kv"],
               "m2": np.logspace(np.log10(lo), np.log10(hi), 200), "events": events[case]}
        fig = plot_scaled_regions(sm, ray=ray, zoom=(zk, zv) if case == "noncollocated" else None,
                                  params=par, box=box,
                                  title=f"{label}, {case.replace('non', 'non-')} PD in scaled "
                                        "gains, every m2")
        save(fig, out / f"scaled_regions_{case}.png", hook)
    readings = {f"{row['id']}": row["m2_readings"] for row in table
                if isinstance(row["id"], int)}
    save(plot_m2_study(study, readings=readings, m2_range=settings.m2_range,
                       runs=[r.m2 for r in runs]), out / "m2_study.png", hook)
    cert = {"mu": certified_points(shares), "gamma": certified_gamma_points(shares)}
    for name, ps in studies.items():
        save(plot_param_study(ps, certified=cert.get(name)), out / f"{name}_study.png", hook)


def convention_figures(run, settings, *, study=None, hook=None, cache=None) -> None:
    """Figs 3-7 of one convention, into its directory.

    ``cache`` (a dict shared by the conventions of a run) keeps the traced boundaries in
    scaled gains: the gain boxes are scaled by ``m2``, so one tracing serves every ``m2``.
    """
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.plotting.orbit import plot_orbit_phase
    from hybridpd.plotting.regions import plot_region_panels

    d = run.directory
    par = _params(run)
    mark = (PAPER["kp"], PAPER["kv"])
    fig = plot_region_panels(run.maps["collocated"], mark=mark, params=par,
                             curves=_traced(run, "collocated", settings, cache),
                             title="Fig. 4, collocated PD")
    save(fig, d / "fig4_regions_collocated.png", hook)
    fig = plot_region_panels(run.maps["noncollocated"], zoom=run.maps["zoom"], mark=mark,
                             params=par, curves=_traced(run, "noncollocated", settings, cache),
                             title="Fig. 5, non-collocated PD")
    save(fig, d / "fig5_regions_noncollocated.png", hook)
    fig = plot_orbit_phase([run.orbits[(c, e)] for c in CASES for e in PAPER["e"]], params=par)
    save(fig, d / "fig3_orbit.png", hook)
    for case, name, label in (("collocated", "fig6_basins_collocated.png", "Fig. 6"),
                              ("noncollocated", "fig7_basins_noncollocated.png", "Fig. 7")):
        save(_basin_figure(run, case, label, par, study), d / name, hook)


def basin_share(b, label=0) -> float:
    """Share of ``b``'s slice with ``label``: over *all* its points, the off-section ones
    included (their own class), the one denominator of summary.md's basin table."""
    labels = np.asarray(b.labels)
    return float((labels == label).sum()) / int(labels.size)


def _no_basin_words(o) -> tuple:
    """``(title line, panel text)`` of a basin panel with no stable orbit to label from."""
    import textwrap

    if not o.exists:
        why = o.reason.split("(")[0].split(":")[-1].strip()
        return ("(no orbit)", "no orbit at these gains:\n" + "\n".join(textwrap.wrap(why, 24))
                + ";\nno basin to draw")
    rho = o.spectral_radius
    return ("(unstable orbit)",
            f"no stable orbit at these gains:\nspectral radius {rho:.4g} > 1;\nno basin to draw")


def _basin_figure(run, case, label, par, study):
    """Figs 6-7 of one convention: one panel per ``e``; the title's share of the symmetric
    orbit is over all the slice's points (:func:`basin_share`, as in summary.md). A panel
    with no stable orbit says so on its face (the orbit's spectral radius along ``m2`` drawn
    when the study is given, an empty frame otherwise)."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd._format import pct
    from hybridpd.plotting._common import legend_from_gids, param_line
    from hybridpd.plotting.basins import plot_basin
    from hybridpd.plotting.studies import plot_rho_along_m2
    from hybridpd.plotting.style import DOUBLE, house_figure, house_style

    es = PAPER["e"]
    points = set()
    with house_style():
        fig = house_figure(DOUBLE, 4.4)
        axes = []
        for k, e in enumerate(es):
            ax = fig.add_subplot(1, len(es), k + 1)
            b, o = run.basins[(case, e)], run.orbits[(case, e)]
            if b is None:
                head, text = _no_basin_words(o)
                if study is not None:
                    plot_rho_along_m2(ax, study.rho_grid, study.rho[(case, e)], m2=run.m2, k=k,
                                      label=f"e = {e:g}: spectral radius along $m_2$")
                    where = dict(x=0.97, y=0.97, ha="right", va="top")
                else:
                    ax.set_xticks([])
                    ax.set_yticks([])
                    where = dict(x=0.5, y=0.5, ha="center", va="center")
                ax.text(s=text, transform=ax.transAxes, fontsize=7, zorder=10,
                        multialignment="left",
                        bbox=dict(boxstyle="round,pad=0.3", fc="white", ec="0.3", lw=0.6),
                        **where)
                ax.set_title(f"e = {e:g} at $m_2$ = {run.m2:g}: no basin\n{head}")
            else:
                labels = np.asarray(b.labels)
                points.add((int(labels.size), len(b.x1), len(b.y1)))
                plot_basin(b, ax=ax, legend=False,
                           title=f"e = {e:g}: symmetric orbit {pct(basin_share(b))}"
                                 + ("\n(touches the window's edge)" if b.reaches_edge else ""))
                if k:
                    ax.set_ylabel("")
            axes.append(ax)
        legend_from_gids(fig, axes, ncol=3)
        head = (f"{label}, {case.replace('non', 'non-')} PD at $k_p$ = {PAPER['kp']:g}, "
                f"$k_v$ = {PAPER['kv']:g}; {param_line(par)}")
        if len(points) == 1:
            n, nx, ny = points.pop()
            head += (f"\nshares of all {n} points of each slice ({nx} x {ny}), the off-section "
                     "ones included")
        elif points:
            head += "\nshares of all the points of each slice, the off-section ones included"
        else:
            head += "\nno basins: no stable orbit at these gains for any e"
        fig.suptitle(head)
    return fig


def _scaled_boxes(settings, case) -> list:
    """``(row, box)`` of the panels of Figs 4-5 in scaled gains (row 1: the zoom)."""
    kpm, kvm, _ = settings.gains
    out = [(0, (0.1, kpm, 0.1, kvm))]
    if case == "noncollocated":
        zk, zv, _ = settings.zoom
        out.append((1, (0.1, zk, 0.1, zv)))
    return out


def _trace_key(case, row, e, box):
    return (case, row, float(e), tuple(round(float(v), 12) for v in box))


def _trace(case, e, box, settings):
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.boundaries import boundary_curves
    from hybridpd.pair.boundarymask import stable_region_edges

    res = boundary_curves(case, e=float(e), mu=PAPER["mu"], gamma=settings.gamma,
                          omega=PAPER["omega"], m2=1.0, x10=settings.x10, n=PAPER["n"],
                          x=("kp", box[0], box[1]), y=("kv", box[2], box[3]))
    return [SimpleNamespace(kind=c.kind, x=np.asarray(c.x, float), y=np.asarray(c.y, float))
            for c in stable_region_edges(res)]


def trace_scaled(settings) -> dict:
    """The traced boundaries of every panel of Figs 4-5 in scaled gains (``m2 = 1``), as the
    ``cache`` of :func:`convention_figures`: one tracing serves every convention, the gain
    boxes being scaled by ``m2``. Nothing when :attr:`Settings.traced_boundaries` is off."""
    cache = {}
    if not settings.traced_boundaries:
        return cache
    for case in CASES:
        for row, box in _scaled_boxes(settings, case):
            for e in PAPER["e"]:
                cache[_trace_key(case, row, e, box)] = _trace(case, e, box, settings)
    return cache


def _traced(run, case: str, settings, cache=None):
    """``{(row, e): curves}`` bounding the exists-and-stable region in each panel's box
    (row 1: the zoom), or None (grid contours) if not wanted.

    Traced once in scaled gains (at ``m2 = 1``, on the box divided by ``m2``; see
    :func:`trace_scaled`) and scaled back: at fixed ``mu`` only ``kp/m2`` and ``kv/m2``
    matter.
    """
    if not settings.traced_boundaries:
        return None
    cache = {} if cache is None else cache
    s = run.m2
    out = {}
    for row, rm in enumerate((run.maps[case], run.maps["zoom"] if case == "noncollocated"
                              else None)):
        if rm is None:
            continue
        box = (float(rm.x[0]) / s, float(rm.x[-1]) / s, float(rm.y[0]) / s,
               float(rm.y[-1]) / s)
        for e in rm.e:
            key = _trace_key(case, row, e, box)
            if key not in cache:
                cache[key] = _trace(case, e, box, settings)
            out[(row, float(e))] = [SimpleNamespace(kind=c.kind, x=c.x * s, y=c.y * s)
                                    for c in cache[key]]
    return out
