"""The linearisation's eigenvalues and entries against the closed forms of docs/theory.md (spins, orbit, tops, hover).

Each closed form is compared with the eigenvalues of the FMU's linear model in attitude-error
coordinates (rotating frame): simple eigenvalues of a matrix whose entries carry a few ε of
round-off are exact to ~1e-15 relative, so 1e-10 leaves room and still fails on any error of
the model or the coordinates.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fmu.linear.eigen import modes
from fmu.linear.linearize import linearize
from fmu.linear.operating_point import start_point
from fmu.linear.trim import trim
from rbcheck.closed_forms.dual_spin import growth_rate, nutation_frequency
from rbcheck.closed_forms.gravity_gradient import pitch_frequency, roll_yaw_frequencies

REL = 1e-10


def eig(fmus, scene, values, **kw):
    p = start_point(fmus[scene], values)
    m = linearize(fmus[scene], p, outputs=[], **kw)
    return m, np.linalg.eigvals(m.A)


def closest(values: np.ndarray, target: complex) -> complex:
    return complex(values[np.argmin(np.abs(values - target))])


def test_dual_spin_nutation_and_growth(fmus):
    I = np.array([350.0, 200.0, 300.0])
    m, ev = eig(fmus, "dual_spin", {"w_body[1]": 0.0})
    assert np.max(np.abs(m.drift)) == 0.0  # the steady spin is a fixed point of the rotating frame
    nu = nutation_frequency(I, 2, 1.0, 100.0)
    got = closest(ev, 1j * nu)
    assert abs(got.imag - nu) / nu < REL and abs(got.real) < REL * nu, (got, nu)
    # no spurious quaternion mode: 7 eigenvalues (3 + 3 + wheel), not 8
    assert len(ev) == 7
    _, ev0 = eig(fmus, "dual_spin", {"w_body[1]": 0.0, "Omega_wheel": 0.0})
    lam = growth_rate(I, 2, 1.0, 0.0)
    got = float(np.max(ev0.real))
    assert abs(got - lam) / lam < REL, (got, lam)


def test_gravity_gradient_pitch_and_roll_yaw(fmus):
    n, I = 0.0011635528346628863, np.array([1000.0, 1020.0, 50.0])
    m, ev = eig(fmus, "gravity_gradient_boom", {"q[1]": 1.0, "q[3]": 0.0})
    assert "orbit_angle" not in m.states and len(m.states) == 6
    assert np.max(np.abs(m.drift)) < 1e-20  # at rest in LVLH: an equilibrium of the rotating frame
    freqs = sorted(abs(e.imag) for e in ev if e.imag > 0)
    expected = sorted([pitch_frequency(n, I), *roll_yaw_frequencies(n, I)])
    assert np.max(np.abs(ev.real)) < REL * n
    for f, e in zip(freqs, expected):
        assert abs(f - e) / e < REL, (f, e)


def test_sleeping_top_threshold(fmus):
    M, g, l, I1cm, I3 = 0.5, 9.81, 0.04, 1.125e-4, 2.25e-4
    I1 = I1cm + M * l * l  # about the pivot
    wc = math.sqrt(4 * M * g * l * I1 / I3**2)

    def top(w3):
        _, ev = eig(
            fmus,
            "sleeping_top",
            {"c_friction": 0.0, "q[1]": 1.0, "q[2]": 0.0, "q[3]": 0.0, "q[4]": 0.0, "w_body[3]": w3},
        )
        return ev

    # below the threshold the tilt grows at √(4 I1 M g l − I3² ω3²)/(2 I1) (the characteristic
    # equation I1 s² − i I3 ω3 s + M g l = 0 of the tilt ξ = θx + iθy; docs/theory.md §4.2)
    for frac in (0.5, 0.9):
        w3 = frac * wc
        expected = math.sqrt(4 * I1 * M * g * l - (I3 * w3) ** 2) / (2 * I1)
        assert abs(np.max(top(w3).real) - expected) / expected < REL
    # it crosses the imaginary axis at ω3 = ωc: just above, nothing grows (beyond the √ε of
    # the double eigenvalues of the spin), just below, the growth rate above
    above, below = top(wc * (1 + 1e-6)), top(wc * (1 - 1e-6))
    scale = np.max(np.abs(below))
    assert np.max(above.real) < 1e-7 * scale
    expected = math.sqrt(4 * I1 * M * g * l - (I3 * wc * (1 - 1e-6)) ** 2) / (2 * I1)
    assert abs(np.max(below.real) - expected) / expected < 1e-6


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_free_asymmetric_axes(fmus, axis):
    I = np.array([1.0, 2.0, 3.0])
    w = 1.3
    values = {f"w_body[{k + 1}]": (w if k == axis else 0.0) for k in range(3)}
    m, ev = eig(fmus, "free_asymmetric", values)
    ms, _ = modes(m)
    if axis == 1:  # intermediate: grows at ω √((I2 − I1)(I3 − I2)/(I1 I3))
        lam = w * math.sqrt((I[1] - I[0]) * (I[2] - I[1]) / (I[0] * I[2]))
        assert abs(np.max(ev.real) - lam) / lam < REL
        assert any(md.kind == "unstable" for md in ms)
    else:  # major and minor axes: no mode grows (real parts at round-off, √ε for the double zeros)
        assert np.max(ev.real) < 1e-7 * w
        assert not any(md.kind == "unstable" for md in ms)


def test_quadrotor_hover(fmus):
    m_, g, kf, km, J, arm = 1.2, 9.81, 1.5e-5, 2.4e-7, 3e-5, 0.2
    Ixx, Izz = 0.012, 0.022
    hover = math.sqrt(m_ * g / (4 * kf))
    start = {f"Omega_dot_p{k}": 0.0 for k in range(1, 5)}
    start.update({f"Omega_p{k}": 400.0 * (-1) ** (k + 1) for k in range(1, 5)})
    p = start_point(fmus["quadrotor"], start)
    res = trim(fmus["quadrotor"], p, ["Omega_p1", "Omega_p2", "Omega_p3", "Omega_p4"], ["der(v_cm[3])", "der(w_body)"])
    for k, v in enumerate(res.values):
        assert abs(abs(v) - hover) / hover < REL and np.sign(v) == (-1) ** k
    m = linearize(fmus["quadrotor"], res.point, outputs=[])
    A, B, S, U = m.A, m.B, list(m.states), list(m.inputs)
    a = lambda r, c: A[S.index(r), S.index(c)]
    b = lambda r, c: B[S.index(r), U.index(c)]
    # vertical: a double integrator driven by 2 k_f Ω_h / m per rotor
    assert a("x_cm[3]", "v_cm[3]") == 1.0 and not np.any(A[S.index("v_cm[3]")])
    assert abs(b("v_cm[3]", "Omega_p1") - 2 * kf * hover / m_) / (2 * kf * hover / m_) < REL
    # a tilt δθ_y tips the thrust m g into x: v̇_x = g δθ_y, v̇_y = −g δθ_x
    assert abs(a("v_cm[1]", "dtheta[2]") - g) / g < REL and abs(a("v_cm[2]", "dtheta[1]") + g) / g < REL
    # roll from the thrust moment of rotor 2 at +y (Ω2 < 0), yaw from the drag −2 k_m |Ω| δΩ and the reaction −J Ω̇
    assert abs(b("w_body[1]", "Omega_p2") - arm * 2 * kf * (-hover) / Ixx) / (arm * 2 * kf * hover / Ixx) < REL
    for k in range(1, 5):
        yaw = -2 * km * hover / Izz
        assert abs(b("w_body[3]", f"Omega_p{k}") - yaw) / abs(yaw) < REL
        assert abs(b("w_body[3]", f"Omega_dot_p{k}") + J / Izz) / (J / Izz) < REL
    # every hover mode is an integrator chain: all eigenvalues 0 (to the √ε of the Jordan blocks)
    assert np.max(np.abs(np.linalg.eigvals(A))) < 1e-6
