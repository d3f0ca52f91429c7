"""Centred forms: first-order interval Taylor enclosures over a box of parameters.

Naive interval evaluation of a long formula over a box overestimates its range, because every
occurrence of a parameter varies independently (the *dependency* problem): the closed forms
of the symmetric orbit (Cramer's rule, the Jacobian blocks, characteristic polynomials) lose
orders of magnitude that way. A :class:`CForm` carries, for one quantity ``f`` over a box
``P`` with a chosen centre ``p0`` (arrays of boxes at once):

* ``c``: an enclosure of ``f(p0)`` (an interval of tiny width);
* ``g``: enclosures of the partial derivatives ``df/dp_i`` over the whole box (``None`` for
  an identically zero derivative);
* ``r``: an enclosure of the range of ``f`` over the box, the intersection of the naive
  interval evaluation and the mean-value (centred) form ``c + sum_i g_i (P_i - p0_i)``.

Every operation propagates the three with interval arithmetic (product rule, chain rule with
the derivative evaluated on the operand's range), so each component stays a rigorous
enclosure, and the centred form, whose excess width shrinks quadratically with the box,
tightens every intermediate range. The enclosures are those of
:class:`hybridpd.pair.intervals.Interval` (outward rounding; see its module for the libm
bound assumed and the rule for NaN).

The naive and the centred enclosures of one quantity always meet. Where they do not, one is
wrong (a derivative enclosed wrongly, a libm beyond its assumed bound), and the empty
intersection would enclose nothing, so that both ``lo > 0`` and ``hi < 0`` hold:
:meth:`~hybridpd.pair.intervals.Interval.intersect` raises
:class:`~hybridpd.pair.intervals.EmptyIntersectionError` instead, which the certifier
(:func:`hybridpd.pair.proofs.classify`) turns into "undecided" for the boxes concerned.
"""
from __future__ import annotations

import math
import types

import numpy as np

from hybridpd.pair import flowintervals as fi
from hybridpd.pair import intervals as iv
from hybridpd.pair.intervals import Interval

__all__ = ["INTERVAL_OPS", "Box", "CForm", "CForm2", "interval_dch", "interval_dsh", "where"]


class Box:
    """The directions of a family of boxes: ``delta[i] = P_i - p0_i`` (intervals).

    Parameters
    ----------
    delta : list of Interval
        One enclosure of ``P_i - p0_i`` per varying parameter (contains 0).
    """

    __slots__ = ("_quad", "delta")

    def __init__(self, delta):
        self.delta = list(delta)
        self._quad = None

    def quad(self):
        """``[(i, j, q_ij)]`` for ``i <= j`` with ``q_ii = delta_i^2 / 2`` and
        ``q_ij = delta_i delta_j`` (the weights of the Hessian in the Taylor remainder)."""
        if self._quad is None:
            q = []
            for i in range(self.k):
                for j in range(i, self.k):
                    if i == j:
                        q.append((i, j, iv.ipow(self.delta[i], 2) * 0.5))
                    else:
                        q.append((i, j, self.delta[i] * self.delta[j]))
            self._quad = q
        return self._quad

    @property
    def k(self) -> int:
        """Number of directions."""
        return len(self.delta)

    @classmethod
    def from_bounds(cls, bounds):
        """A box of directions from ``(lo, hi)`` pairs, and the centres ``p0`` (midpoints).

        Returns
        -------
        box : Box
        centres : list of ndarray
        """
        delta, centres = [], []
        for lo, hi in bounds:
            lo, hi = np.asarray(lo, float), np.asarray(hi, float)
            c = np.clip(0.5 * lo + 0.5 * hi, lo, hi)
            centres.append(c)
            delta.append(Interval(np.minimum(iv.widen_down(lo - c), 0.0),
                                  np.maximum(iv.widen_up(hi - c), 0.0)))
        return cls(delta), centres

    def variable(self, i, lo, hi, centre, order=1):
        """The parameter of direction ``i`` on ``[lo, hi]`` with centre ``centre``.

        ``order`` 1 gives a :class:`CForm`, 2 a :class:`CForm2`.
        """
        g = [None] * self.k
        g[i] = Interval(1.0)
        if order == 2:
            return CForm2(Interval(centre), tuple(g), (None,) * _npairs(self.k), tuple(g),
                          Interval(lo, hi), self, tighten=False)
        return CForm(Interval(centre), tuple(g), Interval(lo, hi), self)

    def constant(self, value, order=1):
        """A quantity that does not vary over the box (a :class:`CForm` or :class:`CForm2`)."""
        v = value if isinstance(value, Interval) else Interval(value)
        if order == 2:
            return CForm2(v, (None,) * self.k, (None,) * _npairs(self.k), (None,) * self.k, v,
                          self, tighten=False)
        return CForm(v, (None,) * self.k, v, self)

    def extend(self, extra) -> Box:
        """A box with the extra directions ``extra`` (list of Interval) appended."""
        return Box(self.delta + list(extra))

    def take(self, idx) -> Box:
        """The boxes at ``idx``."""
        return Box([d.take(idx) for d in self.delta])


