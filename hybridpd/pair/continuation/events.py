"""Branches, bifurcation events and their detection/location along a branch (shared by the
continuation methods), and the branch file (:meth:`Branch.save`, :func:`load_branch`)."""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.analysis.pathfollow import illinois as _illinois
from hybridpd.model import Case
from hybridpd.pair.continuation._common import (
    _END_GRAZE,
    _JUMP_TOL,
    _NONREAL_TOL,
    _f,
    _fixed_parameters,
)


@dataclass(frozen=True)
class BifurcationEvent:
    """A detected (and, where possible, located) event on a branch.

    Attributes
    ----------
    kind : str
        One of :data:`EVENT_KINDS`.
    parameter : float
        Parameter value at the located event (or the midpoint of the bracketing steps when
        location failed).
    point : ndarray, shape (4,)
        Fixed point at the event (``phi`` in ``[0, T)``).
    multipliers : ndarray, shape (4,), complex
        Multipliers at the event (by decreasing modulus); NaN where undefined.
    index : int
        The event lies between branch points ``index`` and ``index + 1``.
    detail : str
        Human-readable description (direction of the crossing, fold vs branch point, ...).
    test_value : float
        Test function at the reported point (0 at an exact event; for grazing the margin or
        the smallest approach speed).
    located : bool
        The location converged (bracket below the tolerance). When False the event is
        uncertain: only a sign change between points ``index`` and ``index + 1`` is known,
        and :attr:`detail` starts with ``"uncertain"``.
    viable : bool
        The orbit at the event is a genuine orbit (symmetric family: viability holds; a
        stability change of a non-viable, "virtual" orbit is reported with ``False``).
    xm : float
        Reference amplitude at the event.
    """

    kind: str
    parameter: float
    point: np.ndarray
    multipliers: np.ndarray
    index: int
    detail: str = ""
    test_value: float = np.nan
    located: bool = False
    viable: bool = True
    xm: float = np.nan
    __repr__ = compact_repr

    def to_dict(self) -> dict:
        """JSON-ready summary."""
        return {"kind": self.kind, "parameter": float(self.parameter),
                "point": [_f(v) for v in self.point],
                "multipliers": [[_f(z.real), _f(z.imag)] for z in self.multipliers],
                "index": int(self.index), "detail": self.detail,
                "test_value": _f(self.test_value), "located": bool(self.located),
                "viable": bool(self.viable), "xm": _f(self.xm)}


