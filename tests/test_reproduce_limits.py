"""The mu -> 0, mu -> inf and gamma -> 0 limits (symbolic/limits.py) against computed maps."""
import importlib.util
from pathlib import Path

import numpy as np
import pytest

from hybridpd.reproduce.params import param_study


@pytest.fixture(scope="module")
def limits():
    path = Path(__file__).resolve().parents[1] / "symbolic" / "limits.py"
    spec = importlib.util.spec_from_file_location("hybridpd_symbolic_limits", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.parametrize("case", ["collocated", "noncollocated"])
def test_symbolic_limits(limits, case):
    d = limits.derive(case)
    e = d["e"]
    assert d["M_free_of_mu"] and d["b_affine_in_mu"]
    assert d["R_mu0"] == 1 and (d["R_muinf"] + e).simplify() == 0
    assert d["impact_entry_mu0"] == 0 and (d["impact_entry_muinf"] - (1 + e)).simplify() == 0


@pytest.mark.parametrize("case", ["collocated", "noncollocated"])
def test_mu_to_zero_limit_matches_the_map_at_1e_4(limits, case):
    for ex, st in limits.check_mu0(case, grid=11, mu=1e-4):
        assert ex >= 0.99 and st >= 0.99


@pytest.mark.parametrize("case", ["collocated", "noncollocated"])
def test_mu_to_infinity_limit_matches_the_map_at_1e4(limits, case):
    for muc_max, n_at_1e4, n_above in limits.check_muinf(case, grid=11, mu=1e4):
        assert muc_max < 1e4 and n_at_1e4 == 0 and n_above == 0


@pytest.mark.parametrize("case", ["collocated", "noncollocated"])
def test_gamma_to_zero_limit(limits, case):
    for exists, wall, ratio in limits.check_gamma0(case, gamma=1e-4):
        assert not exists and wall == -1 and ratio == pytest.approx(1, abs=0.02)


def test_mu_study_reports_the_limits(limits):
    fx = dict(mu=0.1, gamma=0.75, x10=1.0, m2=1.0, omega=5.0, n=1)
    ax = np.linspace(0.1, 50, 7)
    s = param_study("mu", values_range=(0.01, 10), points=4, kp_axis=ax, kv_axis=ax,
                    e=[0.1, 0.5, 0.9], fixed=fx)
    kp, kv = np.meshgrid(ax, ax)
    for case in ("collocated", "noncollocated"):
        for k, e in enumerate((0.1, 0.5, 0.9)):
            ex0, st0 = limits.mu0_map(case, kp, kv, e=e, L=0.75, omega=5.0)
            assert s.limits["0.0001"][case]["exists"][k] == pytest.approx(ex0.mean(), abs=0.03)
            assert s.limits["0.0001"][case]["both"][k] == pytest.approx(st0.mean(), abs=0.03)
            assert s.limits["10000"][case]["exists"][k] == 0
        # the paper: the existence region shrinks as mu grows (here to nothing by mu = 10)
        assert s.fractions[case]["exists"][:, -1].max() == 0
