"""The closed loop of a mechanical system under one or several controllers.

Signals and sign conventions (as in :mod:`hybridpd.loop` for the impact pair)
------------------------------------------------------------------------------
Each controller ``i`` (a :class:`ControlChannel`) has its own:

* measurement ``y_i = c_i . q`` and ``y_i' = cv_i . v`` with ``c_i`` the measured direction
  (a DOF name gives ``c = e_m``) and ``cv_i = c_i`` unless a separate velocity sensor is
  given (``measure_velocity``, e.g. a tachometer on the motor and an encoder on the load);
  "collocated" / "non-collocated" is the choice of measured DOF;
* reference ``xd_i`` from an exosystem (:class:`hybridpd.model.Reference`, the same class as
  the impact pair's): ``offset + sum_j a_j cos(w_j t)`` in absolute time, each sine generated
  by ``pc' = -w ps``, ``ps' = w pc`` (``pc = a cos w t``); controllers with identical
  references (same amplitudes, frequencies and offset) share one exosystem;
* tracking error ``err_i = xd_i - y_i``, ``err_dot_i = xd_i' - y_i'``; the controller is a
  proper linear system (PD gains, a ``Controller`` or a python-control system) from ``err``
  (1 input) or ``[err, err_dot]`` (2 inputs) to the feedback force ``u_fb``
  (:func:`hybridpd.loop.as_controller`). A PD is the static gain ``[kp, kv]`` on
  ``[err, err_dot]`` (any finite gains, ``kv = 0`` included);
* control force ``u_i = feedforward_i * xd_i'' + u_fb_i`` (``reference.feedforward``,
  ``None`` = 0), applied along its direction ``a_i`` (``actuate``; default the system's
  ``B``): the generalised force is ``sum_i a_i u_i``.

Continuous controllers (``dt = 0``) are part of one autonomous LTI flow, written out directly
(python-control is not imported, so loading a model is cheap); a single continuous controller
may instead be joined with :func:`control.interconnect` (``method="interconnect"``,
:func:`hybridpd.loop.interconnect_matrices`). A discrete-time controller (``dt > 0``) is its
own sampled-data channel: the plant and exosystem flow with its force held constant
(zero-order hold), and at its sampling instants ``t0 + k dt`` the automaton jumps (a clock
state ``s`` with ``s' = 1`` and the affine guard ``s >= dt``; the reset ``s -> s - dt`` keeps
the instants free of drift). At a sample the controller reads ``err_k``, computes
``u_k = feedforward xd''(t_k) + C x_k + D err_k``, updates ``x_{k+1} = A x_k + B err_k``, and
``u_k`` is applied after ``delay`` whole samples (held in a shift register). Every sampled
controller takes its first sample at the run's start ``t0``; each has its own clock, so
different periods are allowed.

State layout
------------
``z = [q_1, v_1, ..., q_n, v_n, exo..., ctrl..., then per sampled controller hold..., clock]``:
the exosystem states (``pc, ps`` for one sine, ``pc1, ps1, ...`` for several, ``r`` for a
constant offset), the controller states ``c1, ...``, and, per sampled controller, the held
forces ``h0, ..., h_delay`` (``h_delay`` is applied) and its clock ``s``. With several
controllers every name of a controller's own states is prefixed by ``k{i}.`` (``k0.c1``,
``k1.h0``, ``k1.s``), and so are the exosystem states when the references differ (by the first
controller tracking each: ``k0.pc``); one controller keeps the plain names.
"""
from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.loop import Controller, as_controller, interconnect_matrices
from hybridpd.mechanics.system import MechanicalSystem
from hybridpd.model import Reference, check_finite

__all__ = ["ControlChannel", "LoopChannel", "MechanicalLoop", "Reference", "common_period",
           "mechanical_loop"]

#: largest denominator of the ratio of two periods for them to have a common period
COMMON_PERIOD_MAX_RATIO = 64
#: relative tolerance of that ratio
COMMON_PERIOD_RTOL = 1e-9


