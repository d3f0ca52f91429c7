"""Render ``summary.md`` from the ``summary.json`` dict (nothing here computes a verdict).

Written for a reader who wants to act on it: it leads with one table (what the paper says;
what holds in the scaled gains, free of ``m2``; for which readings of the printed gain box
it holds), then the numbers behind each row, every share with its certification or grid
and its denominator, and a caption for every figure.
"""
from __future__ import annotations

import math

__all__ = ["CAPTIONS", "render", "terminal_lines"]

_CASE = {"collocated": "collocated", "noncollocated": "non-collocated"}


def _f(x, nd=4):
    return "-" if x is None else f"{x:.{nd}g}"


def _p(x):
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd._format import pct as _pct

    return "-" if x is None else _pct(x)


def _iv(iv):
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.reproduce.table import pct_interval

    return pct_interval(iv)


def _es(d):
    return ", ".join(f"{e:g}" for e in d["paper"]["e"])


#: Caption of each figure: what is fixed and what it shows ({m2} is the convention).
CAPTIONS = {
    "scaled_regions_collocated": (
        "Fig. 4 in scaled gains: the collocated regions in (kp/m2, kv/m2) for e = 0.1, 0.5, "
        "0.9, valid for every m2 (mu = 0.1, gamma = 0.75, omega = 5, n = 1 fixed). Filled: the "
        "orbit exists and is stable; hatched: it exists but is unstable; white: no orbit; "
        "dashed: the existence (grazing) boundary; solid: the stability boundary. The "
        "dashed line with ticks is the paper's gains (10/m2, 20/m2) for m2 in [0.1, 1000], "
        "marked where an orbit of Fig. 6 starts to exist or to be stable; the grey square is "
        "the certified box of the verdicts."),
    "scaled_regions_noncollocated": (
        "Fig. 5 in scaled gains: the non-collocated regions in (kp/m2, kv/m2), as for Fig. 4; "
        "the dotted rectangle is the zoom window of Fig. 5's second row."),
    "fig3_orbit": (
        "Fig. 3 at m2 = {m2}: the secondary mass's phase plane (x2, y2) on the symmetric orbit "
        "at kp = 10, kv = 20, one line style per e; dotted segments are the impacts."),
    "fig4_regions_collocated": (
        "Fig. 4 at m2 = {m2}: collocated regions over the gain box scaled by m2, one panel per "
        "e; the star is the paper's gains."),
    "fig5_regions_noncollocated": (
        "Fig. 5 at m2 = {m2}: non-collocated regions, the full box (top) and the zoom window "
        "(bottom, outlined on top)."),
    "fig6_basins_collocated": (
        "Fig. 6 at m2 = {m2}: the basin slice (x1, y1) at the fixed point's phi and y2, "
        "coloured by the attractor reached, on the window shared by every panel of Figs 6-7; "
        "a panel with no stable orbit shows the spectral radius along m2 instead."),
    "fig7_basins_noncollocated": (
        "Fig. 7 at m2 = {m2}: as Fig. 6 for the non-collocated loop, on the same window."),
    "m2_study": (
        "Convention study: spectral radius of the six orbits at kp = 10, kv = 20 against m2 "
        "(no line: no orbit), the conventions of the run marked; below, each claim's verdict "
        "on the paper's gain box as printed, a marker at each m2 where it was computed (bars "
        "only where the located interval ends make it exact)."),
    "mu_study": (
        "Shares of the gain box (kp/m2, kv/m2 in [0.1, 50]) where the orbit exists, and "
        "exists and is stable, against mu, each on its own axis; lines: the sampled grid; "
        "bars: certified intervals (the shares that decide the remarks on mu; a hatched band "
        "per e where every value is certified); bottom: the "
        "(mu, kv) plane at kp = 10 m2."),
    "gamma_study": (
        "As the mu study, against gamma = L / x10 (the paper leaves gamma open); shaded "
        "bands, hatched per e: the certified intervals, where the run certifies every value "
        "of the study (the full run).")}


