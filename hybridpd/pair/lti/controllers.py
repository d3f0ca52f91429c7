"""Common controllers as python-control objects: filtered PD, filtered PID, lead-lag.

Each constructor returns a 1-input (``err = xd - x``), 1-output (``u_fb``)
``control.TransferFunction`` for :func:`hybridpd.pair.lti.lti_symmetric_orbit` and the
controlled pair's general section map (signal conventions: :mod:`hybridpd.pair.lti`).
python-control is imported only when a controller is built.
"""
from __future__ import annotations

import numpy as np

from hybridpd.model import check_positive

__all__ = ["filtered_pd", "filtered_pid", "lead_lag"]


def filtered_pd(kp: float, kv: float, tf: float, name: str = "filtered_pd"):
    """PD with a first-order derivative filter, ``C(s) = kp + kv s / (tf s + 1)``.

    Parameters
    ----------
    kp : float
        Proportional gain (force/length), ``> 0``.
    kv : float
        Derivative gain (force time/length), ``> 0``.
    tf : float
        Filter time constant (time), ``> 0``. As ``tf -> 0`` the loop tends to the PD (3) with
        an ``O(tf)`` error.
    name : str
        python-control system name.

    Returns
    -------
    control.TransferFunction
        1 input ``err = xd - x``, 1 output ``u_fb``, one state once realised.

    Examples
    --------
    >>> C = filtered_pd(10, 20, 0.01)
    >>> bool(abs(C(0) - 10) < 1e-12), bool(abs(C(1e9) - (10 + 20 / 0.01)) < 1e-3)
    (True, True)
    """
    import control as ct

    kp = check_positive("kp", kp)
    kv = check_positive("kv", kv)
    tf = check_positive("tf", tf)
    return ct.tf([kp * tf + kv, kp], [tf, 1.0], inputs="err", outputs="u_fb", name=name)


def filtered_pid(kp: float, ki: float, kv: float, tf: float, name: str = "filtered_pid"):
    """PID with a filtered derivative, ``C(s) = kp + ki / s + kv s / (tf s + 1)``.

    Parameters
    ----------
    kp : float
        Proportional gain (force/length), ``> 0``.
    ki : float
        Integral gain (force/(length time)), ``> 0`` (use :func:`filtered_pd` for ``ki = 0``;
        a zero ``ki`` would leave a cancelled pole at ``s = 0`` in the realisation).
    kv : float
        Derivative gain (force time/length), ``> 0``.
    tf : float
        Derivative filter time constant (time), ``> 0``.
    name : str

    Returns
    -------
    control.TransferFunction
        1 input ``err``, 1 output ``u_fb``, two states once realised (integrator and filter).

    Examples
    --------
    >>> C = filtered_pid(10, 2, 20, 0.01)
    >>> bool(abs(C(1j) - (10 + 2 / 1j + 20j / (0.01j + 1))) < 1e-12)
    True
    """
    import control as ct

    kp = check_positive("kp", kp)
    ki = check_positive("ki", ki)
    kv = check_positive("kv", kv)
    tf = check_positive("tf", tf)
    # kp + ki/s + kv s/(tf s + 1) over the common denominator s (tf s + 1)
    num = [kp * tf + kv, kp + ki * tf, ki]
    return ct.tf(num, [tf, 1.0, 0.0], inputs="err", outputs="u_fb", name=name)


def lead_lag(k: float, t_lead_zero: float, t_lead_pole: float, t_lag_zero: float | None = None,
             t_lag_pole: float | None = None, name: str = "lead_lag"):
    """Lead (optionally lead-lag) compensator with DC gain ``k``.

    ``C(s) = k (t_lead_zero s + 1)/(t_lead_pole s + 1) * (t_lag_zero s + 1)/(t_lag_pole s + 1)``

    Parameters
    ----------
    k : float
        DC gain (force/length), ``> 0``: the stiffness the controller shows at low frequency.
    t_lead_zero, t_lead_pole : float
        Lead time constants (time), ``t_lead_zero > t_lead_pole > 0`` (phase lead; the PD
        ``kp + kv s`` is the limit ``t_lead_zero = kv/kp``, ``t_lead_pole -> 0``).
    t_lag_zero, t_lag_pole : float, optional
        Lag time constants (time), ``t_lag_pole > t_lag_zero > 0``; both or neither.
    name : str

    Returns
    -------
    control.TransferFunction
        1 input ``err``, 1 output ``u_fb`` (1 or 2 states).

    Examples
    --------
    The filtered PD is a lead with ``t_lead_zero = kv/kp + tf``, ``t_lead_pole = tf``:

    >>> C1, C2 = lead_lag(10, 2.01, 0.01), filtered_pd(10, 20, 0.01)
    >>> bool(abs(C1(3j) - C2(3j)) < 1e-12)
    True
    """
    import control as ct

    k = check_positive("k", k)
    tz = check_positive("t_lead_zero", t_lead_zero)
    tp = check_positive("t_lead_pole", t_lead_pole)
    if not tz > tp:
        raise ValueError(f"a lead needs t_lead_zero > t_lead_pole, got {tz:g} <= {tp:g}")
    num, den = [k * tz, k], [tp, 1.0]
    if (t_lag_zero is None) != (t_lag_pole is None):
        raise ValueError("t_lag_zero and t_lag_pole must be given together")
    if t_lag_zero is not None:
        gz = check_positive("t_lag_zero", t_lag_zero)
        gp = check_positive("t_lag_pole", t_lag_pole)
        if not gp > gz:
            raise ValueError(f"a lag needs t_lag_pole > t_lag_zero, got {gp:g} <= {gz:g}")
        num = np.polymul(num, [gz, 1.0])
        den = np.polymul(den, [gp, 1.0])
    return ct.tf(num, den, inputs="err", outputs="u_fb", name=name)