def common_period(periods, max_ratio: int = COMMON_PERIOD_MAX_RATIO,
                  rtol: float = COMMON_PERIOD_RTOL):
    """The smallest common multiple of positive ``periods``, or ``None`` if there is none.

    Each period divided by the smallest one must be a fraction ``p / q`` with
    ``q <= max_ratio`` within the relative tolerance ``rtol``; the common period is then the
    smallest one times the least common multiple of the numerators ``p``.

    Parameters
    ----------
    periods : sequence of float
        Positive, finite (time units); at least one.
    max_ratio : int
    rtol : float

    Returns
    -------
    float or None

    Examples
    --------
    >>> common_period([1e-3, 2.5e-3])        # two sampling periods: every 5 ms together
    0.005
    >>> round(common_period([2 * np.pi / 2.0, 2 * np.pi / 3.0]) / np.pi, 12)   # w = 2 and 3
    2.0
    >>> common_period([1.0, np.sqrt(2.0)]) is None
    True
    """
    ps = [float(p) for p in periods]
    if not ps or not all(math.isfinite(p) and p > 0 for p in ps):
        raise ValueError(f"periods must be positive finite numbers, got {periods!r}")
    base = min(ps)
    lcm = 1
    for p in ps:
        x = p / base
        f = Fraction(x).limit_denominator(int(max_ratio))
        if abs(x - float(f)) > rtol * x:
            return None
        lcm = math.lcm(lcm, f.numerator)
    return base * lcm


@dataclass(frozen=True, eq=False)  # array fields: identity semantics
class ControlChannel:
    """One controller of a mechanical loop: what it measures, where it acts, what it tracks.

    Parameters
    ----------
    controller : (kp, kv), {"kp", "kv"}, PDGains, Controller or python-control LTI system
        From ``err`` or ``[err, err_dot]`` to ``u_fb``; continuous, or discrete with
        ``dt > 0`` (its own sampling period, zero-order hold). Normalised on construction
        (:func:`hybridpd.loop.as_controller`), so ``controller`` is a ``Controller``.
    measure : str or array_like, shape (n,)
        The measured DOF (name) or direction ``c`` (weights over the DOFs, not all zero).
    actuate : str or array_like, shape (n,), optional
        The DOF (name) or direction ``a`` along which this controller's force acts; default
        the system's input direction ``B``.
    reference : Reference, optional
        What this controller tracks; default the loop's ``reference``.
    measure_velocity : str or array_like, shape (n,), optional
        Where the velocity fed to ``err_dot`` is measured (default: as ``measure``).
    delay : int
        Input delay in whole samples (discrete controllers only), ``>= 0``.

    Examples
    --------
    >>> ch = ControlChannel((10.0, 2.0), measure="x2", actuate="x2")
    >>> ch.controller.gains, ch.delay
    ((10.0, 2.0), 0)
    """

    controller: object
    measure: object
    actuate: object = None
    reference: Reference | None = None
    measure_velocity: object = None
    delay: int = 0
    __repr__ = compact_repr

    def __post_init__(self):
        ctrl = as_controller(self.controller)
        delay = self.delay
        try:
            whole = not isinstance(delay, bool) and int(delay) == delay and delay >= 0
        except (TypeError, ValueError):
            whole = False
        if not whole:
            raise ValueError(f"delay must be an int >= 0 (samples), got {delay!r}")
        if delay and not ctrl.dt:
            raise ValueError("delay (whole samples) needs a discrete-time controller (dt > 0)")
        if self.reference is not None and not isinstance(self.reference, Reference):
            raise ValueError(f"reference must be a Reference or None, got "
                             f"{type(self.reference).__name__}")
        for name in ("measure", "actuate", "measure_velocity"):
            v = getattr(self, name)
            if name != "measure" and v is None:
                continue
            if not isinstance(v, (str, Sequence, np.ndarray)) or isinstance(v, bytes):
                raise ValueError(f"{name} must be a DOF name or a list of weights over the "
                                 f"DOFs, got {type(v).__name__}")
        object.__setattr__(self, "controller", ctrl)
        object.__setattr__(self, "delay", int(delay))


