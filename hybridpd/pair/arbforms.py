"""Ball arithmetic for the arb confirmation: boxes, centred forms, jets and the damped flow.

The backend on which :mod:`hybridpd.pair.arbcheck` runs the generated kernels of
:mod:`hybridpd.pair.interval_kernels`: arrays of python-flint ``arb`` balls
(``dtype=object``), NumPy serving only as a container. Nothing here imports NumPy's interval
code (:mod:`~hybridpd.pair.intervals`, :mod:`~hybridpd.pair.centred`), so a fault there cannot
confirm itself.

Centred forms in arb
--------------------
Ball arithmetic over a box of parameters has interval arithmetic's *dependency* problem
(every occurrence of a parameter varies independently): evaluated naively over one cell of
a 101 x 101 map of ``kp, kv`` in ``[0.1, 50]`` the closed forms enclose ``C`` to +-0.44
where it varies by 0.005, and decide nothing. :class:`ArbForms` is the second-order centred
form of :class:`hybridpd.pair.centred.CForm2` written again on balls, for many boxes at once:
for one quantity ``f`` over a box with centre ``p0`` and ``delta = p - p0`` it carries the value
and gradient at the centre, the Hessian and the gradient over the box and the range, and
after every operation tightens the range and the gradient by the Taylor form
``f(p0) + grad f(p0) . delta + delta^T H delta / 2`` and the mean-value form. Elementary
functions enter through their value and first two derivatives on balls; the entire functions
of the damped flow, ``cu(u) = cosh(sqrt(u))``, ``su(u) = sinh(sqrt(u))/sqrt(u)`` (``cos``,
``sin`` continued below 0) and ``emq(x) = (1 - exp(-x))/x``, by their power series with a
bounded tail near 0 and by closed forms away from it. Where ``D = kv^2/4 - kp > 0`` on a
box the damped functions are evaluated both in that general form and in the overdamped form
``exp(-l1 t) (1 + exp(-2 r t))/2`` (``r = sqrt(D)``, ``l1 = (a^2 - D)/(a + r)``), the two
enclosures intersected. :class:`ArbJets` carries only the value and the gradient at the
centre (exact derivatives, no box), for Taylor bounds whose Hessian comes from a larger box
(:func:`taylor_bound`).

The precision is ``ctx.prec`` (callers use :data:`PREC` bits, ``flint.ctx.workprec``).
"""
from __future__ import annotations

import functools
import math
import types

import numpy as np

__all__ = ["PREC", "SCALED", "ArbBoxes", "ArbForms", "ArbJets", "arb_form_ops", "ball_cu",
           "ball_emq", "ball_su", "meet", "negative", "positive"]

#: Working precision (bits) of the confirmation.
PREC = 64

#: The kernels' scaled parameters, in their argument order.
SCALED = ("kpt", "kvt", "mu", "e", "gam", "w")


@functools.cache
def _flint():
    import flint

    return flint


def _arb(x=0, r=None):
    arb = _flint().arb
    return arb(x) if r is None else arb(x, r)


def _obj(values):
    values = list(values)
    out = np.empty(len(values), dtype=object)
    out[:] = list(values)
    return out


def _full(n, value):
    out = np.empty(n, dtype=object)
    out.fill(value)
    return out


def _u(f, nin=1):
    return np.frompyfunc(f, nin, 1)


def _meet1(a, b):
    """Intersection of two enclosures of one quantity; a NaN ball if they miss (a fault).

    A NaN enclosure (``0 * inf``, the root of a ball reaching below 0) says nothing: the
    other is kept.
    """
    try:
        c = a.intersection(b)
    except ValueError:
        return _flint().arb.nan()
    if c.is_finite():
        return c
    return b if not a.is_finite() else a


_meet = _u(_meet1, 2)
_exp = _u(lambda x: x.exp())
_sin = _u(lambda x: x.sin())       # arb encloses the exact range of sin, cos on a ball
_cos = _u(lambda x: x.cos())
_sqrt = _u(lambda x: x.sqrt())
_gt0 = _u(lambda x: bool(x > 0))
_lt0 = _u(lambda x: bool(x < 0))


