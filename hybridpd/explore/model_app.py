"""The explorer's page for a model file: two of its entries mapped, a cell's orbit on click.

``hybridpd explore --model FILE.toml --x KEY MIN MAX NUM --y KEY MIN MAX NUM`` maps where a
periodic orbit exists and is stable over two numeric entries of the file with
:class:`~hybridpd.sweeps.model_regions.ModelSearch` (``hybridpd regions --model``); a click on
a cell finds that cell's orbit on the default (stroboscopic) section with
:func:`~hybridpd.analysis.model_orbits.orbit_from_model` (``hybridpd orbit --model``) and
shows its multipliers, and on demand the basin slice through it in its first two section
coordinates (:func:`~hybridpd.analysis.model_orbits.model_map`,
:func:`~hybridpd.sweeps.basins.basin_of_attraction`). Everything is computed on a worker
thread with a progress indicator; the page stays live.
"""
from __future__ import annotations

import html
import io
import time

import numpy as np
import panel as pn
from bokeh.events import Tap
from bokeh.models import ColumnDataSource, LinearColorMapper
from bokeh.plotting import figure

from hybridpd.explore import figures as F
from hybridpd.explore.app import (
    _BASIN_COLORS,
    _CLASS_COLORS,
    _CLASS_NAMES,
    PairExplorer,
    _num,
    _tid,
    _widget,
)
from hybridpd.model import check_int

__all__ = ["ModelExplorer", "model_app"]

#: Points per axis of a model's basin slice (each point is a run of the section map).
BASIN_NUM = 15


