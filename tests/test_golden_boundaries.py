"""The traced boundaries (curves, ends, codim-2 points) against the stored golden results:
bitwise on the recording machine, to a tolerance elsewhere (``tests/_golden.py``)."""
import _golden
import pytest
from _golden_boundaries import PATH, compute


@pytest.mark.stored_data
def test_traced_boundaries_match_the_golden_results():
    arrays = compute()
    assert arrays["non_e05_zoom.codim2_kinds"].size    # the case with codim-2 points
    _golden.check(PATH, arrays)