def _bools(x):
    return np.asarray(x, dtype=bool)


def positive(x) -> np.ndarray:
    """Elementwise: the ball (or the range of the form) lies above 0."""
    return _bools(_gt0(_range(x)))


def negative(x) -> np.ndarray:
    """Elementwise: the ball (or the range of the form) lies below 0."""
    return _bools(_lt0(_range(x)))


# ----------------------------------------------------------------------------------------
# Boxes, centred forms and jets
# ----------------------------------------------------------------------------------------


class ArbBoxes:
    """``N`` boxes of named parameters, the directions of :class:`ArbForms` and :class:`ArbJets`.

    Parameters
    ----------
    lo, hi : dict
        ``name -> float array`` (shape ``(N,)``) of lower and upper bounds.
    names : sequence of str
        The parameters, in order.

    Attributes
    ----------
    dirs : list of str
        The names with a positive width in some box (the directions).
    """

    def __init__(self, lo, hi, names=SCALED):
        self.names = tuple(names)
        self.lo = {k: np.asarray(lo[k], float).ravel() for k in self.names}
        self.hi = {k: np.asarray(hi[k], float).ravel() for k in self.names}
        self.N = int(self.lo[self.names[0]].size)
        for k in self.names:
            if np.any(~(self.lo[k] <= self.hi[k])):
                raise ValueError(f"{k}: every lower bound must be <= its upper bound")
        self.dirs = [k for k in self.names if np.any(self.hi[k] > self.lo[k])]
        self.k = len(self.dirs)
        arb = _flint().arb
        self.centre, self.ball, self.delta, rads = {}, {}, [], []
        for k in self.names:
            lo, hi = self.lo[k], self.hi[k]
            self.centre[k] = _obj((arb(a) + arb(b)) / 2 for a, b in zip(lo, hi))
            self.ball[k] = _obj(arb(a).union(arb(b)) if b > a else arb(a)
                                for a, b in zip(lo, hi))
        for k in self.dirs:
            r = _obj(((arb(b) - arb(a)) / 2).upper() for a, b in zip(self.lo[k], self.hi[k]))
            rads.append(r)
            self.delta.append(_obj(arb(0, x) for x in r))
        self.pairs = [(i, j) for i in range(self.k) for j in range(i, self.k)]
        self.quad = []
        for i, j in self.pairs:
            if i == j:       # delta_i^2 / 2 in [0, r_i^2 / 2]
                self.quad.append(_obj(arb(h, h) for h in ((x * x) / 4 for x in rads[i])))
            else:
                self.quad.append(self.delta[i] * self.delta[j])
        z = _full(self.N, arb(0))
        self.zero_g = (z,) * self.k
        self.zero_h = (z,) * len(self.pairs)

    def take(self, idx) -> ArbBoxes:
        """The boxes at ``idx``."""
        return ArbBoxes({k: v[idx] for k, v in self.lo.items()},
                        {k: v[idx] for k, v in self.hi.items()}, self.names)

    def value(self, name, jets=False):
        """The parameter ``name``: a form (or jet) along its direction, else a ball array."""
        arb = _flint().arb
        if name not in self.dirs:
            return self.ball[name]
        i = self.dirs.index(name)
        one = [_full(self.N, arb(0)) for _ in range(self.k)]
        one[i] = _full(self.N, arb(1))
        one = tuple(one)
        if jets:
            return ArbJets(self.centre[name], one)
        return ArbForms(self.centre[name], one, self.zero_h, one, self.ball[name], self, False)

    def params(self, jets=False):
        """The kernels' scaled parameters, in order."""
        return [self.value(k, jets) for k in SCALED]


_TIGHTEN = {"g": True, "mv": False, "add": 2}


