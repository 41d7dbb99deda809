"""Command line, pictures, benchmarks and the execution layer."""