def _npairs(k):
    return k * (k + 1) // 2


def _add(a, b):
    if a is None:
        return b
    if b is None:
        return a
    return a + b


def _scale(g, s):
    return None if g is None else g * s


def _mul(a, b):
    return None if a is None or b is None else a * b


class CForm:
    """A first-order centred form of one quantity over an array of boxes (see module).

    Attributes
    ----------
    c : Interval
        Value at the centres.
    g : tuple of (Interval or None)
        Gradient over the boxes, one per direction of :attr:`box`.
    r : Interval
        Range over the boxes.
    box : Box
    """

    __slots__ = ("box", "c", "g", "r")
    __array_priority__ = 1001

    def __init__(self, c, g, r, box, *, tighten=True):
        self.c, self.g, self.box = c, tuple(g), box
        if tighten:
            cf = c
            for gi, d in zip(self.g, box.delta):
                if gi is not None:
                    cf = cf + gi * d
            r = r.intersect(cf)
        self.r = r

    def __repr__(self):
        return f"CForm(range={self.r!r}, directions={self.box.k})"

    def _lift(self, o) -> CForm:
        if isinstance(o, CForm):
            return o
        if isinstance(o, Interval) or iv._is_point(o):
            return self.box.constant(o)
        raise TypeError(f"cannot combine CForm with {type(o).__name__}")

    def take(self, idx) -> CForm:
        """The forms of the boxes at ``idx`` (on ``box.take(idx)``)."""
        return CForm(self.c.take(idx), tuple(None if g is None else g.take(idx) for g in self.g),
                     self.r.take(idx), self.box.take(idx), tighten=False)

    def on(self, box: Box) -> CForm:
        """The same form on a box with more directions (zero derivative along the new ones)."""
        return CForm(self.c, self.g + (None,) * (box.k - self.box.k), self.r, box,
                     tighten=False)

    # -- arithmetic --------------------------------------------------------------------
    def __neg__(self):
        return CForm(-self.c, tuple(None if g is None else -g for g in self.g), -self.r,
                     self.box, tighten=False)

    def __pos__(self):
        return self

    def __add__(self, o):
        if not isinstance(o, CForm):
            if iv._is_point(o) or isinstance(o, Interval):
                return CForm(self.c + o, self.g, self.r + o, self.box, tighten=False)
            return NotImplemented
        return CForm(self.c + o.c, tuple(_add(a, b) for a, b in zip(self.g, o.g)),
                     self.r + o.r, self.box)

    __radd__ = __add__

    def __sub__(self, o):
        if not isinstance(o, (CForm, Interval)) and not iv._is_point(o):
            return NotImplemented
        return self + (-self._lift(o))

    def __rsub__(self, o):
        return (-self) + o

    def __mul__(self, o):
        if not isinstance(o, CForm):
            if iv._is_point(o) or isinstance(o, Interval):
                return CForm(self.c * o, tuple(_scale(g, o) for g in self.g), self.r * o,
                             self.box, tighten=not iv._is_point(o))
            return NotImplemented
        g = tuple(_add(_scale(ga, o.r), _scale(gb, self.r)) for ga, gb in zip(self.g, o.g))
        return CForm(self.c * o.c, g, self.r * o.r, self.box)

    __rmul__ = __mul__

    def __truediv__(self, o):
        o = self._lift(o)
        q = self.r / o.r
        g = tuple(None if (ga is None and gb is None) else
                  (_add(ga, None if gb is None else -(q * gb))) / o.r
                  for ga, gb in zip(self.g, o.g))
        return CForm(self.c / o.c, g, q, self.box)

    def __rtruediv__(self, o):
        return self._lift(o) / self

    # -- functions (the names of the backend namespace, dispatched by intervals) --------
    def _unary(self, f, fprime_of_range):
        r = f(self.r)
        d = fprime_of_range(r)
        return CForm(f(self.c), tuple(_scale(g, d) for g in self.g), r, self.box)

    def exp(self):
        """``exp``."""
        return self._unary(iv.exp, lambda r: r)

    def sqrt(self):
        """``sqrt`` (derivative ``1 / (2 sqrt)``)."""
        return self._unary(iv.sqrt, lambda r: 0.5 / r)

    def sin(self):
        """``sin``."""
        return self._unary(iv.sin, lambda r: iv.cos(self.r))

    def cos(self):
        """``cos``."""
        return self._unary(iv.cos, lambda r: -iv.sin(self.r))

    def pow(self, k):
        """``self ** k`` for an integer ``k >= 1`` (a real exponent raises ``ValueError``)."""
        k = _exponent(k)
        if k == 1:
            return self
        return self._unary(lambda x: iv.ipow(x, k), lambda r: iv.ipow(self.r, k - 1) * k)

    def cu(self):
        """:func:`hybridpd.pair.flowintervals.cu` (derivative ``su / 2``)."""
        return self._unary(fi.cu, lambda r: fi.su(self.r) * 0.5)

    def su(self):
        """:func:`hybridpd.pair.flowintervals.su` (derivative :func:`~hybridpd.pair.flowintervals.su1`)."""
        return self._unary(fi.su, lambda r: fi.su1(self.r))

    def emq(self):
        """:func:`hybridpd.pair.flowintervals.emq`."""
        return self._unary(fi.emq, lambda r: fi.emq1(self.r))


