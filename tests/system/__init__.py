"""Tests of systems of FMUs (fmu.system): system files, their refusals, SSP archives, runs in ECOS and libcosim."""