@dataclass(frozen=True)
class Branch:
    """A continued family of periodic orbits (one row per accepted step).

    Attributes
    ----------
    parameter_name : str
    parameter : ndarray, shape (N,)
    points : ndarray, shape (N, 4)
        Fixed points ``(phi, z1, z2, z4)`` (``phi`` in ``[0, T)``).
    multipliers : ndarray, shape (N, 4), complex
        By decreasing modulus (NaN where undefined).
    spectral_radius : ndarray, shape (N,)
    stable : ndarray of bool, shape (N,)
        Viable and spectral radius < 1.
    viable : ndarray of bool, shape (N,)
        The orbit exists as such (symmetric family: paper's existence incl. viability; map
        continuation: always True, the orbits are simulated).
    margin : ndarray, shape (N,)
        Viability margin (symmetric family, signed: negative when violated) or the smallest
        interior wall distance over ``L`` of the flights (map continuation).
    min_impact_speed : ndarray, shape (N,)
        Smallest approach speed at an impact on the orbit (length/time).
    xm : ndarray, shape (N,)
        Reference amplitude (varies on the symmetric family, or when it is the parameter).
    period : int
        ``k`` of ``P^k`` (1 on the symmetric family).
    patterns : tuple
        Per point, the impact signature ``(((wall, kind), ...) per iteration)``.
    events : list of BifurcationEvent
        In branch order.
    termination : str
        Why the continuation stopped.
    family : str
        ``"periodic"`` (Newton on ``P^k``) or ``"symmetric"`` (closed form).
    method : str
        ``"natural"``, ``"arclength"`` or ``"closed_form"``.
    case : Case
    fixed : dict
        The other parameters.
    n_rejected : int
        Rejected (halved) steps.
    newton_iterations : ndarray of int, shape (N,)
        Corrector iterations per point (0 on the closed-form family).
    """

    parameter_name: str
    parameter: np.ndarray
    points: np.ndarray
    multipliers: np.ndarray
    spectral_radius: np.ndarray
    stable: np.ndarray
    viable: np.ndarray
    margin: np.ndarray
    min_impact_speed: np.ndarray
    xm: np.ndarray
    period: int
    patterns: tuple
    events: list
    termination: str
    family: str
    method: str
    case: Case
    fixed: dict
    n_rejected: int = 0
    newton_iterations: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    __repr__ = compact_repr

    def __len__(self) -> int:
        return int(self.parameter.size)

    def events_of(self, kind: str) -> list:
        """The events of one kind."""
        return [ev for ev in self.events if ev.kind == kind]

    def save(self, path):
        """Write to ``.npz`` (read back with
        :func:`hybridpd.pair.continuation.load_branch`); returns the path."""
        return save_branch(self, path)

    def to_dict(self) -> dict:
        """JSON-ready summary (arrays as lists, complex numbers as ``[re, im]``)."""
        return {
            "parameter_name": self.parameter_name, "family": self.family,
            "method": self.method, "case": self.case.value, "period": self.period,
            "fixed": {k: (v if isinstance(v, str) else float(v)) for k, v in self.fixed.items()},
            "parameter": [float(v) for v in self.parameter],
            "points": [[_f(v) for v in row] for row in self.points],
            "multipliers": [[[_f(z.real), _f(z.imag)] for z in row] for row in self.multipliers],
            "spectral_radius": [_f(v) for v in self.spectral_radius],
            "stable": [bool(v) for v in self.stable], "viable": [bool(v) for v in self.viable],
            "margin": [_f(v) for v in self.margin],
            "min_impact_speed": [_f(v) for v in self.min_impact_speed],
            "xm": [_f(v) for v in self.xm],
            "events": [ev.to_dict() for ev in self.events],
            "termination": self.termination, "n_rejected": int(self.n_rejected)}


@dataclass
class _Point:
    """Everything the continuation keeps about one solution (internal)."""

    u: np.ndarray                 # (s with continuous phase, p)
    DP: np.ndarray | None
    mult: np.ndarray
    rho: float
    signature: tuple
    margin: float
    min_speed: float
    viable: bool = True
    formal: bool = True
    xm: float = np.nan
    reason: int = 0
    newton_its: int = 0
    T: float = np.nan             # period of the reference at this point
    Fp: np.ndarray | None = None  # d(P^k(s) - s)/dp (map continuation: turning points)
    traces: list = field(default_factory=list, repr=False)


def _nonreal(m):
    return np.abs(m.imag) > _NONREAL_TOL * np.maximum(1.0, np.abs(m))


def _test_fold(pt):
    return float(np.prod(1.0 - pt.mult).real) if pt.formal else np.nan


def _test_pd(pt):
    return float(np.prod(1.0 + pt.mult).real) if pt.formal else np.nan


def _test_ns(pt):
    """``|lambda| - 1`` of the non-real multiplier nearest the unit circle (NaN if none)."""
    if not pt.formal:
        return np.nan
    m = pt.mult[_nonreal(pt.mult)]
    if m.size == 0:
        return np.nan
    d = np.abs(m) - 1.0
    return float(d[np.argmin(np.abs(d))])


def _ns_count(pt):
    return int(np.sum(_nonreal(pt.mult) & (np.abs(pt.mult) > 1.0)))


def _test_stability(pt):
    return pt.rho - 1.0 if pt.formal else np.nan


def _changes(fa, fb):
    return bool(np.isfinite(fa) and np.isfinite(fb) and (fa > 0) != (fb > 0)
                and not (fa == 0 and fb == 0))