# ----------------------------------------------------------------------------------------
# Second order
# ----------------------------------------------------------------------------------------

#: ``(f, f', f'')`` on intervals, by backend name.
_FUNCS = {
    "exp": (iv.exp, iv.exp, iv.exp),
    "sin": (iv.sin, iv.cos, lambda x: -iv.sin(x)),
    "cos": (iv.cos, lambda x: -iv.sin(x), lambda x: -iv.cos(x)),
    "sqrt": (iv.sqrt, lambda x: 0.5 / iv.sqrt(x), lambda x: -0.25 / (x * iv.sqrt(x))),
    "recip": (lambda x: 1 / x, lambda x: -1 / iv.ipow(x, 2), lambda x: 2 / iv.ipow(x, 3)),
    "cu": (fi.cu, lambda x: fi.su(x) * 0.5, lambda x: fi.su1(x) * 0.5),
    "su": (fi.su, fi.su1, fi.su2),
    "emq": (fi.emq, fi.emq1, fi.emq2),
}


class CForm2:
    """A second-order centred form (Taylor form with an interval Hessian) over boxes.

    With the centre ``p0`` and ``delta = P - p0``: ``f(p) = f(p0) + gc . delta +
    delta^T H(xi) delta / 2`` with ``xi`` in the box, so the range is enclosed by
    ``c + gc . delta + sum_{i<=j} H_ij q_ij`` (:meth:`Box.quad`); the gradient over the box
    by ``gc + H delta``. Each is intersected with its naive enclosure. The excess width is of
    third order in the box size wherever the Hessian's enclosure stays bounded, which beats
    the first-order form on formulas with cancellations (Cramer's rule, products of
    exponentials whose exponents nearly cancel).

    Attributes
    ----------
    c : Interval
        Value at the centres.
    gc : tuple of (Interval or None)
        Gradient at the centres.
    H : tuple of (Interval or None)
        Hessian over the boxes, entries ``(i, j)``, ``i <= j``, row by row.
    g : tuple of (Interval or None)
        Gradient over the boxes.
    r : Interval
        Range over the boxes.
    box : Box
    """

    __slots__ = ("H", "box", "c", "g", "gc", "r")
    __array_priority__ = 1001

    def __init__(self, c, gc, H, g, r, box, *, tighten=True):
        self.c, self.gc, self.H, self.box = c, tuple(gc), tuple(H), box
        g = list(g)
        if tighten:
            k = box.k
            quad = box.quad()
            cf = c
            for gi, d in zip(self.gc, box.delta):
                if gi is not None:
                    cf = cf + gi * d
            for (i, j, q), h in zip(quad, self.H):
                if h is not None:
                    cf = cf + h * q
            for i in range(k):
                gi = self.gc[i]
                for (a, b, _), h in zip(quad, self.H):
                    if h is not None and i in (a, b):
                        gi = _add(gi, h * box.delta[b if a == i else a])
                if gi is not None and g[i] is not None:
                    g[i] = g[i].intersect(gi)
                elif gi is not None:
                    g[i] = gi
            r = r.intersect(cf)
            mv = c
            for gi, d in zip(g, box.delta):
                if gi is not None:
                    mv = mv + gi * d
            r = r.intersect(mv)
        self.g = tuple(g)
        self.r = r

    def __repr__(self):
        return f"CForm2(range={self.r!r}, directions={self.box.k})"

    def first_order(self) -> CForm:
        """The :class:`CForm` (value at the centre, gradient and range over the box)."""
        return CForm(self.c, self.g, self.r, self.box, tighten=False)

    def take(self, idx) -> CForm2:
        """The forms of the boxes at ``idx`` (on ``box.take(idx)``)."""
        t = lambda x: None if x is None else x.take(idx)
        return CForm2(t(self.c), tuple(map(t, self.gc)), tuple(map(t, self.H)),
                      tuple(map(t, self.g)), t(self.r), self.box.take(idx), tighten=False)

    def on(self, box: Box) -> CForm2:
        """The same form on a box with more directions (zero derivatives along the new ones)."""
        k, extra = self.box.k, box.k - self.box.k
        old = {(i, j): h for (i, j, _), h in zip(self.box.quad(), self.H)}
        H = tuple(old.get((i, j)) if j < k else None
                  for i in range(box.k) for j in range(i, box.k))
        return CForm2(self.c, self.gc + (None,) * extra, H, self.g + (None,) * extra, self.r,
                      box, tighten=False)

    def _lift(self, o) -> CForm2:
        if isinstance(o, CForm2):
            return o
        if isinstance(o, Interval) or iv._is_point(o):
            return self.box.constant(o, order=2)
        raise TypeError(f"cannot combine CForm2 with {type(o).__name__}")

    def __neg__(self):
        n = lambda x: None if x is None else -x
        return CForm2(-self.c, tuple(map(n, self.gc)), tuple(map(n, self.H)),
                      tuple(map(n, self.g)), -self.r, self.box, tighten=False)

    def __pos__(self):
        return self

    def __add__(self, o):
        if not isinstance(o, CForm2):
            if iv._is_point(o) or isinstance(o, Interval):
                return CForm2(self.c + o, self.gc, self.H, self.g, self.r + o, self.box,
                              tighten=False)
            return NotImplemented
        return CForm2(self.c + o.c, tuple(map(_add, self.gc, o.gc)), tuple(map(_add, self.H, o.H)),
                      tuple(map(_add, self.g, o.g)), self.r + o.r, self.box)

    __radd__ = __add__

    def __sub__(self, o):
        if not isinstance(o, (CForm2, Interval)) and not iv._is_point(o):
            return NotImplemented
        return self + (-self._lift(o))

    def __rsub__(self, o):
        return (-self) + o

    def __mul__(self, o):
        if not isinstance(o, CForm2):
            if iv._is_point(o) or isinstance(o, Interval):
                s = lambda x: _scale(x, o)
                return CForm2(self.c * o, tuple(map(s, self.gc)), tuple(map(s, self.H)),
                              tuple(map(s, self.g)), self.r * o, self.box,
                              tighten=not iv._is_point(o))
            return NotImplemented
        a, b = self, o
        gc = tuple(_add(_mul(x, b.c), _mul(a.c, y)) for x, y in zip(a.gc, b.gc))
        g = tuple(_add(_mul(x, b.r), _mul(a.r, y)) for x, y in zip(a.g, b.g))
        H = []
        for (i, j, _), ha, hb in zip(a.box.quad(), a.H, b.H):
            h = _add(_mul(ha, b.r), _mul(a.r, hb))
            cross = _add(_mul(a.g[i], b.g[j]), _mul(a.g[j], b.g[i]))
            H.append(_add(h, cross))
        return CForm2(a.c * b.c, gc, H, g, a.r * b.r, a.box)

    __rmul__ = __mul__

    def _unary(self, name):
        f, f1, f2 = _FUNCS[name]
        d1c = f1(self.c)
        d1, d2 = f1(self.r), f2(self.r)
        H = []
        for (i, j, _), h in zip(self.box.quad(), self.H):
            H.append(_add(_mul(h, d1), _mul(_mul(self.g[i], self.g[j]), d2)))
        return CForm2(f(self.c), tuple(_scale(x, d1c) for x in self.gc), H,
                      tuple(_scale(x, d1) for x in self.g), f(self.r), self.box)

    def __truediv__(self, o):
        if iv._is_point(o) or isinstance(o, Interval):
            return self * (1 / _as_iv(o))
        return self * self._lift(o)._unary("recip")

    def __rtruediv__(self, o):
        return self._lift(o) * self._unary("recip")

    def exp(self):
        """``exp``."""
        return self._unary("exp")

    def sqrt(self):
        """``sqrt``."""
        return self._unary("sqrt")

    def sin(self):
        """``sin``."""
        return self._unary("sin")

    def cos(self):
        """``cos``."""
        return self._unary("cos")

    def cu(self):
        """:func:`hybridpd.pair.flowintervals.cu`."""
        return self._unary("cu")

    def su(self):
        """:func:`hybridpd.pair.flowintervals.su`."""
        return self._unary("su")

    def emq(self):
        """:func:`hybridpd.pair.flowintervals.emq`."""
        return self._unary("emq")

    def pow(self, k):
        """``self ** k`` for an integer ``k >= 1`` (a real exponent raises ``ValueError``)."""
        k = _exponent(k)
        if k == 1:
            return self
        d1c = iv.ipow(self.c, k - 1) * k
        d1 = iv.ipow(self.r, k - 1) * k
        d2 = (iv.ipow(self.r, k - 2) if k > 2 else Interval(1.0)) * (k * (k - 1))
        H = [_add(_mul(h, d1), _mul(_mul(self.g[i], self.g[j]), d2))
             for (i, j, _), h in zip(self.box.quad(), self.H)]
        return CForm2(iv.ipow(self.c, k), tuple(_scale(x, d1c) for x in self.gc), H,
                      tuple(_scale(x, d1) for x in self.g), iv.ipow(self.r, k), self.box)


