"""Benchmarks of the FMU: the C cost of the generated step and of fmi3DoStep (`rbfmu bench`)."""
