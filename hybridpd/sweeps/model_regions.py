"""Region maps of any model file: where a periodic orbit of a section exists and is stable.

:class:`ModelSearch`, a family of :func:`hybridpd.sweeps.regions.region_map`, sweeps two
numeric entries of a model file (dotted paths,
:mod:`hybridpd.mechanics.params`) over a grid and, per cell, looks for the periodic orbits of
one section (a contact's impacts or sticking releases, ``k`` returns per orbit) with
:func:`hybridpd.analysis.model_orbits.solve_at`:

* **Continuation across the grid.** The grid is cut into square tiles (one sweep chunk
  each, so tiles run in parallel on any executor); inside a tile the cells are visited in
  snake order and each starts Newton from the secant predictor of the two cells before it
  in a line (their orbits of one family, extrapolated), then from its solved neighbours'
  orbits, and from a simulation of the model only where they give no orbit (or only
  unstable ones where a neighbour's was stable).
* **No holes from solver trouble.** After the sweep, every cell without an orbit that has a
  neighbour with one, and every cell next to a neighbour with an orbit that looks like
  another family than each of its own (other impact signature, or farther than
  ``FAMILY_DISTANCE``), is tried again from those orbits, in rounds until nothing changes;
  an orbit linked to one of the cell's own is not retried, since Newton from it lands on
  that orbit again (each cell records which neighbour's orbit its orbits continue, or
  landed on). Inside a tile the links join the orbits into families, and a seed of a
  family that gave an orbit is not tried again. A seed that looks like another family
  first takes a few chord steps with the ``DP`` of each orbit already known in the cell
  (:func:`~hybridpd.analysis.model_orbits.solve_at`): one that lands on such an orbit
  costs no Newton run, and a neighbour's orbit retried without result is not retried in
  a later round. So a cell is reported without an orbit only when Newton failed from every
  neighbour's solution and from a simulation. Each round counts its cells on the progress
  report; why the rounds stopped is ``metadata["repair_stopped"]``.
* **Both orbits.** Distinct orbits found in one cell are all counted (``n_orbits``); the
  first two are kept (stable first).

Every orbit is checked by :func:`~hybridpd.analysis.periodic.find_orbit` (whole number of
reference periods, transversal, a simulated period returns to it; on the stroboscopic
section the Newton residual of an orbit continued from a neighbour is that simulation). The result is the one
:class:`~hybridpd.sweeps.regions.RegionMap` (one layer) with the variables ``status``,
``n_orbits``, ``attempts``, ``section_point``, ``signature``, ``period`` (returns ``k`` per
period), ``section_mode``, ``section_state``, ``section_time`` and those of the second orbit
(suffix ``2``). The per-cell work does not depend on the executor, so results are identical
for serial, process-pool and cluster runs, and a run resumes from its Zarr store.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from hybridpd.analysis.model_orbits import (
    STATUS,
    OrbitSearch,
    SectionSpec,
    Seed,
    signature_codes,
    signature_table,
    solve_at,
)
from hybridpd.analysis.model_sections import fix_section
from hybridpd.mechanics.params import ModelTemplate
from hybridpd.mechanics.sections import mode_code, mode_name
from hybridpd.sweeps.regions import RegionMap

__all__ = ["ModelSearch", "template_of"]

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
    (``s``), its full state and time (``z``, ``t``), its returns per period (``k``), its
    section's mode (``mode``, :func:`~hybridpd.mechanics.sections.mode_code`) and its
    ``DP^k`` in that mode's chart (``jac``, top-left block of an ``n x n`` array), with
    which the repair rounds test cheaply whether a neighbour's orbit lands on it."""

    _SLOTS = (("status", "rho", "s", "sig", "z", "t", "k", "mode", "jac"),
              ("status2", "rho2", "s2", "sig2", "z2", "t2", "k2", "mode2", "jac2"))

    def __init__(self, m, dim, n):
        # per stored orbit, the neighbour's orbit it continues: 2 * (flat grid index) + slot
        self.a = {"n_orbits": np.zeros(m, np.int64), "attempts": np.zeros(m, np.int64),
                  "from": np.full((m, 2), -1, np.int64)}
        for j, names in enumerate(self._SLOTS):
            st, rho, s, sig, z, t, k, mode, jac = names
            self.a.update({st: np.full(m, 2 if j == 0 else -1, np.int64),
                           rho: np.full(m, np.nan), s: np.full((m, dim), np.nan),
                           sig: np.full((m, _SIG_LEN), -1, np.int16),
                           z: np.full((m, n), np.nan), t: np.full(m, np.nan),
                           k: np.zeros(m, np.int64), mode: np.full(m, -1, np.int64),
                           jac: np.full((m, n, n), np.nan)})
        self.orbits = {}

    def _store(self, p, slot, o, seed, ctx):
        st, rho, s, sig, z, t, k, mode, jac = self._SLOTS[slot]
        self.a[st][p] = 0 if o.stable else 1
        self.a[rho][p] = o.spectral_radius
        self.a[s][p] = ctx.chart.from_state(seed.z, seed.t)
        self.a[sig][p] = signature_codes(o.signature, ctx.table, _SIG_LEN)
        self.a[z][p], self.a[t][p], self.a[k][p] = seed.z, seed.t, seed.period
        self.a[mode][p] = mode_code(ctx.model.automaton, seed.mode)
        self.a[jac][p] = np.nan
        if seed.jacobian is not None:
            d = seed.jacobian.shape[0]
            self.a[jac][p, :d, :d] = seed.jacobian

    def _seeds(self, res, ctx):
        return [Seed.of(o, ctx.maps(o.mode)) for o in res.orbits]

    def put(self, p, res, ctx, origin=None):
        """Store the orbits of `res`; ``origin(seed)`` gives the code of the neighbour's orbit
        a seed came from (-1: none)."""
        self.a["status"][p] = res.status
        self.a["attempts"][p] += res.attempts
        self.a["n_orbits"][p] = len(res.orbits)
        seeds = self._seeds(res, ctx)
        self.orbits[p] = seeds
        for j, (o, sd) in enumerate(zip(res.orbits[:2], seeds)):
            self._store(p, j, o, sd, ctx)
            self.a["from"][p, j] = _origin_code(res, j, origin)

    def add(self, p, res, ctx, origin=None) -> bool:
        """Merge the new orbits of `res` (searched with this cell's orbits as ``known``)."""
        if not res.orbits:
            self.a["attempts"][p] += res.attempts
            return False
        if self.a["n_orbits"][p] == 0:
            self.put(p, res, ctx, origin)
            return True
        self.a["attempts"][p] += res.attempts
        new = list(zip(res.orbits, self._seeds(res, ctx)))
        fr = self.a["from"]
        if new[0][0].stable and self.a["status"][p] != 0:
            # a stable orbit comes first: the old first orbit moves to the second slot
            for a, b in zip(*self._SLOTS):
                self.a[b][p] = self.a[a][p]
            fr[p, 1] = fr[p, 0]
            self._store(p, 0, *new.pop(0), ctx)
            fr[p, 0] = _origin_code(res, 0, origin)
        elif self.a["status2"][p] < 0:
            self._store(p, 1, *new[0], ctx)
            fr[p, 1] = _origin_code(res, 0, origin)
        self.a["n_orbits"][p] += len(res.orbits)
        self.orbits[p] = self.orbits[p] + [sd for _, sd in zip(res.orbits, self._seeds(res,
                                                                                         ctx))]
        return True

    def seeds_of(self, p, ctx) -> list:
        """The stored orbits of cell `p` as seeds (repair rounds)."""
        out = []
        for names in self._SLOTS:
            _, _, _, sig, z, t, k, mode, jac = names
            if np.all(np.isfinite(self.a[z][p])):
                codes = self.a[sig][p]
                name = mode_name(ctx.model.automaton, self.a[mode][p])
                d = ctx.maps(name).dim
                DP = self.a[jac][p, :d, :d]
                out.append(Seed(self.a[z][p].copy(), float(self.a[t][p]),
                                tuple(ctx.table[c] for c in codes if c >= 0),
                                int(self.a[k][p]), name, bool(self.a[names[0]][p] == 0),
                                DP.copy() if np.all(np.isfinite(DP)) else None))
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