class ArbForms:
    """Second-order centred forms of one quantity over :class:`ArbBoxes` (see the module).

    Attributes
    ----------
    c : ndarray of arb
        Values at the centres.
    gc : tuple of ndarray
        Gradients at the centres, one array per direction.
    H : tuple of ndarray
        Hessians over the boxes, entries ``(i, j)``, ``i <= j``.
    g : tuple of ndarray
        Gradients over the boxes.
    r : ndarray of arb
        Ranges over the boxes.
    """

    __slots__ = ("H", "box", "c", "g", "gc", "r")
    __array_ufunc__ = None       # ndarray (op) ArbForms defers to ArbForms

    def __init__(self, c, gc, H, g, r, box, tighten=True):
        self.c, self.gc, self.H, self.box = c, gc, H, box
        if tighten:
            d = box.delta
            cf = c
            for x, di in zip(gc, d):
                cf = cf + x * di
            for h, q in zip(H, box.quad):
                cf = cf + h * q
            g = list(g)
            for i in (range(box.k) if _TIGHTEN["g"] and tighten != 1 else ()):
                gi = gc[i]
                for (a, b), h in zip(box.pairs, H):
                    if a == i:
                        gi = gi + h * d[b]
                    elif b == i:
                        gi = gi + h * d[a]
                g[i] = _meet(g[i], gi)
            r = _meet(r, cf)
            if _TIGHTEN["mv"]:
                mv = c
                for x, di in zip(g, d):
                    mv = mv + x * di
                r = _meet(r, mv)
            g = tuple(g)
        self.g = g
        self.r = r

    def __repr__(self):
        return f"ArbForms(n={len(self.r)}, directions={self.box.k})"

    def take(self, idx) -> ArbForms:
        """The forms of the boxes at ``idx`` (on ``box.take(idx)``)."""
        t = lambda x: x[idx]
        return ArbForms(t(self.c), tuple(map(t, self.gc)), tuple(map(t, self.H)),
                        tuple(map(t, self.g)), t(self.r), self.box.take(idx), False)

    def __neg__(self):
        n = lambda x: -x
        return ArbForms(-self.c, tuple(map(n, self.gc)), tuple(map(n, self.H)),
                        tuple(map(n, self.g)), -self.r, self.box, False)

    def __pos__(self):
        return self

    def __add__(self, o):
        if not isinstance(o, ArbForms):
            return ArbForms(self.c + o, self.gc, self.H, self.g, self.r + o, self.box, False)
        return ArbForms(self.c + o.c, tuple(x + y for x, y in zip(self.gc, o.gc)),
                        tuple(x + y for x, y in zip(self.H, o.H)),
                        tuple(x + y for x, y in zip(self.g, o.g)), self.r + o.r, self.box,
                        _TIGHTEN["add"])

    __radd__ = __add__

    def __sub__(self, o):
        if not isinstance(o, ArbForms):
            return ArbForms(self.c - o, self.gc, self.H, self.g, self.r - o, self.box, False)
        return ArbForms(self.c - o.c, tuple(x - y for x, y in zip(self.gc, o.gc)),
                        tuple(x - y for x, y in zip(self.H, o.H)),
                        tuple(x - y for x, y in zip(self.g, o.g)), self.r - o.r, self.box,
                        _TIGHTEN["add"])

    def __rsub__(self, o):
        return (-self) + o

    def __mul__(self, o):
        if not isinstance(o, ArbForms):
            m = lambda x: x * o
            return ArbForms(self.c * o, tuple(map(m, self.gc)), tuple(map(m, self.H)),
                            tuple(map(m, self.g)), self.r * o, self.box,
                            not isinstance(o, int))
        a, b = self, o
        ga, gb = a.g, b.g
        gc = tuple(x * b.c + a.c * y for x, y in zip(a.gc, b.gc))
        g = tuple(x * b.r + a.r * y for x, y in zip(ga, gb))
        H = tuple(ha * b.r + a.r * hb + (ga[i] * gb[i] * 2 if i == j else
                                         ga[i] * gb[j] + ga[j] * gb[i])
                  for (i, j), ha, hb in zip(a.box.pairs, a.H, b.H))
        return ArbForms(a.c * b.c, gc, H, g, a.r * b.r, a.box)

    __rmul__ = __mul__

    def unary(self, f, f1, f2):
        """``f(self)`` from vectorised ``f``, ``f'``, ``f''`` (chain rule to second order)."""
        d1c = f1(self.c)
        d1, d2 = f1(self.r), f2(self.r)
        g = self.g
        H = tuple(h * d1 + g[i] * g[j] * d2 for (i, j), h in zip(self.box.pairs, self.H))
        return ArbForms(f(self.c), tuple(x * d1c for x in self.gc), H,
                        tuple(x * d1 for x in g), f(self.r), self.box)

    def recip(self):
        """``1 / self``."""
        return self.unary(lambda x: 1 / x, lambda x: -1 / (x * x), lambda x: 2 / (x * x * x))

    def __truediv__(self, o):
        if not isinstance(o, ArbForms):
            return self * (1 / (_arb(o) if isinstance(o, int) else o))
        return self * o.recip()

    def __rtruediv__(self, o):
        return self.recip() * o

    def pow(self, k):
        """``self ** k`` for an integer ``k >= 1``."""
        k = int(k)
        if k == 1:
            return self
        if k == 2:
            two = _arb(2)
            return self.unary(lambda x: x * x, lambda x: 2 * x, lambda x: _full(len(x), two))
        return self.unary(lambda x: x**k, lambda x: k * x ** (k - 1),
                          lambda x: k * (k - 1) * x ** (k - 2))

    def exp(self):
        """``exp``."""
        return self.unary(_exp, _exp, _exp)

    def sin(self):
        """``sin``."""
        return self.unary(_sin, _cos, lambda x: -_sin(x))

    def cos(self):
        """``cos``."""
        return self.unary(_cos, lambda x: -_sin(x), lambda x: -_cos(x))

    def sqrt(self):
        """``sqrt``."""
        return self.unary(_sqrt, lambda x: 1 / (2 * _sqrt(x)),
                          lambda x: -1 / (4 * x * _sqrt(x)))


