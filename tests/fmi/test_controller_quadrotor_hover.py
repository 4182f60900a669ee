"""The quadrotor_hover controller FMU: its law against numpy, its closed loop with the plant quadrotor_motors.

Built once per module (host binary only), with its plant scene (plants/quadrotor_motors.toml). The law is
re-derived here in numpy from the plant scene (Lee, Leok, McClamroch 2010 without feed-forward, a
mixer inverted from the rotors' positions, k_f, k_m and spin signs; docs/theory.md §12.2); the
closed loop (plant + controller, driven by plain fmpy calls) is compared with the plant driven by
that numpy law.
"""

from __future__ import annotations

import numpy as np
import pytest

from fmu.build.build_fmu import build_fmu
from fmu.build.controller_build import build_controller
from modelsrc.controllers.controller_file import CONTROLLER_DIR, load_controller
from modelsrc.errors import ModelInputError
from modelsrc.scene import load_scene

from ..harness.slave import Slave

X = [f"x_cm[{i}]" for i in (1, 2, 3)]
V = [f"v_cm[{i}]" for i in (1, 2, 3)]
Q = [f"q[{i}]" for i in (1, 2, 3, 4)]
W = [f"w_body[{i}]" for i in (1, 2, 3)]
IN = X + V + Q + W
U = [f"Omega_cmd_p{i}" for i in (1, 2, 3, 4)]
GAINS = {"k_pxy": 1.0, "k_dxy": 1.8, "k_pz": 4.0, "k_dz": 4.0, "k_R": 100.0, "k_w": 20.0, "k_Rz": 4.0, "k_wz": 4.0}
TS = 0.01  # s, the file's sample period
PLANT = CONTROLLER_DIR / "plants" / "quadrotor_motors.toml"  # the controller file's plant scene


@pytest.fixture(scope="module")
def ctrl_fmus(tmp_path_factory):
    out = tmp_path_factory.mktemp("controllers")
    return {v: build_controller("quadrotor_hover", out, fmi_version=v) for v in (3, 2)}


@pytest.fixture(scope="module")
def plant(tmp_path_factory):
    return build_fmu(PLANT, tmp_path_factory.mktemp("plant"))


def rotation(q: np.ndarray) -> np.ndarray:
    """R (body -> world) of a unit quaternion, scalar first."""
    q0, q1, q2, q3 = q / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (q2 * q2 + q3 * q3), 2 * (q1 * q2 - q0 * q3), 2 * (q1 * q3 + q0 * q2)],
        [2 * (q1 * q2 + q0 * q3), 1 - 2 * (q1 * q1 + q3 * q3), 2 * (q2 * q3 - q0 * q1)],
        [2 * (q1 * q3 - q0 * q2), 2 * (q2 * q3 + q0 * q1), 1 - 2 * (q1 * q1 + q2 * q2)],
    ])  # fmt: skip