def _as_iv(o):
    return o if isinstance(o, Interval) else Interval(o)


def _exponent(k) -> int:
    """An integer exponent ``>= 1`` (never a real one truncated), else ``ValueError``."""
    k = iv._exponent(k)
    if k < 1:
        raise ValueError(f"the exponent k of a centred-form power must be an integer >= 1, "
                         f"got {k}")
    return k


# ----------------------------------------------------------------------------------------
# Elementwise selection and the damped functions
# ----------------------------------------------------------------------------------------


def _where_iv(mask, a, b):
    if a is None and b is None:
        return None
    a = Interval(0.0) if a is None else a
    b = Interval(0.0) if b is None else b
    return Interval(np.where(mask, a.lo, b.lo), np.where(mask, a.hi, b.hi))


def where(mask, a, b):
    """Elementwise ``a`` where ``mask`` else ``b`` (intervals or forms of one kind)."""
    if isinstance(a, CForm2) or isinstance(b, CForm2):
        a, b = (x if isinstance(x, CForm2) else (b if x is a else a)._lift(x) for x in (a, b))
        return CForm2(_where_iv(mask, a.c, b.c), tuple(map(lambda x, y: _where_iv(mask, x, y),
                                                           a.gc, b.gc)),
                      tuple(_where_iv(mask, x, y) for x, y in zip(a.H, b.H)),
                      tuple(_where_iv(mask, x, y) for x, y in zip(a.g, b.g)),
                      _where_iv(mask, a.r, b.r), a.box, tighten=False)
    if isinstance(a, CForm) or isinstance(b, CForm):
        a, b = (x if isinstance(x, CForm) else (b if x is a else a)._lift(x) for x in (a, b))
        return CForm(_where_iv(mask, a.c, b.c),
                     tuple(_where_iv(mask, x, y) for x, y in zip(a.g, b.g)),
                     _where_iv(mask, a.r, b.r), a.box, tighten=False)
    return _where_iv(mask, _as_iv(a), _as_iv(b))