class ArbJets:
    """Values and gradients at the centres of boxes (exact derivatives; no box enclosure).

    Attributes
    ----------
    c : ndarray of arb
    gc : tuple of ndarray
    """

    __slots__ = ("c", "gc")
    __array_ufunc__ = None

    def __init__(self, c, gc):
        self.c, self.gc = c, gc

    @property
    def r(self):
        return self.c

    def take(self, idx) -> ArbJets:
        return ArbJets(self.c[idx], tuple(x[idx] for x in self.gc))

    def __neg__(self):
        return ArbJets(-self.c, tuple(-x for x in self.gc))

    def __pos__(self):
        return self

    def __add__(self, o):
        if not isinstance(o, ArbJets):
            return ArbJets(self.c + o, self.gc)
        return ArbJets(self.c + o.c, tuple(x + y for x, y in zip(self.gc, o.gc)))

    __radd__ = __add__

    def __sub__(self, o):
        if not isinstance(o, ArbJets):
            return ArbJets(self.c - o, self.gc)
        return ArbJets(self.c - o.c, tuple(x - y for x, y in zip(self.gc, o.gc)))

    def __rsub__(self, o):
        return (-self) + o

    def __mul__(self, o):
        if not isinstance(o, ArbJets):
            return ArbJets(self.c * o, tuple(x * o for x in self.gc))
        return ArbJets(self.c * o.c, tuple(x * o.c + self.c * y for x, y in zip(self.gc, o.gc)))

    __rmul__ = __mul__

    def unary(self, f, f1, f2=None):
        d1 = f1(self.c)
        return ArbJets(f(self.c), tuple(x * d1 for x in self.gc))

    def recip(self):
        inv = 1 / self.c
        return ArbJets(inv, tuple(-x * inv * inv for x in self.gc))

    def __truediv__(self, o):
        if not isinstance(o, ArbJets):
            return self * (1 / (_arb(o) if isinstance(o, int) else o))
        return self * o.recip()

    def __rtruediv__(self, o):
        return self.recip() * o

    def pow(self, k):
        k = int(k)
        if k == 1:
            return self
        p = self.c ** (k - 1)
        return ArbJets(p * self.c, tuple(x * p * k for x in self.gc))

    def exp(self):
        e = _exp(self.c)
        return ArbJets(e, tuple(x * e for x in self.gc))

    def sin(self):
        return self.unary(_sin, _cos)

    def cos(self):
        return self.unary(_cos, lambda x: -_sin(x))

    def sqrt(self):
        s = _sqrt(self.c)
        return ArbJets(s, tuple(x / (2 * s) for x in self.gc))


