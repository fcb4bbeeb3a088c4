"""lfdfuse: learning behaviour fusion from one demonstration of a mobile robot."""

import os

# The estimator's matrix products are small (steps × a few behaviours × particles): BLAS threads
# cost more than they give there (estimate --trials 8 of the default demo on 2 cores: 29 s wall and
# 34 s CPU with OpenBLAS's threads, 15 s and 14 s with one), and they take the cores that
# --workers and the test runner hand out. One thread per process, unless the user set otherwise;
# this works when lfdfuse is imported before numpy (the command line, a Dask worker's own setting).
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
del _var

__version__ = "0.1.0"