def bottom_line(d: dict) -> list:
    """Three lines: what the paper's own gains do at ``m2 = 1`` (else the first ``m2``
    computed), per case, and how the table's verdicts add up, from the summary's data.

    Examples
    --------
    >>> d = {"paper": {"kp": 10.0, "kv": 20.0}, "table": [{"verdict": "agrees"}],
    ...      "runs": [{"m2": 1.0, "orbits": [
    ...          {"case": "collocated", "e": 0.5, "exists": True, "stable": True,
    ...           "spectral_radius": 0.25, "reason": "exists"},
    ...          {"case": "noncollocated", "e": 0.5, "exists": False, "stable": False,
    ...           "spectral_radius": None, "reason": "the gap leaves the clearance"}]}]}
    >>> for line in bottom_line(d):
    ...     print(line)
    **Bottom line** (the paper's gains kp = 10, kv = 20, at m2 = 1): collocated: e = 0.5 stable (spectral radius 0.25).
    Non-collocated: e = 0.5 no orbit (the gap leaves the clearance).
    Of the 1 statements checked below: 1 agree, 0 contradicted, 0 unresolved or split.
    """
    P = d["paper"]
    runs = d["runs"]
    run = next((r for r in runs if r["m2"] == 1.0), runs[0])

    def case(name):
        parts = []
        for o in sorted((o for o in run["orbits"] if o["case"] == name), key=lambda o: o["e"]):
            if not o["exists"]:
                parts.append(f"e = {o['e']:g} no orbit ({o['reason']})")
            else:
                word = "stable" if o["stable"] else "unstable"
                parts.append(f"e = {o['e']:g} {word} (spectral radius "
                             f"{o['spectral_radius']:.3g})")
        return "; ".join(parts) or "not computed"

    verdicts = [row["verdict"] for row in d["table"]]
    agree, contra = verdicts.count("agrees"), verdicts.count("contradicted")
    return [(f"**Bottom line** (the paper's gains kp = {P['kp']:g}, kv = {P['kv']:g}, at m2 = "
            f"{run['m2']:g}): collocated: {case('collocated')}."),
            f"Non-collocated: {case('noncollocated')}.",
            (f"Of the {len(verdicts)} statements checked below: {agree} agree, {contra} "
            f"contradicted, {len(verdicts) - agree - contra} unresolved or split.")]


def _intro(d, w):
    c, P = d["conventions"], d["paper"]
    w("# Reproduction of Mata-Jimenez, Brogliato & Goswami, Figs 3-7\n")
    for line in bottom_line(d):
        w(line)
    w("")
    w(f"Mode **{d['mode']}**. Fixed by the paper: mu = {P['mu']:g}, gamma = {P['gamma']:g}, "
      f"n = {P['n']}, omega = {P['omega']:g}, e = {_es(d)}, and kp = {P['kp']:g}, "
      f"kv = {P['kv']:g} for Figs 3, 6 and 7. Not given by the paper: the secondary mass m2 "
      f"(with mu fixed only kp/m2 and kv/m2 matter), x10 = {c['x10']:g} (so L = {c['L']:g}) "
      f"and the basin window. Figures are drawn at m2 = "
      f"{', '.join(f'{v:g}' for v in c['m2'])}.\n")


def row_boxes(d: dict) -> dict:
    """Per row of the lead table, the convention and the box it is read on, from the data.

    Rows 1-3 and the remarks on mu: the scaled gain box (``m2``-free, certified); row 4: the
    basins at the chosen ``m2`` in its run's shared window; row 5: its own gain grid and
    plant box (sampled).
    """
    cert, conv = d["certified"], d["conventions"]
    (k0, k1), (v0, v1) = cert["box"]["kp/m2"], cert["box"]["kv/m2"]
    def scaled(group):
        g = cert[group]["grid"]
        return (f"scaled gains kp/m2 in [{k0:g}, {k1:g}], kv/m2 in [{v0:g}, {v1:g}] (free of "
                f"m2; certified, {g[0]} × {g[1]} cells)")

    out = {i: scaled("main") for i in (1, 2, 3)}
    mu = cert.get("mu_ends_values")
    out["mu-existence"] = scaled("mu_ends") + (f", mu in [{mu[0]:g}, {mu[1]:g}]" if mu else "")
    out["mu-small"] = scaled("limit") + f", mu = {cert['mu_limit']:g} and {d['paper']['mu']:g}"
    m2 = conv.get("chosen_m2")
    run = next((r for r in d["runs"] if r["m2"] == m2), None)
    if run is not None:
        x0, x1, y0, y1 = run["basin_window"]
        out[4] = (f"basins at m2 = {m2:g} (all six orbits stable there), the window x1 in "
                  f"[{x0:g}, {x1:g}], y1 in [{y0:.3g}, {y1:.3g}] shared by the panels (sampled)")
    c5 = next((c for c in d["conclusions"] if c["id"] == 5), None)
    if c5 is not None:
        ev = c5["evidence"]
        (a0, a1), (b0, b1) = ev["gains"]["kp"], ev["gains"]["kv"]
        out[5] = (f"log grid kp/m2 in [{a0:g}, {a1:g}], kv/m2 in [{b0:g}, {b1:g}] "
                  f"({ev['grid'][0]} × {ev['grid'][1]}), plants e in {ev['box']['e']}, mu in "
                  f"{ev['box']['mu']} ({ev['uncertainty_grid'][0]} × "
                  f"{ev['uncertainty_grid'][1]}; sampled)")
    return out


