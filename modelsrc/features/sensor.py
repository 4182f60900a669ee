"""A body-fixed sensor point as one feature: the parameter r_sensor and its position, velocity and acceleration.

The point r_sensor (m, body frame, from the point the body turns about) is output as
sensor_r, sensor_v, sensor_a (world frame): r, v = v_B + ω × r, a = a_B + ω̇ × r + ω × (ω × r)
with B the reference point (docs/theory.md §1.4, §7.2). `FEATURE` declares it
(modelsrc.feature).
"""

from __future__ import annotations

from typing import Any

import casadi as ca

from .. import rigid_body as rb
from ..assembly import Assembly
from ..feature import (
    Builder,
    Feature,
    FeatureDoc,
    Output,
    OutputContext,
    OutputValue,
    Phase,
    Reader,
    ReadStage,
    SceneRead,
)
from ..scene_data import SceneData
from ..variables import Kind, Variable, vector_names


def read_sensor(ctx: SceneRead) -> dict[str, Any]:
    """[sensor] point (3 numbers, m, body frame), when given."""
    sensor = ctx.rd.section("sensor")
    return {"sensor_point": ctx.rd.vector("sensor.point", sensor["point"], 3)} if "point" in sensor else {}


def check_sensor_output(ctx: SceneRead) -> dict[str, Any]:
    """The output 'sensor' needs [sensor] point."""
    if "sensor" in ctx.outputs and "sensor_point" not in ctx.fields:
        raise ctx.rd.fail("sensor.point", "required when outputs include 'sensor' (3 numbers, m, body frame)")
    return {}


def sensor_point(a: Assembly) -> ca.SX | None:
    """The sensor's record in the assembly: the symbol r_sensor, or None."""
    point: ca.SX | None = a.feature_states.get("sensor")
    return point


def add_sensor(a: Assembly) -> None:
    """The body-fixed sensor point r_sensor (m, body frame, from the rotation point)."""
    if "sensor" not in a.scene.outputs:
        return
    r_sensor = a.feature_states["sensor"] = ca.SX.sym("r_sensor", 3)
    a.parameter(
        r_sensor,
        vector_names("r_sensor", 3),
        a.scene.sensor_point,
        "m",
        [f"sensor point from the rotation point, body axis {i}" for i in (1, 2, 3)],
    )


def sensor_outputs(a: Assembly, ctx: OutputContext) -> dict[str, OutputValue]:
    """sensor_r, sensor_v, sensor_a (m, m/s, m/s², world) of the sensor point."""
    r_sensor = sensor_point(a)
    if r_sensor is None:
        return {}
    # a body point from the reference point B: r, v = v_B + ω × r,
    # a = a_B + ω̇ × r + ω × (ω × r) (docs/theory.md §1.4, §7.2); B fixed: v_B = a_B = 0
    R, w_world = a.rotation_matrix, ctx.omega_world
    r_world = R @ r_sensor
    moving = a.position is not None
    sensor = ca.vertcat(
        r_world if a.position is None else a.position + r_world,
        rb.point_velocity(w_world, r_world, a.velocity if moving else None),
        rb.point_acceleration(w_world, R @ ctx.omega_dot, r_world, a.acceleration if moving else None),
    )
    variables = tuple(
        Variable(name, Kind.OUTPUT, None, unit, f"{what} of the sensor point, world axis {i}")
        for base, unit, what in (("sensor_r", "m", "position"), ("sensor_v", "m/s", "velocity"),
                                 ("sensor_a", "m/s2", "acceleration"))
        for i, name in enumerate(vector_names(base, 3), 1)
    )  # fmt: skip
    return {"sensor": OutputValue(sensor, None, "", variables)}


def _doc(scene: SceneData) -> FeatureDoc | None:
    """The sensor point's position, velocity and acceleration (§1.4, §7.2)."""
    if "sensor" not in scene.outputs:
        return None
    eq = ("sensor_r = x_B + R r,  v = v_B + ω × r,  a = a_B + ω̇ × r + ω × (ω × r)  (world)", "§1.4, §7.2 (MIT 2.003J)")
    return FeatureDoc("a body-fixed sensor point", (eq,))


FEATURE = Feature(
    name="sensor",
    doc=_doc,
    order=90,
    tables={"sensor": frozenset({"point"})},
    readers=(Reader(ReadStage.INPUTS, 20, read_sensor), Reader(ReadStage.OUTPUTS, 10, check_sensor_output)),
    builders=(Builder(Phase.PARAMETERS, 70, add_sensor),),
    outputs=(Output("sensor", 10, in_default=lambda fields: "sensor_point" in fields),),
    requested=sensor_outputs,
)
