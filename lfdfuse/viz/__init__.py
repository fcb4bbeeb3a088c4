"""Plots and the paper-reproduction report (DESIGN §13).

The only package that imports matplotlib; the CLI imports it lazily, inside the ``plot`` and
``report`` commands, so ``lfdfuse --help`` never pays for it. Figures are drawn on
``matplotlib.figure.Figure`` objects (no pyplot state, no GUI backend).
"""
