"""The library version (a leaf, so that the file container can stamp it)."""

__version__ = "0.1.0"