_FORMS = (ArbForms, ArbJets)


def _range(x):
    return x.r if isinstance(x, _FORMS) else x


def meet(a, b):
    """Component-wise intersection of two enclosures of one quantity (forms, jets or balls)."""
    if isinstance(a, ArbForms) and isinstance(b, ArbForms):
        return ArbForms(_meet(a.c, b.c), tuple(map(_meet, a.gc, b.gc)),
                        tuple(map(_meet, a.H, b.H)), tuple(map(_meet, a.g, b.g)),
                        _meet(a.r, b.r), a.box)
    if isinstance(a, ArbJets) and isinstance(b, ArbJets):
        return ArbJets(_meet(a.c, b.c), tuple(map(_meet, a.gc, b.gc)))
    if isinstance(a, _FORMS) or isinstance(b, _FORMS):
        return a if isinstance(a, _FORMS) else b
    return _meet(a, b)


def _constant_forms(v, box):
    v = v if isinstance(v, np.ndarray) else _full(box.N, v)
    return ArbForms(v, box.zero_g, box.zero_h, box.zero_g, v, box, False)


def _where(mask, a, b):
    """Elementwise ``a`` where ``mask`` else ``b`` (forms, jets or ball arrays of one kind)."""
    w = lambda x, y: np.where(mask, x, y)
    if isinstance(a, ArbForms) and not isinstance(b, ArbForms):
        b = _constant_forms(b, a.box)
    elif isinstance(b, ArbForms) and not isinstance(a, ArbForms):
        a = _constant_forms(a, b.box)
    if isinstance(a, ArbJets) and not isinstance(b, ArbJets):
        b = ArbJets(_full(len(a.c), b) if not isinstance(b, np.ndarray) else b,
                    tuple(_full(len(a.c), _arb(0)) for _ in a.gc))
    elif isinstance(b, ArbJets) and not isinstance(a, ArbJets):
        a = ArbJets(_full(len(b.c), a) if not isinstance(a, np.ndarray) else a,
                    tuple(_full(len(b.c), _arb(0)) for _ in b.gc))
    if isinstance(a, ArbForms):
        return ArbForms(w(a.c, b.c), tuple(map(w, a.gc, b.gc)), tuple(map(w, a.H, b.H)),
                        tuple(map(w, a.g, b.g)), w(a.r, b.r), a.box, False)
    if isinstance(a, ArbJets):
        return ArbJets(w(a.c, b.c), tuple(map(w, a.gc, b.gc)))
    return w(a, b)


# ----------------------------------------------------------------------------------------
# The entire functions of the damped flow, with two derivatives
# ----------------------------------------------------------------------------------------


def _series(u, j, coef):
    """``f^(j)(u)`` of ``f = sum_k coef(k) u^k`` for a ball ``u``, the tail bounded.

    The three series used here have ``|c_(k+1)| <= |c_k| / (k + 1)``; with ``R = |u|`` their
    terms decrease at least by half from ``N >= 2 R`` on, so the tail is at most twice its
    first term (the number of terms grows until that is below ``2^-(prec + 8)``).
    """
    arb = _flint().arb
    if not u.is_finite():
        return arb.nan()
    R = float(abs(u).upper())
    co, N, t = _coefficients(coef, j, R)
    acc = co[N - 1]
    for k in range(N - 2, -1, -1):
        acc = acc * u + co[k]
    return acc + arb(0, t)