def _table(d, w):
    cert = d["certified"]
    g, base, lev = cert["main"]["grid"], cert["main"]["base_grid"], cert["main"]["levels"]
    rg = cert["readings"]["grid"] or g
    eg = cert["mu_ends"]["grid"]
    w("## What the paper says and what holds\n")
    w("| # | the paper says | read on (convention, box) | what holds in the scaled gains, "
      "free of m2 | for which readings of the printed gain box (m2) |")
    w("|---|---|---|---|---|")
    boxes = row_boxes(d)
    for row in d["table"]:
        w(f"| {row['id']} | {row['paper']} | {boxes.get(row['id'], '-')} | "
          f"**{row['verdict']}**: {row['finding']} | {row['m2_text']} |")
    w("")
    w("How to read it:\n")
    w("- *agrees* / *contradicted*: the numbers decide the statement; *unresolved*: they "
      "cannot (certified intervals that overlap: no change within the certified resolution; "
      "or a window or grid that limits the measurement); *split*: two reasonable readings "
      "of the paper's words give opposite answers, both stated. The rules are in "
      "CONVENTIONS.md (\"Verdict rules\").")
    w(f"- Region shares (rows 1-3 and the mu remarks) are **certified**: the box of the "
      f"scaled gains kp/m2, kv/m2 in [{cert['box']['kp/m2'][0]:g}, "
      f"{cert['box']['kp/m2'][1]:g}] is cut into {base} × {base} cells, every cell is proved "
      f"(interval arithmetic on the paper's closed forms) to have the property everywhere, "
      f"nowhere, or is left undecided, and undecided cells are cut in four, up to {lev} "
      f"times. A share is printed as the interval [proved, proved + undecided] of the "
      f"{g[0]} × {g[1]} cells of the finest grid; it encloses the share of the box's area "
      f"(the lower end rounded down, the upper end up).")
    w(f"- The printed box read at m2 is the box [0.1/m2, 50/m2]^2 of the scaled gains "
      f"(certified on {rg[0]} × {rg[1]} cells, m2 = 1 on the finer grid above); m2 is read "
      f"at {', '.join(f'{v:.3g}' for v in cert['readings_m2'])}, and a change of verdict "
      "lies somewhere between two computed values. The remarks on mu are certified on "
      f"{eg[0]} × {eg[1]} cells (mu = {cert['mu_limit']:g} and the ends of the mu range), "
      + (f"and existence at every other value of the mu study on {cert['values']['grid'][0]}"
         f" × {cert['values']['grid'][1]} cells at most; "
         if cert.get("values") else
         "and at the two values between which the sampled existence share rises most; ")
      + "the largest proved rise inside the range is reported beside the trend. "
      "Rows 4 and 5 are sampled (basins, a gain grid), each checked on a second grid.\n")


