"""Every stop of a continuation says why and where: the branch result and the command line."""
import copy
import dataclasses
import json

import numpy as np

from hybridpd import ImpactPair, PDGains, Reference
from hybridpd.analysis.continuation import continue_orbit
from hybridpd.analysis.hybridmap import SectionMap
from hybridpd.analysis.pathfollow import PathOptions, corrector, follow_path
from hybridpd.cli import main
from hybridpd.pair.impactmap import ImpactMap
from hybridpd.pair.impactpair import ControlledImpactPair
from hybridpd.pair.orbits import symmetric_orbit
from hybridpd.pair.section import impact_pair_section

W = 5.0


def _kv_builder(pair, xm):
    """``kv -> SectionMap`` of the collocated pair (loop matrices affine in ``kv``)."""
    base = ControlledImpactPair(pair, PDGains(10, 20), Reference(xm, W))
    one = ControlledImpactPair(pair, PDGains(10, 21), Reference(xm, W))
    dA, df = one.loop.A - base.loop.A, one.loop.force - base.loop.force

    def build(kv):
        s = copy.copy(base)
        s.loop = dataclasses.replace(base.loop, A=base.loop.A + (kv - 20) * dA,
                                     force=base.loop.force + (kv - 20) * df)
        s.automaton = s._build_automaton()
        return SectionMap(impact_pair_section(s))
    return build


def test_a_min_step_stop_names_the_maps_failure_and_the_parameter():
    # e = 0.1: the symmetric orbit's fixed point runs off the section's crossing side near
    # kv = 21.79; natural continuation cannot pass and stops at the smallest step
    pair = ImpactPair(0.1, 0.1, 0.75)
    orb = symmetric_orbit(pair, PDGains(10, 20), W)
    br = continue_orbit(_kv_builder(pair, orb.xm), 20.0, 23.0, orb.fixed_point,
                         method="natural", step=0.5, max_step=0.5, min_step=1e-3)
    assert br.termination == "min_step"
    last = br[-1].p
    assert br.reason.startswith(f"step below min_step = 0.001 at p = {last:.10g}: corrector "
                                "failed: map undefined: bad_start")
    assert br.to_dict()["reason"] == br.reason
    # independent check: the last point is a fixed point of the pair's closed-form map
    Q = ImpactMap(pair, PDGains(10, last), Reference(orb.xm, W))
    np.testing.assert_allclose(Q(br[-1].s), br[-1].s, rtol=0, atol=1e-8)
    assert 21.0 < last < 22.0


def test_the_other_stops_carry_their_reason():
    pair = ImpactPair(0.1, 0.5, 0.75)
    orb = symmetric_orbit(pair, PDGains(10, 20), W)
    build = _kv_builder(pair, orb.xm)
    br = continue_orbit(build, 20.0, 22.0, orb.fixed_point, method="natural", step=1.0)
    assert br.termination == "reached" and br.reason == "reached the end value p = 22"
    br = continue_orbit(build, 20.0, 30.0, orb.fixed_point, method="natural", step=0.5,
                         max_step=0.5, max_steps=3)
    assert br.termination == "max_steps"
    assert len(br.points) == 3
    assert br.reason == f"max_steps = 3 accepted points reached at p = {br[-1].p:.10g}"
    np.testing.assert_allclose(br[-1].p, 21.0, rtol=0, atol=1e-12)
    bad = continue_orbit(build, 20.0, 22.0, [0.0, 5.0, 5.0, -1.0])
    assert bad.termination.startswith("start failed") and "p = 20" in bad.reason


def test_the_path_follower_names_why_the_map_was_undefined():
    # F(u) = u0^2 + p - 1 on the half plane u0 > 0 (undefined elsewhere): the branch
    # u0 = sqrt(1 - p) ends at p = 1, where it meets the boundary of the domain
    why = []

    def F(u):
        if u[0] <= 0:
            why.append(f"map undefined: outside the domain at p = {u[-1]:.6g}")
            return None
        return np.array([u[0] ** 2 + u[1] - 1.0])

    def explain():
        text = why[-1] if why else ""
        why.clear()
        return text

    Fs = lambda u: np.array([[2 * u[0]]])
    Fp = lambda u: np.array([1.0])

    class Pt:
        def __init__(self, u):
            self.u, self.DP, self.Fp = u, Fs(u) + np.eye(1), Fp(u)

    correct = corrector(F, Fs, Fp, tol=1e-12, max_iter=20, scale=lambda x: 1.0,
                        explain=explain)
    opts = PathOptions(step=0.25, min_step=1e-4, max_step=0.25, max_steps=100,
                       method="natural", name="p")
    pts, _, term, _, stuck = follow_path(Pt(np.array([1.0, 0.0])), 2.0, opts, F=F, Fs=Fs,
                                         Fp=Fp, make_point=lambda u, _its: Pt(u),
                                         correct=correct)
    assert term.startswith(f"step below min_step = 0.0001 at p = {pts[-1].u[-1]:.10g}: ")
    assert "map undefined: outside the domain" in stuck and stuck in term
    np.testing.assert_allclose(pts[-1].u[1], 1.0, rtol=0, atol=1e-3)
    np.testing.assert_allclose(pts[-1].u[0], np.sqrt(1.0 - pts[-1].u[1]), rtol=0, atol=1e-9)


def test_the_command_line_reports_the_branch_termination(tmp_path, capsys):
    argv = ["bifurcation", "--case", "collocated", "--mu", "0.1", "--e", "0.1", "--gamma",
            "0.75", "--omega", "5", "--kp", "10", "--param", "kv", "20", "23", "3",
            "--iterations", "40", "--keep", "10", "--out", str(tmp_path / "d.nc"),
            "--plot", str(tmp_path / "d.png")]
    assert main([*argv, "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    br = doc["branch"]
    assert br["drawn"] and br["points"] >= 2 and br["termination"]
    assert main(argv) == 0
    assert f"stopped: {br['termination']}" in capsys.readouterr().out
