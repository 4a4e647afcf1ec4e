"""Bounds over interval probabilities by afsmc's own explorer: parameter lifting on the
explored acyclic model, attained values at points, refinement by splitting the box."""
