"""Every result type written to each file suffix and read back, and the JSON of results
built from their fields, against the stored golden results: bitwise on the recording
machine, to a tolerance elsewhere (``tests/_golden.py``)."""
import _golden
import numpy as np
import pytest
from _golden_results import PATH, compute


@pytest.mark.stored_data
def test_results_read_back_as_the_golden_results():
    arrays = compute()
    # independently of the stored file: every suffix reads back the arrays written
    made = [k for k in arrays if ".made." in k and arrays[k].dtype.kind != "U"]
    assert len(made) >= 29
    for key in made:
        for suffix in (".nc.", ".zarr.", ".npz."):
            back = arrays.get(key.replace(".made.", suffix))
            if back is not None:
                assert back.dtype == arrays[key].dtype, key
                assert np.array_equal(back, arrays[key], equal_nan=back.dtype.kind in "fc"), key
    _golden.check(PATH, arrays)
