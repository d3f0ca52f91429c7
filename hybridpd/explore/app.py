"""The explorer's page for the impact pair (HoloViz Panel and Bokeh).

One :class:`PairExplorer` per browser session: the controls (case, ``e``, ``mu``, ``m2``,
``gamma``, ``omega``, ``n``, the box of gains), the region map over ``(kp, kv)``, and for the
gains clicked on the map the orbit's time series and phase portrait over one period, its
multipliers on the unit circle with the spectral radius, the viability margin, the basin slice
(on demand) and a branch followed along ``kp`` or ``kv`` with its events. The state lives in
the page's URL (:mod:`hybridpd.explore.state`), so a view is shared by its address.

Computations longer than a click (the map, the basin, the branch) run on a worker thread and
the page stays live; a newer request supersedes an older one still running. Bad input is
refused beside its control with the package's own message, a computation that fails says why
in its panel, and no request stops the server. Values the tests read carry ``data-testid``
attributes (``spectral-radius``, ``exists``, ``stable``, ``selected-kp``, ``selected-kv``,
``status`` and a few more), numbers with 12 significant digits.
"""
from __future__ import annotations

import asyncio
import html
import io
import time
import traceback
from concurrent.futures import ThreadPoolExecutor
from functools import partial

import numpy as np
import panel as pn
from bokeh.events import Tap
from bokeh.models import ColumnDataSource, HoverTool, LinearColorMapper
from bokeh.plotting import figure

from hybridpd.explore import figures as F
from hybridpd.explore import state as S
from hybridpd.plotting.style import OKABE_ITO

__all__ = ["PairExplorer", "pair_app", "warm_up"]

#: Worker threads of every session together: the computations are NumPy-bound, and the
#: machine's cores are what they share.
_POOL = ThreadPoolExecutor(max_workers=2, thread_name_prefix="hybridpd-explore")

#: Milliseconds after which a computation's final text is sent again (:meth:`_resend`).
_RESEND_MS = 200

#: Map classes 0 no orbit, 1 unstable orbit, 2 stable orbit.
_CLASS_COLORS = ["#f2f2f2", OKABE_ITO["orange"], OKABE_ITO["blue"]]
_CLASS_NAMES = ["no orbit", "orbit, unstable", "orbit, stable"]
_BASIN_COLORS = [OKABE_ITO[k] for k in ("bluish green", "vermillion", "sky blue",
                                        "reddish purple", "yellow", "orange", "blue")]
_TEXT_FIELDS = ("e", "mu", "m2", "gamma", "omega", "n", "kp_min", "kp_max", "kv_min",
                "kv_max", "num")


def _num(x) -> str:
    """A number on the page: 12 significant digits, 'none' where missing or not finite."""
    x = S.finite_or_none(x)
    return "none" if x is None else f"{x:.12g}"


def _widget(cls, label: str, *, primary: bool = False, **kw):
    """A Panel widget labelled ``label`` (``label``/``color`` where this Panel has them,
    else the older ``name``/``button_type``)."""
    kw["label" if "label" in cls.param else "name"] = label
    if primary:
        kw["color" if "color" in cls.param else "button_type"] = "primary"
    return cls(**kw)


def _tid(name: str, text) -> str:
    return f'<span data-testid="{name}">{html.escape(str(text))}</span>'


def _fig(title, x_label, y_label, width=360, height=260, **kw):
    f = figure(title=title, width=width, height=height, toolbar_location="right",
               tools="pan,wheel_zoom,box_zoom,reset,save", **kw)
    f.xaxis.axis_label, f.yaxis.axis_label = x_label, y_label
    return f


