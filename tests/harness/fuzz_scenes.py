"""Scene files the fuzzers build that no shipped scene covers: an off-axis wheel on an orbit, a central field.

With the shipped quadrotor (four speed-mode propellers) these give the fuzz tests
(tests/robustness/test_fuzz_fmi.py) an FMU of every rotor, orbit and central-field variable
(issue 39, item 3). Both take fixed rk4 steps (tolerance 0), as the fuzzer's work
prediction assumes, and start far inside the ranges of docs/robustness.md §2 ("Ranges of
every quantity"): |x_cm| = 40 m against a body's size sqrt(tr I / m) of at most ~8 m for
the inertias and masses the fuzzer draws, so a few seconds of fuzzed doSteps never reach it.
"""

from __future__ import annotations

# An orbit (orbit_angle a state, n_orbit a parameter), the gravity-gradient torque and a
# torque-mode wheel whose axis (0.6, 0.8, 0) is along no body axis.
OFFAXIS_WHEEL_TOML = """
name = "offaxis_wheel"
description = "Fuzz scene: I = diag(2, 3, 4) kg m^2 on an orbit, a wheel along (0.6, 0.8, 0), off the body axes."
outputs = ["q", "w_body", "E_kin", "L_world"]
[features]
orbit = true
gravity_gradient = true
[orbit]
rate = 0.001
[body]
principal_moments = [2.0, 3.0, 4.0]
[rotors.wheel]
axis = [0.6, 0.8, 0.0]
J = 0.05
[initial]
w_body = [0.0, 0.0, 1.0]
Omega_wheel = 10.0
[experiment]
stop_time = 1.0
step = 0.01
h_max = 0.001
tolerance = 0.0
method = "rk4"
"""

# The central field (x_cm, v_cm states, mu) with a torque-mode wheel along body z.
CENTRAL_WHEEL_TOML = """
name = "central_wheel"
description = "Fuzz scene: m = 2 kg in the central field mu = 40 m^3/s^2 at |x| = 40 m, a wheel along body z."
outputs = ["q", "w_body", "E_kin", "E_total", "L_world", "x_cm", "v_cm"]
[features]
translation = true
central_gravity = true
[central_gravity]
mu = 40.0
[body]
principal_moments = [0.01, 0.02, 0.025]
mass = 2.0
[rotors.wheel]
axis = [0.0, 0.0, 1.0]
J = 0.001
[initial]
x_cm = [40.0, 0.0, 0.0]
v_cm = [0.0, 1.0, 0.0]
w_body = [0.0, 0.0, 1.0]
Omega_wheel = 5.0
[experiment]
stop_time = 1.0
step = 0.01
h_max = 0.001
tolerance = 0.0
method = "rk4"
"""

FUZZ_SCENES = {"offaxis_wheel": OFFAXIS_WHEEL_TOML, "central_wheel": CENTRAL_WHEEL_TOML}
