"""The symmetric family continued in ``m2`` and in ``gamma`` (``x10`` fixed).

Independent checks: a mass scaling law of the closed loop, and the simulated impact map at the
continued points (the fixed point of the closed form must be a fixed point of ``P``).
"""
import numpy as np
import pytest

from hybridpd import ImpactPair, PDGains, Reference
from hybridpd.analysis.continuation import continue_orbit
from hybridpd.pair.continuation import SYMMETRIC_PARAMETERS, continue_symmetric
from hybridpd.pair.impactmap import ImpactMap
from hybridpd.pair.orbits import symmetric_orbit

W = 5.0


def test_new_parameters_are_listed():
    assert "m2" in SYMMETRIC_PARAMETERS and "gamma" in SYMMETRIC_PARAMETERS


@pytest.mark.parametrize("case", ["collocated", "noncollocated"])
def test_m2_branch_obeys_the_mass_scaling(case):
    """m1 = mu m2, m2, kp, kv all scaled by c leave the motion unchanged (U scales with c)."""
    br = continue_symmetric(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), W, "m2", 2.0,
                            case=case, step=0.1, max_step=0.2)
    assert br.termination == "reached stop" and br.parameter_name == "m2"
    assert br.parameter[0] == 1.0 and br.parameter[-1] == 2.0
    for i in (len(br) // 2, len(br) - 1):
        c = br.parameter[i]
        ref = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10 / c, 20 / c), W,
                              case=case)
        assert ref.exists == bool(br.viable[i])
        assert np.max(np.abs(ref.fixed_point - br.points[i])) < 1e-9
        assert abs(ref.xm - br.xm[i]) < 1e-9
        assert abs(ref.spectral_radius - br.spectral_radius[i]) < 1e-8


def test_gamma_branch_moves_the_clearance_at_fixed_x10():
    x10 = 1.5
    br = continue_symmetric(ImpactPair(0.1, 0.5, 0.75 * x10), PDGains(10, 20), W, "gamma",
                            0.6, x10=x10, step=0.02)
    assert br.termination == "reached stop"
    assert abs(br.parameter[0] - 0.75) < 1e-15 and "L" not in br.fixed
    assert br.fixed["x10"] == x10
    for i in (len(br) // 3, len(br) - 1):
        g = br.parameter[i]
        pair = ImpactPair(0.1, 0.5, g * x10)
        # the simulated map at the family's xm has the continued point as a fixed point
        P = ImpactMap(pair, PDGains(10, 20), Reference(br.xm[i], W))
        s = br.points[i]
        assert br.viable[i]
        assert np.max(np.abs(P(s) - s)) < 1e-9
        ref = symmetric_orbit(pair, PDGains(10, 20), W, x10=x10)
        assert np.max(np.abs(ref.fixed_point - s)) < 1e-9


def test_bad_parameter_names_the_allowed_ones():
    with pytest.raises(ValueError, match="gamma"):
        continue_symmetric(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), W, "m1", 2.0)
    with pytest.raises(ValueError, match="gamma"):
        continue_symmetric(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), W, "gamma", -0.5)


def test_map_continuation_on_the_design_path_meets_the_closed_form_grazing():
    """The map's family with x10 (xm follows the design) is continue_symmetric's path: Newton
    on the simulated P finds the closed-form points and ends at the same grazing value."""
    pair = ImpactPair(0.1, 0.1, 0.75)
    fam = continue_symmetric(pair, PDGains(10, 21.5), W, "kv", 22.5)
    kg = fam.events_of("grazing")[0].parameter
    o = symmetric_orbit(pair, PDGains(10, 21.5), W)
    P = ImpactMap(pair, PDGains(10, 21.5), Reference(0.5, W))     # xm replaced by the design
    br = continue_orbit(P.family("kv", x10=1.0), 21.5, 22.5, o.fixed_point, step=0.1)
    assert abs(br.xm[0] - o.xm) < 1e-12 and br.fixed["x10"] == 1.0 and "xm" not in br.fixed
    ev = br.events_of("grazing")
    assert ev and "ends at grazing" in br.termination
    assert abs(ev[-1].parameter - kg) < 1e-6
    for i in (1, len(br) // 2):
        ref = symmetric_orbit(pair, PDGains(10, br.parameter[i]), W)
        assert abs(ref.xm - br.xm[i]) < 1e-12
        assert np.max(np.abs(ref.fixed_point - br.points[i])) < 1e-9
    with pytest.raises(ValueError, match="parameter must be one of"):
        P.family("xm", x10=1.0)


def test_map_continuation_in_m2_on_the_design_path_matches_the_closed_form():
    pair = ImpactPair(0.1, 0.5, 0.75)
    o = symmetric_orbit(pair, PDGains(10, 20), W)
    P = ImpactMap(pair, PDGains(10, 20), o.reference())
    br = continue_orbit(P.family("m2", x10=1.0), 1.0, 1.6, o.fixed_point, step=0.2)
    assert br.termination == "reached stop" and br.parameter[-1] == 1.6
    for i in (len(br) // 2, len(br) - 1):
        ref = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75, br.parameter[i]), PDGains(10, 20), W)
        assert abs(ref.xm - br.xm[i]) < 1e-12
        assert np.max(np.abs(ref.fixed_point - br.points[i])) < 1e-9
        assert abs(ref.spectral_radius - br.spectral_radius[i]) < 1e-7
