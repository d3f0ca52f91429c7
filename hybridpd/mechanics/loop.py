"""The closed loop of a mechanical system.

Signals and sign conventions (as in :mod:`hybridpd.loop` for the impact pair)
------------------------------------------------------------------------------
* Measurement: ``y = c . q`` and ``y' = c_v . v`` with ``c`` the measured direction (a DOF
  name gives ``c = e_m``) and ``c_v = c`` unless a separate velocity sensor is given
  (``measure_velocity``, e.g. a tachometer on the motor and an encoder on the load);
  "collocated" / "non-collocated" is the choice of measured DOF.
* Reference ``xd`` from an exosystem (:class:`hybridpd.model.Reference`, the same class as
  the impact pair's): ``offset + sum_i a_i cos(w_i t)`` in absolute time, each sine generated
  by ``pc' = -w ps``, ``ps' = w pc`` (``pc = a cos w t``).
* Tracking error ``err = xd - y``, ``err_dot = xd' - y'``; the controller is a proper linear
  system (PD gains, a ``Controller`` or a python-control system) from ``err`` (1 input) or
  ``[err, err_dot]`` (2 inputs) to the feedback force ``u_fb``
  (:func:`hybridpd.loop.as_controller`). A PD is the static gain
  ``[kp, kv]`` on ``[err, err_dot]`` (any finite gains, ``kv = 0`` included).
* Control force ``u = feedforward * xd'' + u_fb`` (``reference.feedforward``, ``None`` = 0),
  applied along ``B``.

Continuous controllers (``dt = 0``) give one autonomous LTI system, written out directly by
:func:`hybridpd.loop.loop_matrices` (the builder the impact pair uses too; python-control is
not imported, so loading a model is cheap) or, with ``method="interconnect"``, joined with
:func:`control.interconnect`. A discrete-time controller (``dt > 0``) runs as a sampled-data loop:
the plant and exosystem flow with the force held constant (zero-order hold), and at the
sampling instants ``t0 + k dt`` the automaton jumps (a clock state ``s`` with ``s' = 1`` and
the affine guard ``s >= dt``; the reset ``s -> s - dt`` keeps the instants free of drift).
At a sample the controller reads ``err_k``, computes ``u_k = feedforward xd''(t_k) + C x_k +
D err_k``, updates ``x_{k+1} = A x_k + B err_k``, and ``u_k`` is applied after ``delay`` whole
samples (held in a shift register). The first sample is taken at ``t0``.

State layout
------------
``z = [q_1, v_1, ..., q_n, v_n, exo..., ctrl..., hold..., clock]``: the exosystem states
(``pc, ps`` for one sine, ``pc1, ps1, ...`` for several, ``r`` for a constant offset), the
controller states ``c1, ...``, and, in a sampled-data loop only, the held forces
``h0, ..., h_delay`` (``h_delay`` is applied) and the clock ``s``.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np

from hybridpd._repr import compact_repr
from hybridpd.loop import (
    Controller,
    _signal_rows,
    as_controller,
    interconnect_matrices,
    loop_matrices,
)
from hybridpd.mechanics.system import MechanicalSystem
from hybridpd.model import Reference, check_finite

__all__ = ["MechanicalLoop", "Reference", "mechanical_loop"]


@dataclass(frozen=True, eq=False)  # array fields: identity semantics
class MechanicalLoop:
    """The closed loop between contacts (no contact forces), ``z' = A z + b``.

    Attributes
    ----------
    system : MechanicalSystem
    reference : Reference
    measure : ndarray, shape (n,)
        Measured direction ``c`` (``y = c . q``).
    measure_velocity : ndarray, shape (n,)
        Direction of the measured velocity ``c_v`` (``y' = c_v . v``).
    controller : hybridpd.loop.Controller
        The controller (inputs ``err[, err_dot]``, output ``u_fb``); discrete if ``dt > 0``.
    dt : float
        Sampling period (0: continuous controller).
    delay : int
        Input delay in whole samples (sampled-data only).
    A : ndarray, shape (N, N)
    b : ndarray, shape (N,)
        Free flow; ``b`` is zero except ``b[clock] = 1`` in a sampled-data loop.
    force : ndarray, shape (N,)
        The applied control force ``u = force @ z``.
    sample_reset : (R, r) or None
        Affine jump ``z+ = R z + r`` at a sampling instant (sampled-data only).
    state_names : tuple of str
    layout : dict
        Index arrays: ``q``, ``v`` (shape ``(n,)``), ``exo``, ``ctrl``, ``hold`` (may be empty)
        and ``clock`` (``-1`` if continuous).
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
    __repr__ = compact_repr

    @functools.cached_property
    def sys(self):
        """The flow as a python-control ``StateSpace`` (no inputs; outputs ``[q, v, u]`` in
        the order of ``state_names``), built on first access. In a sampled-data loop this is
        the continuous part between samples (the affine clock term is left out)."""
        import control as ct

        n2 = 2 * self.system.n
        C = np.vstack([np.eye(n2, self.n_states), self.force])
        outs = list(self.state_names[:n2]) + ["U"]
        return ct.ss(self.A, np.zeros((self.n_states, 0)), C, np.zeros((n2 + 1, 0)),
                     states=list(self.state_names), outputs=outs, name="closed_loop")

    @property
    def n_states(self) -> int:
        """Dimension ``N`` of the closed-loop state."""
        return self.A.shape[0]

    @property
    def sampled(self) -> bool:
        """True for a sampled-data (discrete controller) loop."""
        return self.dt > 0

    @property
    def clocks(self) -> tuple:
        """``((index, dt), ...)``: the state index of every sampling clock and its period.

        Each clock is the time since its controller's last sample, ``(t - t0) mod dt`` for a
        run started at ``t0`` (the first sample is taken at ``t0``); empty when continuous.
        """
        return ((int(self.layout["clock"]), float(self.dt)),) if self.sampled else ()

    def initial_state(self, q0, v0, t0: float = 0.0, controller_state=None) -> np.ndarray:
        """Full state at ``t0``: exosystem set from ``t0``, controller states (default 0).

        In a sampled-data loop the first sample is taken at ``t0`` (the reset is applied).
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
        z[self.layout["exo"]] = self.reference.exo_state(t0)
        k = self.layout["ctrl"].size
        if controller_state is not None:
            c = np.asarray(controller_state, dtype=float).reshape(-1)
            if c.shape != (k,):
                raise ValueError(f"controller_state must have shape ({k},), got {c.shape}")
            z[self.layout["ctrl"]] = c
        if self.sampled:
            R, r = self.sample_reset
            z = R @ z + r
            z[self.layout["clock"]] = 0.0
        return z


def _measure_vector(system, measure):
    if isinstance(measure, str):
        c = np.zeros(system.n)
        c[system.index(measure)] = 1.0
        return c
    try:
        c = np.array(measure, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise ValueError("measure must be a DOF name or a list of n weights") from None
    if c.shape != (system.n,) or not np.all(np.isfinite(c)) or not np.any(c):
        raise ValueError(f"measure must be a DOF name or {system.n} finite weights, not all 0")
    return c


def mechanical_loop(system: MechanicalSystem, controller, reference: Reference, measure,
                    delay: int = 0, measure_velocity=None, *,
                    method: str = "auto") -> MechanicalLoop:
    """Close the loop around ``system`` (see the module docstring for the conventions).

    Parameters
    ----------
    system : MechanicalSystem
    controller : (kp, kv), Controller or python-control LTI system
        From ``err`` or ``[err, err_dot]`` to ``u_fb``; continuous, or discrete with
        ``dt > 0`` (sampled-data loop with zero-order hold). Gains may be any finite numbers.
    reference : Reference
    measure : str or array_like, shape (n,)
        The measured DOF (name) or direction ``c``.
    delay : int
        Input delay in whole samples (discrete controllers only), ``>= 0``.
    measure_velocity : str or array_like, shape (n,), optional
        Where the velocity fed to ``err_dot`` is measured (default: as ``measure``).
    method : {"auto", "interconnect"}
        How a continuous loop is built: written out directly (default) or with
        :func:`control.interconnect`; the tests check that both agree.

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
    """
    if not isinstance(system, MechanicalSystem):
        raise ValueError("system must be a MechanicalSystem")
    if not isinstance(reference, Reference):
        raise ValueError("reference must be a Reference")
    if method not in ("auto", "interconnect"):
        raise ValueError(f"method must be 'auto' or 'interconnect', got {method!r}")
    c = _measure_vector(system, measure)
    cv = c if measure_velocity is None else _measure_vector(system, measure_velocity)
    ctrl = as_controller(controller)
    if isinstance(delay, bool) or int(delay) != delay or delay < 0:
        raise ValueError(f"delay must be an int >= 0 (samples), got {delay!r}")
    delay = int(delay)
    if delay and not ctrl.dt:
        raise ValueError("delay (whole samples) needs a discrete-time controller (dt > 0)")
    plant = _plant(system, c, cv)
    ff = reference.feedforward or 0.0
    n2, ne, nc = 2 * system.n, len(reference.exo_names), ctrl.n_states
    names = system.state_names() + reference.exo_names + ctrl.state_names
    layout = {"q": np.arange(0, n2, 2), "v": np.arange(1, n2, 2),
              "exo": np.arange(n2, n2 + ne), "ctrl": np.arange(n2 + ne, n2 + ne + nc),
              "hold": np.arange(0), "clock": -1}
    common = dict(system=system, reference=reference, measure=c, measure_velocity=cv,
                  controller=ctrl, dt=ctrl.dt, delay=delay)
    if not ctrl.dt:
        build = loop_matrices if method == "auto" else interconnect_matrices
        A, force = build(*plant, reference, ctrl, ff)
        return MechanicalLoop(**common, A=A, b=np.zeros(A.shape[0]), force=force,
                              sample_reset=None, state_names=names, layout=layout)
    return _sampled(common, plant, reference, ctrl, ff, names, layout)


def _plant(system, c, cv):
    """``(Ap, bp, cy, cyd)`` of the mechanical plant in the state order ``[q1, v1, ...]``."""
    n = system.n
    Minv = system.Minv
    A = np.zeros((2 * n, 2 * n))
    A[0::2, 1::2] = np.eye(n)
    A[1::2, 0::2] = -Minv @ system.K
    A[1::2, 1::2] = -Minv @ system.C
    b = np.zeros(2 * n)
    b[1::2] = system.Minv_B
    cy, cyd = np.zeros(2 * n), np.zeros(2 * n)
    cy[0::2], cyd[1::2] = c, cv
    return A, b, cy, cyd


def _sampled(common, plant, ref, ctrl: Controller, ff, names, layout):
    """Sampled-data loop: the plant flows under the held force; controller, hold register and
    clock jump at the samples (state ``[plant, exo, ctrl, h0..h_delay, s]``)."""
    Ap, bp, cy, cyd = plant
    exo_A, exo_C = ref.exo_matrices()
    n2, ne, nc, nh = Ap.shape[0], exo_A.shape[0], ctrl.n_states, common["delay"] + 1
    N = n2 + ne + nc + nh + 1
    ic, ih, clock = layout["ctrl"], np.arange(n2 + ne + nc, N - 1), N - 1
    A = np.zeros((N, N))
    A[:n2, :n2] = Ap
    A[:n2, ih[-1]] = bp                            # the oldest held force acts
    A[n2:n2 + ne, n2:n2 + ne] = exo_A
    b = np.zeros(N)
    b[clock] = 1.0
    xd, vd, ad, y, yd = _signal_rows(n2, cy, cyd, exo_C, N)
    E = np.vstack([xd - y, vd - yd])[:ctrl.n_inputs]    # (ninputs, N): the sampled inputs
    S = np.zeros((nc, N))
    S[:, ic] = np.eye(nc)
    R = np.eye(N)
    if nc:
        R[ic] = ctrl.A @ S + ctrl.B @ E
    for i in range(nh - 1, 0, -1):                 # shift register of the delayed forces
        R[ih[i]] = 0.0
        R[ih[i], ih[i - 1]] = 1.0
    R[ih[0]] = ff * ad + (ctrl.C @ S)[0] + (ctrl.D @ E)[0]
    r = np.zeros(N)
    r[clock] = -ctrl.dt
    force = np.zeros(N)
    force[ih[-1]] = 1.0
    layout = dict(layout, hold=ih, clock=clock)
    names = names + tuple(f"h{i}" for i in range(nh)) + ("s",)
    return MechanicalLoop(**common, A=A, b=b, force=force, sample_reset=(R, r),
                          state_names=names, layout=layout)