@functools.lru_cache(maxsize=256)
def _coefficients_at(coef, j, R_bin, prec):
    """The coefficients ``c_(k+j) (k+j)!/k!`` of the ``j``-th derivative, the number ``N`` of
    terms and the tail bound for ``|u| <= R_bin``."""
    arb = _flint().arb
    R = float(R_bin)
    N = max(16, int(2 * R) + 2)
    tiny = arb(2) ** -(prec + 8)
    while True:
        t = abs(coef(N + j) * arb.fac_ui(N + j) / arb.fac_ui(N)) * arb(R) ** N
        if t < tiny or N > 400:
            break
        N += 8
    co = [coef(k + j) * (arb.fac_ui(k + j) / arb.fac_ui(k)) for k in range(N)]
    return co, N, (2 * t).upper()


def _coefficients(coef, j, R):
    # R rounded up to a quarter, so that few tables serve all balls
    R_bin = math.ceil(R * 4) / 4
    return _coefficients_at(coef, j, R_bin, _flint().ctx.prec)


def _cu_c(k):
    return 1 / _flint().arb.fac_ui(2 * k)


def _su_c(k):
    return 1 / _flint().arb.fac_ui(2 * k + 1)


def _emq_c(k):
    return (-1) ** k / _flint().arb.fac_ui(k + 1)


_NEAR = 4   # |u| below this: power series


def _su_point(u, j):
    """``su^(j)(u)`` from the closed form and ``4 u y'' + 6 y' - y = 0`` (``|u| > 4``)."""
    if u > 0:
        r = u.sqrt()
        y = [r.sinh() / r]
    else:
        r = (-u).sqrt()
        y = [r.sin() / r]
    if j >= 1:
        y.append((_cu_point(u, 0) - y[0]) / (2 * u))    # 2 u su' = cu - su
    for m in range(j - 1):                              # y^(m+2) from y^(m), y^(m+1)
        y.append((y[m] - (4 * m + 6) * y[m + 1]) / (4 * u))
    return y[j]


def _cu_point(u, j):
    if j >= 1:
        return _su_point(u, j - 1) / 2                  # cu' = su / 2
    return u.sqrt().cosh() if u > 0 else (-u).sqrt().cos()


def _emq_point(x, j):
    """``emq^(j)(x)`` from ``x y^(m+1) + (m + 1) y^(m) = (-1)^m exp(-x)`` (``|x| > 4``)."""
    ex = (-x).exp()
    y = (1 - ex) / x
    for m in range(j):
        y = ((-1) ** m * ex - (m + 1) * y) / x
    return y


def _direct(u, j, point, coef, near):
    if not (u > near or u < -near):
        return _series(u, j, coef)
    return point(u, j)


def _entire(u, j, point, coef, near=_NEAR, monotone=False):
    """``f^(j)`` on a ball: at its ends where ``f^(j+1)`` has a sign (``monotone``, or
    proved here), else the direct evaluation met with the centred form
    ``f^(j)(m) + f^(j+1)(u) (u - m)``."""
    arb = _flint().arb
    if not u.is_finite():
        return arb.nan()
    if u.rad() <= 1e-15 * (1 + abs(u.mid())):
        return _direct(u, j, point, coef, near)
    d = None if monotone else _direct(u, j + 1, point, coef, near)
    if monotone or d > 0 or d < 0:
        a, b = u.lower(), u.upper()
        return _direct(a, j, point, coef, near).union(_direct(b, j, point, coef, near))
    y = _direct(u, j, point, coef, near)
    m = u.mid()
    return _meet1(y, _direct(m, j, point, coef, near) + d * arb(0, u.rad()))


