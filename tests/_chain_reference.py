"""An independent reference for the chains of hybridpd.mechanics.samples.mass_chain.

Unit masses in a line, neighbours joined by a spring (k) and damper (c) in parallel with a
clearance |q_i - q_{i+1}| <= L, a PD force on mass 0 tracking amp cos(om t). Written from
the equations, not from the package: scipy's solve_ivp (DOP853) between events, terminal
events on the gaps and on the held contacts' forces, Newton's law for the impacting contact
and the held ones by enumerating the active sets of their LCP, and a hand-written sticking
rule: a rebound slower than ``v_stick`` (too small to resolve, the tail of an accumulation)
is plastic, and a contact at rest on its bound stays held while its force pushes (an LCP in
the forces, again by enumeration). Contacts left closing on their bounds by an impact are hit
at once, one after the other (the sequential model of impacts in no time).
"""
from __future__ import annotations

import itertools

import numpy as np
from scipy.integrate import solve_ivp


def _lcp(A, q, tol=1e-12):
    """``z >= 0, A z + q >= 0, z . (A z + q) = 0`` by enumerating the active sets."""
    k = len(q)
    scale = 1.0 + np.abs(q).max(initial=0.0)
    for r in range(k + 1):
        for J in itertools.combinations(range(k), r):
            z = np.zeros(k)
            if J:
                z[list(J)] = np.linalg.solve(A[np.ix_(J, J)], -q[list(J)])
            if np.all(z >= -tol * scale) and np.all(A @ z + q >= -tol * scale):
                return np.maximum(z, 0.0)
    raise RuntimeError("no LCP solution")


