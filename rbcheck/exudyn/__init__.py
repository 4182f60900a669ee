"""Exudyn multibody models of the scenes: an independent reference solved by Exudyn's own integrators.

``models`` (a rigid body, free or on a spherical joint; every scene's rotation),
``motion`` (free flight, the moving pivot), ``orbit`` (the gravity-gradient torque),
``rotors`` (each rotor a body on a revolute joint) and ``skewed_bar`` (a revolute joint);
``coverage`` says which scenes the rigid-body models cover.
"""
