"""confront: fuzzy RL and curriculum transfer for teams of Robocode tanks."""

__version__ = "0.1.0"
