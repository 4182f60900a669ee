"""Tests of the linear models (fmu.linear): closed forms, finite differences, trim, step map, CLI."""
