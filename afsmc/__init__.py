"""afsmc: a compiler for autonomous probabilistic finite-state machines."""

__version__ = "0.1.0"
