"""The traced boundaries (curves, ends, codim-2 points) against the stored golden results:
bitwise on the recording machine, to a tolerance elsewhere (``tests/_golden.py``)."""
import _golden
import pytest
from _golden_boundaries import PATH, compute


@pytest.mark.stored_data
def test_traced_boundaries_match_the_golden_results():
    arrays = compute()
    assert arrays["non_e05_zoom.codim2_kinds"].size    # the case with codim-2 points
    # the multipliers at a codim-2 point (a 1:1 resonance is a double multiplier +1) move
    # like the square root of a change in the last digits of DP: 1e-16 -> 1e-8
    lam = {k: 1e-6 for k in arrays if k.endswith(".codim2_lam")}
    _golden.check(PATH, arrays, atol=lam)
