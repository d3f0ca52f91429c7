"""Bifurcation events along a continued branch: their test functions and the one detector.

A branch is a sequence of points; a point has ``u`` (the fixed point followed by the
parameter), ``mult`` (its multipliers), ``rho`` (spectral radius), ``formal`` (False where
the multipliers mean nothing, e.g. a closed-form family's point where the orbit does not
exist) and, for turning points, ``DP`` and ``Fp`` (``d(P^k(s) - s)/dp``). Between two
consecutive points :class:`EventTracker` detects sign changes of the test functions below and
locates their roots by Illinois iterations on a caller's ``evaluate(pa, pb, theta)`` (a point
between the two), with one rule for every family:

=====================  =====================================================================
``fold``               the parameter component of the branch tangent changes sign (a turning
                       point, with a multiplier at +1 where located), or ``det(DP - I)`` does
                       while the branch goes on (a branch point: pitchfork or transcritical)
``period_doubling``    ``det(DP + I)`` changes sign
``neimark_sacker``     the number of non-real multipliers outside the unit circle changes and
                       ``|lambda| - 1`` of the nearest non-real pair changes sign
``stability_change``   the spectral radius crosses 1
=====================  =====================================================================

A smooth kind whose located point still has its critical multiplier further than
``1e-3`` from the critical value is a *jump* of the multipliers across it, or the bend of
the branch at a nonsmooth point such as grazing, not that bifurcation: it is dropped (a
stability change is kept and says so). A location that does not converge is reported with ``located=False`` and a detail
starting ``"uncertain"``. What only one family has (the impact pair's grazing, a change of
the jump sequence) comes in as extra events.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from hybridpd.analysis.pathfollow import _tangent, illinois

__all__ = ["EventTracker", "turn_test"]

NONREAL_TOL = 1e-9     # |Im lambda| above this (relative) counts as a complex pair
JUMP_TOL = 1e-3        # a located crossing this far from the critical value is a jump


def nonreal(m):
    """Which multipliers are non-real (relative tolerance ``1e-9``)."""
    return np.abs(m.imag) > NONREAL_TOL * np.maximum(1.0, np.abs(m))


def fold_test(pt):
    """``det(I - DP)`` from the multipliers (NaN at a non-formal point)."""
    return float(np.prod(1.0 - pt.mult).real) if pt.formal else np.nan


def pd_test(pt):
    """``det(I + DP)`` from the multipliers."""
    return float(np.prod(1.0 + pt.mult).real) if pt.formal else np.nan


def ns_test(pt):
    """``|lambda| - 1`` of the non-real multiplier nearest the unit circle (NaN if none)."""
    if not pt.formal:
        return np.nan
    m = pt.mult[nonreal(pt.mult)]
    if m.size == 0:
        return np.nan
    d = np.abs(m) - 1.0
    return float(d[np.argmin(np.abs(d))])


def ns_count(pt):
    """Number of non-real multipliers outside the unit circle."""
    return int(np.sum(nonreal(pt.mult) & (np.abs(pt.mult) > 1.0)))


def stability_test(pt):
    """Spectral radius minus 1."""
    return pt.rho - 1.0 if pt.formal else np.nan


def changes(fa, fb):
    """Whether a test function changes sign between two finite values."""
    return bool(np.isfinite(fa) and np.isfinite(fb) and (fa > 0) != (fb > 0)
                and not (fa == 0 and fb == 0))


def turn_test(pt, chord):
    """Parameter component of the unit branch tangent at ``pt`` (the kernel of
    ``[DP - I, dF/dp]``) oriented along ``chord``: it changes sign at a turning point (NaN
    without ``dF/dp``)."""
    if pt.Fp is None:
        return np.nan
    v = _tangent(pt.DP, pt.Fp)
    return float(v[-1] if v @ chord >= 0 else -v[-1])


@dataclass
class EventTracker:
    """Detection and location of events between consecutive branch points.

    Parameters
    ----------
    kinds : tuple of str
        Kinds to detect.
    evaluate : callable
        ``evaluate(pa, pb, theta)``: the branch point at chord fraction ``theta`` between two
        accepted points, or None where it cannot be computed.
    size : callable
        ``size(pa, pb)``: the length that a location bracket ``[0, 1]`` of ``theta`` stands
        for (location stops below ``tol``).
    tol : float
    max_iter : int
        Bound on location iterations per event.
    locate : bool
        Locate roots (otherwise the nearer bracketing point is reported, ``uncertain``).
    to_event : callable
        ``to_event(kind, pt, index, detail, test_value, located)``: the family's event.
    turn_test : callable, optional
        ``turn_test(pt, chord)`` (see :func:`turn_test`): turning points are folds.
    nonsmooth : callable, optional
        ``nonsmooth(pt)``: True next to a nonsmooth point, where a finite-difference tangent
        means nothing (no turning-point test there).
    """

    kinds: tuple
    evaluate: Callable
    size: Callable
    tol: float
    max_iter: int
    locate: bool
    to_event: Callable
    turn_test: Callable | None = None
    nonsmooth: Callable | None = None

    def root(self, kind, ftest, pa, pb, index, detail_fn, critical=None):
        """The event of ``kind`` where the test function ``ftest`` (of a point) changes sign
        between points ``pa`` and ``pb`` (``index``, ``index + 1``), its detail
        ``detail_fn(point)``; a family's own kinds (the pair's grazing) use it too.

        ``critical(pt)`` is the distance of the critical multiplier(s) from the critical
        value: when it stays large at the located point the multipliers *jumped* across (a
        nonsmooth point such as grazing), and the event of a smooth bifurcation kind is
        dropped (returns None)."""
        fa, fb = ftest(pa), ftest(pb)
        if self.locate:
            pt, fv, ok = illinois(lambda th: self.evaluate(pa, pb, th), ftest, fa, fb, pa, pb,
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
            if np.isfinite(c) and c > JUMP_TOL:
                if kind != "stability_change":
                    return None
                detail += (f"; the multipliers jump across the unit circle here (spectral "
                           f"radius {pa.rho:.4g} -> {pb.rho:.4g} at a nonsmooth point, e.g. "
                           "grazing)")
        return self.to_event(kind, pt, index, detail, fv, ok)

    def _fold(self, pa, pb, index):
        chord = pb.u - pa.u
        cross = changes(fold_test(pa), fold_test(pb))
        turn = False
        if self.turn_test is not None and not (self.nonsmooth is not None and (
                self.nonsmooth(pa) or self.nonsmooth(pb))):
            # (next to a nonsmooth point the finite-difference tangent straddles its
            # singularity and its sign means nothing)
            turn = changes(self.turn_test(pa, chord), self.turn_test(pb, chord))
        if turn:
            def detail(pt):
                m1 = float(np.min(np.abs(pt.mult - 1.0)))
                if cross:
                    return "fold: the branch turns back (a real multiplier crosses +1)"
                return ("turning point without a multiplier crossing +1 (closest "
                        f"|lambda - 1| = {m1:.2g}): the branch passes through a branch point, "
                        "e.g. a pitchfork, onto the symmetric partner of the family")
            # a smooth turning point has a multiplier +1 (the tangent (v, 0) solves
            # (DP - I) v = 0); a turn without one is the bend of a nonsmooth point (grazing)
            return self.root("fold", lambda pt: self.turn_test(pt, chord), pa, pb, index,
                              detail, critical=lambda pt: float(np.min(np.abs(pt.mult - 1.0))))
        if cross:
            return self.root(
                "fold", fold_test, pa, pb, index,
                lambda pt: ("branch point: a real multiplier crosses +1 while the branch goes "
                            "on (pitchfork or transcritical; on a symmetric orbit typically the "
                            "symmetry-breaking pitchfork)"),
                critical=lambda pt: float(np.min(np.abs(pt.mult - 1.0))))
        return None

    def _neimark_sacker(self, pa, pb, index):
        if not (pa.formal and pb.formal and ns_count(pa) != ns_count(pb)
                and changes(ns_test(pa), ns_test(pb))):
            return None
        ev = self.root(
            "neimark_sacker", ns_test, pa, pb, index,
            lambda pt: ("complex pair crosses the unit circle "
                        f"({'outwards' if ns_count(pb) > ns_count(pa) else 'inwards'}"
                        f", angle {_ns_angle(pt):.4g} rad)"),
            critical=lambda pt: abs(ns_test(pt)))
        if ev is None:
            return None
        # a pair that became real inside the interval is not a Neimark-Sacker point
        m = ev.multipliers
        if np.all(np.isfinite(m)) and nonreal(
                np.array([m[np.argmin(np.abs(np.abs(m) - 1.0))]]))[0]:
            return ev
        return None

    def _stability(self, pa, pb, index):
        if not changes(stability_test(pa), stability_test(pb)):
            return None

        def detail(pt):
            d = "stable -> unstable" if pb.rho > pa.rho else "unstable -> stable"
            m = pt.mult
            if np.all(np.isfinite(m)):
                c = m[np.argmin(np.abs(np.abs(m) - 1.0))]
                kind = ("complex pair" if nonreal(np.array([c]))[0] else
                        ("real multiplier at +1" if c.real > 0 else "real multiplier at -1"))
                d += f" ({kind})"
            return d
        return self.root("stability_change", stability_test, pa, pb, index, detail,
                          critical=lambda pt: abs(pt.rho - 1.0))

    def detect(self, pa, pb, index, extra=()):
        """Events between two consecutive points (and the ``extra`` ones), nearest first."""
        out = []
        if "fold" in self.kinds:
            out.append(self._fold(pa, pb, index))
        if "period_doubling" in self.kinds and changes(pd_test(pa), pd_test(pb)):
            out.append(self.root(
                "period_doubling", pd_test, pa, pb, index,
                lambda pt: ("real multiplier crosses -1 "
                            f"({'outwards' if _outside(pb) > _outside(pa) else 'inwards'})"),
                critical=lambda pt: float(np.min(np.abs(pt.mult + 1.0)))))
        if "neimark_sacker" in self.kinds:
            out.append(self._neimark_sacker(pa, pb, index))
        if "stability_change" in self.kinds:
            out.append(self._stability(pa, pb, index))
        out.extend(extra)
        out = [ev for ev in out if ev is not None]
        out.sort(key=lambda ev: abs(ev.parameter - pa.u[-1]))
        return out


def _outside(pt):
    """1 if a real multiplier lies below -1 at ``pt`` (the direction of a flip)."""
    m = pt.mult
    return int(np.any((~nonreal(m)) & (m.real < -1.0)))


def _ns_angle(pt):
    m = pt.mult[nonreal(pt.mult)]
    if m.size == 0:
        return np.nan
    c = m[np.argmin(np.abs(np.abs(m) - 1.0))]
    return float(abs(np.angle(c)))