@dataclass(frozen=True, eq=False)  # array fields: identity semantics
class LoopChannel:
    """One controller as it sits in a :class:`MechanicalLoop` (directions resolved, indices
    into the loop state).

    Attributes
    ----------
    index : int
        Position in the loop's list of controllers.
    controller : hybridpd.loop.Controller
    reference : Reference
        What it tracks.
    measure, measure_velocity, actuate : ndarray, shape (n,)
        Directions ``c``, ``cv`` and ``a``.
    delay : int
    force : ndarray, shape (N,)
        Its control force ``u_i = force @ z``.
    exo, ctrl, hold : ndarray of int
        State indices of its exosystem (possibly shared), controller states and held forces
        (``hold`` empty when continuous).
    clock : int
        State index of its clock (``-1`` when continuous).
    sample_reset : (R, r) or None
        Its sampling jump ``z+ = R z + r`` (sampled only): its controller states, hold
        register and clock change, nothing else.
    guard : str
        Name of its sampling guard in the automaton (``""`` when continuous).
    """

    index: int
    controller: Controller = field(repr=False)
    reference: Reference
    measure: np.ndarray
    measure_velocity: np.ndarray
    actuate: np.ndarray
    delay: int
    force: np.ndarray = field(repr=False)
    exo: np.ndarray = field(repr=False)
    ctrl: np.ndarray = field(repr=False)
    hold: np.ndarray = field(repr=False)
    clock: int
    sample_reset: tuple | None = field(repr=False)
    guard: str
    __repr__ = compact_repr

    @property
    def dt(self) -> float:
        """Sampling period (0: continuous)."""
        return self.controller.dt

    @property
    def sampled(self) -> bool:
        """True for a discrete-time controller."""
        return self.controller.dt > 0


