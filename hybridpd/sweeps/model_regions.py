"""Region maps of any model file: where a periodic orbit of a section exists and is stable.

:func:`model_region_map` sweeps two numeric entries of a model file (dotted paths,
:mod:`hybridpd.mechanics.params`) over a grid and, per cell, looks for the periodic orbits of
one section (a contact's impacts or sticking releases, ``k`` returns per orbit) with
:func:`hybridpd.analysis.model_orbits.solve_at`:

* **Continuation across the grid.** The grid is cut into square tiles (one sweep chunk
  each, so tiles run in parallel on any executor); inside a tile the cells are visited in
  snake order and each starts Newton from its solved neighbours' orbits, or from a
  simulation of the model where no neighbour has one (or only unstable ones).
* **No holes from solver trouble.** After the sweep, every cell without an orbit that has a
  neighbour with one, and every cell next to a neighbour whose orbit looks like another
  family (other impact signature, or more than 5 % away), is tried again from all its
  neighbours' orbits, in rounds until nothing changes. So a cell is reported without an
  orbit only when Newton failed from every neighbour's solution and from a simulation.
* **Both orbits.** Distinct orbits found in one cell are all counted (``n_orbits``); the
  first two are kept (stable first).

Every orbit is checked by :func:`~hybridpd.analysis.periodic.find_orbit` (whole number of
reference periods, transversal, a simulated period returns to it). The result converts to
the labelled xarray format of the pair's region maps (``hybridpd plot`` draws it) with the
extra variables ``status``, ``section_point``, ``signature``, ``n_orbits`` and those of the
second orbit. The per-cell work does not depend on the executor, so results are identical
for serial, process-pool and cluster runs, and a run resumes from its Zarr store.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.analysis.model_orbits import (
    STATUS,
    OrbitSearch,
    SectionSpec,
    Seed,
    signature_codes,
    signature_table,
    simulated_returns,
    solve_at,
)
from hybridpd.analysis.sections import mode_code, mode_name
from hybridpd.mechanics.params import ModelTemplate
from hybridpd.sweeps.labelled import (
    axis_attrs,
    decode_attrs,
    encode_attrs,
    load_result,
    save_result,
)

__all__ = ["ModelRegionMap", "load_model_region_map", "model_region_map", "template_of"]

_SIG_LEN = 48          # jumps of a signature kept per cell
_NEIGH = [(-1, -1), (-1, 0), (-1, 1), (0, -1), (0, 1), (1, -1), (1, 0), (1, 1)]


def template_of(model) -> ModelTemplate:
    """A :class:`ModelTemplate` from a file path, a parsed dict or a template."""
    if isinstance(model, ModelTemplate):
        return model
    if isinstance(model, dict):
        t = ModelTemplate(model)
        t.model()
        return t
    if isinstance(model, (str, Path)):
        return ModelTemplate.load(model)
    raise ValueError(f"model must be a model file path, a parsed dict or a ModelTemplate, got "
                     f"{type(model).__name__}")


def _grid_spec(name, spec, what, check):
    """``(key, (lo, hi, num))`` of ``spec = (KEY, MIN, MAX, NUM)``: ``check(key)`` refuses an
    unknown key, ``what`` names KEY in the messages. A model entry's KEY may be a pattern or a
    comma-separated list of paths (:func:`~hybridpd.mechanics.params.resolve_path`): the axis
    sets every entry it matches, and is named by KEY as given."""
    try:
        key, lo, hi, num = spec
        lo, hi, numf = float(lo), float(hi), float(num)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be ({what}, MIN, MAX, NUM), got {spec!r}") from None
    check(key)
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise ValueError(f"{name} ({key}): MIN < MAX must be finite, got {lo:g}, {hi:g}")
    if numf != int(numf) or numf < 2:
        raise ValueError(f"{name} ({key}): NUM must be an integer >= 2, got {num!r}")
    return str(key), (lo, hi, int(numf))


def _axis(name, spec, template):
    key, (lo, hi, num) = _grid_spec(name, spec, "KEY", template.check)
    return key, np.linspace(lo, hi, num)


@dataclass(frozen=True, eq=False)
class ModelRegionMap:
    """Existence and stability of a section's periodic orbits over a grid of two model entries.

    Arrays are indexed ``[iy, ix]`` (``y`` the rows).

    Attributes
    ----------
    source : str
        The model file.
    x_name, y_name : str
        Dotted paths of the swept entries.
    x, y : ndarray
    spec : dict
        The section and orbit settings (:class:`~hybridpd.analysis.model_orbits.SectionSpec`).
    coords : tuple of str
        Names of the section coordinates.
    sig_table : tuple of (str, str)
        The ``(guard, kind)`` pairs the signature codes index.
    status : ndarray of int, shape (ny, nx)
        :data:`~hybridpd.analysis.model_orbits.STATUS` code per cell.
    spectral_radius, spectral_radius2 : ndarray, shape (ny, nx)
        Of the first (stable first) and second orbit (NaN where none).
    section_point, section_point2 : ndarray, shape (ny, nx, dim)
    signature, signature2 : ndarray of int16, shape (ny, nx, 48)
        Impact signatures as codes into ``sig_table`` (``-1`` padding, ``-2`` cut).
    period, period2 : ndarray of int, shape (ny, nx)
        Returns to the section per period of the first and second orbit (``k``; 0: none).
    mode, mode2 : ndarray of int, shape (ny, nx)
        The section's mode of each orbit (:func:`~hybridpd.analysis.sections.mode_code`;
        ``metadata["modes"]`` names the codes present; -1: none).
    section_state, section_state2 : ndarray, shape (ny, nx, n)
        Full pre-jump state of each orbit at its section point (``metadata["state_names"]``).
    section_time, section_time2 : ndarray, shape (ny, nx)
        Its time (the phase ``phi``).
    status2 : ndarray of int, shape (ny, nx)
        Status of the second orbit (``-1`` where there is none).
    n_orbits : ndarray of int, shape (ny, nx)
        Distinct orbits found.
    attempts : ndarray of int, shape (ny, nx)
        Newton runs made per cell.
    metadata : dict
    """

    source: str
    x_name: str
    y_name: str
    x: np.ndarray
    y: np.ndarray
    spec: dict
    coords: tuple
    sig_table: tuple
    status: np.ndarray
    spectral_radius: np.ndarray
    section_point: np.ndarray = field(repr=False)
    signature: np.ndarray = field(repr=False)
    n_orbits: np.ndarray = field(repr=False)
    status2: np.ndarray = field(repr=False)
    spectral_radius2: np.ndarray = field(repr=False)
    section_point2: np.ndarray = field(repr=False)
    signature2: np.ndarray = field(repr=False)
    attempts: np.ndarray = field(repr=False)
    metadata: dict = field(default_factory=dict)
    period: np.ndarray | None = field(default=None, repr=False)
    period2: np.ndarray | None = field(default=None, repr=False)
    mode: np.ndarray | None = field(default=None, repr=False)
    mode2: np.ndarray | None = field(default=None, repr=False)
    section_state: np.ndarray | None = field(default=None, repr=False)
    section_time: np.ndarray | None = field(default=None, repr=False)
    section_state2: np.ndarray | None = field(default=None, repr=False)
    section_time2: np.ndarray | None = field(default=None, repr=False)
    __repr__ = compact_repr

    def __post_init__(self):
        sh = self.status.shape
        defaults = {"period": np.where(self.n_orbits > 0, 1, 0),
                    "period2": np.where(self.status2 >= 0, 1, 0),
                    "mode": np.full(sh, -1), "mode2": np.full(sh, -1),
                    "section_time": np.full(sh, np.nan), "section_time2": np.full(sh, np.nan),
                    "section_state": np.full((*sh, 0), np.nan),
                    "section_state2": np.full((*sh, 0), np.nan)}
        for k, v in defaults.items():
            if getattr(self, k) is None:
                object.__setattr__(self, k, v)

    @property
    def exists(self) -> np.ndarray:
        """A periodic orbit was found (bool, ``(ny, nx)``)."""
        return self.n_orbits > 0

    @property
    def stable(self) -> np.ndarray:
        """A stable periodic orbit was found."""
        return self.status == 0

    def counts(self) -> dict:
        """``{status name: cells}``."""
        return {STATUS[c]: int(np.sum(self.status == c)) for c in STATUS}

    def signature_of(self, iy: int, ix: int, which: int = 1) -> tuple:
        """The impact signature ``((guard, kind), ...)`` of orbit `which` (1 or 2) of a cell."""
        codes = (self.signature if which == 1 else self.signature2)[iy, ix]
        return tuple(self.sig_table[c] if c >= 0 else ("...", "cut") for c in codes if c != -1)

    def summary(self) -> str:
        """A few lines: grid, share of each status, cells with two orbits, signatures."""
        n = self.status.size
        parts = [f"{name} {100 * c / n:.1f}%" for name, c in self.counts().items() if c]
        head = (f"{Path(self.source).name}: periodic orbits of contact {self.spec['contact']}"
                f" ({self.spec['event']}, k = {self.spec['period']}) on {self.x_name} x "
                f"{self.y_name} = {len(self.x)} x {len(self.y)}")
        ks = {int(k): int(np.sum(self.period[self.exists] == k))
              for k in np.unique(self.period[self.exists])}
        lines = [head,
                 "  " + ", ".join(parts),
                 f"  cells with two or more orbits: {int(np.sum(self.n_orbits > 1))}"]
        if ks:
            lines.append("  returns to the section per period (k): " + ", ".join(
                f"k = {k}: {c} cells" for k, c in sorted(ks.items())))
        sigs = {}
        for iy, ix in zip(*np.nonzero(self.exists)):
            s = self.signature_of(iy, ix)
            sigs[s] = sigs.get(s, 0) + 1
        for s, c in sorted(sigs.items(), key=lambda t: -t[1])[:4]:
            lines.append(f"  signature ({c} cells): {_sig_text(s)}")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-ready form (``regions --model --json``), arrays ``[iy][ix]``."""
        f = lambda a: [[None if not np.isfinite(v) else float(v) for v in row] for row in a]
        return {"model": self.source, "x_name": self.x_name, "y_name": self.y_name,
                "x": self.x.tolist(), "y": self.y.tolist(), "spec": self.spec,
                "coordinates": list(self.coords), "status": self.status.tolist(),
                "statuses": {str(k): v for k, v in STATUS.items()}, "counts": self.counts(),
                "exists": self.exists.tolist(), "stable": self.stable.tolist(),
                "spectral_radius": f(self.spectral_radius), "n_orbits": self.n_orbits.tolist(),
                "spectral_radius2": f(self.spectral_radius2),
                "status2": self.status2.tolist()}

    def to_dataset(self):
        """The labelled form of the pair's region maps (dimensions ``e, y_name, x_name`` with
        ``e`` the section contact's restitution, NaN for a compliant contact) plus the
        per-cell ``status``, ``section_point``, ``signature`` and second-orbit variables."""
        # deferred import: loaded only when this runs, for start-up time
        import xarray as xr

        e = np.array([self.metadata.get("restitution", math.nan)], float)
        dims = ("e", self.y_name, self.x_name)
        coords = {"e": ("e", e, axis_attrs("e")), self.y_name: (self.y_name, self.y),
                  self.x_name: (self.x_name, self.x), "coordinate": ("coordinate",
                                                                      list(self.coords))}
        reason = np.where(self.exists, 0, self.status)
        flags = sorted(STATUS)
        one = lambda a: a[None]
        data = {
            "exists": (dims, one(self.exists), {"long_name": "a periodic orbit was found"}),
            "stable": (dims, one(self.stable), {"long_name": "a stable periodic orbit was "
                                                              "found"}),
            "spectral_radius": (dims, one(self.spectral_radius),
                                axis_attrs("spectral_radius")),
            "xm": (dims, np.full((1, *self.status.shape), np.nan),
                   {"long_name": "unused for model files"}),
            "reason": (dims, one(reason), {"long_name": "why no orbit was found (0: found)",
                                           "flag_values": flags,
                                           "flag_meanings": " ".join(STATUS[c] for c in flags)}),
            "status": (dims, one(self.status), {"long_name": "status of the cell",
                                                "flag_values": flags,
                                                "flag_meanings": " ".join(STATUS[c]
                                                                          for c in flags)}),
            "n_orbits": (dims, one(self.n_orbits), {"long_name": "distinct orbits found"}),
            "attempts": (dims, one(self.attempts), {"long_name": "Newton runs"}),
            "section_point": ((*dims, "coordinate"), one(self.section_point),
                              {"long_name": "section point of the orbit"}),
            "signature": ((*dims, "jump"), one(self.signature),
                          {"long_name": "impact signature (codes into sig_table)"}),
            "status2": (dims, one(self.status2), {"long_name": "status of a second orbit "
                                                               "(-1: none)"}),
            "spectral_radius2": (dims, one(self.spectral_radius2),
                                 {"long_name": "spectral radius of a second orbit"}),
            "section_point2": ((*dims, "coordinate"), one(self.section_point2),
                               {"long_name": "section point of a second orbit"}),
            "signature2": ((*dims, "jump"), one(self.signature2),
                           {"long_name": "impact signature of a second orbit"}),
            "period": (dims, one(self.period), {"long_name": "returns to the section per "
                                                              "period of the orbit (0: none)"}),
            "period2": (dims, one(self.period2), {"long_name": "returns per period of a "
                                                                "second orbit"}),
            "section_mode": (dims, one(self.mode), {"long_name": "mode of the section "
                                                                 "(codes named in metadata)"}),
            "section_mode2": (dims, one(self.mode2), {"long_name": "mode of the section of a "
                                                                   "second orbit"}),
            "section_time": (dims, one(self.section_time), {"long_name": "time of the "
                                                                         "section point"}),
            "section_time2": (dims, one(self.section_time2), {"long_name": "time of the "
                                                                           "second orbit"}),
            "section_state": ((*dims, "state"), one(self.section_state),
                              {"long_name": "full state at the section point"}),
            "section_state2": ((*dims, "state"), one(self.section_state2),
                               {"long_name": "full state at the second orbit's point"})}
        fixed = {"model": self.source, **{f"section_{k}": v for k, v in self.spec.items()}}
        attrs = {"kind": "region_map", "case": f"{Path(self.source).name}",
                 "model_kind": "model_region_map", "x_name": self.x_name,
                 "y_name": self.y_name, "fixed_names": " ".join(fixed), **encode_attrs(fixed),
                 **encode_attrs({"sig_table": [list(p) for p in self.sig_table],
                                 "spec": self.spec, "metadata": self.metadata})}
        return xr.Dataset(data, coords=coords, attrs=attrs)

    @classmethod
    def from_dataset(cls, ds) -> ModelRegionMap:
        """Inverse of :meth:`to_dataset`."""
        a = decode_attrs(ds.attrs)
        if a.get("model_kind") != "model_region_map":
            raise ValueError("the dataset does not hold a model region map (attribute "
                             "model_kind)")
        ds = ds.transpose("e", a["y_name"], a["x_name"], ...)
        v = lambda k: ds[k].values[0]
        return cls(a["model"], a["x_name"], a["y_name"], ds[a["x_name"]].values,
                   ds[a["y_name"]].values, dict(a["spec"]), tuple(ds["coordinate"].values),
                   tuple(tuple(p) for p in a["sig_table"]), v("status").astype(np.int64),
                   v("spectral_radius"), v("section_point"), v("signature").astype(np.int16),
                   v("n_orbits").astype(np.int64), v("status2").astype(np.int64),
                   v("spectral_radius2"), v("section_point2"),
                   v("signature2").astype(np.int16), v("attempts").astype(np.int64),
                   dict(a.get("metadata") or {}),
                   *(v(k).astype(np.int64) if k in ds else None
                     for k in ("period", "period2", "section_mode", "section_mode2")),
                   *(v(k) if k in ds else None for k in ("section_state", "section_time",
                                                         "section_state2", "section_time2")))

    def save(self, path) -> Path:
        """Write to ``.nc`` or ``.zarr`` (by suffix)."""
        return save_result(self, path)