def _m2_section(d, w):
    c = d["conventions"]
    w("## The secondary mass m2\n")
    w("Along the paper's gains, the ray (10/m2, 20/m2) of the scaled gains, the orbits of "
      "Figs 6-7 exist and are stable on these intervals of m2 (studied in "
      f"[{_f(d['m2_study']['range'][0])}, {_f(d['m2_study']['range'][1])}]; an upper end "
      "equal to the study's end means stable beyond it; every other end is a bifurcation "
      "point located by Brent's method on the exact test function and verified):\n")
    w("| case | e | m2 where the orbit exists and is stable | ends (kind, residual) |")
    w("|---|---|---|---|")
    for case in ("noncollocated", "collocated"):
        for e, lst in d["m2_interval_ends"][case].items():
            iv = "; ".join(f"[{i['lo']['m2']:.6g}, {i['hi']['m2']:.6g}]" for i in lst) or "none"
            ends = []
            for i in lst:
                for x in (i["lo"], i["hi"]):
                    if x["kind"] == "window":
                        continue
                    res = "" if x["residual"] is None else f", residual {x['residual']:.1e}"
                    ends.append(f"{x['m2']:.6g} ({x['kind']}{res})")
            w(f"| {_CASE[case]} | {e} | {iv} | {'; '.join(ends) or '-'} |")
    w("")
    fb = c.get("feedback_at_chosen_m2")
    if c["chosen_m2"] is None or fb is None:
        w("No m2 in the studied range makes all six orbits stable: only the given m2 are "
          "drawn.\n")
        return
    rho = fb["spectral_radius"]
    w(f"The figures' second convention is **m2 = {c['chosen_m2']:g}**, "
      f"{c['chosen_m2_rule']}. There the feedback is weak: kp/m2 = {fb['kp_over_m2']:.3g}, "
      f"kv/m2 = {fb['kv_over_m2']:.3g}, spectral radii at e = {_es(d)} "
      + ", ".join(f"{v:.3f}" for v in rho["collocated"]) + " (collocated) and "
      + ", ".join(f"{v:.3f}" for v in rho["noncollocated"]) + " (non-collocated). The first, "
      "m2 = 1, keeps the paper's axes as printed.\n")


def _certified(d, w):
    cert = d["certified"]["main"]
    g = cert["grid"]
    w("## Certified shares of the scaled box\n")
    w(f"mu = {d['paper']['mu']:g}; kp/m2, kv/m2 in [{d['certified']['box']['kp/m2'][0]:g}, "
      f"{d['certified']['box']['kp/m2'][1]:g}]; intervals of the {g[0]} × {g[1]} cells of the "
      f"finest grid ({cert['base_grid']} × {cert['base_grid']} cells refined up to "
      f"{cert['levels']} times).\n")
    w("| case | e | exists and stable | exists | exists, unstable | no orbit | undecided cells "
      "(exists and stable) |")
    w("|---|---|---|---|---|---|---|")
    for case, per_e in d["certified_shares"].items():
        for e, s in per_e.items():
            u = s["cells"]["exists_stable"]
            w(f"| {_CASE[case]} | {e} | {_iv(s['exists_stable'])} | {_iv(s['exists'])} | "
              f"{_iv(s['exists_unstable'])} | {_iv(s['no_orbit'])} | {u['undecided']} of "
              f"{u['of']} |")
    w("")


def _details(d, w):
    w("## Each claim in detail\n")
    for row in d["table"]:
        w(f"### {row['id']}. *{row['statement']}*\n")
        w(f"- **{row['verdict']}** ({row['basis']}): {row['finding']}.")
        w(f"- Printed box along m2: {row['m2_text']}.")
        if row["id"] == 4:
            for m2, ev in next(c for c in d["conclusions"] if c["id"] == 4)[
                    "evidence"]["by_convention"].items():
                r = ev["run_grid"]
                x0, x1, y0, y1 = r["window"]
                dist = r.get("distance") or {}
                parts = []
                for case in ("collocated", "noncollocated"):
                    for row_d in dist.get(case, []):
                        parts.append("-" if row_d is None else
                                     ("≥ " if row_d["lower_bound"] else "")
                                     + f"{row_d['distance']:.3g}")
                w(f"- Basins at m2 = {m2}: {ev['verdict']} ({r['verdict']} on "
                  f"{ev['grids'][0][0]} × {ev['grids'][0][1]} points, "
                  f"{ev['check_grid']['verdict']} on {ev['grids'][1][0]} × "
                  f"{ev['grids'][1][1]}); window x1 in [{x0:.3g}, {x1:.3g}], y1 in "
                  f"[{y0:.3g}, {y1:.3g}]; distance from the fixed point to the nearest point "
                  f"outside its basin (x1/x10, y1/(omega x10); collocated then non-collocated, "
                  f"e = {_es(d)}): {', '.join(parts)}.")
        w("")


