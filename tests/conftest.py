"""Test configuration.

The tests evaluate thousands of 6x6 matrix exponentials; multithreaded BLAS only adds
synchronisation cost at that size (a 1000x slowdown was seen on a loaded 2-core machine), so
one BLAS thread is requested before NumPy loads, unless the user chose otherwise.
"""
import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