class HoverLaw:
    """The quadrotor_hover law in numpy for the plant quadrotor_motors (the height integral given)."""

    def __init__(self, x_d, psi_d: float, om_max: float = 1000.0) -> None:
        sc = load_scene(PLANT)
        self.m, self.I, self.g = sc.mass, np.asarray(sc.inertia, dtype=float), np.asarray(sc.g, dtype=float)
        r = [sc.rotors[f"p{i}"] for i in (1, 2, 3, 4)]
        self.k_f = r[0].k_f
        pos = [np.asarray(ri.position, dtype=float) for ri in r]  # m, body, from the centre of mass
        self.s = np.array([np.sign(ri.Omega0) for ri in r])
        # T = Σ f_i; τ = Σ r_i × (f_i e_3) − s_i k_m Ω_i² e_3 = Σ (r_y f, −r_x f, −s k_m/k_f f)
        self.M = np.array([
            [1.0] * 4,
            [p[1] for p in pos],
            [-p[0] for p in pos],
            [-self.s[i] * r[i].k_m / self.k_f for i in range(4)],
        ])  # fmt: skip
        self.x_d, self.psi_d, self.om_max = np.asarray(x_d, dtype=float), psi_d, om_max

    def __call__(self, y: np.ndarray, k_iz: float = 0.0, e_z: float = 0.0) -> np.ndarray:
        """Ω_cmd (rad/s) at the plant outputs y = (x, v, q, w); k_iz e_z the height integral's term."""
        x, v, q, w = y[0:3], y[3:6], y[6:10], y[10:13]
        k = GAINS
        a = np.array([k["k_pxy"] * (self.x_d[0] - x[0]) - k["k_dxy"] * v[0],
                      k["k_pxy"] * (self.x_d[1] - x[1]) - k["k_dxy"] * v[1],
                      k["k_pz"] * (self.x_d[2] - x[2]) - k["k_dz"] * v[2] + k_iz * e_z])  # fmt: skip
        F = self.m * (a - self.g)
        b3 = F / np.linalg.norm(F)
        b2 = np.cross(b3, [np.cos(self.psi_d), np.sin(self.psi_d), 0.0])
        b2 /= np.linalg.norm(b2)
        Rd = np.column_stack([np.cross(b2, b3), b2, b3])
        R = rotation(q)
        E = 0.5 * (Rd.T @ R - R.T @ Rd)
        e_R = np.array([E[2, 1], E[0, 2], E[1, 0]])
        K_R = np.array([k["k_R"], k["k_R"], k["k_Rz"]])
        K_w = np.array([k["k_w"], k["k_w"], k["k_wz"]])
        tau = self.I @ (-K_R * e_R - K_w * w)
        f = np.linalg.solve(self.M, np.concatenate([[F @ R[:, 2]], tau]))
        f = np.clip(f, 0.0, self.k_f * self.om_max**2)
        return self.s * np.sqrt(f / self.k_f)


@pytest.mark.parametrize("version", [3, 2])
def test_the_outputs_are_the_numpy_law_at_the_current_inputs(ctrl_fmus, version):
    """300 random states near hover (tilts up to ~0.6 rad, any yaw, rates ~1 rad/s): the outputs
    are the numpy law's Ω_cmd to round-off (|Ω| ~ 450 rad/s; the mixer's inverse and the square
    root differ in the last bits: measured 1.6e-12 rad/s, asserted ≤ 1e-10 rad/s, relative 2e-13)."""
    c = Slave(ctrl_fmus[version], version)
    law = HoverLaw([0.0, 0.0, 2.0], 0.5)
    rng = np.random.default_rng(3)
    worst = 0.0
    for _ in range(300):
        q = np.concatenate([[1.0], 0.3 * rng.normal(size=2), [rng.normal()]])
        q /= np.linalg.norm(q)
        y = np.concatenate([rng.normal(size=3) + [0, 0, 1.5], 0.5 * rng.normal(size=3), q, rng.normal(size=3)])
        c.set(dict(zip(IN, y)))
        worst = max(worst, float(np.max(np.abs(c.get(U) - law(y)))))
    c.close()
    print(f"FMI {version}: max |Omega_cmd - numpy law| = {worst:.3g} rad/s")
    assert worst <= 1e-10


def closed_loop(plant_fmu, step_law, T: float, H: float) -> np.ndarray:
    """The plant stepped by plain fmpy calls with its commands from step_law(t, y) at each t_k;
    the plant's (x, v, q, w) at the communication points."""
    p = Slave(plant_fmu, 3)
    rows, n = [], round(T / H)
    for k in range(n + 1):
        t = k * H
        y = p.get(IN)
        rows.append(y)
        if k == n:
            break
        p.set(dict(zip(U, step_law(t, y, H))))
        p.step(t, H)
    p.close()
    return np.array(rows)


def with_fmu(ctrl_fmu, version: int, start: dict[str, float] | None = None):
    c = Slave(ctrl_fmu, version, start)

    def step_law(t: float, y: np.ndarray, H: float) -> np.ndarray:
        c.set(dict(zip(IN, y)))
        u = c.get(U)
        c.step(t, H)
        return u

    return c, step_law


