"""afsmc's own exploration and backward pass with the layers on disk (``verify --scratch``):
memory bounded by a window of buckets, not by the whole model."""
