"""The explorer's state and computations, without any web library.

A page of the explorer is one :class:`PairState`: the case, the plant (``e``, ``mu``,
``m2``, ``gamma``), the reference (``omega``, ``n``), the box of gains mapped
(``kp_min .. kp_max`` by ``kv_min .. kv_max`` on ``num`` points per axis), the selected gains
``kp, kv`` and the branch to follow (``branch`` along ``kp`` or ``kv`` up to ``stop``). The
state reads from and writes to a URL query (:func:`parse_query`, :func:`to_query`), so a view
is shared by its address. Every field is checked by the package's own validators: a bad
value gives their ``ValueError`` message, naming the parameter and its allowed range.

The computations call the package's APIs and nothing else: the region map is
:class:`hybridpd.pair.regions.SymmetricFamily` (vectorised closed form), the orbit
:func:`hybridpd.pair.orbits.symmetric_orbit` (what ``hybridpd orbit`` prints), the basin
:func:`hybridpd.sweeps.basins.basin_of_attraction` on the window of ``hybridpd basin``, the branch
:func:`hybridpd.pair.continuation.continue_symmetric`.
"""
from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass

import numpy as np

from hybridpd.model import (
    Case,
    ImpactPair,
    PDGains,
    check_axis,
    check_in_range,
    check_int,
    check_odd_order,
    check_positive,
)

__all__ = ["FIELDS", "MAP_FIELDS", "MAX_BASIN_NUM", "MAX_NUM", "PairState", "check_field",
           "finite_or_none", "map_classes", "orbit_series", "pair_basin", "pair_branch",
           "pair_map", "pair_orbit", "parse_query", "same_map", "snap", "timed_map", "to_query",
           "warm_map"]

#: Largest points per axis of the page's region map: 401 x 401 cells classify in about a
#: second, beyond that a control change would keep the page waiting.
MAX_NUM = 401
#: Largest points per axis of the page's basin slice (a 201 x 201 slice is ~4 times the 101 x
#: 101 default).
MAX_BASIN_NUM = 201

#: Names of the fields that are numbers (``case`` and ``branch`` are words).
FIELDS = ("case", "e", "mu", "m2", "gamma", "omega", "n", "kp_min", "kp_max", "kv_min",
          "kv_max", "num", "kp", "kv", "branch", "stop", "basin_num")


def _number(name: str, raw):
    """A query value as a number where it reads as one; anything else is handed on unchanged,
    so that the package's validator names it in its message."""
    if isinstance(raw, bytes):
        raw = raw.decode("utf-8", "replace")
    if isinstance(raw, str):
        s = raw.strip()
        try:
            return int(s) if name in ("n", "num", "basin_num") and s.lstrip("+-").isdigit() \
                else float(s)
        except ValueError:
            return raw
    return raw


def check_field(name: str, raw):
    """One field of the page, checked by the package's validator of that parameter.

    Parameters
    ----------
    name : str
        One of :data:`FIELDS`.
    raw : str, bytes or number
        The value as typed or read from the URL.

    Returns
    -------
    The value (``str`` for ``case`` and ``branch``, ``int`` for ``n``, ``num``,
    ``basin_num``, else ``float``).

    Raises
    ------
    ValueError
        The message of the package's validator (parameter and allowed range).

    Examples
    --------
    >>> check_field("e", "0.25")
    0.25
    >>> check_field("e", "1.5")
    Traceback (most recent call last):
    ...
    ValueError: e must lie in [0, 1], got 1.5
    """
    if name not in FIELDS:
        raise ValueError(f"field must be one of {', '.join(FIELDS)}, got {name!r}")
    if isinstance(raw, bytes):
        raw = raw.decode("utf-8", "replace")
    if name == "case":
        return Case.parse(raw).value
    if name == "branch":
        if raw not in ("kp", "kv"):
            raise ValueError(f"branch must be 'kp' or 'kv' (the gain followed), got {raw!r}")
        return raw
    v = _number(name, raw)
    if name == "e":
        return check_in_range("e", v, 0.0, 1.0)
    if name == "n":
        return check_odd_order(v)
    if name == "num":
        return check_int("num", v, 2, MAX_NUM)
    if name == "basin_num":
        return check_int("basin_num", v, 2, MAX_BASIN_NUM)
    return check_positive(name, v)


