"""The behaviour primitives, one module per primitive or family: each holds its ``SPECS``.

:mod:`lfdfuse.behaviors.catalogue` gathers every module of this package, so a new primitive is
one new module here (with its spec: name, acronym, colour, inputs, default role, compute).
"""