def ball_cu(u, j=0):
    """``cu(u) = cosh(sqrt(u))`` (``cos(sqrt(-u))`` below 0), or its derivative of order ``j``."""
    # every derivative of cu and su is positive on u >= 0 (positive coefficients)
    return _entire(u, j, _cu_point, _cu_c, monotone=u.is_finite() and u.lower() >= 0)


def ball_su(u, j=0):
    """``su(u) = sinh(sqrt(u))/sqrt(u)`` (``sin`` below 0), or its derivative of order ``j``."""
    return _entire(u, j, _su_point, _su_c, monotone=u.is_finite() and u.lower() >= 0)


def ball_emq(x, j=0):
    """``emq(x) = (1 - exp(-x))/x`` (1 at 0), or its derivative of order ``j``."""
    # emq^(j)(x) = (-1)^j int_0^1 s^j exp(-x s) ds: every derivative has a fixed sign
    return _entire(x, j, _emq_point, _emq_c, 1, monotone=True)


_CU = tuple(_u(lambda v, j=j: ball_cu(v, j)) for j in range(3))
_SU = tuple(_u(lambda v, j=j: ball_su(v, j)) for j in range(3))
_EMQ = tuple(_u(lambda v, j=j: ball_emq(v, j)) for j in range(3))


def _fn(x, F):
    if isinstance(x, _FORMS):
        return x.unary(*F)
    if isinstance(x, np.ndarray):
        return F[0](x)
    return F[0](np.asarray([x], dtype=object))[0] if not isinstance(x, int) else \
        F[0](np.asarray([_arb(x)], dtype=object))[0]


def _elem(x, method, ufunc):
    if isinstance(x, _FORMS):
        return getattr(x, method)()
    if isinstance(x, np.ndarray):
        return ufunc(x)
    return getattr(_arb(x) if isinstance(x, int) else x, method)()


def _pow(x, k):
    if isinstance(x, _FORMS):
        return x.pow(k)
    return x**k


def _damped(a, D, t, which):
    """``exp(-a t) cosh(sqrt(D) t)`` or ``exp(-a t) sinh(sqrt(D) t)/sqrt(D)`` (see module)."""
    u = D * t * t
    e = _elem(-(a * t), "exp", _exp)
    gen = e * _fn(u, _CU) if which == "ch" else t * e * _fn(u, _SU)
    Dr = _range(D)
    pos = _bools(_gt0(Dr)) if isinstance(Dr, np.ndarray) else np.array(bool(Dr > 0))
    if not np.any(pos):
        return gen
    Ds = _where(pos, D, _arb(4)) if not np.all(pos) else D
    if isinstance(Ds, np.ndarray) or not isinstance(Ds, _FORMS):
        r = _elem(Ds, "sqrt", _sqrt)
    else:
        r = Ds.sqrt()
    l1 = (a * a - Ds) / (a + r)
    e1 = _elem(-(l1 * t), "exp", _exp)
    x = 2 * r * t
    alt = e1 * (_elem(-x, "exp", _exp) + 1) / 2 if which == "ch" else t * e1 * _fn(x, _EMQ)
    if not np.all(pos):
        alt = _where(pos, alt, gen)
    return meet(gen, alt)


def arb_form_ops():
    """The backend of the generated kernels on ball arrays, :class:`ArbForms` and
    :class:`ArbJets` (built at the current ``ctx.prec``: ``PI`` is a ball at that precision).
    """
    arb = _flint().arb
    return types.SimpleNamespace(
        Q=lambda p, q: arb(p) / q, PI=arb.pi(), POW=_pow,
        SQRT=lambda x: _elem(x, "sqrt", _sqrt), EXP=lambda x: _elem(x, "exp", _exp),
        SIN=lambda x: _elem(x, "sin", _sin), COS=lambda x: _elem(x, "cos", _cos),
        DCH=lambda a, D, t: _damped(a, D, t, "ch"), DSH=lambda a, D, t: _damped(a, D, t, "sh"))