@dataclass(frozen=True)
class PairState:
    """What one page of the explorer shows (module docstring); every field checked.

    Examples
    --------
    >>> s = PairState(e=0.1, kp=12.0)
    >>> s.kp_axis()[[0, -1]].tolist(), s.gains()
    ([0.1, 50.0], (12.0, 20.0))
    >>> PairState(kp_min=60.0)
    Traceback (most recent call last):
    ...
    ValueError: kp range must be increasing (MIN < MAX), got (60.0, 50.0, 201)
    """

    case: str = "collocated"
    e: float = 0.5
    mu: float = 0.1
    m2: float = 1.0
    gamma: float = 0.75
    omega: float = 5.0
    n: int = 1
    kp_min: float = 0.1
    kp_max: float = 50.0
    kv_min: float = 0.1
    kv_max: float = 50.0
    num: int = 201
    kp: float = 10.0
    kv: float = 20.0
    branch: str = "kv"
    stop: float | None = None
    basin_num: int = 101

    def __post_init__(self):
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if v is not None or f.name != "stop":
                object.__setattr__(self, f.name, check_field(f.name, v))
        self.kp_axis()
        self.kv_axis()
        if self.stop is not None and self.stop == getattr(self, self.branch):
            raise ValueError(f"stop must differ from the start {self.branch} = "
                             f"{self.stop:g} (the branch's end value), got {self.stop:g}")

    def kp_axis(self) -> np.ndarray:
        """The map's ``kp`` grid."""
        return check_axis("kp", (self.kp_min, self.kp_max, self.num), min_num=2, positive=True)

    def kv_axis(self) -> np.ndarray:
        """The map's ``kv`` grid."""
        return check_axis("kv", (self.kv_min, self.kv_max, self.num), min_num=2, positive=True)

    def gains(self) -> tuple:
        return (self.kp, self.kv)

    def stop_value(self) -> float:
        """The branch's end: ``stop``, or by default the far end of the box along the gain
        followed (its other end when the gain sits on the far one)."""
        if self.stop is not None:
            return self.stop
        lo, hi = (self.kp_min, self.kp_max) if self.branch == "kp" else (self.kv_min,
                                                                           self.kv_max)
        return hi if getattr(self, self.branch) != hi else lo

    @property
    def L(self) -> float:
        """The half clearance, ``gamma x10`` with ``x10 = 1`` (CONVENTIONS.md, section 2)."""
        return self.gamma

    def pair(self) -> ImpactPair:
        return ImpactPair(self.mu, self.e, self.L, self.m2)

    def replace(self, **changes) -> PairState:
        """A copy with ``changes`` (checked)."""
        return dataclasses.replace(self, **changes)


def parse_query(query, base: PairState | None = None) -> tuple:
    """The state a URL query describes, and a message per refused field.

    Parameters
    ----------
    query : mapping of str to str, bytes or a list of them
        A query as parsed from the URL (Panel's ``session_args`` or
        :func:`urllib.parse.parse_qs`); the last value of a list counts. Unknown keys are
        ignored.
    base : PairState, optional
        The state the query changes (default :class:`PairState`'s defaults).

    Returns
    -------
    state : PairState
        The fields given and valid, ``base``'s for the others.
    errors : dict of str to str
        For every refused field, the validator's message (the field keeps its default).

    Examples
    --------
    >>> s, err = parse_query({"e": ["0.9"], "kp": [b"12.5"], "mu": "-1"})
    >>> s.e, s.kp, s.mu, err
    (0.9, 12.5, 0.1, {'mu': 'mu must be > 0 (allowed range (0, inf)), got -1.0'})
    """
    base = PairState() if base is None else base
    values, errors = {}, {}
    for name in FIELDS:
        if name not in query:
            continue
        raw = query[name]
        if isinstance(raw, (list, tuple)):
            if not raw:
                continue
            raw = raw[-1]
        try:
            values[name] = check_field(name, raw)
        except ValueError as exc:
            errors[name] = str(exc)
    return _consistent(base, values, errors), errors


def _consistent(base: PairState, values: dict, errors: dict) -> PairState:
    """A state from checked fields; a combination that is refused (an empty box, a branch
    ending where it starts) drops the fields it involves, each with the message."""
    groups = {"kp": ("kp_min", "kp_max", "num"), "kv": ("kv_min", "kv_max", "num")}
    for _ in range(3):          # the kp box, the kv box and the stop: each dropped once at most
        try:
            return dataclasses.replace(base, **values)
        except ValueError as exc:
            msg = str(exc)
            dropped = [k for k in groups.get(msg.split()[0], ("stop",)) if k in values]
            if not dropped:
                raise
            for k in dropped:
                errors[k] = msg
                values.pop(k)
    return dataclasses.replace(base, **values)


