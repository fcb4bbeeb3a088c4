"""Test rigs shared by the tests and the benchmarks: robots to drive, transports to plug in."""