def yaw(q: np.ndarray) -> float:
    return float(np.arctan2(2 * (q[0] * q[3] + q[1] * q[2]), 1 - 2 * (q[2] ** 2 + q[3] ** 2)))


@pytest.mark.slow
@pytest.mark.parametrize("version", [3, 2])
def test_takes_off_to_the_height_and_turns_to_the_yaw_as_the_numpy_law_does(plant, ctrl_fmus, version):
    """quadrotor_motors + quadrotor_hover (file targets: 2 m, yaw 0.5 rad) over 6 s, H = Ts: the
    two-FMU loop follows the plant driven by the numpy law at every communication point (measured
    4.4e-16 m, 5.3e-16 in q; asserted 1e-12, the laws' round-off carried through 600 steps of a
    stable loop), and after 6 s the height is within 1 mm of 2 m (ω_n = 2 rad/s, critically
    damped: e^{-12}·13 ≈ 8e-5 of the 1 m step left) and the yaw within 1e-3 rad of 0.5."""
    c, step_law = with_fmu(ctrl_fmus[version], version)
    Y = closed_loop(plant, step_law, 6.0, TS)
    c.close()
    law = HoverLaw([0.0, 0.0, 2.0], 0.5)
    Yn = closed_loop(plant, lambda t, y, H: law(y), 6.0, TS)
    dx = float(np.max(np.abs(Y[:, 0:3] - Yn[:, 0:3])))
    dq = float(np.max(np.abs(Y[:, 6:10] - Yn[:, 6:10])))
    print(f"FMI {version}: FMU loop vs numpy law loop: max |dx| = {dx:.3g} m, max |dq| = {dq:.3g}")
    print(f"FMI {version}: at 6 s height {float(Y[-1, 2])!r} m, yaw {yaw(Y[-1, 6:10])!r} rad")
    assert dx <= 1e-12 and dq <= 1e-12
    assert abs(Y[-1, 2] - 2.0) < 1e-3 and abs(yaw(Y[-1, 6:10]) - 0.5) < 1e-3
    assert np.max(np.abs(Y[:, 0:2])) < 1e-9  # no horizontal drift: the '+' layout is symmetric


@pytest.mark.slow
def test_hover_holds_when_the_target_is_the_start(plant, ctrl_fmus):
    """Targets set to the start (1 m, yaw 0) through the tunable parameters: over 2 s the body
    stays at rest to round-off (measured 0; asserted 1e-12 m and in q)."""
    c, step_law = with_fmu(ctrl_fmus[3], 3, {"x_d[3]": 1.0, "psi_d": 0.0})
    Y = closed_loop(plant, step_law, 2.0, TS)
    c.close()
    dx = float(np.max(np.abs(Y[:, 0:3] - [0.0, 0.0, 1.0])))
    dq = float(np.max(np.abs(Y[:, 6:10] - [1.0, 0.0, 0.0, 0.0])))
    print(f"hover: max |x - x0| = {dx:.3g} m, max |q - q0| = {dq:.3g}")
    assert dx <= 1e-12 and dq <= 1e-12


def random_state(rng: np.random.Generator) -> np.ndarray:
    """Plant outputs (x, v, q, w) near hover: tilts up to ~0.6 rad, any yaw, rates ~1 rad/s."""
    q = np.concatenate([[1.0], 0.3 * rng.normal(size=2), [rng.normal()]])
    q /= np.linalg.norm(q)
    return np.concatenate([rng.normal(size=3) + [0, 0, 1.5], 0.5 * rng.normal(size=3), q, rng.normal(size=3)])


