"""Shared helpers of the tests: ctypes bindings of FMI 3.0 and fmpy's FMI 2.0, harnesses, fuzz drivers, scene files."""