class _Tracker:
    """Shared event detection/location along a sequence of points (internal).

    ``evaluate(pa, pb, theta)`` computes the solution between two accepted points;
    ``turn_test(pt, chord)``, when given, is the parameter component of the branch tangent
    at ``pt`` oriented along ``chord`` (its sign change is a turning point).
    """

    def __init__(self, kinds, evaluate, size, tol, max_iter, locate, to_event,
                 turn_test=None):
        self.kinds = kinds
        self.evaluate = evaluate
        self.size = size
        self.tol = tol
        self.max_iter = max_iter
        self.locate = locate
        self.to_event = to_event
        self.turn_test = turn_test

    def _root(self, kind, ftest, pa, pb, index, detail_fn, critical=None):
        """Locate a sign change of ``ftest``; ``critical(pt)`` is the distance of the critical
        multiplier(s) from the critical value: when it stays large at the located point the
        multipliers *jumped* across (a nonsmooth point such as grazing), and the event of a
        smooth bifurcation kind is dropped (returns None)."""
        fa, fb = ftest(pa), ftest(pb)
        if self.locate:
            pt, fv, ok = _illinois(lambda th: self.evaluate(pa, pb, th), ftest, fa, fb, pa, pb,
                                   size=self.size(pa, pb), tol=self.tol, max_iter=self.max_iter)
        else:
            pt, fv, ok = (pa if abs(fa) <= abs(fb) else pb), min(fa, fb, key=abs), False
        detail = detail_fn(pt)
        if not ok:
            # the bracket did not shrink (a failed corrector or no location asked for): what
            # is known is a sign change between two points, not an event at this parameter
            why = ("the corrector failed inside the bracket" if self.locate
                   else "location was not asked for")
            detail = (f"uncertain: not located ({why}); a sign change between branch points "
                      f"{index} and {index + 1}, possibly {detail}")
        if critical is not None and ok:
            c = critical(pt)
            if np.isfinite(c) and c > _JUMP_TOL:
                if kind != "stability_change":
                    return None
                detail += (f"; the multipliers jump across the unit circle here (spectral "
                           f"radius {pa.rho:.4g} -> {pb.rho:.4g} at a nonsmooth point, e.g. "
                           "grazing)")
        return self.to_event(kind, pt, index, detail, fv, ok)

    def detect(self, pa, pb, index, extra=()):
        """Events between two consecutive points."""
        out = []
        chord = pb.u - pa.u
        cross = _changes(_test_fold(pa), _test_fold(pb))
        turn = False
        if self.turn_test is not None and not (_near_grazing(pa) or _near_grazing(pb)):
            # (next to grazing the finite-difference tangent straddles the square-root
            # singularity of P and its sign means nothing; grazing has its own events)
            turn = _changes(self.turn_test(pa, chord), self.turn_test(pb, chord))
        if "fold" in self.kinds and turn:
            def detail(pt):
                m1 = float(np.min(np.abs(pt.mult - 1.0)))
                if cross:
                    return "fold: the branch turns back (a real multiplier crosses +1)"
                return ("turning point without a multiplier crossing +1 (closest "
                        f"|lambda - 1| = {m1:.2g}): the branch passes through a branch point, "
                        "e.g. a pitchfork, onto the symmetric partner of the family")
            out.append(self._root("fold", lambda pt: self.turn_test(pt, chord), pa, pb, index,
                                  detail))
        elif "fold" in self.kinds and cross:
            out.append(self._root(
                "fold", _test_fold, pa, pb, index,
                lambda pt: ("branch point: a real multiplier crosses +1 while the branch goes "
                            "on (pitchfork or transcritical; on a symmetric orbit typically the "
                            "symmetry-breaking pitchfork)"),
                critical=lambda pt: float(np.min(np.abs(pt.mult - 1.0)))))
        if "period_doubling" in self.kinds and _changes(_test_pd(pa), _test_pd(pb)):
            out.append(self._root(
                "period_doubling", _test_pd, pa, pb, index,
                lambda pt: ("real multiplier crosses -1 "
                            f"({'outwards' if _sgn_outside(pb) > _sgn_outside(pa) else 'inwards'})"),
                critical=lambda pt: float(np.min(np.abs(pt.mult + 1.0)))))
        if "neimark_sacker" in self.kinds and pa.formal and pb.formal \
                and _ns_count(pa) != _ns_count(pb):
            fa, fb = _test_ns(pa), _test_ns(pb)
            if _changes(fa, fb):
                ev = self._root(
                    "neimark_sacker", _test_ns, pa, pb, index,
                    lambda pt: ("complex pair crosses the unit circle "
                                f"({'outwards' if _ns_count(pb) > _ns_count(pa) else 'inwards'}"
                                f", angle {_ns_angle(pt):.4g} rad)"),
                    critical=lambda pt: abs(_test_ns(pt)))
                # a pair that became real inside the interval is not a Neimark-Sacker point
                if ev is not None:
                    m = ev.multipliers
                    if np.all(np.isfinite(m)):
                        crit = m[np.argmin(np.abs(np.abs(m) - 1.0))]
                        if _nonreal(np.array([crit]))[0]:
                            out.append(ev)
        if "stability_change" in self.kinds and _changes(_test_stability(pa),
                                                         _test_stability(pb)):
            def detail(pt):
                d = "stable -> unstable" if pb.rho > pa.rho else "unstable -> stable"
                m = pt.mult
                if np.all(np.isfinite(m)):
                    c = m[np.argmin(np.abs(np.abs(m) - 1.0))]
                    kind = ("complex pair" if _nonreal(np.array([c]))[0] else
                            ("real multiplier at +1" if c.real > 0 else "real multiplier at -1"))
                    d += f" ({kind})"
                return d
            out.append(self._root("stability_change", _test_stability, pa, pb, index, detail,
                                  critical=lambda pt: abs(pt.rho - 1.0)))
        out.extend(extra)
        out = [ev for ev in out if ev is not None]
        out.sort(key=lambda ev: abs(ev.parameter - pa.u[-1]))
        return out