def _solve_cell(template, values, spec, seeds, simulate, known=(), families=None):
    try:
        model = template.model(values)
    except ValueError as exc:
        return OrbitSearch(10, (), 0, str(exc))
    return solve_at(model, spec, seeds, simulate=simulate, known=known, families=families)


def _tile_chunk(chunk, *, data, source, x_name, y_name, spec, dim, n, main_mode, nx):
    """One tile (module-level: runs in worker processes): continuation in visiting order."""
    template = ModelTemplate(data, source)
    ctx = _Context(template, spec, main_mode)
    ix, iy = chunk["ix"].astype(int), chunk["iy"].astype(int)
    m = len(ix)
    cells = _Cells(m, dim, n)
    where = {(int(iy[p]), int(ix[p])): p for p in range(m)}
    fam = _Families(np.zeros((0, 2), np.int64))

    def code(q, j):
        return 2 * int(iy[q] * nx + ix[q]) + j

    for p in range(m):
        codes = {}      # id(seed) -> the code of the neighbour's orbit it comes from
        seeds = []
        for sd, q1 in _predicted(cells, where, p, int(iy[p]), int(ix[p]), ctx):
            codes[id(sd)] = code(q1, 0)
            seeds.append(sd)
        for dy, dx in _NEIGH:
            q = where.get((iy[p] + dy, ix[p] + dx))
            if q is not None and q < p:
                for j, sd in enumerate(cells.orbits.get(q, [])[:2]):
                    codes[id(sd)] = code(q, j)
                seeds += cells.orbits.get(q, [])
        families = [fam.root(codes[id(sd)]) if id(sd) in codes else None for sd in seeds]
        res = _solve_cell(template, {x_name: chunk["x"][p], y_name: chunk["y"][p]}, ctx.spec,
                          seeds, True, families=families)
        cells.put(p, res, ctx, lambda sd, codes=codes: codes.get(id(sd), -1))
        for j in range(2):
            if cells.a["from"][p, j] >= 0:
                fam.join(code(p, j), int(cells.a["from"][p, j]))
        for sd, j in res.also:        # other neighbours' orbits that continue orbit j
            if j < 2 and codes.get(id(sd), -1) >= 0:
                fam.join(code(p, j), codes[id(sd)])
    return cells.a