def load_model_region_map(path) -> ModelRegionMap:
    """Read a :class:`ModelRegionMap` written by :meth:`ModelRegionMap.save`."""
    return load_result(ModelRegionMap, path)


def _sig_text(sig) -> str:
    out, prev, n = [], None, 0
    for p in [*sig, None]:
        if p == prev:
            n += 1
            continue
        if prev is not None:
            out.append(f"{prev[0]}({prev[1]})" + (f" x{n}" if n > 1 else ""))
        prev, n = p, 1
    return " ".join(out)


# ----------------------------------------------------------------------------------------
# the sweep: tiles with continuation inside, then repair rounds across the whole grid
# ----------------------------------------------------------------------------------------
def _tile_order(nx, ny, tile):
    """Flat cell indices tile by tile, snake order inside each tile."""
    order = []
    for ty in range(0, ny, tile):
        for tx in range(0, nx, tile):
            for r, iy in enumerate(range(ty, min(ty + tile, ny))):
                cols = list(range(tx, min(tx + tile, nx)))
                order += [iy * nx + ix for ix in (cols if r % 2 == 0 else cols[::-1])]
    return np.array(order)


class _Cells:
    """Per-cell results as arrays (the sweep's outputs): :meth:`put` a search, :meth:`add`
    the new orbits of a later search. Each orbit keeps its section point in the map's chart
    (``s``), its full state and time (``z``, ``t``), its returns per period (``k``) and its
    section's mode (``mode``, :func:`~hybridpd.analysis.sections.mode_code`)."""

    _SLOTS = (("status", "rho", "s", "sig", "z", "t", "k", "mode"),
              ("status2", "rho2", "s2", "sig2", "z2", "t2", "k2", "mode2"))

    def __init__(self, m, dim, n):
        self.a = {"n_orbits": np.zeros(m, np.int64), "attempts": np.zeros(m, np.int64)}
        for j, names in enumerate(self._SLOTS):
            st, rho, s, sig, z, t, k, mode = names
            self.a.update({st: np.full(m, 2 if j == 0 else -1, np.int64),
                           rho: np.full(m, np.nan), s: np.full((m, dim), np.nan),
                           sig: np.full((m, _SIG_LEN), -1, np.int16),
                           z: np.full((m, n), np.nan), t: np.full(m, np.nan),
                           k: np.zeros(m, np.int64), mode: np.full(m, -1, np.int64)})
        self.orbits = {}

    def _store(self, p, slot, o, seed, ctx):
        st, rho, s, sig, z, t, k, mode = self._SLOTS[slot]
        self.a[st][p] = 0 if o.stable else 1
        self.a[rho][p] = o.spectral_radius
        self.a[s][p] = ctx.chart.from_state(seed.z, seed.t)
        self.a[sig][p] = signature_codes(o.signature, ctx.table, _SIG_LEN)
        self.a[z][p], self.a[t][p], self.a[k][p] = seed.z, seed.t, seed.period
        self.a[mode][p] = mode_code(ctx.model.automaton, seed.mode)

    def _seeds(self, res, ctx):
        return [Seed.of(o, ctx.maps(o.mode)) for o in res.orbits]

    def put(self, p, res, ctx):
        self.a["status"][p] = res.status
        self.a["attempts"][p] += res.attempts
        self.a["n_orbits"][p] = len(res.orbits)
        seeds = self._seeds(res, ctx)
        self.orbits[p] = seeds
        for j, (o, sd) in enumerate(zip(res.orbits[:2], seeds)):
            self._store(p, j, o, sd, ctx)

    def add(self, p, res, ctx) -> bool:
        """Merge the new orbits of `res` (searched with this cell's orbits as ``known``)."""
        if not res.orbits:
            self.a["attempts"][p] += res.attempts
            return False
        if self.a["n_orbits"][p] == 0:
            self.put(p, res, ctx)
            return True
        self.a["attempts"][p] += res.attempts
        new = list(zip(res.orbits, self._seeds(res, ctx)))
        if new[0][0].stable and self.a["status"][p] != 0:
            # a stable orbit comes first: the old first orbit moves to the second slot
            for a, b in zip(*self._SLOTS):
                self.a[b][p] = self.a[a][p]
            self._store(p, 0, *new.pop(0), ctx)
        elif self.a["status2"][p] < 0:
            self._store(p, 1, *new[0], ctx)
        self.a["n_orbits"][p] += len(res.orbits)
        self.orbits[p] = self.orbits[p] + [sd for _, sd in zip(res.orbits, self._seeds(res,
                                                                                         ctx))]
        return True

    def seeds_of(self, p, ctx) -> list:
        """The stored orbits of cell `p` as seeds (repair rounds)."""
        out = []
        for names in self._SLOTS:
            _, _, _, sig, z, t, k, mode = names
            if np.all(np.isfinite(self.a[z][p])):
                codes = self.a[sig][p]
                out.append(Seed(self.a[z][p].copy(), float(self.a[t][p]),
                                tuple(ctx.table[c] for c in codes if c >= 0),
                                int(self.a[k][p]), mode_name(ctx.model.automaton, self.a[mode][p])))
        return out


