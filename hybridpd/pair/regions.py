"""Existence and stability regions of the symmetric orbit in a parameter plane (Figs 4-5).

:class:`SymmetricFamily` is the impact pair's family of symmetric orbits for
:func:`hybridpd.sweeps.regions.region_map`: its hook ``classify_grid`` evaluates
:func:`hybridpd.pair.orbits.symmetric_orbits` over a grid of two parameters (by default the
gains ``kp``, ``kv``) for a list of restitution coefficients, vectorised. Every grid point
gets exactly the answer :func:`hybridpd.pair.orbits.symmetric_orbit` gives for it (existence
with rigorous viability, multipliers of ``DP``); with ``certify=True`` the interval proofs of
:mod:`hybridpd.pair.certified` classify every cell. Arrays are indexed ``[e][y][x]``.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from hybridpd.model import (
    Case,
    check_array,
    check_int,
    check_named_axis,
    check_odd_order,
    check_positive,
)
from hybridpd.pair.orbits import REASONS, symmetric_orbits
from hybridpd.sweeps.regions import RegionMap as _RegionMap  # the old name: __getattr__

__all__ = ["AXES", "SymmetricFamily"]

# Each call of the vectorised evaluation costs ~10 ms besides its points (~8 us each):
# chunks of 16384 points keep that overhead near 10%.
_MIN_REGION_CHUNK = 16384

#: Parameters a region map can sweep (any two of them), besides the list of ``e``.
AXES = ("kp", "kv", "mu", "L", "omega", "m2", "x10")


@dataclass(frozen=True)
class SymmetricFamily:
    """The impact pair's symmetric orbits, classified in closed form: a family of
    :func:`~hybridpd.sweeps.regions.region_map`.

    Parameters
    ----------
    case : {"collocated", "noncollocated"}
    e : sequence of float
        Restitution coefficients in [0, 1] (one map each).
    mu, omega, L or gamma, x10, m2, n, kp, kv
        The fixed parameters (``L = gamma * x10`` when ``gamma`` is given). Each is needed
        only when it is not a swept axis.

    Examples
    --------
    >>> fam = SymmetricFamily("collocated", e=[0.5], mu=0.1, omega=5.0, gamma=0.75)
    >>> rm = fam.classify_grid(("kp", 9, 11, 3), ("kv", 19, 21, 2), certify=True,
    ...                        progress=False)
    >>> rm.stable.all(), rm.certified.tolist()            # every cell proved stable
    (np.True_, [[[1, 1, 1], [1, 1, 1]]])
    """

    case: str = "collocated"
    e: tuple = (0.1, 0.5, 0.9)
    mu: float | None = None
    omega: float | None = None
    L: float | None = None
    gamma: float | None = None
    x10: float = 1.0
    m2: float = 1.0
    n: int = 1
    kp: float | None = None
    kv: float | None = None

    def _fixed(self, swept) -> dict:
        """The parameters not swept, checked (``ValueError`` naming the culprit)."""
        x10, L = self.x10, self.L
        if "x10" not in swept:
            x10 = check_positive("x10", x10)
        if "L" in swept:
            if self.gamma is not None or L is not None:
                raise ValueError("L is a swept axis: do not give L or gamma as well")
        elif (L is None) == (self.gamma is None):
            raise ValueError("give exactly one of L or gamma (L = gamma * x10)")
        elif L is None and "x10" in swept:
            raise ValueError("with x10 swept give L, not gamma (L would change along the "
                             "axis)")
        else:
            L = check_positive("L", L) if L is not None else \
                check_positive("gamma", self.gamma) * x10
        given = {"mu": self.mu, "omega": self.omega, "L": L, "x10": x10, "m2": self.m2,
                 "kp": self.kp, "kv": self.kv}
        fixed = {}
        for nm, val in given.items():
            if nm in swept:
                continue
            if val is None:
                raise ValueError(f"{nm} must be given when it is not a swept axis")
            fixed[nm] = check_positive(nm, val)
        return fixed

    def classify_grid(self, x=("kp", 0.1, 50.0, 200), y=("kv", 0.1, 50.0, 200), *,
                      executor="serial", max_workers=None, chunk_size=None, store=None,
                      progress=True, certify=False, certify_depth="auto") -> _RegionMap:
        """Existence and stability of the symmetric orbit over a grid of two parameters.

        Parameters
        ----------
        x, y : (name, MIN, MAX, NUM)
            The swept parameters (names from :data:`AXES`), each on
            ``linspace(MIN, MAX, NUM)``.
        executor, max_workers, chunk_size, store, progress
            See :func:`hybridpd.sweeps.sweep.run_sweep`. ``"serial"`` is the default because
            the evaluation is vectorised (a 200 x 200 x 3 map takes about a second), which
            beats starting worker processes; a ``store`` (a ``.zarr`` directory) makes the
            sweep write as it goes and resume. Progress is labelled e.g. ``regions
            collocated e=0.1,0.5``. The default ``chunk_size`` is at least 16384 points (a
            function of the grid size only): smaller chunks lose to per-call overhead.
        certify : bool
            Also prove the class of every grid point's cell (the box half-way to its
            neighbours; edge cells end at the first and last points) with the interval
            proofs of :mod:`hybridpd.pair.certified`, into the variable ``certified`` (CF
            flags: 0 undecided, 1 proved stable, 2 proved unstable, 3 proved no orbit). About
            a second per thousand cells; with ``store`` it writes and resumes
            ``NAME.certified.zarr`` beside it.
        certify_depth : int or "auto"
            Bisections of an undecided cell (0 to 12; ``"auto"``: 3 for a 101 x 101 grid, one
            more for every factor 2 fewer cells, :func:`hybridpd.pair.certified.auto_depth`).

        Returns
        -------
        RegionMap
            With the variable ``xm`` (the reference amplitude, NaN where no orbit exists)
            and, certified, ``certified``.
        """
        case = Case.parse(self.case).value
        n = check_odd_order(self.n)
        xname, xs = check_named_axis("x", x, AXES, min_num=2, positive=True)
        yname, ys = check_named_axis("y", y, AXES, min_num=2, positive=True)
        if xname == yname:
            raise ValueError(f"x and y must sweep different parameters, got {xname!r} twice")
        es = _check_e(self.e)
        fixed = self._fixed((xname, yname))
        if certify:
            # deferred import: loaded only when this runs, for start-up time
            from hybridpd.pair.selftest import require_libm

            require_libm()  # refuse before any work where NumPy's libm misses its bound
        E, Y, X = np.meshgrid(es, ys, xs, indexing="ij")
        points = {"e": E.ravel(), yname: Y.ravel(), xname: X.ravel()}
        # deferred import: loaded only when this runs, for start-up time
        from hybridpd.sweeps.sweep import default_chunk_size, run_sweep

        label = f"regions {case} e={','.join(f'{v:g}' for v in es)}"
        if chunk_size is None:
            chunk_size = min(E.size, max(default_chunk_size(E.size), _MIN_REGION_CHUNK))
        out = run_sweep(_region_chunk, points, chunk_size=chunk_size, executor=executor,
                        max_workers=max_workers, store=store, progress=progress, label=label,
                        func_kwargs={"case": case, "n": n, "fixed": fixed},
                        metadata={"kind": "region_sweep", "version": 1}).outputs
        get = lambda k: np.asarray(out[k]).reshape(E.shape)
        variables = {"xm": get("xm").astype(float)}
        meta = {"reasons": {str(k): v for k, v in REASONS.items()}}
        if certify:
            # deferred import: loaded only when this runs, for start-up time
            from hybridpd.pair.certified import FLAG_MEANINGS, FLAG_VALUES, auto_depth

            depth = auto_depth(xs.size * ys.size) if certify_depth == "auto" else \
                check_int("certify_depth", certify_depth, 0, 12)
            variables["certified"] = _certify(
                case, n, fixed, depth, xname, xs,
                yname, ys, es, executor=executor, max_workers=max_workers, store=store,
                progress=progress)
            meta["flags"] = {"certified": {"values": list(FLAG_VALUES),
                                           "meanings": FLAG_MEANINGS}}
        return _RegionMap(case, xname, yname, xs, ys, es, {**fixed, "n": n},
                         get("exists").astype(bool), get("stable").astype(bool),
                         get("spectral_radius").astype(float), get("reason").astype(np.int64),
                         variables, meta)


def _check_e(e) -> np.ndarray:
    es = np.atleast_1d(check_array("e", e, lo=0.0, lo_open=False, hi=1.0))
    if es.size == 0 or es.ndim != 1:
        raise ValueError("e must be a non-empty list of restitution coefficients")
    if not np.all(np.isfinite(es)) or np.any((es < 0) | (es > 1)):
        raise ValueError(f"e must lie in [0, 1], got {es.tolist()}")
    return es


def _region_chunk(chunk, case, n, fixed):
    """Evaluate one chunk of flattened grid points (module-level: runs in worker processes)."""
    kw = dict(fixed)
    kw.update({k: v for k, v in chunk.items()})
    kp, kv = kw.pop("kp"), kw.pop("kv")
    r = symmetric_orbits(kp, kv, case=case, n=n, **kw)
    return {"exists": r.exists, "stable": r.stable, "spectral_radius": r.spectral_radius,
            "xm": r.xm, "reason": r.reason}


def _certify_chunk(chunk, case, n, fixed, depth, xname, yname):
    """Certify one chunk of grid cells (module-level: runs in worker processes)."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.certified import certify_cells

    kw = dict(fixed)
    kw[xname] = (chunk["x_lo"], chunk["x_hi"])
    kw[yname] = (chunk["y_lo"], chunk["y_hi"])
    r = certify_cells(case, n=n, depth=depth, e=chunk["e"], **kw)
    return {"certified": r.flags, "certified_reason": r.reasons}