def to_query(state: PairState) -> dict:
    """The URL query of a state: every field, numbers in full precision (``repr``).

    Examples
    --------
    >>> q = to_query(PairState(kp=1 / 3))
    >>> q["kp"], parse_query(q)[0].kp == 1 / 3
    ('0.3333333333333333', True)
    """
    return {f.name: (v if isinstance(v := getattr(state, f.name), str) else repr(v))
            for f in dataclasses.fields(state) if getattr(state, f.name) is not None}


def pair_map(state: PairState):
    """The region map of the state's box at its ``e`` (one layer), vectorised closed form:
    :class:`hybridpd.pair.regions.SymmetricFamily` as in ``hybridpd regions``."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.regions import SymmetricFamily

    fam = SymmetricFamily(state.case, e=[state.e], mu=state.mu, omega=state.omega,
                          gamma=state.gamma, x10=1.0, m2=state.m2, n=state.n)
    return fam.classify_grid(("kp", state.kp_min, state.kp_max, state.num),
                             ("kv", state.kv_min, state.kv_max, state.num), progress=False)


#: The fields a region map depends on (the selection and the other panels' fields do not).
MAP_FIELDS = FIELDS[:12]


def same_map(a: PairState, b: PairState) -> bool:
    """Whether two states draw the same region map (:data:`MAP_FIELDS` equal).

    Examples
    --------
    >>> same_map(PairState(kp=3.0), PairState(kp=4.0)), same_map(PairState(e=0.1), PairState())
    (True, False)
    """
    return all(getattr(a, f) == getattr(b, f) for f in MAP_FIELDS)


def timed_map(state: PairState) -> tuple:
    """``(state, map, milliseconds)``: :func:`pair_map` and the time it took."""
    t0 = time.perf_counter()
    rm = pair_map(state)
    return state, rm, 1000 * (time.perf_counter() - t0)


def warm_map(state: PairState):
    """Start computing ``state``'s region map in a forked process: a future of ``(state,
    map, milliseconds)``.

    Run first when a server starts: the child, forked before the web libraries load, loads
    the compiled kernels and computes the map on the other core while the parent imports
    Panel, so the first page can show its map as it is built. Where processes cannot be
    forked (``spawn`` platforms) it runs on a thread instead. The process ends with its
    one job.
    """
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor

    try:
        if "fork" not in multiprocessing.get_all_start_methods():
            raise OSError("no fork on this platform")
        pool = ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("fork"))
        future = pool.submit(timed_map, state)
    except OSError:      # no fork, or no process to be had: the thread does the same work
        pool = ThreadPoolExecutor(1, thread_name_prefix="hybridpd-warm")
        future = pool.submit(timed_map, state)
    future.add_done_callback(lambda _f: pool.shutdown(wait=False))
    return future


def map_classes(rm) -> np.ndarray:
    """The classes drawn on the map, ``[iy, ix]`` of the first layer: 0 no orbit, 1 an
    unstable orbit, 2 a stable orbit."""
    return np.where(rm.stable[0], 2, np.where(rm.exists[0], 1, 0)).astype(np.int8)


def snap(state: PairState, x: float, y: float) -> tuple:
    """The grid point of the state's box nearest to ``(x, y) = (kp, kv)`` (a click).

    Examples
    --------
    >>> snap(PairState(kp_min=1, kp_max=3, kv_min=1, kv_max=3, num=3), 2.4, 0.2)
    (2.0, 1.0)
    """
    xs, ys = state.kp_axis(), state.kv_axis()
    ix = int(np.argmin(np.abs(xs - float(x))))
    iy = int(np.argmin(np.abs(ys - float(y))))
    return float(xs[ix]), float(ys[iy])


def pair_orbit(state: PairState):
    """The symmetric orbit at the selected gains: :func:`hybridpd.pair.orbits.symmetric_orbit`
    with exactly the arguments ``hybridpd orbit`` passes."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.orbits import symmetric_orbit

    return symmetric_orbit(state.pair(), PDGains(state.kp, state.kv), state.omega, x10=1.0,
                           n=state.n, case=state.case)