class _Context:
    """What a tile needs besides its points: the model at the file's values, the map's chart,
    the signature table and the section maps per mode (for seeds)."""

    def __init__(self, template, spec, main_mode):
        self.model = template.model()
        self.spec = SectionSpec(**spec)
        self.chart = self.spec.section_map(self.model, main_mode or None).section
        self.table = signature_table(self.model.automaton)
        self._maps = {}

    def maps(self, mode):
        if mode not in self._maps:
            self._maps[mode] = self.spec.section_map(self.model, mode or None)
        return self._maps[mode]


def _solve_cell(template, values, spec, seeds, simulate, known=()):
    try:
        model = template.model(values)
    except ValueError as exc:
        return OrbitSearch(10, (), 0, str(exc))
    return solve_at(model, spec, seeds, simulate=simulate, known=known)


def _tile_chunk(chunk, *, data, source, x_name, y_name, spec, dim, n, main_mode):
    """One tile (module-level: runs in worker processes): continuation in visiting order."""
    template = ModelTemplate(data, source)
    ctx = _Context(template, spec, main_mode)
    ix, iy = chunk["ix"].astype(int), chunk["iy"].astype(int)
    m = len(ix)
    cells = _Cells(m, dim, n)
    where = {(int(iy[p]), int(ix[p])): p for p in range(m)}
    for p in range(m):
        seeds = []
        for dy, dx in _NEIGH:
            q = where.get((iy[p] + dy, ix[p] + dx))
            if q is not None and q < p:
                seeds += cells.orbits.get(q, [])
        res = _solve_cell(template, {x_name: chunk["x"][p], y_name: chunk["y"][p]}, ctx.spec,
                          seeds, True)
        cells.put(p, res, ctx)
    return cells.a