@dataclass(frozen=True, eq=False)  # array fields: identity semantics
class MechanicalLoop:
    """The closed loop between contacts (no contact forces), ``z' = A z + b``.

    The single-controller attributes (``measure``, ``measure_velocity``, ``controller``,
    ``delay``, ``force``) describe the only controller; with several they describe the first
    one, and :attr:`channels` describes each.

    Attributes
    ----------
    system : MechanicalSystem
    reference : Reference
        The loop's reference (the one given to :func:`mechanical_loop`; the first
        controller's when none was given); per controller :attr:`references`.
    measure : ndarray, shape (n,)
        Measured direction ``c`` (``y = c . q``).
    measure_velocity : ndarray, shape (n,)
        Direction of the measured velocity ``c_v`` (``y' = c_v . v``).
    controller : hybridpd.loop.Controller
        The controller (inputs ``err[, err_dot]``, output ``u_fb``); discrete if ``dt > 0``.
    dt : float
        Sampling period of the single sampled controller (0: none is sampled). With several
        sampled controllers: their common period, the shortest time after which every clock
        is back where it was (:func:`common_period`), NaN when they have none; each period is
        in :attr:`clocks`.
    delay : int
        Input delay in whole samples (sampled-data only).
    A : ndarray, shape (N, N)
    b : ndarray, shape (N,)
        Free flow; ``b`` is zero except ``b[clock] = 1`` for every sampling clock.
    force : ndarray, shape (N,)
        The applied control force ``u = force @ z`` (all of them: :attr:`forces`).
    sample_reset : (R, r) or None
        Affine jump ``z+ = R z + r`` at a sampling instant (sampled-data only); with several
        sampled controllers the jump of all of them at once (as at ``t0``), each one's own in
        :attr:`channels`.
    state_names : tuple of str
    layout : dict
        Index arrays: ``q``, ``v`` (shape ``(n,)``), ``exo``, ``ctrl``, ``hold`` (all
        controllers', may be empty) and ``clock`` (the first clock's index, ``-1`` if no
        controller is sampled).
    channels : tuple of LoopChannel
        Every controller, in order.
    """

    system: MechanicalSystem
    reference: Reference
    measure: np.ndarray
    measure_velocity: np.ndarray
    controller: object = field(repr=False)
    dt: float
    delay: int
    A: np.ndarray = field(repr=False)
    b: np.ndarray = field(repr=False)
    force: np.ndarray = field(repr=False)
    sample_reset: tuple | None = field(repr=False)
    state_names: tuple
    layout: dict = field(repr=False)
    channels: tuple = field(repr=False)
    __repr__ = compact_repr

    @functools.cached_property
    def sys(self):
        """The flow as a python-control ``StateSpace`` (no inputs; outputs ``[q, v, U]`` in
        the order of ``state_names``, ``U0, U1, ...`` with several controllers), built on
        first access. In a sampled-data loop this is the continuous part between samples
        (the affine clock term is left out)."""
        import control as ct

        n2 = 2 * self.system.n
        F = self.forces
        C = np.vstack([np.eye(n2, self.n_states), F])
        us = ["U"] if len(F) == 1 else [f"U{i}" for i in range(len(F))]
        outs = list(self.state_names[:n2]) + us
        return ct.ss(self.A, np.zeros((self.n_states, 0)), C, np.zeros((len(outs), 0)),
                     states=list(self.state_names), outputs=outs, name="closed_loop")

    @property
    def n_states(self) -> int:
        """Dimension ``N`` of the closed-loop state."""
        return self.A.shape[0]

    @property
    def sampled(self) -> bool:
        """True when some controller is sampled (discrete-time)."""
        return bool(self.clocks)

    @property
    def clocks(self) -> tuple:
        """``((index, dt), ...)``: the state index of every sampling clock and its period, one
        per sampled controller in controller order.

        Each clock is the time since its controller's last sample, ``(t - t0) mod dt`` for a
        run started at ``t0`` (the first sample is taken at ``t0``); empty when continuous.
        """
        return tuple((int(ch.clock), float(ch.dt)) for ch in self.channels if ch.sampled)

    @property
    def forces(self) -> np.ndarray:
        """Every controller's force ``u_i = forces[i] @ z``, shape ``(m, N)``; the first row
        is :attr:`force`."""
        return np.array([self.force] + [ch.force for ch in self.channels[1:]])

    @property
    def references(self) -> tuple:
        """The reference of every controller, in order."""
        return tuple(ch.reference for ch in self.channels)

    @property
    def reference_period(self) -> float | None:
        """The common period of every sine of every reference (:func:`common_period`), or
        ``None`` when no reference has a sine.

        Raises ``ValueError`` when the frequencies have no common period (ratios of periods
        with denominators up to 64, relative tolerance 1e-9).
        """
        ws = sorted({w for r in self.references for w in r.omegas})
        if not ws:
            return None
        T = common_period([2.0 * math.pi / w for w in ws])
        if T is None:
            raise ValueError(f"the references' frequencies {ws} have no common period (ratios "
                             f"of periods p/q with q <= {COMMON_PERIOD_MAX_RATIO})")
        return T

    def exo_state(self, t) -> np.ndarray:
        """The exosystem states ``z[layout["exo"]]`` at time(s) ``t``, shape ``(..., ne)``."""
        t = np.asarray(t, dtype=float)
        out = np.zeros(t.shape + (self.layout["exo"].size,))
        base = int(self.layout["exo"][0]) if self.layout["exo"].size else 0
        done = set()
        for ch in self.channels:
            key = int(ch.exo[0]) if ch.exo.size else -1
            if key < 0 or key in done:
                continue
            done.add(key)
            out[..., ch.exo - base] = ch.reference.exo_state(t)
        return out

    def initial_state(self, q0, v0, t0: float = 0.0, controller_state=None) -> np.ndarray:
        """Full state at ``t0``: exosystem set from ``t0``, controller states (default 0).

        ``controller_state`` holds every controller's states (``layout["ctrl"]``). Every
        sampled controller takes its first sample at ``t0`` (its reset is applied, its clock
        set to 0).
        """
        n = self.system.n
        q0 = np.asarray(q0, dtype=float).reshape(-1)
        v0 = np.asarray(v0, dtype=float).reshape(-1)
        if q0.shape != (n,) or v0.shape != (n,):
            raise ValueError(f"initial q and v must have shape ({n},), got {q0.shape} and "
                             f"{v0.shape}")
        if not (np.all(np.isfinite(q0)) and np.all(np.isfinite(v0))):
            raise ValueError("initial q and v must be finite")
        t0 = check_finite("t0", t0)
        z = np.zeros(self.n_states)
        z[self.layout["q"]] = q0
        z[self.layout["v"]] = v0
        z[self.layout["exo"]] = self.exo_state(t0)
        k = self.layout["ctrl"].size
        if controller_state is not None:
            c = np.asarray(controller_state, dtype=float).reshape(-1)
            if c.shape != (k,):
                raise ValueError(f"controller_state must have shape ({k},), got {c.shape}")
            z[self.layout["ctrl"]] = c
        if self.sampled:
            R, r = self.sample_reset
            z = R @ z + r
            for i, _ in self.clocks:
                z[i] = 0.0
        return z