class PairExplorer:
    """The page of one session (module docstring).

    Parameters
    ----------
    state : PairState
        Where the page starts.
    errors : dict of str to str, optional
        Messages for fields refused in the URL, shown beside their controls.
    url : bool
        Keep the page's URL in step with the state (on a server; off in a notebook).
    ready : (RegionMap, float), optional
        The state's region map, already computed, and the milliseconds it took: drawn at
        once instead of computed after the page loads.
    """

    def __init__(self, state: S.PairState, errors: dict | None = None, url: bool = True,
                 ready: tuple | None = None):
        self.state = state
        self.url = url
        self._doc = pn.state.curdoc
        self.rm = self.orb = self.basin = self.branch = None
        self._gen = {"map": 0, "basin": 0, "branch": 0}
        self._tasks = set()       # the page's pending computations (see _schedule)
        self._build_controls()
        self._build_map()
        self._build_orbit()
        self._build_basin()
        self._build_branch()
        self.status = pn.pane.HTML(_tid("status", "starting"), margin=(2, 10))
        for name, msg in (errors or {}).items():
            self._error(name, msg)
        self.select(state.kp, state.kv)
        self.layout = self._layout()
        if self.url and self._doc is not None and self._doc.session_context is not None:
            pn.state.onload(self._push_url)   # the URL states every field from the start
        if ready is None:
            self._schedule(self._refresh_map)
        else:   # drawn in the page's first document: no round trip after it loads
            self._show_map(ready[0], state, ready[1])

    # ---- controls -----------------------------------------------------------------------
    def _build_controls(self):
        st = self.state
        self.case = _widget(pn.widgets.Select, "case", options=["collocated", "noncollocated"],
                                      value=st.case, width=160)
        self.inputs = {k: _widget(pn.widgets.TextInput, k, value=repr(getattr(st, k)), width=110)
                       for k in _TEXT_FIELDS}
        self.messages = {k: pn.pane.HTML("", width=220, margin=(0, 10),
                                         styles={"color": "#b00000", "font-size": "12px"})
                         for k in ("case", *_TEXT_FIELDS, "branch", "stop", "basin_num")}
        self.case.param.watch(self._on_control, "value")
        for w in self.inputs.values():
            w.param.watch(self._on_control, "value")

    def _control(self, name):
        w = self.case if name == "case" else self.inputs[name]
        return pn.Column(w, self.messages[name], margin=0)

    def _error(self, name: str, msg: str):
        """Show ``msg`` beside the control ``name`` ('' clears it)."""
        pane = self.messages.get(name)
        if pane is not None:
            pane.object = (f'<div data-testid="error-{name}">{html.escape(msg)}</div>'
                           if msg else "")

    def _on_control(self, _event=None):
        # Panel calls widget watchers without the document's lock, which the map's and the
        # orbit's Bokeh sources need: the change is applied on the next tick, under it
        self._on_doc(self._apply_controls)

    def _apply_controls(self):
        raw = {"case": self.case.value, **{k: w.value for k, w in self.inputs.items()}}
        values, bad = {}, {}
        for k, v in raw.items():
            try:
                values[k] = S.check_field(k, v)
            except ValueError as exc:
                bad[k] = str(exc)
        for k in raw:
            self._error(k, bad.get(k, ""))
        if bad:
            self._say("refused: " + "; ".join(bad.values()))
            return
        try:
            new = self.state.replace(**values, stop=None)
        except ValueError as exc:
            key = str(exc).split()[0]
            self._error({"kp": "kp_min", "kv": "kv_min"}.get(key, "num"), str(exc))
            self._say(f"refused: {exc}")
            return
        plant_changed = any(getattr(new, k) != getattr(self.state, k)
                            for k in ("case", "e", "mu", "m2", "gamma", "omega", "n"))
        self.state = new
        self._push_url()
        if plant_changed:
            self.select(new.kp, new.kv)
        self._schedule(self._refresh_map)

    def _push_url(self):
        if self.url and pn.state.location is not None:
            pn.state.location.update_query(**S.to_query(self.state))

    def _say(self, text: str):
        self.status.object = _tid("status", text)

    def _schedule(self, start):
        """Run ``start()`` under the document's lock; the coroutine it returns (None: nothing
        to compute) then runs on the event loop, its work on a worker thread."""
        def go():
            coro = start()
            if coro is None:
                return
            try:
                task = asyncio.get_running_loop().create_task(coro)
            except RuntimeError:      # no event loop (a plain script): run it to the end
                asyncio.run(coro)
                return
            # the loop keeps only a weak reference to a task: without this one a pending
            # computation could be collected and its result never shown
            self._tasks.add(task)
            task.add_done_callback(self._tasks.discard)
        self._on_doc(go)

    async def _off_loop(self, fn, *args):
        return await asyncio.get_running_loop().run_in_executor(_POOL, fn, *args)

    def _on_doc(self, fn, *args):
        """Apply ``fn(*args)`` to the page holding its document's lock: Bokeh models change
        only under it, which a coroutine resumed after a worker thread does not hold."""
        doc = self._doc
        if doc is not None and doc.session_context is not None:
            doc.add_next_tick_callback(lambda: self._safely(fn, *args))
        else:
            self._safely(fn, *args)

    def _resend(self, *panes):
        """Send the panes' final text once more, a moment later. Panel writes a change made
        while the page's socket is busy writing later, from a queue, and a change made
        after it directly, so the two can arrive in the other order: a computation that
        ends within ~0.1 s of its start could leave "computing" on the page."""
        doc = self._doc
        if doc is not None and doc.session_context is not None:
            for pane in panes:
                doc.add_timeout_callback(partial(self._safely, self._again, pane, pane.object),
                                         _RESEND_MS)

    @staticmethod
    def _again(pane, text):
        # the same text changed by an invisible comment: Bokeh sends only a real change
        if pane.object == text:
            pane.object = text + "<!-- final -->"

    def _safely(self, fn, *args):
        try:
            fn(*args)
        except Exception as exc:   # noqa: BLE001 - a request never stops the server
            self._say(f"error: {exc}")
            traceback.print_exc()

    # ---- the region map -------------------------------------------------------------------
    def _build_map(self):
        self.map_src = ColumnDataSource(dict(image=[np.zeros((2, 2), np.int8)], x=[0.0],
                                             y=[0.0], dw=[1.0], dh=[1.0]))
        self.sel_src = ColumnDataSource(dict(x=[self.state.kp], y=[self.state.kv]))
        f = figure(title="region map: click to select the gains", frame_width=420,
                   frame_height=420, min_border_left=70, min_border_bottom=55,
                   min_border_top=40, min_border_right=20, toolbar_location=None,
                   tools="", name="region-map")
        f.xaxis.axis_label, f.yaxis.axis_label = "kp (force/length)", "kv (force time/length)"
        cm = LinearColorMapper(palette=_CLASS_COLORS, low=-0.5, high=2.5)
        img = f.image(image="image", x="x", y="y", dw="dw", dh="dh", source=self.map_src,
                      color_mapper=cm)
        f.add_tools(HoverTool(renderers=[img], tooltips=[("kp", "$x{0.000}"),
                                                         ("kv", "$y{0.000}")]))
        f.scatter("x", "y", source=self.sel_src, marker="circle_cross", size=14,
                  fill_alpha=0.0, line_color="black", line_width=2)
        f.on_event(Tap, self._on_tap)
        self.map_fig = f
        self.map_info = pn.pane.HTML("", width=520)
        self.map_downloads = self._downloads("map", lambda: self.rm)

    def _refresh_map(self):
        self._gen["map"] += 1
        self._say("computing the region map")
        return self._run_map(self._gen["map"], self.state, time.perf_counter())

    async def _run_map(self, gen, st, t0):
        try:
            rm = await self._off_loop(S.pair_map, st)
        except Exception as exc:   # noqa: BLE001 - the panel says why
            if gen == self._gen["map"]:
                self._on_doc(self._map_failed, str(exc))
            return
        if gen == self._gen["map"]:   # else a newer request is on its way
            self._on_doc(self._show_map, rm, st, 1000 * (time.perf_counter() - t0))

    def _map_failed(self, why: str):
        self.map_info.object = _tid("map-error", f"region map failed: {why}")
        self._say(f"error: region map failed: {why}")

    def _show_map(self, rm, st, ms: float):
        self.rm = rm
        xs, ys = rm.x, rm.y
        dx, dy = xs[1] - xs[0], ys[1] - ys[0]
        self.map_src.data = dict(image=[S.map_classes(rm)], x=[xs[0] - dx / 2],
                                 y=[ys[0] - dy / 2], dw=[xs[-1] - xs[0] + dx],
                                 dh=[ys[-1] - ys[0] + dy])
        self.map_fig.x_range.start, self.map_fig.x_range.end = xs[0] - dx / 2, xs[-1] + dx / 2
        self.map_fig.y_range.start, self.map_fig.y_range.end = ys[0] - dy / 2, ys[-1] + dy / 2
        legend = " ".join(f'<span style="background:{c};padding:0 6px">&nbsp;</span> {n}'
                          for c, n in zip(_CLASS_COLORS, _CLASS_NAMES))
        self.map_info.object = (
            f"{legend}<br>{st.case}, e = {_tid('map-e', _num(rm.e[0]))}, "
            f"{len(xs)} x {len(ys)} cells: orbit exists on "
            f"{_tid('map-exists-share', _num(rm.fraction('exists')[0]))}, stable on "
            f"{_tid('map-stable-share', _num(rm.fraction('stable')[0]))} of the box "
            f"(computed in {_tid('map-ms', f'{ms:.0f}')} ms)")
        self._say("ready")
        self._resend(self.map_info, self.status)

    def _on_tap(self, event):
        try:
            kp, kv = S.snap(self.state, event.x, event.y)
            self.select(kp, kv)
        except Exception as exc:   # noqa: BLE001 - a request never stops the server
            self._say(f"error: {exc}")

    # ---- the orbit --------------------------------------------------------------------
    def _build_orbit(self):
        empty = dict(t=[], x1=[], y1=[], x2=[], y2=[], z3=[])
        self.orbit_src = ColumnDataSource(dict(empty))
        self.impact_src = ColumnDataSource(dict(t=[], x1=[], z3=[]))
        self.jump_src = ColumnDataSource(dict(px=[], py=[]))
        self.mult_src = ColumnDataSource(dict(re=[], im=[]))
        ts = _fig("positions over one period", "t (time)", "position (length)")
        ts.line("t", "x1", source=self.orbit_src, color=OKABE_ITO["blue"], legend_label="x1")
        ts.line("t", "x2", source=self.orbit_src, color=OKABE_ITO["vermillion"],
                line_dash="dashed", legend_label="x2")
        ts.scatter("t", "x1", source=self.impact_src, marker="inverted_triangle", size=9,
                   color="black", legend_label="impact")
        gap = _fig("gap z3 = x1 - x2 and the walls", "t (time)", "z3 (length)")
        gap.line("t", "z3", source=self.orbit_src, color="black")
        gap.scatter("t", "z3", source=self.impact_src, marker="inverted_triangle", size=9,
                    color="black")
        self.wall_src = ColumnDataSource(dict(t=[], up=[], lo=[]))
        gap.line("t", "up", source=self.wall_src, color="gray", line_dash="dashed")
        gap.line("t", "lo", source=self.wall_src, color="gray", line_dash="dashed")
        ph = _fig("phase portrait", "position (length)", "velocity (length/time)")
        ph.line("x1", "y1", source=self.orbit_src, color=OKABE_ITO["blue"], legend_label="mass 1")
        ph.line("x2", "y2", source=self.orbit_src, color=OKABE_ITO["vermillion"],
                line_dash="dashed", legend_label="mass 2")
        ph.scatter("px", "py", source=self.jump_src, size=6, color="black",
                   legend_label="impact states")
        mu = _fig("multipliers and the unit circle", "Re", "Im", width=300, height=300,
                  match_aspect=True)
        th = np.linspace(0, 2 * np.pi, 361)
        mu.line(np.cos(th), np.sin(th), color="gray")
        mu.scatter("re", "im", source=self.mult_src, size=10, fill_alpha=0.0,
                   line_color=OKABE_ITO["blue"], line_width=2)
        for f in (ts, ph):
            f.legend.location = "top_left"
            f.legend.label_text_font_size = "9pt"
        self.orbit_figs = (ts, gap, ph)
        self.mult_fig = mu
        self.orbit_info = pn.pane.HTML("", width=320)
        self.orbit_downloads = self._downloads("orbit", lambda: self._existing_orbit())
        self.mult_downloads = self._downloads("multipliers", lambda: self._existing_orbit())

    def _existing_orbit(self):
        if self.orb is None or not self.orb.exists:
            raise ValueError("no orbit at the selected gains: nothing to save")
        return self.orb

    def select(self, kp: float, kv: float):
        """Show the orbit at the gains ``(kp, kv)`` (a click on the map)."""
        try:
            self.state = self.state.replace(kp=kp, kv=kv, stop=None)
        except ValueError as exc:
            self._say(f"refused: {exc}")
            return
        self.sel_src.data = dict(x=[self.state.kp], y=[self.state.kv])
        self._push_url()
        self.basin = self.branch = None
        self._gen["basin"] += 1
        self._gen["branch"] += 1
        self._clear_basin()
        self._clear_branch()
        try:
            self.orb = S.pair_orbit(self.state)
        except Exception as exc:   # noqa: BLE001 - the panel says why
            self.orb = None
            self.orbit_info.object = self._summary(None, f"the orbit failed: {exc}")
            return
        self._show_orbit(self.orb)

    def _show_orbit(self, orb):
        self.orbit_info.object = self._summary(orb, orb.reason)
        if not orb.exists:
            self.orbit_src.data = dict(t=[], x1=[], y1=[], x2=[], y2=[], z3=[])
            self.impact_src.data = dict(t=[], x1=[], z3=[])
            self.jump_src.data = dict(px=[], py=[])
            self.wall_src.data = dict(t=[], up=[], lo=[])
            self.mult_src.data = dict(re=[], im=[])
            return
        s = S.orbit_series(orb)
        self.orbit_src.data = {k: s[k] for k in ("t", "x1", "y1", "x2", "y2", "z3")}
        pre, post = s["impact_pre"], s["impact_post"]
        self.impact_src.data = dict(t=s["impact_t"], x1=pre[:, 0], z3=pre[:, 0] - pre[:, 2])
        # both masses before and after each impact: the velocity jumps
        both = np.concatenate([pre, post])
        self.jump_src.data = dict(px=np.concatenate([both[:, 0], both[:, 2]]),
                                  py=np.concatenate([both[:, 1], both[:, 3]]))
        L = orb.pair.L
        t = s["t"][[0, -1]]
        self.wall_src.data = dict(t=t, up=[L, L], lo=[-L, -L])
        z = np.asarray(orb.multipliers)
        self.mult_src.data = dict(re=z.real, im=z.imag)

    def _summary(self, orb, reason: str) -> str:
        st = self.state
        head = (f"selected kp = {_tid('selected-kp', _num(st.kp))}, kv = "
                f"{_tid('selected-kv', _num(st.kv))}<br>")
        if orb is None:
            return head + _tid("orbit-error", reason)
        rows = [("exists", _tid("exists", str(bool(orb.exists)).lower())),
                ("reason", _tid("reason", reason)),
                ("viability margin", _tid("viability-margin", _num(orb.viability_margin))),
                ("xm", _tid("xm", _num(orb.xm)))]
        if orb.exists:
            mods = ", ".join(_num(abs(z)) for z in orb.multipliers)
            rows += [("spectral radius", _tid("spectral-radius", _num(orb.spectral_radius))),
                     ("stable", _tid("stable", str(bool(orb.stable)).lower())),
                     ("|multipliers|", _tid("multiplier-moduli", mods))]
        else:
            rows += [("spectral radius", _tid("spectral-radius", "none")),
                     ("stable", _tid("stable", "none"))]
        return head + "<table>" + "".join(f"<tr><td>{k}</td><td>{v}</td></tr>"
                                          for k, v in rows) + "</table>"

    # ---- the basin --------------------------------------------------------------------
    def _build_basin(self):
        self.basin_src = ColumnDataSource(dict(image=[np.zeros((2, 2))], x=[0.0], y=[0.0],
                                               dw=[1.0], dh=[1.0]))
        self.basin_fp = ColumnDataSource(dict(x=[], y=[]))
        self.basin_cm = LinearColorMapper(palette=_BASIN_COLORS, low=-0.5, high=6.5,
                                          nan_color=(0, 0, 0, 0))
        self.basin_fig = self._basin_figure()
        self.basin_pane = pn.pane.Bokeh(self.basin_fig)
        self.basin_num = _widget(pn.widgets.TextInput, "points per axis",
                                 value=repr(self.state.basin_num), width=110)
        self.basin_button = _widget(pn.widgets.Button, "compute basin slice", primary=True)
        self.basin_button.on_click(lambda _e: self._schedule(self._compute_basin))
        self.basin_progress = pn.indicators.Progress(active=False, value=0, max=100,
                                                      width=200, visible=False)
        self.basin_info = pn.pane.HTML(_tid("basin-status", "not computed"), width=420)
        self.basin_downloads = self._downloads("basin", lambda: self.basin)

    def _basin_figure(self):
        f = _fig("basin slice (x1, y1) through the orbit", "x1 (length)",
                 "y1 (length/time)", width=420, height=360)
        f.image(image="image", x="x", y="y", dw="dw", dh="dh", source=self.basin_src,
                color_mapper=self.basin_cm)
        f.scatter("x", "y", source=self.basin_fp, marker="x", size=12, color="black")
        return f

    def _clear_basin(self):
        self.basin_src.data = dict(image=[np.full((2, 2), np.nan)], x=[0.0], y=[0.0],
                                   dw=[1.0], dh=[1.0])
        self.basin_fp.data = dict(x=[], y=[])
        self.basin_progress.visible = False
        self.basin_info.object = _tid("basin-status", "not computed")

    def _compute_basin(self):
        try:
            num = S.check_field("basin_num", self.basin_num.value)
        except ValueError as exc:
            self._error("basin_num", str(exc))
            return None
        self._error("basin_num", "")
        if self.orb is None or not self.orb.exists:
            self.basin_info.object = _tid("basin-status", "no orbit at the selected gains: "
                                          "no basin")
            return None
        self._gen["basin"] += 1
        self.basin_progress.visible, self.basin_progress.active = True, True
        self.basin_progress.value = 0
        slow = "" if self.orb.stable else (
            " (the orbit is unstable: no point converges to it; each runs "
            f"{S.UNSTABLE_ITERATIONS} iterations, looking for other attractors)")
        self.basin_info.object = _tid("basin-status", f"computing {num} x {num} points{slow}")
        return self._run_basin(self._gen["basin"], self.orb, num, time.perf_counter())

    async def _run_basin(self, gen, orb, num, t0):
        err = ""
        try:
            ab = await self._off_loop(S.pair_basin, orb, num,
                                      lambda done, total: self._on_doc(
                                          self._basin_done, gen, done, total))
        except Exception as exc:   # noqa: BLE001 - the panel says why
            ab, err = None, str(exc)
        if gen == self._gen["basin"]:
            self._on_doc(self._show_basin, ab, orb, err, 1000 * (time.perf_counter() - t0))

    def _basin_done(self, gen, done: int, total: int):
        if gen == self._gen["basin"] and total:
            self.basin_progress.value = int(100 * done / total)

    def _show_basin(self, ab, orb, err, ms: float):
        self.basin_progress.active, self.basin_progress.visible = False, False
        if ab is None:
            self.basin_info.object = _tid("basin-status", f"basin failed: {err}")
            return
        self.basin = ab
        codes = sorted({int(a.label) for a in ab.attractors})
        index = {c: i for i, c in enumerate(codes)}
        img = np.vectorize(lambda v: index.get(int(v), np.nan), otypes=[float])(ab.labels)
        dx, dy = ab.x[1] - ab.x[0], ab.y[1] - ab.y[0]
        self.basin_src.data = dict(image=[img], x=[ab.x[0] - dx / 2], y=[ab.y[0] - dy / 2],
                                   dw=[ab.x[-1] - ab.x[0] + dx], dh=[ab.y[-1] - ab.y[0] + dy])
        fp = orb.pre_plus
        self.basin_fp.data = dict(x=[fp[0]], y=[fp[1]])
        keys = [f'<span style="background:{_BASIN_COLORS[index[int(a.label)] % 7]};'
                f'padding:0 6px">&nbsp;</span> {html.escape(line)}'
                for a, line in zip(ab.attractors, ab.summary()[-len(ab.attractors):])]
        self.basin_info.object = (
            _tid("basin-status", "done") + f" in {_tid('basin-ms', f'{ms:.0f}')} ms; "
            f"the orbit's basin: {_tid('basin-share', _num(ab.converged_fraction))} of the "
            "slice<br>" + "<br>".join(keys))
        self._resend(self.basin_info)

    # ---- the branch -------------------------------------------------------------------
    def _build_branch(self):
        self.branch_param = _widget(pn.widgets.Select, "follow along", options=["kp", "kv"],
                                              value=self.state.branch, width=100)
        self.branch_stop = _widget(pn.widgets.TextInput, "up to", value="", width=110,
                                                placeholder="the box's end")
        self.branch_button = _widget(pn.widgets.Button, "follow branch", primary=True)
        self.branch_button.on_click(lambda _e: self._schedule(self._compute_branch))
        self.branch_src = ColumnDataSource(dict(p=[], rho=[], stable=[]))
        self.event_src = ColumnDataSource(dict(p=[], rho=[], kind=[]))
        self.branch_fig = self._branch_figure()
        self.branch_pane = pn.pane.Bokeh(self.branch_fig)
        self.branch_info = pn.pane.HTML(_tid("branch-status", "not computed"), width=420)
        self.branch_downloads = self._downloads("branch", lambda: self.branch)

    def _branch_figure(self):
        # log scale: the crossings of 1 show however large the radius grows along the branch
        f = _fig("spectral radius along the branch (log scale)", "parameter",
                 "spectral radius", width=420, height=300, y_axis_type="log")
        f.line("p", "rho", source=self.branch_src, color="black")
        f.scatter("p", "rho", source=self.event_src, size=11, marker="diamond",
                  color=OKABE_ITO["vermillion"])
        f.add_tools(HoverTool(tooltips=[("event", "@kind"), ("at", "@p{0.000000}")]))
        return f

    def _clear_branch(self):
        self.branch_src.data = dict(p=[], rho=[], stable=[])
        self.event_src.data = dict(p=[], rho=[], kind=[])
        self.branch_info.object = _tid("branch-status", "not computed")

    def _compute_branch(self):
        raw = {"branch": self.branch_param.value}
        if self.branch_stop.value.strip():
            raw["stop"] = self.branch_stop.value
        try:
            st = self.state.replace(**{k: S.check_field(k, v) for k, v in raw.items()})
        except ValueError as exc:
            self._error("stop", str(exc))
            return None
        self._error("stop", "")
        self._gen["branch"] += 1
        self.branch_info.object = _tid("branch-status", f"following along {st.branch} to "
                                       f"{st.stop_value():.6g}")
        return self._run_branch(self._gen["branch"], st)

    async def _run_branch(self, gen, st):
        try:
            br = await self._off_loop(S.pair_branch, st)
        except Exception as exc:   # noqa: BLE001 - the panel says why
            if gen == self._gen["branch"]:
                self._on_doc(setattr, self.branch_info, "object",
                             _tid("branch-status", f"branch failed: {exc}"))
            return
        if gen == self._gen["branch"]:
            self._on_doc(self._show_branch, br)

    def _show_branch(self, br):
        self.branch = br
        self.branch_fig.xaxis.axis_label = br.parameter_name
        self.branch_src.data = dict(p=br.parameter, rho=br.spectral_radius,
                                    stable=br.stable.astype(int))
        ev = br.events
        rho_at = [float(np.interp(e.parameter, *_sorted(br.parameter, br.spectral_radius)))
                  for e in ev]
        self.event_src.data = dict(p=[e.parameter for e in ev], rho=rho_at,
                                   kind=[e.kind for e in ev])
        lines = [f"{html.escape(e.kind)} at {br.parameter_name} = "
                 f"{_tid('event-' + e.kind, _num(e.parameter))}" for e in ev]
        self.branch_info.object = (
            _tid("branch-status", f"done: {br.termination}") + f", {len(br.parameter)} points"
            f", {_tid('branch-events', len(ev))} events<br>" + "<br>".join(lines))
        self._resend(self.branch_info)

    # ---- saving -----------------------------------------------------------------------
    def _downloads(self, panel: str, get):
        """Two buttons: the panel's figure (PNG, house style) and its data file."""
        def fig():
            return io.BytesIO(self._guarded(lambda: F.figure_bytes(panel, self._need(get))))

        def data():
            return io.BytesIO(self._guarded(lambda: F.data_bytes(panel, self._need(get))))

        return pn.Row(
            pn.widgets.FileDownload(callback=fig, filename=f"{panel}.png",
                                    label=f"save {panel} figure"),
            pn.widgets.FileDownload(callback=data, filename=f"{panel}{F.PANELS[panel]}",
                                    label=f"save {panel} data"))

    @staticmethod
    def _need(get):
        r = get()
        if r is None:
            raise ValueError("nothing computed yet in this panel")
        return r

    def _guarded(self, make) -> bytes:
        try:
            out = make()
        except Exception as exc:   # noqa: BLE001 - a request never stops the server
            self._say(f"error: cannot save: {exc}")
            return f"cannot save: {exc}\n".encode()
        self._say("saved")
        return out

    # ---- the page ---------------------------------------------------------------------
    def _layout(self):
        controls = pn.Column(
            "### Impact pair", self._control("case"),
            *(self._control(k) for k in ("e", "mu", "m2", "gamma", "omega", "n")),
            "**box of gains**",
            *(self._control(k) for k in ("kp_min", "kp_max", "kv_min", "kv_max", "num")),
            width=250)
        map_col = pn.Column(pn.pane.Bokeh(self.map_fig), self.map_info, self.map_downloads)
        orbit = pn.Column(
            pn.Row(*(pn.pane.Bokeh(f) for f in self.orbit_figs)), self.orbit_downloads)
        mult = pn.Column(pn.pane.Bokeh(self.mult_fig), self.mult_downloads)
        basin = pn.Column(pn.Row(self.basin_num, self.messages["basin_num"]),
                          pn.Row(self.basin_button, self.basin_progress),
                          self.basin_pane, self.basin_info, self.basin_downloads)
        branch = pn.Column(pn.Row(self.branch_param, self.branch_stop,
                                  self.messages["stop"]),
                           self.branch_button, self.branch_pane,
                           self.branch_info, self.branch_downloads)
        main = pn.Column(
            self.status,
            pn.Row(map_col, pn.Column(self.orbit_info, mult)),
            pn.Card(orbit, title="orbit over one period", collapsible=False),
            pn.Row(pn.Card(basin, title="basin slice", collapsible=False),
                   pn.Card(branch, title="branch", collapsible=False)))
        return pn.Row(controls, main)

    def __panel__(self):
        return self.layout


