"""Benchmarks (``bille bench``)."""
