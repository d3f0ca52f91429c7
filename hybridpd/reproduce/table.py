"""The summary's lead table in plain language, built from the checks (nothing here decides).

One row per claim of the paper (its five conclusions and two remarks on ``mu``):

* ``paper``: what the paper says, in a few words;
* ``verdict`` and ``finding``: what holds in the scaled gains ``(kp/m2, kv/m2)``, free of
  ``m2``, and the numbers that decide it, each with its certification (or grid) and its
  denominator;
* ``m2_readings`` and ``m2_text``: for which readings of the paper's gain box as printed
  (the box ``[0.1, 50]^2`` in ``kp, kv`` at a secondary mass ``m2``) the statement holds, as
  intervals of ``m2`` (:func:`~hybridpd.reproduce.rules.m2_readings`).

Certified shares are printed with their lower end rounded down and their upper end rounded up
(:func:`pct_interval`), so the printed interval still encloses the share.
"""
from __future__ import annotations

import math

from hybridpd.reproduce import conclusions as C
from hybridpd.reproduce import rules as R

__all__ = ["build_table", "m2_text", "pct_interval", "pct_pair"]


def pct_interval(iv, nd=1) -> str:
    """``"38.1–42.9 %"``: a share interval in percent, rounded outward to ``nd`` decimals.

    Examples
    --------
    >>> from hybridpd.reproduce.table import pct_interval
    >>> pct_interval((0.38149, 0.42811)), pct_interval((1.0, 1.0)), pct_interval((0, 0.0004))
    ('38.1–42.9 %', '100 %', '0–0.1 %')
    """
    lo, hi = (100.0 * float(v) for v in iv)
    k = 10 ** nd
    a = math.floor(lo * k + 1e-9) / k
    b = math.ceil(hi * k - 1e-9) / k
    f = lambda v: f"{v:.{nd}f}".rstrip("0").rstrip(".")
    return f"{f(a)} %" if a == b else f"{f(a)}–{f(b)} %"


def pct_pair(a, b) -> tuple:
    """Two share intervals printed so that disjoint ones read disjoint.

    ``(text_a, text_b, note)``: both rounded outward (:func:`pct_interval`) with one decimal,
    or as many more (up to four) as keep two disjoint intervals from touching once rounded;
    ``note`` says so where the certified gap between them is narrower than the one-decimal
    precision (``""`` otherwise), since a verdict then rests on that gap.

    Examples
    --------
    >>> from hybridpd.reproduce.table import pct_pair
    >>> pct_pair((0.0141, 0.0229), (0.0233, 0.027))
    ('1.41–2.29 %', '2.33–2.7 %', '; a certified gap of 0.04 % between them, narrower than the printed 0.1 %')
    >>> pct_pair((0.1, 0.2), (0.5, 0.6))
    ('10–20 %', '50–60 %', '')
    """
    (a0, a1), (b0, b1) = (tuple(map(float, v)) for v in (a, b))
    gap = max(b0 - a1, a0 - b1)
    nd = 1
    if gap > 0:
        while nd < 4:
            lo, hi = (a, b) if a1 < b0 else (b, a)
            k = 10 ** nd
            if math.ceil(100 * lo[1] * k - 1e-9) < math.floor(100 * hi[0] * k + 1e-9):
                break
            nd += 1
    note = (f"; a certified gap of {100 * gap:.2g} % between them, narrower than the printed "
            f"0.1 %" if 0 < gap < 1e-3 else "")
    return pct_interval(a, nd), pct_interval(b, nd), note


def _es(d):
    return ", ".join(f"{e:g}" for e in d)


def _m2(v) -> str:
    return f"{v:.3g}"


def m2_text(runs, *, exact=False) -> str:
    """Readings along ``m2`` in words: each verdict with the ``m2`` it holds at, and where a
    change lies between computed values.

    Examples
    --------
    >>> from hybridpd.reproduce.rules import m2_readings
    >>> from hybridpd.reproduce.table import m2_text
    >>> m2_text(m2_readings([0.1, 1, 10], ["unresolved", "agrees", "contradicted"]))
    'unresolved at m2 = 0.1; agrees at m2 = 1; contradicted at m2 = 10; changes between 1 and 10'
    """
    parts, changes = [], []
    for r in runs:
        if r.get("exact"):
            lo, hi = r["m2"]
            parts.append(f"{r['verdict']} for m2 in [{_m2(lo)}, {_m2(hi)}) (exact ends)")
            continue
        comp = ", ".join(_m2(v) for v in r["computed"])
        parts.append(f"{r['verdict']} at m2 = {comp}")
        if r.get("change_after") and r["verdict"] != "unresolved":
            a, b = r["change_after"]
            changes.append(f"{_m2(a)} and {_m2(b)}")
    text = "; ".join(parts)
    decided = [r for r in runs if r["verdict"] in (R.AGREES, R.CONTRADICTED)]
    if len({r["verdict"] for r in decided}) == 2 and changes and not exact:
        text += "; changes between " + ", ".join(changes)
    return text