class ReferenceChain:
    """The chain's motion from rest at ``t = 0`` (see the module docstring)."""

    def __init__(self, n, e, L=0.05, k=20.0, c=0.1, kp=50.0, kv=5.0, amp=1.0, om=3.0,
                 v_stick=1e-5, rtol=1e-11, atol=1e-13):
        self.n, self.e, self.L = n, e, L
        self.kp, self.kv, self.amp, self.om = kp, kv, amp, om
        self.v_stick, self.rtol, self.atol = v_stick, rtol, atol
        self.K = np.zeros((n, n))
        self.C = np.zeros((n, n))
        for i in range(n - 1):
            for A, val in ((self.K, k), (self.C, c)):
                A[i:i + 2, i:i + 2] += val * np.array([[1.0, -1.0], [-1.0, 1.0]])
        self.Wg = np.eye(n)[:-1] - np.eye(n)[1:]          # gap rows: q_i - q_{i+1}

    # -- the equations
    def force(self, t, q, v):
        f = -self.K @ q - self.C @ v
        f[0] += (self.kp * (self.amp * np.cos(self.om * t) - q[0])
                 + self.kv * (-self.amp * self.om * np.sin(self.om * t) - v[0]))
        return f

    def normals(self, S):
        """Rows ``-wall w_k``: their product with v is the separating velocity."""
        return np.array([-w * self.Wg[kk] for kk, w in S]).reshape(len(S), self.n)

    def accel(self, t, q, v, S):
        """Accelerations with the contacts of ``S`` held, and their forces."""
        f = self.force(t, q, v)
        if not S:
            return f, np.zeros(0)
        N = self.normals(S)
        lam = -np.linalg.solve(N @ N.T, N @ f)
        return f + N.T @ lam, lam

    def gap(self, q, s):
        return self.L - s[1] * (self.Wg[s[0]] @ q)          # >= 0 inside

    # -- the rules
    def hold(self, t, q, v, cand):
        """The candidates (at rest on their bounds) whose forces push."""
        if not cand:
            return []
        N = self.normals(cand)
        f = self.force(t, q, v)
        lam = _lcp(N @ N.T, N @ f)
        acc = N @ N.T @ lam + N @ f
        return [s for s, a in zip(cand, acc) if a <= 1e-9 * (1.0 + np.abs(f).max())]

    def impact(self, v, S, hit, again):
        """Newton's law of ``hit`` with the held ``S``; the contacts left at rest."""
        allc = list(S) + [hit]
        N = self.normals(allc)
        u = N @ v
        slow = self.e * abs(u[-1]) < self.v_stick or again
        b = np.zeros(len(allc))
        b[-1] = 0.0 if slow else self.e * max(-u[-1], 0.0)
        v1 = v + N.T @ _lcp(N @ N.T, u - b)
        u1 = N @ v1
        return v1, [s for s, x in zip(allc, u1) if abs(x) <= 1e-12 * (1 + np.abs(u).max())]

    def snap(self, q, s):
        """Put contact ``s`` exactly on its bound (a shift of ~1e-15): its gap event, 1e-14
        inside, then needs a real approach to fire again."""
        d = s[1] * self.L - self.Wg[s[0]] @ q
        q[s[0]] += 0.5 * d
        q[s[0] + 1] -= 0.5 * d

    # -- the run
    def _events(self, S, free):
        def gap(s):
            ev = lambda t, y: self.gap(y[:self.n], s) - 1e-14
            ev.terminal, ev.direction = True, -1
            return ev

        def pull(i):
            ev = lambda t, y: self.accel(t, y[:self.n], y[self.n:], S)[1][i] + 1e-9
            ev.terminal, ev.direction = True, -1
            return ev

        return [gap(s) for s in free] + [pull(i) for i in range(len(S))]

    def _hit(self, t, y, S, s, again):
        n = self.n
        self.pre.append((t, s, tuple(S), y.copy()))
        y[n:], rest = self.impact(y[n:], S, s, again)
        self.snap(y[:n], s)
        self.impacts.append((t, s))
        return sorted(self.hold(t, y[:n], y[n:], rest))

    def run(self, t_end, max_events=20000):
        n = self.n
        y, t, S = np.zeros(2 * n), 0.0, []
        self.segments, self.impacts, self.sticks, self.pre = [], [], [], []
        last, t_start = None, None
        for _ in range(max_events):
            free = [(kk, w) for kk in range(n - 1) for w in (1, -1) if kk not in dict(S)]
            pend = [(float(self.normals([s])[0] @ y[n:]), s) for s in free
                    if self.gap(y[:n], s) <= 1e-12 and self.normals([s])[0] @ y[n:] < -1e-12]
            if pend:       # left closing on its bound by the last impact: hit at once
                s = min(pend)[1]
                new = self._hit(t, y, S, s, again=(s == last and t == t_start))
                last, t_start = s, t
            else:
                t_start = t
                sol = solve_ivp(
                    lambda tt, yy, S=S: np.concatenate([yy[n:],
                                                        self.accel(tt, yy[:n], yy[n:], S)[0]]),
                    (t, t_end), y, method="DOP853", rtol=self.rtol, atol=self.atol,
                    events=self._events(S, free), dense_output=True, first_step=1e-10)
                self.segments.append((t, sol.t[-1], sol.sol))
                y, t = sol.y[:, -1].copy(), float(sol.t[-1])
                if sol.status == 0:
                    return self
                i = min((j for j, te in enumerate(sol.t_events) if len(te)),
                        key=lambda j: sol.t_events[j][0])
                if i < len(free):
                    s = free[i]
                    new = self._hit(t, y, S, s, again=(s == last and t == t_start))
                    last = s
                else:
                    rel = S[i - len(free)]
                    new = sorted(self.hold(t, y[:n], y[n:], [x for x in S if x != rel]))
            self.sticks += [(t, s) for s in new if s not in S]
            S = new
        raise RuntimeError("max_events reached")

    def positions(self, ts):
        out = np.empty((len(ts), self.n))
        for j, tt in enumerate(ts):
            sol = next(seg[2] for seg in self.segments if seg[0] <= tt <= seg[1])
            out[j] = sol(tt)[:self.n]
        return out