def _origin_code(res, j, origin) -> int:
    """The code of the neighbour's orbit that orbit `j` of `res` continues (-1: none)."""
    if origin is None or j >= len(res.origins) or res.origins[j] is None:
        return -1
    return int(origin(res.origins[j]))


def _predicted(cells, where, p, iy, ix, ctx) -> list:
    """The secant predictor of cell `p`: ``2 a - b`` from the first orbits ``a`` and ``b`` of
    the two cells before it in a line (solved earlier), when they are of one family (states
    and times extrapolated, the phase difference wrapped); at most one ``(seed, q)``, ``q``
    the chunk index of the cell of ``a``."""
    for dy, dx in ((0, -1), (0, 1), (-1, 0), (1, 0)):
        q1, q2 = where.get((iy + dy, ix + dx)), where.get((iy + 2 * dy, ix + 2 * dx))
        if q1 is None or q2 is None or q1 >= p or q2 >= p:
            continue
        a, b = cells.orbits.get(q1, []), cells.orbits.get(q2, [])
        if not a or not b:
            continue
        period = ctx.maps(a[0].mode).section.period
        if a[0].other_family(b[0], period):
            continue
        dt = a[0].t - b[0].t
        if period:
            dt = (dt + 0.5 * period) % period - 0.5 * period
        return [(replace(a[0], z=2.0 * a[0].z - b[0].z, t=a[0].t + dt), q1)]
    return []


class _Families:
    """The orbits of the grid joined into families by continuation (a union-find over the
    codes ``2 * cell + slot``): an orbit found from a neighbour's orbit is of its family."""

    def __init__(self, fr):
        self.parent, self.edges = {}, set()
        for p, row in enumerate(fr):
            for j, code in enumerate(row):
                if code >= 0:
                    self.join(2 * p + j, int(code))

    def root(self, c):
        path = []
        while self.parent.get(c, c) != c:
            path.append(c)
            c = self.parent[c]
        for x in path:             # path compression: later look-ups are short
            self.parent[x] = c
        return c

    def linked(self, a, b) -> bool:
        """Whether orbit `a` was continued from `b`, or `b` from `a`, or one landed on the
        other (a direct link, not through the family)."""
        return (min(a, b), max(a, b)) in self.edges

    def join(self, a, b):
        self.edges.add((min(a, b), max(a, b)))
        ra, rb = self.root(a), self.root(b)
        if ra != rb:
            self.parent[max(ra, rb)] = min(ra, rb)