def _row(ident, verdict, finding, readings=None, readings_text=None, basis="certified"):
    return {"id": ident, "paper": C.SHORT[ident],
            "statement": C.STATEMENTS[ident] if isinstance(ident, int) else C.REMARKS[ident],
            "verdict": verdict, "finding": finding, "m2_readings": readings or [],
            "m2_text": readings_text or "-", "basis": basis}


def _cert(g) -> str:
    return f"certified, {g[0]} × {g[1]} cells of the box"


def _row_1(c, readings, grid):
    def side(v):
        return ", ".join(pct_interval(iv) for iv in v)
    ratios = ", ".join("≤ " + ("∞" if r[1] is None else f"{r[1]:.2g}") for r in c["ratio"])
    text = (f"exists and stable on {side(c['collocated'])} of the box (collocated, e = "
            f"{_es(c['e'])}) against {side(c['noncollocated'])} (non-collocated); ratio "
            f"{ratios} against the threshold {c['threshold']:g} ({_cert(grid)})")
    ex = c.get("existence_alone")
    if ex is not None and ex["verdict"] != R.AGREES:
        how = ("is not much smaller" if ex["verdict"] == R.CONTRADICTED
               else "is not shown much smaller")
        text += (f". Existence alone (stable or not) {how}: {side(ex['noncollocated'])} "
                 f"(non-collocated) against {side(ex['collocated'])} (collocated)")
    return _row(1, c["verdict"], text, readings, m2_text(readings))


def _trend_words(t, what, values, ivs, name="e"):
    a, b, note = pct_pair(ivs[0], ivs[-1])
    x0, x1 = f"{values[0]:g}", f"{values[-1]:g}"
    if t["verdict"] == R.AGREES:
        move = "falls" if t["direction"] == "decreasing" else "rises"
        s = f"the {what} share {move} from {a} ({name} = {x0}) to {b} ({name} = {x1})"
    elif t["verdict"] == R.CONTRADICTED:
        move = "rises" if t["direction"] == "decreasing" else "falls"
        s = f"the {what} share {move} from {a} ({name} = {x0}) to {b} ({name} = {x1})"
    else:
        s = (f"the {what} share goes from {a} ({name} = {x0}) to {b} ({name} = {x1}): "
             f"{R.NO_CHANGE}")
    s += note
    if t["against"] is not None:
        p, q = t["against"]["interval"]
        s += f" (it moves the other way between {name} = {p:g} and {q:g})"
    return s


def _row_2(c, readings, grid):
    text = (_trend_words(c["noncollocated_trend"], "non-collocated", c["e"], c["noncollocated"])
            + "; " + _trend_words(c["collocated_trend"], "collocated", c["e"], c["collocated"])
            + f" ({_cert(grid)})")
    return _row(2, c["verdict"], text, readings, m2_text(readings))


def _row_3(c, readings, grid):
    lows = min(iv[0] for iv in c["collocated"])
    text = (f"the collocated region covers {', '.join(pct_interval(iv) for iv in c['collocated'])}"
            f" of the box (e = {_es(c['e'])}), at least {pct_interval((lows, lows))} for every "
            f"e against the threshold {100 * c['threshold']:g} % ({_cert(grid)})")
    return _row(3, c["verdict"], text, readings, m2_text(readings))


def _row_4(readings, measured):
    if measured:
        m = measured[0]
        x0, x1, y0, y1 = m["window"]
        text = (f"only where all six orbits at the paper's gains are stable can the basins be "
                f"compared; there (measured at m2 = {m['m2']:g}) "
                + ("every basin touches the window shared by the panels" if m["verdict"] ==
                   R.UNRESOLVED else f"the comparison says {m['verdict']}")
                + f" (x1 in [{x0:.3g}, {x1:.3g}], y1 in [{y0:.3g}, {y1:.3g}], "
                f"{m['grid'][0]} × {m['grid'][1]} points): the sizes "
                + ("cannot be compared" if m["verdict"] == R.UNRESOLVED else "are decided"))
        verdict = m["verdict"]
    else:
        text = "no convention of the run has all six orbits stable: no basins to compare"
        verdict = R.UNRESOLVED
    return _row(4, verdict, text, readings, m2_text(readings), basis="sampled basins")


def _row_5(c, readings_by):
    f = c["fractions"]
    parts = []
    for crit in C.CRITERIA_5:
        v = c["by_criterion"][crit]
        parts.append(f"by {crit} {v}: {100 * f[crit]['noncollocated']:.1f} % of the gain grid "
                     f"(non-collocated) against {100 * f[crit]['collocated']:.1f} % "
                     "(collocated)")
    g, u = c["grid"], c["uncertainty_grid"]
    text = ("; ".join(parts) + f" (sampled: {g[0]} × {g[1]} log grid of kp/m2, kv/m2 in "
            f"[{c['gains']['kp'][0]:g}, {c['gains']['kp'][1]:g}], {u[0]} × {u[1]} plants over "
            f"e in [{c['box']['e'][0]:g}, {c['box']['e'][1]:g}] × mu in "
            f"[{c['box']['mu'][0]:g}, {c['box']['mu'][1]:g}]; checked on "
            f"{c['check_grid'][0]} × {c['check_grid'][1]})")
    rtext = "; ".join(f"{crit}: {m2_text(r)}" for crit, r in readings_by.items())
    return _row(5, c["verdict"], text, readings_by, rtext, basis="sampled grid")