def _sorted(p, v):
    order = np.argsort(p)
    return np.asarray(p)[order], np.asarray(v)[order]


def warm_up(state: S.PairState, warm=None):
    """Start computing ``state``'s map and orbit (numba's kernels and the closed forms'
    cached code load on their first call): run when a server starts, so the first page
    does not wait for them.

    Returns a future of ``(state, map, milliseconds)`` (``warm``, a future of
    :func:`hybridpd.explore.state.warm_map` already started for the map, if given; else a
    worker thread computes it); :func:`pair_app` given it draws the map in the page it
    builds when the page's box is the same and the map is ready. The orbit is computed on
    a worker thread here, for the caches of this process.
    """
    def orbit():
        orb = S.pair_orbit(state)
        if orb.exists:
            S.orbit_series(orb)
    if warm is None:
        warm = _POOL.submit(lambda: (S.timed_map(state), orbit())[0])
    else:
        _POOL.submit(orbit)
    return warm


def pair_app(base: S.PairState | None = None, warm=None):
    """A new page for the session that asks: the state read from its URL, fields not given
    from ``base`` (refused fields keep ``base``'s values and say why beside their
    controls). ``warm``: the future of :func:`warm_up`, whose map a page of the same box
    shows from the start."""
    args = dict(pn.state.session_args or {}) if pn.state.curdoc is not None else {}
    state, errors = S.parse_query(args, base)
    return PairExplorer(state, errors, url=True, ready=_ready_map(warm, state)).layout


def _ready_map(warm, state: S.PairState):
    """``(map, ms)`` of the warm-up when it has finished for ``state``'s box, else None."""
    if warm is None or not warm.done() or warm.exception() is not None:
        return None
    done, rm, ms = warm.result()
    return (rm, ms) if S.same_map(done, state) else None
