"""Compiled loops: :mod:`~lfdfuse.kernels.jit` wraps a numba loop as a lazily compiled, disk-cached
kernel with its numpy reference beside it; :mod:`~lfdfuse.kernels.pairwise` is numpy's pairwise sum
written out for loops that must give numpy's bits. Each stage keeps its own loops (``kernels.py``
beside the code that calls them); nothing here imports numba until a kernel is first called."""
