"""The paper's simple symmetric orbit (order 1), written from its equations only.

An independent reference for the certified classification (tests and
``benchmarks/bench_certified_coarse.py``): nothing of hybridpd's closed forms is used. The
closed loop between impacts is a 6 x 6 linear system flowed with ``scipy.linalg.expm``,
Newton's impact law is applied by hand, the symmetry conditions (13)-(14) are solved as a
linear system for ``(C, S) = xm (cos w t0, sin w t0)``, viability is decided by dense
sampling of the gap (a stepped propagator ``expm(A dt)^k``), and the multipliers are the
eigenvalues of central finite differences of the impact map (contacts bracketed on a grid
and located with ``brentq``).
"""
import math

import numpy as np
import scipy.linalg
from scipy.optimize import brentq

STABLE, UNSTABLE, NO_ORBIT = 1, 2, 3


class Paper:
    """The simple symmetric orbit of order 1 from the paper's equations (see the module)."""

    def __init__(self, case, kp, kv, mu, e, L, omega, m2=1.0, x10=1.0):
        self.mu, self.e, self.L, self.w, self.x10 = mu, e, L, omega, x10
        A = np.zeros((6, 6))
        A[0, 1] = A[2, 3] = 1.0
        A[4, 5], A[5, 4] = -omega, omega
        # m2 y2' = m2 xd'' + kp (xd - x) + kv (xd' - y), xd = pc, xd' = -w ps, xd'' = -w^2 pc
        x_col, y_col = (2, 3) if case == "collocated" else (0, 1)
        A[3, 4] = -omega**2 + kp / m2
        A[3, 5] = -kv * omega / m2
        A[3, x_col] -= kp / m2
        A[3, y_col] -= kv / m2
        self.A = A
        self.tau = math.pi / omega
        self.v = 2 * x10 * omega / math.pi
        self.y20 = self.v * (e - 2 * mu - 1) / (1 + e)
        self.y21 = self.v * (e + 2 * e * mu - 1) / (1 + e)
        x20 = x10 - L
        Phi = scipy.linalg.expm(A * self.tau)
        # x2(tau) = -x20, y2(tau) = -y20, linear in (C, S)
        base = Phi @ np.array([x10, -self.v, x20, self.y21, 0.0, 0.0])
        Mcs = Phi[2:4, 4:6]
        self.C, self.S = np.linalg.solve(Mcs, -np.array([x20, self.y20]) - base[2:4])
        self.xm = math.hypot(self.C, self.S)
        self.X0 = np.array([x10, -self.v, x20, self.y21, self.C, self.S])
        self._steps = {}

    def flow(self, X, t):
        return scipy.linalg.expm(self.A * t) @ X

    def _stepper(self, dt):
        if dt not in self._steps:
            self._steps[dt] = scipy.linalg.expm(self.A * dt)
        return self._steps[dt]

    def _track(self, X, dt, num):
        """States at ``dt, 2 dt, ..., num dt`` from ``X`` (rows)."""
        E = self._stepper(dt)
        out = np.empty((num, X.size))
        for k in range(num):
            X = E @ X
            out[k] = X
        return out

    def gap_max(self, num=2000):
        """max |x1 - x2| over the open flight (dense sampling, ``num`` interior times)."""
        dt = self.tau / (num + 1)
        Y = self._track(self.X0, dt, num)
        return float(np.max(np.abs(Y[:, 0] - Y[:, 2])))

    def _impact(self, X):
        y1, y2 = X[1], X[3]
        mu, e = self.mu, self.e
        X = X.copy()
        X[1] = ((mu - e) * y1 + (1 + e) * y2) / (1 + mu)
        X[3] = ((1 + e) * mu * y1 + (1 - mu * e) * y2) / (1 + mu)
        return X

    def _to_wall(self, X, wall, num=240):
        """Flow until z3 = wall * L (first crossing after leaving the other wall)."""
        # a step incommensurate with tau: a symmetric orbit's contact at t = tau falls
        # inside a step, not on a grid point where the two propagators could differ in sign
        dt = 3 * self.tau / (num + 0.381966)
        Y = np.vstack([X, self._track(X, dt, num)])
        vals = Y[:, 0] - Y[:, 2] - wall * self.L

        def g(t):
            Z = self.flow(X, t)
            return Z[0] - Z[2] - wall * self.L

        for k in range(2, num + 1):
            if vals[k - 1] * vals[k] <= 0:
                a, b = (k - 1) * dt, min(k + 1, num) * dt
                if g(a) * g(b) > 0:   # the stepped values' sign was rounding: go on
                    continue
                t = brentq(g, a, b, xtol=1e-15, rtol=1e-15)
                return self.flow(X, t)
        raise AssertionError("no contact")

    def section_map(self, s):
        """P on the pre-impact section z3 = +L: (phi, z1, z2, z4) -> the next one."""
        phi, z1, z2, z4 = s
        X = np.array([z1 + self.L, z2 + z4, z1, z2, self.xm * math.cos(self.w * phi),
                      self.xm * math.sin(self.w * phi)])
        X = self._to_wall(self._impact(X), -1)
        X = self._to_wall(self._impact(X), +1)
        ph = math.atan2(X[5], X[4]) / self.w
        ph += round((phi - ph) * self.w / (2 * math.pi)) * 2 * math.pi / self.w
        return np.array([ph, X[2], X[3], X[1] - X[3]])

    def fixed_point(self):
        phi0 = math.atan2(self.S, self.C) / self.w % (2 * math.pi / self.w)
        return np.array([phi0, self.x10 - self.L, self.y20, self.v - self.y20])

    def multipliers(self, h=1e-6):
        """Moduli of the eigenvalues of central finite differences of ``P``, largest first."""
        s0 = self.fixed_point()
        J = np.zeros((4, 4))
        for j in range(4):
            d = np.zeros(4)
            d[j] = h * max(1.0, abs(s0[j]))
            J[:, j] = (self.section_map(s0 + d) - self.section_map(s0 - d)) / (2 * d[j])
        return np.sort(np.abs(np.linalg.eigvals(J)))[::-1]

    def verdict(self):
        """``(class, gap margin, spectral radius)``: 1 stable, 2 unstable, 3 no orbit (an
        extra contact); the margin is ``L - max |z3|`` over the sampled flight, the radius
        NaN without an orbit."""
        margin = self.L - self.gap_max()
        if margin <= 0:
            return NO_ORBIT, margin, math.nan
        rho = float(self.multipliers()[0])
        return (STABLE if rho < 1 else UNSTABLE), margin, rho


def paper_class(case, kp, kv, *, mu, e, L, omega):
    """The class (1 stable, 2 unstable, 3 no orbit) of ``(kp, kv)`` by :class:`Paper`."""
    return Paper(case, kp, kv, mu, e, L, omega).verdict()[0]