class ModelExplorer:
    """The page of one session for a model file (module docstring).

    Parameters
    ----------
    path : str
        The model file.
    x, y : (str, float, float, int)
        The two entries mapped (dotted paths) and their grids, checked by the caller as
        ``hybridpd regions --model`` checks them.
    section : dict
        ``contact, wall, event, period, periods, mode, phase`` of the section (as the
        command line's options).
    """

    # the worker-thread and document helpers are the impact pair's page's
    _schedule = PairExplorer._schedule
    _off_loop = PairExplorer._off_loop
    _on_doc = PairExplorer._on_doc
    _safely = PairExplorer._safely
    _resend = PairExplorer._resend
    _again = PairExplorer._again
    _say = PairExplorer._say
    _need = staticmethod(PairExplorer._need)
    _guarded = PairExplorer._guarded

    def __init__(self, path: str, x: tuple, y: tuple, section: dict):
        self.path, self.x, self.y, self.section = path, x, y, dict(section)
        self._doc = pn.state.curdoc
        self.rm = self.orb = self.mb = None
        self.record = None
        self.values = None
        self._gen = {"orbit": 0, "basin": 0}
        self._tasks = set()       # the page's pending computations (see _schedule)
        self.status = pn.pane.HTML(_tid("status", "starting"), margin=(2, 10))
        self.map_src = ColumnDataSource(dict(image=[np.zeros((2, 2), np.int8)], x=[0.0],
                                             y=[0.0], dw=[1.0], dh=[1.0]))
        self.sel_src = ColumnDataSource(dict(x=[], y=[]))
        f = figure(title=f"{path}: click a cell", frame_width=420, frame_height=420,
                   min_border_left=70, min_border_bottom=55, min_border_top=40,
                   min_border_right=20, toolbar_location=None, tools="", name="region-map")
        f.xaxis.axis_label, f.yaxis.axis_label = x[0], y[0]
        f.image(image="image", x="x", y="y", dw="dw", dh="dh", source=self.map_src,
                color_mapper=LinearColorMapper(palette=_CLASS_COLORS, low=-0.5, high=2.5))
        f.scatter("x", "y", source=self.sel_src, marker="circle_cross", size=14,
                  fill_alpha=0.0, line_color="black", line_width=2)
        f.on_event(Tap, self._on_tap)
        self.map_fig = f
        self.progress = pn.indicators.Progress(active=True, value=-1, width=200)
        self.map_info = pn.pane.HTML(_tid("map-status", "computing the map"), width=520)
        self.orbit_info = pn.pane.HTML("", width=420)
        self.mult_src = ColumnDataSource(dict(re=[], im=[]))
        m = figure(title="multipliers and the unit circle", width=300, height=300,
                   match_aspect=True)
        th = np.linspace(0, 2 * np.pi, 361)
        m.line(np.cos(th), np.sin(th), color="gray")
        m.scatter("re", "im", source=self.mult_src, size=10, fill_alpha=0.0, line_width=2)
        self.mult_fig = m
        self.basin_button = _widget(pn.widgets.Button, "compute basin slice", primary=True)
        self.basin_button.on_click(lambda _e: self._schedule(self._start_basin))
        self.basin_src = ColumnDataSource(dict(image=[np.full((2, 2), np.nan)], x=[0.0],
                                               y=[0.0], dw=[1.0], dh=[1.0]))
        b = figure(title="basin slice through the orbit", width=420, height=360)
        b.image(image="image", x="x", y="y", dw="dw", dh="dh", source=self.basin_src,
                color_mapper=LinearColorMapper(palette=_BASIN_COLORS, low=-0.5, high=6.5,
                                               nan_color=(0, 0, 0, 0)))
        self.basin_fig = b
        self.basin_info = pn.pane.HTML(_tid("basin-status", "not computed"), width=420)
        self.layout = pn.Column(
            self.status,
            pn.Row(pn.Column(pn.pane.Bokeh(f), self.progress, self.map_info,
                             self._downloads("map", lambda: self.rm)),
                   pn.Column(self.orbit_info, pn.pane.Bokeh(m),
                             self._downloads("orbit", lambda: self.record))),
            pn.Row(pn.Column(self.basin_button, pn.pane.Bokeh(b), self.basin_info,
                             self._downloads("basin", lambda: self.mb))))
        self._schedule(self._start_map)

    # ---- the map ------------------------------------------------------------------------
    def _start_map(self):
        self._say("computing the map")
        return self._run_map(time.perf_counter())

    async def _run_map(self, t0):
        # deferred import: loaded only when a model's page is built
        from hybridpd.sweeps.model_regions import ModelSearch
        from hybridpd.sweeps.regions import region_map

        s = self.section
        options = {k: s[k] for k in ("mode", "phase") if s.get(k) is not None} or None
        try:
            fam = ModelSearch(self.path, contact=s["contact"], wall=s["wall"],
                              event=s["event"], period=s["period"], periods=s["periods"],
                              options=options)
            rm = await self._off_loop(lambda: region_map(fam, self.x, self.y, progress=False))
        except Exception as exc:   # noqa: BLE001 - the panel says why
            self._on_doc(self._failed, self.map_info, "map-status", f"the map failed: {exc}")
            return
        self._on_doc(self._show_map, rm, time.perf_counter() - t0)

    def _failed(self, pane, tid, text):
        self.progress.visible = False
        pane.object = _tid(tid, text)
        self._say(f"error: {text}")

    def _show_map(self, rm, seconds):
        # deferred import: loaded only when a model's page is built
        from hybridpd.explore.state import map_classes

        self.rm = rm
        xs, ys = rm.x, rm.y
        dx, dy = xs[1] - xs[0], ys[1] - ys[0]
        self.map_src.data = dict(image=[map_classes(rm)], x=[xs[0] - dx / 2],
                                 y=[ys[0] - dy / 2], dw=[xs[-1] - xs[0] + dx],
                                 dh=[ys[-1] - ys[0] + dy])
        self.map_fig.x_range.start, self.map_fig.x_range.end = xs[0] - dx / 2, xs[-1] + dx / 2
        self.map_fig.y_range.start, self.map_fig.y_range.end = ys[0] - dy / 2, ys[-1] + dy / 2
        self.progress.visible = False
        legend = " ".join(f'<span style="background:{c};padding:0 6px">&nbsp;</span> {n}'
                          for c, n in zip(_CLASS_COLORS, _CLASS_NAMES))
        self.map_info.object = (
            f"{legend}<br>{_tid('map-status', 'done')} in {seconds:.1f} s: "
            f"{html.escape(rm.summary().splitlines()[0])}<br>orbit exists on "
            f"{_tid('map-exists-share', _num(rm.fraction('exists')[0]))}, stable on "
            f"{_tid('map-stable-share', _num(rm.fraction('stable')[0]))} of the grid")
        self._say("ready")
        self._resend(self.map_info, self.status)

    # ---- a cell's orbit ---------------------------------------------------------------------
    def _on_tap(self, event):
        if self.rm is None:
            self._say("the map is not ready yet")
            return
        ix = int(np.argmin(np.abs(self.rm.x - event.x)))
        iy = int(np.argmin(np.abs(self.rm.y - event.y)))
        self.select(float(self.rm.x[ix]), float(self.rm.y[iy]))

    def select(self, xv: float, yv: float):
        """Find and show the orbit of the cell ``(xv, yv)`` (on a worker thread)."""
        self.values = {self.x[0]: xv, self.y[0]: yv}
        self.sel_src.data = dict(x=[xv], y=[yv])
        self._gen["orbit"] += 1
        self._gen["basin"] += 1
        self.orb = self.record = self.mb = None
        self.orbit_info.object = (self._head() + "<br>" + _tid("orbit-status", "searching"))
        self._schedule(lambda: self._run_orbit(self._gen["orbit"], dict(self.values)))

    def _head(self):
        v = self.values
        return (f"selected {html.escape(self.x[0])} = {_tid('selected-x', _num(v[self.x[0]]))}"
                f", {html.escape(self.y[0])} = {_tid('selected-y', _num(v[self.y[0]]))}")

    def _model(self, values):
        # deferred import: loaded only when a model's page is built
        from hybridpd.sweeps.model_regions import template_of

        return template_of(self.path).model(values)

    async def _run_orbit(self, gen, values):
        # deferred import: loaded only when a model's page is built
        from hybridpd.analysis.model_orbits import orbit_from_model, orbit_record

        s = self.section

        def find():
            model = self._model(values)
            orb, P = orbit_from_model(model, s["contact"], s["wall"], s["period"],
                                      event=s["event"], periods=s["periods"], mode=s["mode"],
                                      phase=s["phase"])
            rec = orbit_record(model, orb, P)
            rec["values"] = dict(values)
            return orb, rec
        try:
            orb, rec = await self._off_loop(find)
        except Exception as exc:   # noqa: BLE001 - the panel says why
            if gen == self._gen["orbit"]:
                self._on_doc(self._failed, self.orbit_info, "orbit-status",
                             f"the orbit search failed: {exc}")
            return
        if gen == self._gen["orbit"]:
            self._on_doc(self._show_orbit, orb, rec)

    def _show_orbit(self, orb, record=None):
        self.orb, self.record = orb, record
        rows = [("exists", _tid("exists", str(bool(orb.converged)).lower())),
                ("reason", _tid("reason", orb.reason))]
        if orb.converged:
            z = np.asarray(orb.multipliers)
            self.mult_src.data = dict(re=z.real, im=z.imag)
            rows += [("spectral radius", _tid("spectral-radius", _num(orb.spectral_radius))),
                     ("stable", _tid("stable", str(bool(orb.stable)).lower())),
                     ("section point", ", ".join(f"{html.escape(n)} = {_num(v)}"
                                                 for n, v in zip(orb.names, orb.s)))]
        else:
            self.mult_src.data = dict(re=[], im=[])
            rows += [("spectral radius", _tid("spectral-radius", "none"))]
        self.orbit_info.object = (self._head() + "<br>" + _tid("orbit-status", "done")
                                  + "<table>" + "".join(f"<tr><td>{k}</td><td>{v}</td></tr>"
                                                        for k, v in rows) + "</table>")
        self._say("ready")
        self._resend(self.orbit_info, self.status)

    # ---- the basin ----------------------------------------------------------------------
    def _start_basin(self):
        if self.orb is None or not self.orb.converged:
            self.basin_info.object = _tid("basin-status", "no orbit selected: no basin")
            return None
        self._gen["basin"] += 1
        self.basin_info.object = _tid("basin-status", f"computing {BASIN_NUM} x {BASIN_NUM} "
                                      "points (each a run of the section map)")
        return self._run_basin(self._gen["basin"], self.orb, dict(self.values))

    async def _run_basin(self, gen, orb, values):
        # deferred import: loaded only when a model's page is built
        from hybridpd.analysis.model_orbits import default_axes, model_map
        from hybridpd.sweeps.basins import basin_of_attraction

        s = self.section
        (xn, *x), (yn, *y) = default_axes(orb.s, orb.names,
                                           check_int("basin points", BASIN_NUM, 2))

        def run():
            ms = model_map(self.path, values=values, contact=s["contact"], wall=s["wall"],
                           event=s["event"], period=s["period"], periods=s["periods"],
                           mode=s["mode"], phase=s["phase"])
            return basin_of_attraction(ms.mapper(n_iter=300), x, y, axes=(xn, yn),
                                       max_period=4)
        try:
            mb = await self._off_loop(run)
        except Exception as exc:   # noqa: BLE001 - the panel says why
            if gen == self._gen["basin"]:
                self._on_doc(self._failed, self.basin_info, "basin-status",
                             f"the basin failed: {exc}")
            return
        if gen == self._gen["basin"]:
            self._on_doc(self._show_basin, mb)

    def _show_basin(self, mb):
        self.mb = mb
        codes = sorted({int(a.label) for a in mb.attractors})
        index = {c: i for i, c in enumerate(codes)}
        img = np.vectorize(lambda v: index.get(int(v), np.nan), otypes=[float])(mb.labels)
        dx, dy = mb.x[1] - mb.x[0], mb.y[1] - mb.y[0]
        self.basin_src.data = dict(image=[img], x=[mb.x[0] - dx / 2], y=[mb.y[0] - dy / 2],
                                   dw=[mb.x[-1] - mb.x[0] + dx], dh=[mb.y[-1] - mb.y[0] + dy])
        self.basin_fig.xaxis.axis_label, self.basin_fig.yaxis.axis_label = mb.x_name, mb.y_name
        self.basin_info.object = (_tid("basin-status", "done") + "<br>"
                                  + "<br>".join(html.escape(x) for x in mb.summary()))
        self._resend(self.basin_info)


    # ---- saving -----------------------------------------------------------------------
    def _downloads(self, panel: str, get):
        """Two buttons: the panel's figure (PNG, house style: the region map of ``hybridpd
        regions --plot``, the multipliers on the unit circle, the basin of ``hybridpd basin
        --plot``) and its data as the command line writes it (the map's ``.nc``, ``hybridpd
        orbit --model --json``'s object with the mapped values, the basin's ``.npz``)."""
        def fig():
            def make():
                r = self._need(get)
                if panel == "orbit":
                    if self.orb is None or not self.orb.converged:
                        raise ValueError("no orbit at the selected cell: no multipliers")
                    return F.figure_bytes("multipliers", self.orb)
                return F.figure_bytes(panel, r)
            return io.BytesIO(self._guarded(make))

        def data():
            def make():
                r = self._need(get)
                if panel == "orbit":
                    # deferred import: loaded only when a file is saved
                    from hybridpd.cli._common import dumps_json

                    return (dumps_json(r) + "\n").encode()
                return F.data_bytes(panel, r)
            return io.BytesIO(self._guarded(make))

        suffix = {"map": ".nc", "orbit": ".json", "basin": ".npz"}[panel]
        return pn.Row(
            pn.widgets.FileDownload(callback=fig, filename=f"{panel}.png",
                                    label=f"save {panel} figure"),
            pn.widgets.FileDownload(callback=data, filename=f"{panel}{suffix}",
                                    label=f"save {panel} data"))


def model_app(path: str, x: tuple, y: tuple, section: dict):
    """A new model page for the session that asks."""
    return ModelExplorer(path, x, y, section).layout
