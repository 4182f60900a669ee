"""The equations and integrators inside the FMU: closed forms, invariants, error control and each feature's physics."""