def _direction(system, value, key):
    """A DOF name or ``n`` weights as a direction over the DOFs; ``ValueError`` naming key."""
    if isinstance(value, str):
        c = np.zeros(system.n)
        try:
            c[system.index(value)] = 1.0
        except ValueError as exc:
            raise ValueError(f"{key}: {exc}") from None
        return c
    try:
        c = np.array(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise ValueError(f"{key} must be a DOF name or a list of {system.n} weights") from None
    if c.shape != (system.n,) or not np.all(np.isfinite(c)):
        raise ValueError(f"{key} must be a DOF name or {system.n} finite weights, got "
                         f"shape {c.shape}")
    if not np.any(c):
        raise ValueError(f"{key}: all {system.n} weights are zero (give a DOF name or "
                         "weights that are not all zero)")
    return c


def _channels_given(controller) -> bool:
    if isinstance(controller, ControlChannel):
        return True
    return (isinstance(controller, (list, tuple)) and len(controller) > 0
            and all(isinstance(c, ControlChannel) for c in controller))


def mechanical_loop(system: MechanicalSystem, controller, reference: Reference | None = None,
                    measure=None, delay: int = 0, measure_velocity=None, *,
                    method: str = "auto") -> MechanicalLoop:
    """Close the loop around ``system`` (see the module docstring for the conventions).

    Either one controller (``controller``, ``measure``, ``delay``, ``measure_velocity``,
    acting along the system's ``B``), or several: ``controller`` a list of
    :class:`ControlChannel` (each with its measurement, direction, reference and delay;
    ``measure``, ``delay`` and ``measure_velocity`` are then not given).

    Parameters
    ----------
    system : MechanicalSystem
    controller : (kp, kv), Controller, python-control LTI system, or list of ControlChannel
        From ``err`` or ``[err, err_dot]`` to ``u_fb``; continuous, or discrete with
        ``dt > 0`` (sampled-data loop with zero-order hold). Gains may be any finite numbers.
    reference : Reference, optional
        Tracked by every controller that has no reference of its own (required unless each
        has one).
    measure : str or array_like, shape (n,)
        The measured DOF (name) or direction ``c`` (one controller only; required then).
    delay : int
        Input delay in whole samples (discrete controllers only), ``>= 0``.
    measure_velocity : str or array_like, shape (n,), optional
        Where the velocity fed to ``err_dot`` is measured (default: as ``measure``).
    method : {"auto", "interconnect"}
        How a continuous loop is built: written out directly (default) or, for one
        controller, with :func:`control.interconnect`; the tests check that both agree.

    Returns
    -------
    MechanicalLoop

    Examples
    --------
    The impact pair of the paper (``m1 = 0.1``, ``m2 = 1``), collocated PD:

    >>> sysm = MechanicalSystem(["x1", "x2"], M=[[0.1, 0], [0, 1.0]], B=[0, 1])
    >>> cl = mechanical_loop(sysm, (10.0, 20.0), Reference.sine(1.0, 5.0, 1.0), "x2")
    >>> cl.state_names
    ('x1', 'x1_dot', 'x2', 'x2_dot', 'pc', 'ps')
    >>> cl.force
    array([   0.,    0.,  -10.,  -20.,  -15., -100.])

    Two controllers, a continuous PD on ``x1`` and a PD sampled at 1 kHz on ``x2``, each
    acting on the DOF it measures (the system needs no ``B``):

    >>> two = MechanicalSystem(["x1", "x2"], M=[[1.0, 0], [0, 1.0]], K=[[2, -1], [-1, 1]])
    >>> import control as ct
    >>> pd_1khz = ct.ss([], [], [], [[30.0, 4.0]], 1e-3)
    >>> cl = mechanical_loop(two, [ControlChannel((10.0, 2.0), "x1", actuate="x1"),
    ...                            ControlChannel(pd_1khz, "x2", actuate="x2")],
    ...                      Reference.sine(0.5, 6.283185307179586))
    >>> cl.state_names
    ('x1', 'x1_dot', 'x2', 'x2_dot', 'pc', 'ps', 'k1.h0', 'k1.s')
    >>> cl.clocks, cl.reference_period
    (((7, 0.001),), 1.0)
    """
    if not isinstance(system, MechanicalSystem):
        raise ValueError("system must be a MechanicalSystem")
    if reference is not None and not isinstance(reference, Reference):
        raise ValueError("reference must be a Reference")
    if method not in ("auto", "interconnect"):
        raise ValueError(f"method must be 'auto' or 'interconnect', got {method!r}")
    if _channels_given(controller):
        chans = (controller,) if isinstance(controller, ControlChannel) else tuple(controller)
        if measure is not None or measure_velocity is not None or delay:
            raise ValueError("measure, measure_velocity and delay belong to each ControlChannel "
                             "when the controllers are given as ControlChannel")
        where = ["controller"] if len(chans) == 1 else [f"controller[{i}]"
                                                          for i in range(len(chans))]
    else:
        if measure is None:
            raise ValueError("measure is required (the measured DOF or direction)")
        chans = (ControlChannel(controller, measure, None, None, measure_velocity, delay),)
        where = [""]
    resolved = [_resolve(system, ch, reference, w) for ch, w in zip(chans, where)]
    if method == "interconnect" and len(resolved) > 1:
        raise ValueError("method='interconnect' builds one continuous controller; write "
                         "several out (method='auto')")
    if resolved[0][0].dt:
        method = "auto"         # a sampled-data loop has no interconnection to choose
    return _build(system, resolved, reference, method)


def _resolve(system, ch: ControlChannel, reference, where):
    """``(ctrl, c, cv, a, ref, delay)`` of a channel; errors name ``where``."""
    pre = f"{where}." if where else ""
    c = _direction(system, ch.measure, f"{pre}measure")
    cv = c if ch.measure_velocity is None else _direction(system, ch.measure_velocity,
                                                          f"{pre}measure_velocity")
    if ch.actuate is not None:
        a = _direction(system, ch.actuate, f"{pre}actuate")
    elif system.B is not None:
        a = system.B
    elif where:
        raise ValueError(f"{pre}actuate is required: the system has no input direction B")
    else:
        raise ValueError("the system has no input direction B: give MechanicalSystem(B=...) "
                         "or the controller as a ControlChannel with actuate")
    ref = ch.reference if ch.reference is not None else reference
    if ref is None:
        raise ValueError(f"{pre}reference is required (none given for the loop either)")
    return ch.controller, c, cv, a, ref, ch.delay


def _plant(system):
    """Plant flow ``Ap`` without control in the state order ``[q1, v1, ...]``."""
    n = system.n
    Minv = system.Minv
    A = np.zeros((2 * n, 2 * n))
    A[0::2, 1::2] = np.eye(n)
    A[1::2, 0::2] = -Minv @ system.K
    A[1::2, 1::2] = -Minv @ system.C
    return A


def _exo_groups(refs):
    """Group the references by exosystem: ``(group of each channel, first channel of each
    group)``; identical amplitudes, frequencies and offset share one exosystem."""
    keys, first, group = [], [], []
    for i, r in enumerate(refs):
        key = (r.amplitudes, r.omegas, r.offset)
        if key not in keys:
            keys.append(key)
            first.append(i)
        group.append(keys.index(key))
    return group, first


def _build(system, resolved, reference, method):
    """Assemble the loop (state layout in the module docstring)."""
    m = len(resolved)
    refs = [r[4] for r in resolved]
    group, first = _exo_groups(refs)
    n2 = 2 * system.n
    names = list(system.state_names())
    exo_idx, pos = [], n2
    for i in first:
        en = refs[i].exo_names
        exo_idx.append(np.arange(pos, pos + len(en)))
        names += list(en) if len(first) == 1 else [f"k{i}.{s}" for s in en]
        pos += len(en)
    pre = [""] * m if m == 1 else [f"k{i}." for i in range(m)]
    ctrl_idx = []
    for i, (ctrl, *_) in enumerate(resolved):
        ctrl_idx.append(np.arange(pos, pos + ctrl.n_states))
        names += [pre[i] + s for s in ctrl.state_names]
        pos += ctrl.n_states
    hold_idx, clock_idx = [np.arange(0)] * m, [-1] * m
    for i, (ctrl, *_, delay) in enumerate(resolved):
        if ctrl.dt:
            hold_idx[i] = np.arange(pos, pos + delay + 1)
            clock_idx[i] = pos + delay + 1
            names += [f"{pre[i]}h{j}" for j in range(delay + 1)] + [pre[i] + "s"]
            pos += delay + 2
    N = pos
    n_sampled = sum(1 for r in resolved if r[0].dt)
    A = np.zeros((N, N))
    Ap = _plant(system)
    A[:n2, :n2] = Ap
    for g, i in enumerate(first):
        ix = exo_idx[g]
        A[np.ix_(ix, ix)] = refs[i].exo_matrices()[0]
    b = np.zeros(N)
    channels = []
    for i, (ctrl, c, cv, a, ref, delay) in enumerate(resolved):
        bp = np.zeros(n2)
        bp[1::2] = np.linalg.solve(system.M, a)
        cy, cyd = np.zeros(n2), np.zeros(n2)
        cy[0::2], cyd[1::2] = c, cv
        if method == "interconnect":
            A, force = interconnect_matrices(Ap, bp, cy, cyd, ref, ctrl,
                                             ref.feedforward or 0.0)
            reset = None
        else:
            force, reset = _channel(A, b, bp, cy, cyd, ref, ctrl, exo_idx[group[i]],
                                    ctrl_idx[i], hold_idx[i], clock_idx[i])
        guard = "" if not ctrl.dt else ("sample" if n_sampled == 1 else f"sample{i}")
        channels.append(LoopChannel(i, ctrl, ref, c, cv, a, delay, force, exo_idx[group[i]],
                                    ctrl_idx[i], hold_idx[i], int(clock_idx[i]), reset,
                                    guard))
    channels = tuple(channels)
    empty = np.arange(0)
    sampled = [ch for ch in channels if ch.sampled]
    layout = {"q": np.arange(0, n2, 2), "v": np.arange(1, n2, 2),
              "exo": np.concatenate(exo_idx) if exo_idx else empty,
              "ctrl": np.concatenate(ctrl_idx) if ctrl_idx else empty,
              "hold": np.concatenate([ch.hold for ch in sampled]) if sampled else empty,
              "clock": sampled[0].clock if sampled else -1}
    if len(sampled) == 1:
        dt = sampled[0].dt
    elif sampled:
        dt = common_period([ch.dt for ch in sampled])
        dt = math.nan if dt is None else dt
    else:
        dt = 0.0
    first_ch = channels[0]
    return MechanicalLoop(system=system, reference=reference if reference is not None
                          else first_ch.reference, measure=first_ch.measure,
                          measure_velocity=first_ch.measure_velocity,
                          controller=first_ch.controller, dt=dt, delay=first_ch.delay, A=A,
                          b=b, force=first_ch.force, sample_reset=_joint_reset(sampled, N),
                          state_names=tuple(names), layout=layout, channels=channels)


def _channel(A, b, bp, cy, cyd, ref, ctrl: Controller, ie, ic, ih, clock):
    """Write one controller into ``A`` and ``b`` (in place); ``(force row, sample reset)``.

    Continuous: its force ``ff xd'' + C c + D e`` drives the plant along ``bp`` and its states
    flow by ``A c + B e``. Sampled: the oldest held force drives the plant, and at its samples
    the reset updates its states, shifts its hold register and winds its clock back.
    """
    N, n2, k = A.shape[0], bp.size, ctrl.n_states
    xd, vd, ad, y, yd = np.zeros((5, N))
    xd[ie], vd[ie], ad[ie] = ref.exo_matrices()[1]
    y[:n2], yd[:n2] = cy, cyd
    E = np.vstack([xd - y, vd - yd])[:ctrl.n_inputs]    # (ninputs, N): the inputs
    S = np.zeros((k, N))
    S[:, ic] = np.eye(k)
    law = (ref.feedforward or 0.0) * ad + (ctrl.C @ S)[0] + (ctrl.D @ E)[0]
    if not ctrl.dt:
        A[:n2] += np.outer(bp, law)
        if k:
            A[ic] = ctrl.A @ S + ctrl.B @ E
        return law, None
    A[:n2, ih[-1]] += bp
    b[clock] = 1.0
    R = np.eye(N)
    if k:
        R[ic] = ctrl.A @ S + ctrl.B @ E
    for j in range(ih.size - 1, 0, -1):              # shift register of the delayed forces
        R[ih[j]] = 0.0
        R[ih[j], ih[j - 1]] = 1.0
    R[ih[0]] = law
    r = np.zeros(N)
    r[clock] = -ctrl.dt
    force = np.zeros(N)
    force[ih[-1]] = 1.0
    return force, (R, r)


def _joint_reset(sampled, N):
    """The jump of every sampled controller at once (they touch disjoint states and read only
    the plant and exosystem, so the order does not matter); None if none is sampled."""
    if not sampled:
        return None
    if len(sampled) == 1:
        return sampled[0].sample_reset
    R, r = np.eye(N), np.zeros(N)
    for ch in sampled:
        Ri, ri = ch.sample_reset
        rows = np.concatenate([ch.ctrl, ch.hold, [ch.clock]])
        R[rows] = Ri[rows]
        r[rows] = ri[rows]
    return R, r