def _runs(d, w):
    w("## Orbits at kp = 10, kv = 20\n")
    w("| m2 | case | e | exists | xm | spectral radius | stable | viability margin |")
    w("|---|---|---|---|---|---|---|---|")
    for r in d["runs"]:
        for o in r["orbits"]:
            ex = "yes" if o["exists"] else "no: " + o["reason"]
            st = "-" if o["stable"] is None else ("yes" if o["stable"] else "no")
            w(f"| {r['m2']:g} | {_CASE[o['case']]} | {o['e']:g} | {ex} | {_f(o['xm'], 6)} | "
              f"{_f(o['spectral_radius'], 6)} | {st} | {_f(o['viability_margin'], 4)} |")
    w("")
    w("## Basins (Figs 6-7)\n")
    w("Each point of the slice is labelled by what it reaches (the symmetric orbit by the "
      "paper's criterion; other periodic orbits of P found by Newton on P^k), or as off the "
      "section. One window per convention, shared by every panel and both cases. Every "
      "percentage in a row has one denominator, that row's grid points (third column).\n")
    w("| m2 | case | e | grid points (the denominator) | symmetric orbit: % of the points "
      "(count) | other outcomes: % of the points (count) |")
    w("|---|---|---|---|---|---|")
    for r in d["runs"]:
        for b in r["basins"]:
            if not b["measured"]:
                w(f"| {r['m2']:g} | {_CASE[b['case']]} | {b['e']:g} | - | no basin: "
                  f"{b['why_empty']} | - |")
                continue
            sh = b["shares"]
            sym = next((s for s in sh if s["label"] == 0), None)
            rest = ", ".join(f"{s['name']} {_p(s['share'])} ({s['count']})" for s in sh
                             if s["label"] != 0 and s["count"])
            edge = ", touches the window's edge" if b.get("reaches_edge") else ""
            w(f"| {r['m2']:g} | {_CASE[b['case']]} | {b['e']:g} | {b['points']} "
              f"({b['grid'][0]} × {b['grid'][1]}) | "
              f"{_p(sym['share'] if sym else 0.0)} ({sym['count'] if sym else 0}{edge}) | "
              f"{rest or '-'} |")
    w("")


