"""Build and solve: the watched Storm child, afsmc's own explorer and backward pass, strategies and paths inside an engine, Storm's parametric engine."""
