"""What both quaternion-feedback attitude laws share: the target, the plant's attitude inputs, the error quaternion.

Wie, "Space Vehicle Dynamics and Control", §7.3 (docs/theory.md §12.1, §12.3): with q and the
target q_d (body -> world, scalar first) the error quaternion is q_e = q_d* ⊗ q (body frame), and
sgn(q_e0) picks the shorter way round. attitude_pd turns it into wheel torques,
attitude_torque_pd into a body torque.
"""

from __future__ import annotations

from collections.abc import Callable

import casadi as ca
import numpy as np

from ..quaternion import quat_mul
from ..scene_reader import UNIT_LENGTH_TOL, SceneReader
from .controller import CKind, CVar

Q_NAMES = [f"q[{i}]" for i in range(1, 5)]
W_NAMES = [f"w_body[{i}]" for i in range(1, 4)]
QD_NAMES = [f"q_d[{i}]" for i in range(1, 5)]


def target_quaternion(rd: SceneReader, target: dict) -> np.ndarray:
    """The file's [target] q (default: the identity), refused unless it is a unit quaternion."""
    qd = rd.vector("target.q", target.get("q", [1.0, 0.0, 0.0, 0.0]), 4)
    if abs(np.linalg.norm(qd) - 1.0) > UNIT_LENGTH_TOL:
        raise rd.fail(
            "target.q", f"must be a unit quaternion (|q| within {UNIT_LENGTH_TOL:g} of 1), |q| = {np.linalg.norm(qd)!r}"
        )
    return qd


def attitude_inputs() -> list[CVar]:
    """The plant's attitude q (body -> world, starting at the identity) and body rate ω (rad/s, body frame)."""
    what = "attitude of the plant (body -> world), component"
    inputs = [CVar(n, CKind.INPUT, 1.0 if n == "q[1]" else 0.0, None, f"{what} {n[2]}") for n in Q_NAMES]
    return inputs + [CVar(n, CKind.INPUT, 0.0, "rad/s", "angular velocity of the plant, body frame") for n in W_NAMES]


def target_parameters(qd: np.ndarray) -> list[CVar]:
    """q_d[1..4], the target attitude, tunable."""
    return [
        CVar(n, CKind.PARAM_TUNABLE, float(qd[i]), None, "target attitude (body -> world), scalar first")
        for i, n in enumerate(QD_NAMES)
    ]


def error_quaternion(P: Callable[[str], ca.SX], q: ca.SX) -> tuple[ca.SX, ca.SX]:
    """(q_e = q_d* ⊗ q with q_d normalised, sgn(q_e0)) for the parameter accessor P and the attitude q."""
    q_d = ca.vertcat(*[P(n) for n in QD_NAMES])
    q_d = q_d / ca.norm_2(q_d)
    qe = quat_mul(ca.vertcat(q_d[0], -q_d[1:4]), q)
    return qe, ca.if_else(qe[0] >= 0, 1.0, -1.0)  # the shorter way round


def target_check(P: Callable[[str], ca.SX]) -> tuple[ca.SX, str]:
    """The check a tunable q_d must pass (|q_d| within UNIT_LENGTH_TOL of 1) and its text."""
    nq = ca.norm_2(ca.vertcat(*[P(n) for n in QD_NAMES]))
    return ca.fabs(nq - 1) <= UNIT_LENGTH_TOL, f"| |q_d| - 1 | <= {UNIT_LENGTH_TOL:g}"
