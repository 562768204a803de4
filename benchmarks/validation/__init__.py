"""Validation suite: ``python -m benchmarks.validation`` compares warpsim with analytic solutions and published
measurements, measures how the stick stretch converges with iterations and dt, and runs a simulated hour of
the gusty kite. See :mod:`benchmarks.validation.cases` and the README's Validation section."""