def _studies(d, w):
    for name, label in (("mu", "mu"), ("gamma", "gamma = L / x10")):
        s = d["studies"][name]
        vals = s["values"]
        b = s["box"]
        idx = sorted({0, len(vals) // 4, len(vals) // 2, 3 * len(vals) // 4, len(vals) - 1})
        w(f"## Regions against {label}\n")
        w(f"Share of the {b['kp'][2]} × {b['kv'][2]} grid points of the gain box kp in "
          f"[{b['kp'][0]:g}, {b['kp'][1]:g}], kv in [{b['kv'][0]:g}, {b['kv'][1]:g}] where "
          f"the orbit exists and is stable, at {len(vals)} log-spaced values of {name}:\n")
        w("| case | e | " + " | ".join(f"{name} = {vals[i]:.3g}" for i in idx) + " |")
        w("|---|---|" + "---|" * len(idx))
        for case, q in s["fractions"].items():
            for k, e in enumerate(s["e"]):
                w(f"| {_CASE[case]} | {e:g} | "
                  + " | ".join(_p(q["both"][k][i]) for i in idx) + " |")
        w("")
        w(f"Grid points of {name} where some gains of the box give an existing stable orbit "
          "(the continuous ends lie between them and their neighbours):\n")
        for case, q in s["fractions"].items():
            for k, e in enumerate(s["e"]):
                both = q["both"][k]
                on = [i for i, f in enumerate(both) if f and f > 0]
                peak = max(range(len(vals)), key=lambda i, bb=both: bb[i] or 0)
                rng = (f"from {vals[on[0]]:.3g} to {vals[on[-1]]:.3g}" if on else "nowhere")
                w(f"- {_CASE[case]}, e = {e:g}: {rng}; largest share {_p(both[peak])} of the "
                  f"grid points at {name} = {vals[peak]:.3g}")
        w("")
        if name == "gamma" and d.get("gamma_certified"):
            _gamma_certified(d["gamma_certified"], w)


def _gamma_certified(gc, w):
    """The gamma study certified at every value: where stable gains are proved to exist."""
    g = gc["grid"]
    w(f"Certified at every value of gamma ({g[0]} × {g[1]} cells of the scaled box at most, "
      f"{gc['base_grid']} × {gc['base_grid']} refined up to {gc['levels']} times): the "
      "values where some gains of the box are proved to give an existing stable orbit "
      "(lower end of the certified share above 0), and where none is (upper end 0):\n")
    for case, per_e in gc["shares"].items():
        for e, r in per_e.items():
            some, none = r["proved_somewhere"], r["proved_nowhere"]
            a = (f"proved at {len(some)} of {len(r['gamma'])} values, from {min(some):.3g} to "
                 f"{max(some):.3g}" if some else f"proved at none of {len(r['gamma'])} values")
            b = (f"; proved absent at {len(none)} values ({min(none):.3g} to {max(none):.3g})"
                 if none else "; proved absent at none")
            # the largest upper end, rounded up: a bound that still holds once printed
            top = math.ceil(1000 * max(iv[1] for iv in r["exists_stable"]) - 1e-9) / 10
            w(f"- {_CASE[case]}, e = {e}: stable gains {a}{b}; the certified share is at most "
              f"{top:g} % of the box at every value")
    w("")


def _figures(d, w):
    w("## Figures\n")
    w("Saved at print size (3.5 in or 7.2 in wide), PNG at 300 dpi and PDF, no text under "
      "7 pt, Okabe-Ito colours with a second encoding (line style, marker or hatch).\n")
    for path in d.get("figures", []):
        stem = path.rsplit("/", 1)[-1].rsplit(".", 1)[0]
        m2 = path.split("/")[0][3:] if path.startswith("m2=") else ""
        cap = CAPTIONS.get(stem)
        if cap:
            w(f"- `{path}`: {cap.format(m2=m2)}")
    w("")


def render(d: dict) -> str:
    lines = []
    w = lines.append
    _intro(d, w)
    _table(d, w)
    _m2_section(d, w)
    _certified(d, w)
    _details(d, w)
    _runs(d, w)
    _studies(d, w)
    _figures(d, w)
    w("## Files\n")
    w("Per convention `m2=<value>/`: `regions_*.nc` (region maps, "
      "`hybridpd.load_region_map`), `basin_*.nc` (attractor basins, "
      "`hybridpd.analysis.basins.load_basin`); `robustness.json` (the "
      "comparison of conclusion 5); `hybridpd plot FILE` draws each `.nc` file.\n")
    w("## Timings (s)\n")
    for k, v in d["timings"].items():
        w(f"- {k}: {v:.2f}")
    for r in d["runs"]:
        for k, v in r["timings"].items():
            w(f"- m2 = {r['m2']:g}, {k}: {v:.2f}")
    w("")
    return "\n".join(lines)


def terminal_lines(d: dict) -> list:
    """The terminal summary of ``hybridpd reproduce``: one line per claim of the lead table
    (its id, the verdict in the scaled gains, the paper's words, the readings of the printed
    gain box along ``m2``) and the stable intervals of the non-collocated orbits.

    Examples
    --------
    >>> from hybridpd.reproduce.markdown import terminal_lines
    >>> d = {"table": [{"id": 3, "verdict": "agrees", "paper": "collocated range large",
    ...                 "m2_text": "agrees at m2 = 1"}],
    ...      "m2_stable_intervals": {"noncollocated": {"0.5": [[3.7, 1000.0]]}}}
    >>> print("\\n".join(terminal_lines(d)))
    claim         verdict (scaled gains)  the paper says | printed box read at m2
    3             agrees                  collocated range large | agrees at m2 = 1
    non-collocated orbit at kp = 10, kv = 20 exists and is stable for m2 in: e = 0.5: [3.7, 1000]
    """
    out = [f"{'claim':<13} {'verdict (scaled gains)':<23} the paper says | printed box read at m2"]
    for row in d["table"]:
        out.append(f"{row['id']!s:<13} {row['verdict']:<23} {row['paper']} | "
                   f"{row['m2_text']}")
    ivs = d["m2_stable_intervals"]["noncollocated"]
    out.append("non-collocated orbit at kp = 10, kv = 20 exists and is stable for m2 in: "
               + "; ".join(f"e = {e}: " + (", ".join(f"[{a:.6g}, {b:.6g}]" for a, b in v)
                                          or "never") for e, v in ivs.items()))
    return out
