"""Fusion estimation (paper Section IV-B): the particle filter and its baselines."""