def _certify(case, n, fixed, depth, xname, xs, yname, ys, es, *, executor, max_workers, store,
             progress):
    """The certified flags of every cell of the grid, shape ``(len(e), len(y), len(x))``."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.certified import cell_boxes, cell_edges
    from hybridpd.sweeps.sweep import run_sweep

    cells = cell_boxes(xname, cell_edges(xs), yname, cell_edges(ys))
    (xl, xh), (yl, yh) = cells[xname], cells[yname]
    shape = (es.size,) + xl.shape
    rep = lambda a: np.broadcast_to(a, shape).ravel()
    points = {"e": np.repeat(es, xl.size), "x_lo": rep(xl), "x_hi": rep(xh), "y_lo": rep(yl),
              "y_hi": rep(yh)}
    if store is not None:
        p = Path(store)
        store = p.with_name(f"{p.stem}.certified{p.suffix}")
    out = run_sweep(_certify_chunk, points, chunk_size=min(points["e"].size, 4096),
                    executor=executor, max_workers=max_workers, store=store, progress=progress,
                    label=f"certify {case} e={','.join(f'{v:g}' for v in es)}",
                    func_kwargs={"case": case, "n": n, "fixed": fixed, "depth": depth,
                                 "xname": xname, "yname": yname},
                    metadata={"kind": "certified_region_sweep", "version": 1}).outputs
    return np.asarray(out["certified"]).reshape(shape).astype(np.int8)