def _row_mu_existence(c, grid, values_grid=None):
    parts, moves = [], 0
    for key, t in c["trends"].items():
        case, e = key.split(" ")
        ivs = [c["first"][case][_idx(c, case, e)], c["last"][case][_idx(c, case, e)]]
        a, b, note = pct_pair(ivs[0], ivs[1])
        item = f"{case.replace('non', 'non-')} {e.replace('=', ' = ')}: {a} → {b}{note}"
        if t.get("against") is not None:
            # the largest proved rise inside the range, with its certified shares
            p, q = t["against"]["interval"]
            pts = dict(c.get("series", {}).get(key, ()))
            ra, rb, _ = pct_pair(pts[p], pts[q]) if p in pts and q in pts else ("", "", "")
            item += (f", but it rises from {ra} at mu = {p:.3g} to {rb} at mu = {q:.3g} "
                     f"(by at least {100 * t['against']['by']:.2g} % of the box)")
            moves += 1
        parts.append(item)
    mu0, mu1 = c["mu"]
    counts = sorted({len(v) for v in c.get("series", {}).values()}) or [2]
    where = (f"at {counts[-1]} values of mu" if len(counts) == 1
             else f"at {counts[0]}-{counts[-1]} values of mu")
    others = ("" if values_grid is None else
              f", the values other than the ends and the largest sampled rise on "
              f"{values_grid[0]} × {values_grid[1]} cells at most")
    text = (f"existence share of the box at mu = {mu0:g} → mu = {mu1:g}: " + "; ".join(parts)
            + f" ({_cert(grid)}; certified {where} in the range{others}, whose ends decide "
            "a trend over it; "
            + ("the largest proved rise inside the range is reported and does not decide"
               if moves else "no rise inside the range is proved")
            + ")")
    return _row("mu-existence", c["verdict"], text,
                readings_text="read on the scaled box (m2 = 1)")


def _idx(c, case, e):
    es = c.get("e")
    return [f"e={v:g}" for v in es].index(e)


def _row_mu_small(c, grid_limit, grid):
    easier, same, harder = [], [], []
    for key, t in c["trends"].items():
        case, e = key.split(" ")
        k = _idx(c, case, e)
        ta, tb, note = pct_pair(c["limit"][case][k], c["paper"][case][k])
        item = (f"{case.replace('non', 'non-')} {e.replace('=', ' = ')} {ta} at mu = "
                f"{c['mu'][0]:g} against {tb} at mu = {c['mu'][1]:g}{note}")
        {R.AGREES: easier, R.CONTRADICTED: harder}.get(t["verdict"], same).append(item)
    parts = []
    if easier:
        parts.append("easier: " + "; ".join(easier))
    if harder:
        parts.append("harder: " + "; ".join(harder))
    if same:
        parts.append(R.NO_CHANGE + ": " + "; ".join(same))
    text = ("exists and stable, " + "; ".join(parts) + f" ({_cert(grid_limit)} at mu = "
            f"{c['mu'][0]:g}, {grid[0]} × {grid[1]} at mu = {c['mu'][1]:g})")
    return _row("mu-small", c["verdict"], text, readings_text="read on the scaled box (m2 = 1)")


def build_table(*, checks: dict, readings: dict, basins_measured: list, grids: dict) -> list:
    """The rows of the lead table (see the module docstring).

    Parameters
    ----------
    checks : dict
        ``{1, 2, 3, 5, "mu-existence", "mu-small": check result}`` in scaled gains.
    readings : dict
        ``{1, 2, 3, 4: m2_readings runs; 5: {criterion: runs}}``.
    basins_measured : list
        Conclusion 4 at the conventions where all six orbits are stable: ``{"m2",
        "verdict", "window", "grid"}``.
    grids : dict
        Cells ``(n, n)`` of the finest grids of the certified boxes: ``"main"`` (the scaled
        box), ``"limit"`` (the same at ``mu = 1e-4``), ``"mu_ends"`` (the ends of the
        ``mu`` range) and, where the run certifies every value of the ``mu`` study,
        ``"mu_values"``.
    """
    g = grids["main"]
    return [_row_1(checks[1], readings[1], g), _row_2(checks[2], readings[2], g),
            _row_3(checks[3], readings[3], g), _row_4(readings[4], basins_measured),
            _row_5(checks[5], readings[5]),
            _row_mu_existence(checks["mu-existence"], grids["mu_ends"], grids.get("mu_values")),
            _row_mu_small(checks["mu-small"], grids["limit"], g)]