def _range(x) -> Interval:
    return x.r if isinstance(x, (CForm, CForm2)) else _as_iv(x)


def _call(name, x, *args):
    m = getattr(x, name, None)
    if m is not None and not isinstance(x, Interval):
        return m(*args)
    fn = {"pow": iv.ipow, "exp": iv.exp, "sqrt": iv.sqrt, "sin": iv.sin, "cos": iv.cos}.get(name)
    return (fn or getattr(fi, name))(_as_iv(x), *args)


def _overdamped(D):
    """Boxes where ``D > 0`` is at least 4 times its own width away from 0.

    There ``sqrt(D)`` (singular at 0) is smooth over the box, and the overdamped form of
    :func:`_damped` applies.
    """
    Dr = _range(D)
    return (Dr.lo > 0) & (Dr.lo >= _D_SEPARATION * (Dr.hi - Dr.lo))


_D_SEPARATION = 4.0


def _damped(a, D, t, which):
    """``exp(-a t) cosh(sqrt(D) t)`` (``which = "ch"``) or ``exp(-a t) sinh(sqrt(D) t)/sqrt(D)``.

    In general as ``exp(-a t) cu(D t^2)`` and ``t exp(-a t) su(D t^2)``. Where ``D`` is
    positive and away from 0 (:func:`_overdamped`), as ``exp(-l1 t) (1 + exp(-2 r t))/2`` and
    ``t exp(-l1 t) emq(2 r t)`` with ``r = sqrt(D)``, ``l1 = (a^2 - D)/(a + r)`` (the slow
    rate, without cancellation) and ``emq(x) = (1 - exp(-x))/x``: in the general form the
    factors ``exp(-a t)`` and ``cu``, ``su`` grow and decay together and interval arithmetic
    loses their product's cancellation, while ``l1 t`` and ``r t`` vary slowly.
    """
    u = D * _call("pow", t, 2)
    e = _call("exp", -(a * t))
    gen = e * _call("cu", u) if which == "ch" else t * e * _call("su", u)
    over = _overdamped(D)
    if not np.any(over):
        return gen
    Ds = where(over, D, 4.0)
    r = _call("sqrt", Ds)
    l1 = (_call("pow", a, 2) - Ds) / (a + r)
    e1 = _call("exp", -(l1 * t))
    x = r * t * 2
    if which == "ch":
        alt = e1 * (_call("exp", -x) + 1) * 0.5
    else:
        alt = t * e1 * _call("emq", x)
    return where(over, alt, gen)


def interval_dch(a, D, t):
    """``exp(-a t) cosh(sqrt(D) t)`` (entire in ``D``) of intervals or centred forms."""
    return _damped(a, D, t, "ch")


def interval_dsh(a, D, t):
    """``exp(-a t) sinh(sqrt(D) t) / sqrt(D)`` (entire in ``D``) of intervals or forms."""
    return _damped(a, D, t, "sh")


#: The backend of the generated kernels on :class:`~hybridpd.pair.intervals.Interval`,
#: :class:`CForm` and :class:`CForm2` operands.
INTERVAL_OPS = types.SimpleNamespace(
    Q=lambda p, q: Interval(iv.widen_down(p / q), iv.widen_up(p / q)),
    PI=Interval(iv.widen_down(math.pi), iv.widen_up(math.pi)),
    POW=lambda x, k: _call("pow", x, k), SQRT=lambda x: _call("sqrt", x),
    EXP=lambda x: _call("exp", x), SIN=lambda x: _call("sin", x),
    COS=lambda x: _call("cos", x), DCH=interval_dch, DSH=interval_dsh)
