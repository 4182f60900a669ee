"""The momentum-bias satellite (issue 34 item 5): roll–yaw with wheel momentum, pitch with a free wheel.

docs/theory.md §9.8. The shipped scene momentum_bias (I = diag(1200, 1000, 800) kg m², one
wheel J = 0.1 kg m² on the pitch axis at −200 rad/s: its momentum along the orbit normal; a
90-min orbit) is held to the closed forms of rbcheck.closed_forms.gravity_gradient two ways:
the eigenvalues of the FMU's linear model at rest in LVLH (fmu.linear; simple eigenvalues of
a matrix with entries exact to a few ε, so 1e-10 relative, as tests/linear/test_closed_forms.py)
for both signs of the wheel's momentum and without it, and frequencies fitted to short runs of
the FMU at its defaults (rbcheck.checks.momentum_bias).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fmu.linear.linearize import linearize
from fmu.linear.operating_point import start_point
from modelsrc.scene import load_scene
from rbcheck.checks import momentum_bias as mb
from rbcheck.closed_forms import gravity_gradient as gg

from ..harness.scenes import shared_fmu

REL = 1e-10


@pytest.fixture(scope="module")
def fmu(build_dir):
    """The shipped scene's FMU (shared with the session's `fmus` where that runs too)."""
    return shared_fmu(build_dir, "momentum_bias")


SC = load_scene("momentum_bias")
N = SC.orbit_rate
I = mb.moments(SC)
J, H_Y = mb.wheel_along_normal(SC)


def at_rest(fmu, omega_wheel: float) -> np.ndarray:
    """Eigenvalues (1/s) of the linear model at rest in LVLH with the wheel at omega_wheel (rad/s)."""
    values = {"q[1]": 1.0, "q[2]": 0.0, "q[3]": 0.0, "q[4]": 0.0, "w_body[1]": 0.0, "w_body[2]": -N}
    values.update({"w_body[3]": 0.0, "Omega_wheel": omega_wheel})
    m = linearize(fmu, start_point(fmu, values), outputs=[])
    assert np.max(np.abs(m.drift)) < 1e-20  # at rest in LVLH: an equilibrium of the rotating frame
    return np.linalg.eigvals(m.A)


def test_scene_is_a_wheel_along_the_orbit_normal():
    # g = e_y (−orbit normal at rest in LVLH), Ω₀ < 0: h_y = J Ω₀ g_y = −20 N m s, the stiffening sign
    assert abs(H_Y + 20.0) < 1e-13 and J == 0.1
    # alone the body would be unstable in roll–yaw (I_x > I_y): the bias is what holds it
    with pytest.raises(ValueError, match="not oscillatory"):
        gg.momentum_bias_roll_yaw(N, I, 0.0)


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_linear_model_matches_the_roll_yaw_and_pitch_closed_forms(fmu, sign):
    """Both signs of h are stable here (the other one only gyroscopically, docs/theory.md §9.8);
    each pair of frequencies is the closed form's, and the pitch frequency has I_y − J."""
    omega = sign * SC.rotors["wheel"].Omega0
    ev = at_rest(fmu, omega)
    assert np.max(np.abs(ev.real)) < REL * N
    freqs = sorted(e.imag for e in ev if e.imag > 0)
    slow, fast = gg.momentum_bias_roll_yaw(N, I, sign * H_Y)
    pitch = gg.pitch_frequency_free_wheel(N, I, J)
    expected = sorted([slow, fast, pitch])
    assert len(freqs) == 3 and len(ev) == 7  # 3 attitude + 3 rates + the wheel (its conserved momentum: 0)
    for f, e in zip(freqs, expected):
        assert abs(f - e) / e < REL, (f, e)
    # the pitch inertia is I_y − J: with I_y the frequency is 5.0e-5 off
    assert abs(pitch / gg.pitch_frequency(N, I) - 1) > 1e-5


def test_the_stiffening_sign_and_no_wheel(fmu):
    """h along the orbit normal (h_y < 0) raises the stiffnesses by n|h|: the slow mode is above
    the other sign's; without the wheel the yaw diverges at the polynomial's real root."""
    slow_bias, _ = gg.momentum_bias_roll_yaw(N, I, H_Y)
    slow_other, _ = gg.momentum_bias_roll_yaw(N, I, -H_Y)
    assert slow_bias > slow_other
    ev = at_rest(fmu, 0.0)
    # I_x I_z s⁴ + (I_x K_ψ + I_z K_φ + G²) s² + K_φ K_ψ = 0 at h = 0 (§9.8): one positive root s²
    G, Kr, Ky = N * (I[0] - I[1] + I[2]), 4 * N * N * (I[1] - I[2]), N * N * (I[1] - I[0])
    s2 = np.roots([I[0] * I[2], I[0] * Ky + I[2] * Kr + G * G, Kr * Ky])
    growth = math.sqrt(float(np.max(s2.real)))
    got = float(np.max(ev.real))
    assert abs(got - growth) / growth < REL, (got, growth)


def test_fmu_runs_match_the_closed_forms(fmu):
    """Frequencies fitted to runs at the FMU's defaults (rk8, tolerance 1e-10 1/s): the pitch
    against the pendulum's exact 2π/T(θ₀) with inertia I_y − J, the roll–yaw pair against the
    linear closed form. Bounds: the pitch fit came within 2.7e-11 of the pendulum (5 periods
    fitted by one sinusoid); 1e-10 still separates the amplitude effect m/4 = 2.5e-9 and J's 5.0e-5; roll and yaw reach
    ε ≈ 2.6e-4 rad, so the nonlinear shift is O(ε²) ≈ 7e-8: bound 1e-7."""
    m = mb.measure(fmu, SC)
    assert abs(m.pitch / m.pitch_closed - 1) < 1e-10, (m.pitch, m.pitch_closed)
    assert abs(m.pitch_closed / m.pitch_small_closed - 1) == pytest.approx(2.5e-9, rel=1e-3)
    for got, closed in zip(m.roll_yaw, m.roll_yaw_closed):
        assert abs(got / closed - 1) < 1e-7, (got, closed)
    # the Jacobi integral (§9.3, the wheel's terms included) over the scene's three orbits: round-off
    assert m.jacobi_drift < 1e-13
