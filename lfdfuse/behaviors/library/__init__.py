"""The behaviour primitives, one module per primitive or family: each holds its ``SPECS``.

:mod:`lfdfuse.behaviors.catalogue` gathers every module of this package, so a new primitive is
one new module here (its spec: name, acronym, colour, inputs, default role, compute with any
state it carries between scans). Two data files name every behaviour for readers outside
Python — the fusion-table schema's name pattern (``catalogue.name_pattern()``) and the weights
plot of ``lfdfuse/foxglove/run-layout.json`` — and ``tests/behaviors/test_catalogue.py`` says
what they lack. A preset (a contract) names a new primitive only when asked to.
"""
