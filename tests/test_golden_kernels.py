"""The compiled kernels' results (simulations with accumulations, sticking, divergence and
joint contacts, a first crossing, section maps and their Jacobians, the pair's impact map and
symmetric orbits) against the stored golden results: bitwise on the recording machine, to a
tolerance elsewhere (``tests/_golden.py``)."""
import _golden
import pytest
from _golden_kernels import PATH, compute


@pytest.mark.stored_data
def test_kernels_match_the_golden_results():
    _golden.check(PATH, compute())