def _repair(out, order, nx, ny, template, x_name, y_name, xs, ys, ctx, rounds):
    """Rounds of retries from every neighbour's orbits (module docstring). Returns the cells
    (grid order) and the number of cells that gained an orbit."""
    m = nx * ny
    cells = _Cells(m, out["s"].shape[1], out["z"].shape[1])
    inv = np.empty(m, int)
    inv[order] = np.arange(m)
    for k in cells.a:       # grid order (flat iy * nx + ix)
        cells.a[k] = out[k][inv].copy()
    for p in range(m):
        cells.orbits[p] = cells.seeds_of(p, ctx)
    changed_total = 0
    todo = range(m)
    for _ in range(int(rounds)):
        changed = set()
        for p in sorted(todo):
            iy, ix = divmod(p, nx)
            own = cells.orbits[p]
            seeds = [o for dy, dx in _NEIGH
                     if 0 <= iy + dy < ny and 0 <= ix + dx < nx
                     for o in cells.orbits[(iy + dy) * nx + ix + dx]
                     if all(o.other_family(k, ctx.maps(k.mode).section.period) for k in own)]
            if not seeds:
                continue
            res = _solve_cell(template, {x_name: xs[ix], y_name: ys[iy]}, ctx.spec, seeds,
                              False, own)
            if cells.add(p, res, ctx):
                changed.add(p)
        changed_total += len(changed)
        if not changed:
            break
        todo = {(q // nx + dy) * nx + q % nx + dx for q in changed for dy, dx in _NEIGH
                if 0 <= q // nx + dy < ny and 0 <= q % nx + dx < nx}
    return cells.a, changed_total


def model_region_map(model, x, y, *, contact: int = 0, wall: int | None = None,
                     event: str = "impact", period="auto", periods: int | None = None,
                     tile: int = 8, repair_rounds: int = 20, executor="serial",
                     max_workers=None, store=None, progress: bool = True,
                     options: dict | None = None) -> ModelRegionMap:
    """Map where a periodic orbit of a model file's section exists and is stable.

    Parameters
    ----------
    model : str, Path, dict or ModelTemplate
        The model file (or its parsed tables).
    x, y : (str, float, float, int)
        ``(KEY, MIN, MAX, NUM)``: a dotted path of a numeric entry of the file
        (``"controller.kp"``) and its grid (``NUM >= 2`` points, ``MIN < MAX``); a pattern
        (``"controller.*.kp"``) or a comma-separated list of paths sets every entry it
        matches, and names the axis as given. The two axes set different entries.
    contact, wall, event, period, periods
        The section and the orbits sought (:class:`~hybridpd.analysis.model_orbits.
        SectionSpec`): contact ``contact``'s impacts (``event="impact"``) or sticking
        releases (``"release"``), in whichever mode the motion crosses them;
        ``period`` returns per orbit (``"auto"``: the neighbours', then what a simulation
        shows, up to ``options["max_period"]``, default 4; each cell records its ``k``),
        ``periods`` reference periods per orbit (None: any whole number).
    tile : int
        Side of the square tiles (sweep chunks) in cells.
    repair_rounds : int
        Bound on the rounds of retries from neighbours after the sweep.
    executor, max_workers, store, progress
        As in :func:`hybridpd.sweeps.sweep.run_sweep` (a scheduler address runs the tiles on
        an existing Dask cluster; ``store``, a ``.zarr`` directory, is written as tiles
        finish and resumed from).
    options : dict, optional
        Further :class:`SectionSpec` fields (``tol``, ``max_iter``, ``transient``,
        ``t_max``).

    Returns
    -------
    ModelRegionMap

    Raises
    ------
    ValueError
        A path that names no numeric entry of the file (naming the entries that exist), a bad
        grid or section, before anything runs.

    Examples
    --------
    >>> from pathlib import Path
    >>> import hybridpd
    >>> f = Path(hybridpd.__file__).parents[1] / "examples" / "models" / "drivetrain.toml"
    >>> rm = model_region_map(f, ("controller.kp", 15, 25, 2), ("controller.kv", 4, 6, 2),
    ...                       event="release", progress=False) if f.exists() else None
    >>> rm is None or bool(rm.stable.all())
    True
    """
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.sweeps.sweep import run_sweep

    template = template_of(model)
    x_name, xs = _axis("x", x, template)
    y_name, ys = _axis("y", y, template)
    if x_name == y_name:
        raise ValueError(f"x and y must be different entries, both are {x_name!r}")
    both = sorted(set(template.resolve(x_name)) & set(template.resolve(y_name)))
    if both:
        raise ValueError(f"x ({x_name}) and y ({y_name}) must set different entries, both "
                         f"set {', '.join(both)}")
    spec = SectionSpec(contact=contact, wall=wall, event=event, period=period,
                       periods=periods, **dict(options or {}))
    if isinstance(tile, bool) or int(tile) != tile or tile < 1:
        raise ValueError(f"tile must be an int >= 1, got {tile!r}")
    base = template.model()
    try:        # the map's chart: the mode where the motion crosses the section at the file's
        main_mode = simulated_returns(base, spec).mode      # values (else the default one)
    except ValueError:
        main_mode = spec.mode or ""
    P = spec.section_map(base, main_mode or None)
    specd = {k: getattr(spec, k) for k in spec.__dataclass_fields__}
    nx, ny = len(xs), len(ys)
    order = _tile_order(nx, ny, int(tile))
    iy, ix = np.divmod(order, nx)
    points = {"x": xs[ix], "y": ys[iy], "ix": ix.astype(float), "iy": iy.astype(float)}
    t = int(tile)
    res = run_sweep(_tile_chunk, points, chunk_size=min(t * t, len(order)), executor=executor,
                    max_workers=max_workers, store=store, progress=progress,
                    label=f"region map of {Path(template.source).name}",
                    func_kwargs={"data": template.data, "source": template.source,
                                 "x_name": x_name, "y_name": y_name, "spec": specd,
                                 "dim": P.dim, "n": base.automaton.automaton.n_states,
                                 "main_mode": main_mode},
                    metadata={"kind": "model_region_map", "version": 2})
    ctx = _Context(template, specd, main_mode)
    a, n_rep = _repair(res.outputs, order, nx, ny, template, x_name, y_name, xs, ys, ctx,
                       repair_rounds)
    sh = (ny, nx)
    c = base.automaton.contacts[int(contact)]
    codes = sorted({int(v) for v in np.concatenate([a["mode"], a["mode2"]]) if v >= 0})
    meta = {"repaired_cells": int(n_rep), "executor": res.executor,
            "restitution": float(c.restitution) if getattr(c, "rigid", False) and
            c.restitution is not None else math.nan, "chart_mode": P.section.mode,
            "modes": {str(v): mode_name(base.automaton, v) for v in codes},
            "state_names": list(base.automaton.state_names)}
    grid = {k: a[k].reshape(*sh, *a[k].shape[1:]) for k in a}
    return ModelRegionMap(template.source, x_name, y_name, xs, ys, specd, P.section.names,
                          ctx.table, grid["status"], grid["rho"], grid["s"], grid["sig"],
                          grid["n_orbits"], grid["status2"], grid["rho2"], grid["s2"],
                          grid["sig2"], grid["attempts"], meta, grid["k"], grid["k2"],
                          grid["mode"], grid["mode2"], grid["z"], grid["t"], grid["z2"],
                          grid["t2"])
