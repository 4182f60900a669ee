"""Systems of FMUs: system files, their checks, SSP 1.0 archives and the co-simulation masters that run them."""