def orbit_series(orb, samples: int = 200) -> dict:
    """The orbit over one period ``n T`` from its ``+L`` impact: times and states.

    The second half-period is the first one mirrored (the orbit is symmetric about the
    origin, CONVENTIONS.md section 2), so one flight is evaluated and negated.

    Parameters
    ----------
    orb : SymmetricOrbitResult
        An orbit that exists.
    samples : int
        Points per half-period, at least 2.

    Returns
    -------
    dict
        ``t`` (shape ``(2 samples,)``), ``x1, y1, x2, y2`` and ``z3 = x1 - x2`` at those
        times (a NaN between the halves breaks the lines at the jump); ``impact_t``,
        ``impact_pre``, ``impact_post`` (shape ``(2, 4)``: the ``+L`` and ``-L`` impacts).
    """
    if not orb.exists:
        raise ValueError(f"the orbit does not exist ({orb.reason}): no time series")
    samples = check_int("samples", samples, 2)
    t = np.linspace(orb.t0, orb.t0 + orb.tau, samples)
    X = orb.flight(t)
    gap = np.full((1, 4), np.nan)
    XX = np.concatenate([X, gap, -X])
    tt = np.concatenate([t, [orb.t0 + orb.tau], t + orb.tau])
    return {"t": tt, "x1": XX[:, 0], "y1": XX[:, 1], "x2": XX[:, 2], "y2": XX[:, 3],
            "z3": XX[:, 0] - XX[:, 2],
            "impact_t": np.array([orb.t0, orb.t0 + orb.tau]),
            "impact_pre": np.stack([orb.pre_plus, orb.pre_minus]),
            "impact_post": np.stack([orb.post_plus, orb.post_minus])}


#: Iterations of each point of an unstable orbit's basin slice (no point converges to the
#: orbit: the iterations only look for other attractors; 1500 would take 10-12 s at 101 x 101).
UNSTABLE_ITERATIONS = 300


def pair_basin(orb, num: int = 101, progress=False):
    """The basin slice ``(x1, y1)`` through the orbit on ``hybridpd basin``'s default window
    (``x1`` in ``[-3, 5] x10``, ``y1`` in ``[-2, 10] x10``), ``num`` points per axis, the
    window kept (no extension, so the time stays bounded).

    A stable orbit's points run up to 1500 iterations of the impact map (as ``hybridpd
    basin``), stopping once they are within the orbit's certified ball. An unstable orbit
    attracts no open set of the slice, so no point stops early; its points run
    :data:`UNSTABLE_ITERATIONS` iterations, which only serve to find the other attractors in
    their tails (the basin's metadata ``n_iter`` says how many ran). ``progress``: False,
    True (stderr) or a callable ``progress(done, total)`` in points.
    """
    if not orb.exists:
        raise ValueError(f"no symmetric orbit at these parameters: {orb.reason}")
    num = check_int("basin_num", num, 2, MAX_BASIN_NUM)
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.analysis.mappers import Growth
    from hybridpd.reproduce.basins import orbit_mapper
    from hybridpd.reproduce.settings import Settings
    from hybridpd.sweeps.basins import basin_of_attraction

    win = Settings.__dataclass_fields__["basin_window"].default
    n_iter = 1500 if orb.stable else UNSTABLE_ITERATIONS
    # Growth(0): the one window, the edges its orbit's basin touches reported
    return basin_of_attraction(orbit_mapper(orb, n_iter=n_iter),
                               (win[0] * orb.x10, win[1] * orb.x10, num),
                               (win[2] * orb.x10, win[3] * orb.x10, num), grow=Growth(0),
                               progress=progress)


def pair_branch(state: PairState):
    """The symmetric family followed from the selected gains along ``state.branch`` up to
    ``state.stop``, its events located: :func:`hybridpd.pair.continuation.continue_symmetric`
    (closed form; bounded by its ``max_steps``, it says why it stopped)."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.continuation import continue_symmetric

    return continue_symmetric(state.pair(), PDGains(state.kp, state.kv), state.omega,
                              state.branch, state.stop_value(), x10=1.0, n=state.n, case=state.case)


def finite_or_none(x):
    """A float for JSON and the page, ``None`` where not finite or missing."""
    if x is None:
        return None
    x = float(x)
    return x if math.isfinite(x) else None
