"""An example simulator plugin for afsmc (see README.md)."""