def _retry_seeds(cells, fam, p, q, ctx) -> list:
    """The orbits of neighbour `q` that cell `p` retries: not linked directly to one of its
    own (continued from or to it, or found to land on it: Newton from it would land there
    again), and of another family than each own orbit by the seeds' test. Links through a
    chain of cells are not enough: where the map is discontinuous (an impact crossing a
    sample instant) two orbits close together each continue to the neighbours."""
    own = cells.orbits[p]
    return [o for i, o in enumerate(cells.orbits[q])
            if not (i < 2 and any(fam.linked(2 * p + j, 2 * q + i)
                                  for j in range(min(len(own), 2))))
            and all(o.other_family(k, ctx.maps(k.mode).section.period) for k in own)]


def _repair(out, order, nx, ny, template, x_name, y_name, xs, ys, ctx, rounds,
            progress=True):
    """Rounds of retries from every neighbour's orbits (module docstring), each round's
    cells counted by a progress report. Returns the cells (grid order), the number of cells
    that gained an orbit and why the rounds stopped (``"no cell gained an orbit"`` after
    how many rounds, or the bound `rounds` reached)."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.sweeps.progress import Progress

    m = nx * ny
    cells = _Cells(m, out["s"].shape[1], out["z"].shape[1])
    inv = np.empty(m, int)
    inv[order] = np.arange(m)
    for k in cells.a:       # grid order (flat iy * nx + ix)
        cells.a[k] = out[k][inv].copy()
    for p in range(m):
        cells.orbits[p] = cells.seeds_of(p, ctx)
    fam = _Families(cells.a["from"])
    changed_total = 0
    todo = range(m)
    # (cell, neighbour's orbit) pairs already retried: a cell's orbits only grow, so a
    # retry that found nothing new finds nothing in a later round either
    tried = set()
    stop = f"the bound of {int(rounds)} rounds reached"
    for r in range(int(rounds)):
        changed = set()
        with Progress(len(todo), f"{Path(template.source).name}: repair round {r + 1}",
                      enabled=bool(progress), unit="cell") as bar:
            _repair_round(cells, fam, sorted(todo), tried, changed, bar, nx, ny, template,
                          x_name, y_name, xs, ys, ctx)
        changed_total += len(changed)
        if not changed:
            stop = f"no cell gained an orbit in round {r + 1}"
            break
        todo = {(q // nx + dy) * nx + q % nx + dx for q in changed for dy, dx in _NEIGH
                if 0 <= q // nx + dy < ny and 0 <= q % nx + dx < nx}
    return cells.a, changed_total, stop


def _repair_round(cells, fam, todo, tried, changed, bar, nx, ny, template, x_name, y_name,
                  xs, ys, ctx):
    """One repair round over the cells `todo`: those that gain an orbit go into `changed`."""
    for p in todo:
        bar.update()
        iy, ix = divmod(p, nx)
        own = cells.orbits[p]
        codes, seeds = {}, []
        for dy, dx in _NEIGH:
            if 0 <= iy + dy < ny and 0 <= ix + dx < nx:
                q = (iy + dy) * nx + ix + dx
                for o in _retry_seeds(cells, fam, p, q, ctx):
                    if (p, id(o)) in tried:
                        continue
                    tried.add((p, id(o)))
                    i = cells.orbits[q].index(o)
                    codes[id(o)] = 2 * q + i if i < 2 else -1
                    seeds.append(o)
        if not seeds:
            continue
        res = _solve_cell(template, {x_name: xs[ix], y_name: ys[iy]}, ctx.spec, seeds,
                          False, own, [fam.root(codes[id(o)]) if codes[id(o)] >= 0
                                       else None for o in seeds])
        for sd, i in res.matched:     # a neighbour's orbit that continues an own one
            if sd is not None and codes.get(id(sd), -1) >= 0 and i < 2:
                fam.join(2 * p + i, codes[id(sd)])
        if cells.add(p, res, ctx, lambda sd, codes=codes: codes.get(id(sd), -1)):
            changed.add(p)
            for j in range(2):
                if cells.a["from"][p, j] >= 0:
                    fam.join(2 * p + j, int(cells.a["from"][p, j]))


@dataclass(frozen=True, eq=False)
class ModelSearch:
    """A model file's periodic orbits of one section: a family of
    :func:`~hybridpd.sweeps.regions.region_map`, searched cell by cell (module docstring).

    Parameters
    ----------
    model : str, Path, dict or ModelTemplate
        The model file (or its parsed tables).
    contact, wall, event, period, periods
        The section and the orbits sought (:class:`~hybridpd.analysis.model_orbits.
        SectionSpec`): by default (``event="auto"``) the stroboscopic section (its phase
        chosen once from a simulation at the file's values), else contact ``contact``'s
        impacts (``event="impact"``) or sticking releases (``"release"``), in whichever
        mode the motion crosses them;
        ``period`` returns per orbit (``"auto"``: the neighbours', then what a simulation
        shows, up to ``options["max_period"]``, default 4; each cell records its ``k``),
        ``periods`` reference periods per orbit (None: any whole number).
    options : dict, optional
        Further :class:`SectionSpec` fields (``tol``, ``max_iter``, ``transient``,
        ``t_max``).

    Examples
    --------
    >>> from pathlib import Path
    >>> import hybridpd
    >>> f = Path(hybridpd.__file__).parents[1] / "examples" / "models" / "drivetrain.toml"
    >>> rm = hybridpd.region_map(ModelSearch(f, event="release"), ("controller.kp", 15, 25, 2),
    ...                          ("controller.kv", 4, 6, 2), progress=False) \\
    ...     if f.exists() else None
    >>> rm is None or bool(rm.stable.all())
    True
    """

    model: object
    contact: int = 0
    wall: int | None = None
    event: str = "auto"
    period: object = "auto"
    periods: int | None = None
    options: dict | None = None

    def classify_grid(self, x, y, *, tile: int = 8, repair_rounds: int = 20,
                      executor="serial", max_workers=None, store=None,
                      progress: bool = True):
        """Map where a periodic orbit of the section exists and is stable.

        Parameters
        ----------
        x, y : (str, float, float, int)
            ``(KEY, MIN, MAX, NUM)``: a dotted path of a numeric entry of the file
            (``"controller.kp"``) and its grid (``NUM >= 2`` points, ``MIN < MAX``); a
            pattern (``"controller.*.kp"``) or a comma-separated list of paths sets every
            entry it matches, and names the axis as given. The two axes set different
            entries.
        tile : int
            Side of the square tiles (sweep chunks) in cells.
        repair_rounds : int
            Bound on the rounds of retries from neighbours after the sweep.
        executor, max_workers, store, progress
            As in :func:`hybridpd.sweeps.sweep.run_sweep` (a scheduler address runs the
            tiles on an existing Dask cluster; ``store``, a ``.zarr`` directory, is written
            as tiles finish and resumed from).

        Returns
        -------
        RegionMap
            One layer (``e``: the section contact's restitution, NaN for a compliant one),
            the variables of the module docstring.

        Raises
        ------
        ValueError
            A path that names no numeric entry of the file (naming the entries that exist),
            a bad grid or section, before anything runs.
        """
        template = template_of(self.model)
        x_name, xs = _axis("x", x, template)
        y_name, ys = _axis("y", y, template)
        if x_name == y_name:
            raise ValueError(f"x and y must be different entries, both are {x_name!r}")
        both = sorted(set(template.resolve(x_name)) & set(template.resolve(y_name)))
        if both:
            raise ValueError(f"x ({x_name}) and y ({y_name}) must set different entries, "
                             f"both set {', '.join(both)}")
        spec = SectionSpec(contact=self.contact, wall=self.wall, event=self.event,
                           period=self.period, periods=self.periods,
                           **dict(self.options or {}))
        if isinstance(tile, bool) or int(tile) != tile or tile < 1:
            raise ValueError(f"tile must be an int >= 1, got {tile!r}")
        # the section actually used (its event and phase fixed once) is what the map records
        a, meta, P, spec = _search(template, spec, x_name, xs, y_name, ys, int(tile),
                                   repair_rounds, executor=executor, max_workers=max_workers,
                                   store=store, progress=progress)
        return _region_map_of(template, spec, x_name, xs, y_name, ys, a, meta, P)


def _search(template, spec, x_name, xs, y_name, ys, tile, repair_rounds, **sweep):
    """The tiles on the executor, then the repair rounds: per-cell arrays in grid order,
    the metadata, the map of the chart and the section spec used (fixed)."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.sweeps.sweep import run_sweep

    base = template.model()
    # one section for every cell (its event, the stroboscopic phase) and the map's chart:
    # the mode of the section point of the motion at the file's values (else the default)
    spec, main_mode, _ = fix_section(base, spec)
    P = spec.section_map(base, main_mode or None)
    specd = {k: getattr(spec, k) for k in spec.__dataclass_fields__}
    nx, ny = len(xs), len(ys)
    order = _tile_order(nx, ny, tile)
    iy, ix = np.divmod(order, nx)
    points = {"x": xs[ix], "y": ys[iy], "ix": ix.astype(float), "iy": iy.astype(float)}
    res = run_sweep(_tile_chunk, points, chunk_size=min(tile * tile, len(order)),
                    label=f"region map of {Path(template.source).name}",
                    func_kwargs={"data": template.data, "source": template.source,
                                 "x_name": x_name, "y_name": y_name, "spec": specd,
                                 "dim": P.dim, "n": base.automaton.automaton.n_states,
                                 "main_mode": main_mode, "nx": nx},
                    metadata={"kind": "model_region_map", "version": 3}, **sweep)
    ctx = _Context(template, specd, main_mode)
    a, n_rep, stop = _repair(res.outputs, order, nx, ny, template, x_name, y_name, xs, ys,
                             ctx, repair_rounds, sweep.get("progress", True))
    return a, {"repaired_cells": int(n_rep), "repair_stopped": stop, "executor": res.executor,
               "sig_table": [list(p) for p in ctx.table]}, P, spec


#: The variables of a model's region map and the arrays of the search they come from.
_VARIABLES = {"status": "status", "n_orbits": "n_orbits", "attempts": "attempts",
              "status2": "status2", "spectral_radius2": "rho2", "section_point": "s",
              "section_point2": "s2", "signature": "sig", "signature2": "sig2",
              "period": "k", "period2": "k2", "section_mode": "mode",
              "section_mode2": "mode2", "section_state": "z", "section_time": "t",
              "section_state2": "z2", "section_time2": "t2"}


def _region_map_of(template, spec, x_name, xs, y_name, ys, a, meta, P):
    """The :class:`~hybridpd.sweeps.regions.RegionMap` of a search (one layer)."""
    base = template.model()
    c = base.automaton.contacts[int(spec.contact)]
    rigid = getattr(c, "rigid", False) and c.restitution is not None
    codes = sorted({int(v) for v in np.concatenate([a["mode"], a["mode2"]]) if v >= 0})
    specd = {k: getattr(spec, k) for k in spec.__dataclass_fields__}
    flags = {"values": sorted(STATUS), "meanings": " ".join(STATUS[k] for k in sorted(STATUS))}
    meta = dict(meta, chart_mode=P.section.mode, spec=specd, coords=list(P.section.names),
                restitution=float(c.restitution) if rigid else math.nan,
                modes={str(v): mode_name(base.automaton, v) for v in codes},
                state_names=list(base.automaton.state_names),
                reasons={str(k): v for k, v in STATUS.items()},
                flags={"status": flags, "status2": flags})
    grid = {k: a[src].reshape(1, len(ys), len(xs), *a[src].shape[1:])
            for k, src in _VARIABLES.items()}
    exists = grid["n_orbits"] > 0
    fixed = {"model": template.source, **{f"section_{k}": v for k, v in specd.items()}}
    return RegionMap(Path(template.source).name, x_name, y_name, xs, ys,
                     np.array([meta["restitution"]]), fixed, exists, grid["status"] == 0,
                     a["rho"].reshape(1, len(ys), len(xs)),
                     np.where(exists, 0, grid["status"]).astype(np.int64), grid, meta)
