"""The impact pair's map continuations and branch switches against the stored golden
results: bitwise on the recording machine, to a tolerance elsewhere (``tests/_golden.py``)."""
import _golden
import pytest
from _golden_continuation import PATH, atol, compute


@pytest.mark.stored_data
def test_map_continuations_match_the_golden_results():
    arrays = compute()
    # the cases exercise what they are there for: a fold, grazing ends, period doublings
    assert "fold" in arrays["period2_kv.ev.kind"]
    assert "grazing" in arrays["symmetric_kv_grazing.ev.kind"]
    assert "grazing" in arrays["design_kv.ev.kind"]
    assert "period_doubling" in arrays["asym_kp.ev.kind"]
    assert arrays["switch_flip.period"] == arrays["switch_grazing.period"] == 2
    _golden.check(PATH, arrays, atol(arrays))