def _near_grazing(pt):
    if not pt.traces:
        return False
    g = min(pt.margin, _rel_speed(pt))
    return bool(np.isfinite(g) and g < _END_GRAZE)


def _sgn_outside(pt):
    """1 if a real multiplier lies below -1 at ``pt`` (used for the PD direction)."""
    m = pt.mult
    return int(np.any((~_nonreal(m)) & (m.real < -1.0)))


def _ns_angle(pt):
    m = pt.mult[_nonreal(pt.mult)]
    if m.size == 0:
        return np.nan
    c = m[np.argmin(np.abs(np.abs(m) - 1.0))]
    return float(abs(np.angle(c)))


def _rel_speed(pt):
    speeds = [st.speed for tr in pt.traces for st in tr.steps if st.kind != "stick"]
    vmax = max(speeds, default=0.0)
    return min(speeds) / vmax if vmax > 0 else np.nan


def _sig_str(sig):
    return " | ".join(",".join(f"{w:+d}{'' if kd == 'impact' else kd[0]}" for w, kd in it)
                      for it in sig)


def _empty_branch(name, P, k, method, reason) -> Branch:
    z = np.zeros(0)
    return Branch(parameter_name=name, parameter=z, points=np.zeros((0, 4)),
                  multipliers=np.zeros((0, 4), complex), spectral_radius=z,
                  stable=np.zeros(0, bool), viable=np.zeros(0, bool), margin=z,
                  min_impact_speed=z, xm=z, period=k, patterns=(), events=[],
                  termination=reason, family="periodic", method=method, case=P.case,
                  fixed=_fixed_parameters(P), n_rejected=0,
                  newton_iterations=np.zeros(0, int))


def _branch_from_points(pts, evs, name, P0, k, method, termination, rejected, *,
                        omega=None, case=None, fixed=None) -> Branch:
    p = np.array([pt.u[-1] for pt in pts])
    S = np.array([pt.u[:4] for pt in pts])
    if P0 is not None:
        omega, case, fixed = P0.reference.omega, P0.case, _fixed_parameters(P0)
    w = p if name == "omega" else omega
    S[:, 0] = np.mod(S[:, 0], 2 * np.pi / w)
    mult = np.array([pt.mult for pt in pts])
    rho = np.array([pt.rho for pt in pts])
    viable = np.array([pt.viable for pt in pts])
    return Branch(
        parameter_name=name, parameter=p, points=S, multipliers=mult, spectral_radius=rho,
        stable=viable & (rho < 1.0), viable=viable, margin=np.array([pt.margin for pt in pts]),
        min_impact_speed=np.array([pt.min_speed for pt in pts]),
        xm=np.array([pt.xm for pt in pts]), period=k,
        patterns=tuple(pt.signature for pt in pts), events=evs, termination=termination,
        family="periodic" if method != "closed_form" else "symmetric", method=method,
        case=case, fixed=fixed, n_rejected=rejected,
        newton_iterations=np.array([pt.newton_its for pt in pts]))