def test_the_height_integral_sums_the_error_at_each_sample(ctrl_fmus):
    """k_iz = 2: at t = 0 the output has e = 0; each doStep from a sample adds Ts (x_d,3 − x_3)
    at that sample's inputs; the outputs at the next samples are the numpy law with that e
    (asserted 1e-10 rad/s as the law test)."""
    c = Slave(ctrl_fmus[3], 3, {"k_iz": 2.0})
    law = HoverLaw([0.0, 0.0, 2.0], 0.5)
    rng = np.random.default_rng(11)
    e, worst = 0.0, 0.0
    for k in range(5):
        y = random_state(rng)
        c.set(dict(zip(IN, y)))
        worst = max(worst, float(np.max(np.abs(c.get(U) - law(y, 2.0, e)))))
        c.step(k * TS, TS)
        e += TS * (2.0 - y[2])
    c.close()
    print(f"k_iz = 2: max |Omega_cmd - numpy law| = {worst:.3g} rad/s, e after 5 samples {e:.3g} m s")
    assert worst <= 1e-10 and abs(e) > 1e-3


def test_the_rotor_speed_limit_and_the_zero_thrust_floor_clip_each_command(ctrl_fmus):
    """Omega_max = 300 rad/s (below the hover speed 443): at hover every command is ±300; a fast
    roll (w_x = 60 rad/s) asks rotor p2 (+y) for negative thrust: its command is 0 (f_i ≥ 0), and
    p4 (−y) for more than the limit: −300; both as the numpy law with the same limits."""
    c = Slave(ctrl_fmus[3], 3, {"Omega_max": 300.0})
    law = HoverLaw([0.0, 0.0, 2.0], 0.5, om_max=300.0)
    hover = np.array([0, 0, 2.0, 0, 0, 0, np.cos(0.25), 0, 0, np.sin(0.25), 0, 0, 0])
    c.set(dict(zip(IN, hover)))
    assert np.array_equal(np.abs(c.get(U)), [300.0] * 4)
    roll = hover.copy()
    roll[10] = 60.0
    c.set(dict(zip(IN, roll)))
    u = c.get(U)
    assert u[1] == 0.0 and u[3] == -300.0 and np.max(np.abs(u - law(roll))) <= 1e-10, (u, law(roll))
    c.close()


def write(tmp_path, text: str, name: str = "c.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


BASE = f'law = "quadrotor_hover"\nplant = "{PLANT}"\nsample_period = 0.01\n'


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (BASE + "[gains]\nk_R = -1\n", r"field 'gains.k_R': must be >= 0, got -1"),
        (BASE + "[gains]\nk_pz = nan\n", r"field 'gains.k_pz': must be finite, got nan"),
        (BASE + "[limits]\nrotor_speed = 0\n", r"field 'limits.rotor_speed': must be"),
        (BASE + "[target]\nposition = [0.0, 2.0]\n", r"field 'target.position'"),
        (BASE.replace("0.01", "0.0"), r"field 'sample_period': must be > 0, got 0.0"),
        (BASE.replace(str(PLANT), "quadrotor"), r"scene 'quadrotor' has 0 command-mode propellers .*exactly 4"),
        (BASE.replace(str(PLANT), "reaction_wheel_slew"), r"field 'plant'.*exactly 4"),
    ],
)
def test_a_bad_controller_file_is_refused_naming_the_value(tmp_path, text, message):
    with pytest.raises(ModelInputError, match=message):
        load_controller(write(tmp_path, text))


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ("Omega_p1 = 442.944691807002", "Omega_p1 = 0.0", r"rotor p1 has start rate 0"),
        ("k_f = 1.5e-5                 #", "k_f = 1.6e-5                 #", r"the rotors' k_f differ"),
        ("g = [0.0, 0.0, -9.81]", "g = [0.0, 9.81, 0.0]", r"needs translation and gravity along world -z"),
    ],
)
def test_a_plant_the_law_cannot_drive_is_refused_naming_it(tmp_path, old, new, message):
    text = PLANT.read_text()
    assert old in text
    plant = write(tmp_path, text.replace(old, new, 1), "plant.toml")
    with pytest.raises(ModelInputError, match=message):
        load_controller(write(tmp_path, BASE.replace(str(PLANT), str(plant))))
