"""The impact pair as a family of maps for bifurcation diagrams.

:class:`ImpactMapFamily` is the builder that the one diagram,
:func:`hybridpd.analysis.diagrams.bifurcation_diagram` (or its executor sweep
:func:`hybridpd.sweeps.diagrams.diagram_sweep`), iterates: at each value of one parameter the
impact map ``P`` (:class:`~hybridpd.pair.impactmap.ImpactMap`, whose hooks run the iterations
in the compiled engine, batch the finite-difference Jacobians of the Lyapunov exponents and map
the engine's statuses to the classes ``sticking``, ``no_impact``, ``unresolved``).

Parameter path: with ``xm`` None (default), the *design path*: at every value the reference
amplitude is the one that realises the primary-mass amplitude ``x10`` on the order-``n``
symmetric orbit (paper (20); the path of
:func:`~hybridpd.pair.continuation.continue_symmetric`); with ``xm`` given, ``xm`` is
fixed. ``gamma`` means ``L / x10`` (CONVENTIONS.md). The diagram records ``xm`` and ``L`` per
value (``d.xm``, ``d.L``) and ``case``, ``fixed``, ``design`` in its metadata.

Examples
--------
Collocated, ``e = 0.5``, ``kp = 10``: the symmetric orbit attracts for these ``kv``:

>>> import numpy as np
>>> import hybridpd as hp
>>> fam = ImpactMapFamily(hp.ImpactPair(0.1, 0.5, 0.75), hp.PDGains(10, 20), 5.0, "kv")
>>> d = hp.bifurcation_diagram(fam, np.linspace(18, 20, 3), iterations=300, keep=40,
...                            follow=False, lyapunov=True)
>>> d.classification, d.periods.tolist()
(['periodic', 'periodic', 'periodic'], [1, 1, 1])
>>> bool(np.all(d.lyapunov < 0))
True
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hybridpd.model import Case, ImpactPair, PDGains, Reference, check_finite
from hybridpd.pair.impactmap import ImpactMap
from hybridpd.pair.orbits import symmetric_orbits

__all__ = ["COORDINATES", "DIAGRAM_PARAMETERS", "ImpactMapFamily", "section_coordinate"]

#: Parameters a diagram can sweep.
DIAGRAM_PARAMETERS = ("kp", "kv", "e", "mu", "gamma", "omega", "m2", "xm")
#: Section coordinates by name (``phi, z1, z2, z4`` and the physical ``x1, y1, x2, y2``).
COORDINATES = ("phi", "z1", "z2", "z4", "x1", "y1", "x2", "y2")
#: The settings of the pair's diagrams in hybridpd 0.2.0 (its function's defaults).
PAIR_SETTINGS = {"iterations": 1000, "keep": 100, "follow": False, "max_period": 32,
                 "period_tol": 1e-8, "chaos_tol": 1e-3, "escape": 1e3, "lyapunov": True}


def section_coordinate(points, name: str, L: float) -> np.ndarray:
    """A named coordinate of section points ``(..., 4) = (phi, z1, z2, z4)``.

    ``x1 = z1 + L`` (pre-impact at ``z3 = +L``), ``y1 = z2 + z4``, ``x2 = z1``, ``y2 = z2``.
    """
    P = np.asarray(points, float)
    if name not in COORDINATES:
        raise ValueError(f"coordinate must be one of {COORDINATES}, got {name!r}")
    i = {"phi": 0, "z1": 1, "z2": 2, "z4": 3, "x2": 1, "y2": 2}.get(name)
    if i is not None:
        return P[..., i]
    if name == "x1":
        return P[..., 1] + L
    return P[..., 2] + P[..., 3]


@dataclass(frozen=True, eq=False)
class ImpactMapFamily:
    """The impact maps along one parameter: a family of :mod:`hybridpd.analysis.diagrams`.

    Parameters
    ----------
    pair : ImpactPair
        ``mu, e, L, m2`` (the swept one is replaced by the values).
    gains : PDGains or (kp, kv)
    omega : float
        Reference frequency (rad/time).
    parameter : str
        One of :data:`DIAGRAM_PARAMETERS` (``gamma = L / x10`` with ``x10`` fixed; ``xm``
        only with a fixed ``xm``).
    case : {"collocated", "noncollocated"}
    x10, n : float, int
        Primary-mass amplitude (length) and odd order of the design orbit.
    xm : float, optional
        Fixed reference amplitude; default None: ``xm`` follows the design at every value.
    tol, max_impacts : float, int
        Contact tolerance and impact bound per application of ``P`` (see ImpactMap).

    Calling the family with a value gives the :class:`ImpactMap` there (``ValueError`` where
    the design has no ``xm``); its hooks (``prepare``, ``variables``, ``initial``,
    ``metadata``) are those of the module docstring of :mod:`hybridpd.analysis.diagrams`.
    The default start is the closed-form symmetric fixed point at the first value, displaced
    by ``1e-3`` in ``z1``.

    Examples
    --------
    >>> fam = ImpactMapFamily(ImpactPair(0.1, 0.5, 0.75), (10, 20), 5.0, "kv")
    >>> round(fam(20.0).reference.xm, 6) == round(float(fam.variables([20.0, 21.0])["xm"][0]), 6)
    True
    """

    pair: ImpactPair
    gains: PDGains
    omega: float
    parameter: str
    case: str = "collocated"
    x10: float = 1.0
    n: int = 1
    xm: float | None = None
    tol: float = 1e-13
    max_impacts: int = 1000
    _table: dict = field(default_factory=dict, repr=False)

    def __post_init__(self):
        if not isinstance(self.pair, ImpactPair):
            raise ValueError(f"pair must be an ImpactPair, got {type(self.pair).__name__}")
        if not isinstance(self.gains, PDGains):
            object.__setattr__(self, "gains", PDGains(*self.gains))
        omega = check_finite("omega", self.omega)
        if omega <= 0:
            raise ValueError(f"omega must be > 0, got {omega!r}")
        object.__setattr__(self, "omega", omega)
        object.__setattr__(self, "case", Case.parse(self.case).value)
        if not isinstance(self.parameter, str) or self.parameter not in DIAGRAM_PARAMETERS:
            raise ValueError(f"parameter must be one of {DIAGRAM_PARAMETERS}, got "
                             f"{self.parameter!r}")
        if self.parameter == "xm" and self.xm is None:
            raise ValueError("parameter 'xm' needs a fixed-xm diagram (give xm=...); on the "
                             "design path xm follows x10")
        if not check_finite("x10", self.x10) > 0:
            raise ValueError(f"x10 must be > 0, got {self.x10!r}")
        if int(self.n) != self.n or self.n < 1 or self.n % 2 == 0:
            raise ValueError(f"n must be a positive odd integer, got {self.n!r}")
        if self.xm is not None and not check_finite("xm", self.xm) >= 0:
            raise ValueError(f"xm must be >= 0, got {self.xm!r}")

    def columns(self, values) -> tuple:
        """``(cols, xm)``: every parameter at each value (dict of (M,) arrays ``kp, kv, e,
        mu, m2, L, omega``) and the reference amplitude (NaN where the design has none)."""
        v = _check_values(self.parameter, values)
        M, g, p, name = v.size, self.gains, self.pair, self.parameter
        cols = {"kp": np.full(M, g.kp), "kv": np.full(M, g.kv), "e": np.full(M, p.e),
                "mu": np.full(M, p.mu), "m2": np.full(M, p.m2), "L": np.full(M, p.L),
                "omega": np.full(M, self.omega)}
        if name == "gamma":
            cols["L"] = v * self.x10
        elif name != "xm":
            cols[name] = v.copy()
        if self.xm is not None:
            return cols, v.copy() if name == "xm" else np.full(M, float(self.xm))
        r = symmetric_orbits(cols["kp"], cols["kv"], mu=cols["mu"], e=cols["e"], L=cols["L"],
                             omega=cols["omega"], m2=cols["m2"], x10=self.x10, n=int(self.n),
                             case=self.case, margin=False, jacobian=False)
        xms = np.asarray(r.xm, float).reshape(M)
        return cols, np.where(np.isfinite(xms) & (xms > 0), xms, np.nan)

    def prepare(self, values) -> ImpactMapFamily:
        """The family with the design's ``xm`` of all ``values`` computed at once."""
        cols, xms = self.columns(values)
        table = {float(x): (tuple(float(c[i]) for c in cols.values()), float(xms[i]))
                 for i, x in enumerate(np.asarray(values, float).reshape(-1))}
        return ImpactMapFamily(self.pair, self.gains, self.omega, self.parameter, self.case,
                               self.x10, self.n, self.xm, self.tol, self.max_impacts, table)

    def __call__(self, value) -> ImpactMap:
        row = self._table.get(float(value))
        if row is None:
            cols, xms = self.columns([value, value])
            row = (tuple(float(c[0]) for c in cols.values()), float(xms[0]))
        (kp, kv, e, mu, m2, L, omega), xm = row
        if not np.isfinite(xm):
            raise ValueError(f"no design reference amplitude xm at {self.parameter} = "
                             f"{value:g}")
        return ImpactMap(ImpactPair(mu, e, L, m2), PDGains(kp, kv), Reference(xm, omega),
                         self.case, tol=self.tol, max_impacts=self.max_impacts)

    def variables(self, values) -> dict:
        """``{"xm": (M,), "L": (M,)}`` at ``values``."""
        cols, xms = self.columns(values)
        return {"xm": xms, "L": cols["L"]}

    def initial(self, values) -> np.ndarray:
        """The closed-form symmetric fixed point at the first value, ``z1`` displaced by
        ``1e-3`` (``ValueError`` if there is none)."""
        cols, _ = self.columns(values)
        r = symmetric_orbits(cols["kp"][0], cols["kv"][0], mu=cols["mu"][0], e=cols["e"][0],
                             L=cols["L"][0], omega=cols["omega"][0], m2=cols["m2"][0],
                             x10=self.x10, n=int(self.n), case=self.case, margin=False,
                             jacobian=False)
        s = np.asarray(r.fixed_point, float).reshape(4) + np.array([0.0, 1e-3, 0.0, 0.0])
        if not (np.all(np.isfinite(s)) and s[3] > 0):
            raise ValueError("no symmetric fixed point at the first value to start from: give "
                             "s0=(phi, z1, z2, z4)")
        return s

    @property
    def metadata(self) -> dict:
        """``case``, ``design`` and ``fixed`` (the parameters not swept)."""
        g, p, name = self.gains, self.pair, self.parameter
        fixed = {"kp": g.kp, "kv": g.kv, "e": p.e, "mu": p.mu, "m2": p.m2, "L": p.L,
                 "omega": self.omega}
        fixed = {k: float(x) for k, x in fixed.items()
                 if k != name and not (name == "gamma" and k == "L")}
        if self.xm is None:
            fixed.update({"x10": float(self.x10), "n": int(self.n)})
        elif name != "xm":
            fixed["xm"] = float(self.xm)
        return {"case": self.case, "design": self.xm is None, "fixed": fixed}


def _check_values(name, values):
    v = np.asarray(values, dtype=float).reshape(-1)
    if v.size < 2:
        raise ValueError(f"values must hold at least 2 parameter values, got {v.size}")
    if not np.all(np.isfinite(v)):
        raise ValueError("values must be finite")
    lo = 0.0
    if name == "e":
        if np.any(v < 0) or np.any(v > 1):
            raise ValueError(f"e must lie in [0, 1], got values in [{v.min():g}, {v.max():g}]")
    elif np.any(v <= lo) and name != "xm":
        raise ValueError(f"{name} must be > 0, got values down to {v.min():g}")
    elif name == "xm" and np.any(v < 0):
        raise ValueError(f"xm must be >= 0, got values down to {v.min():g}")
    return v