# ----------------------------------------------------------------------------------------
# the branch file: ``.npz`` in the layout of :mod:`hybridpd.sweeps.npz` (readable by
# :func:`numpy.load` without pickle): the per-point arrays as NumPy arrays, everything else
# (parameter name, family, case, fixed parameters, impact patterns, events) as JSON in the 0-d
# entry ``__metadata__`` with ``"kind": "branch"``. Written here directly because analyses do
# not import the sweeps layer.
# ----------------------------------------------------------------------------------------
_ARRAYS = ("parameter", "points", "multipliers", "spectral_radius", "stable", "viable",
           "margin", "min_impact_speed", "xm", "newton_iterations")


def _nan(v):
    return np.nan if v is None else float(v)


def _tuples(obj):
    return tuple(_tuples(o) for o in obj) if isinstance(obj, list) else obj


def save_branch(branch: Branch, path):
    """Write `branch` to an ``.npz`` file (see the module docstring); returns the path."""
    _check_npz(path)
    arrays = {k: np.asarray(getattr(branch, k)) for k in _ARRAYS}
    meta = {"kind": "branch", "parameter_name": branch.parameter_name,
            "period": int(branch.period), "patterns": branch.patterns,
            "events": [ev.to_dict() for ev in branch.events],
            "termination": branch.termination, "family": branch.family,
            "method": branch.method, "case": Case.parse(branch.case).value,
            "fixed": dict(branch.fixed), "n_rejected": int(branch.n_rejected)}
    text = json.dumps(meta, sort_keys=True, default=_plain)
    path = Path(path)
    with open(path, "wb") as fh:  # a file object: numpy would otherwise append .npz
        np.savez_compressed(fh, **arrays, __metadata__=np.array(text))
    return path


def _plain(v):
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, np.ndarray):
        return v.tolist()
    raise TypeError(f"cannot store {type(v).__name__} in the branch metadata")


def _check_npz(path):
    if not isinstance(path, (str, Path)) or Path(path).suffix.lower() != ".npz":
        raise ValueError(f"path must end in .npz, got {path!r}")


def _event(d: dict) -> BifurcationEvent:
    mult = np.array([complex(_nan(re), _nan(im)) for re, im in d["multipliers"]])
    return BifurcationEvent(kind=d["kind"], parameter=float(d["parameter"]),
                            point=np.array([_nan(v) for v in d["point"]]), multipliers=mult,
                            index=int(d["index"]), detail=d["detail"],
                            test_value=_nan(d["test_value"]), located=bool(d["located"]),
                            viable=bool(d["viable"]), xm=_nan(d["xm"]))


def load_branch(path) -> Branch:
    """Read a :class:`Branch` written by :meth:`Branch.save`.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> from hybridpd import ImpactPair, PDGains
    >>> from hybridpd.pair.continuation import continue_symmetric
    >>> br = continue_symmetric(ImpactPair(0.1, 0.1, 0.75), PDGains(10, 20), 5.0, "kv", 23.0)
    >>> p = br.save(Path(tempfile.mkdtemp()) / "kv.npz")
    >>> back = load_branch(p)
    >>> bool((back.spectral_radius == br.spectral_radius).all()), len(back.events)
    (True, 1)
    """
    _check_npz(path)
    with np.load(path, allow_pickle=False) as z:
        a = {k: z[k] for k in z.files}
    meta = json.loads(str(a.pop("__metadata__", np.array("{}"))[()]))
    if meta.get("kind") != "branch":
        raise ValueError(f"{path} does not hold a continued branch")
    return Branch(parameter_name=meta["parameter_name"], parameter=a["parameter"],
                  points=a["points"], multipliers=a["multipliers"],
                  spectral_radius=a["spectral_radius"], stable=a["stable"].astype(bool),
                  viable=a["viable"].astype(bool), margin=a["margin"],
                  min_impact_speed=a["min_impact_speed"], xm=a["xm"],
                  period=int(meta["period"]), patterns=_tuples(meta["patterns"]),
                  events=[_event(d) for d in meta["events"]],
                  termination=meta["termination"], family=meta["family"],
                  method=meta["method"], case=Case.parse(meta["case"]), fixed=meta["fixed"],
                  n_rejected=int(meta["n_rejected"]),
                  newton_iterations=a["newton_iterations"].astype(np.int64))
