"""lfdfuse: learning behaviour fusion from one demonstration of a mobile robot."""

__version__ = "0.1.0"
