"""linearize's lean path (the plan's buffers, one product, LinearModel.made_with) gives the plain formulas' bits.

The reference is written as docs/theory.md §10.1-10.2 states it: the chart from
fmu.linear.attitude.chart (its own code, chart_values), J·T from the FMU's directional
derivatives seeded with T, then A_z = S (A_x T) + turning, B_z = S B_x, C_z = C_x T and
ż₀ = S ẋ₀ − ω₀, S applied to [A_x T, ẋ₀, B_x] in one numpy product and the turning and
ω₀ added and subtracted apart. Every scene, at its start point and at a moved
one, in both coordinates and both frames: A, B, C, D, drift and nominals byte for byte.
"""

from __future__ import annotations

import numpy as np
import pytest

from fmu.linear.attitude import ATTITUDE, chart
from fmu.linear.bench import moved_point
from fmu.linear.linearize import at_point, linearize
from fmu.linear.model_exchange import ModelExchange
from fmu.linear.operating_point import start_point
from modelsrc.scene import list_scenes


def reference(me: ModelExchange, point, coordinates: str, frame: str | None, outs: list[str]):
    x0 = point.x
    xdot = at_point(me, point)
    out_vrs = me.value_references(outs, me.outputs, "outputs")
    unknowns, knowns = me.derivative_vrs + out_vrs, me.state_vrs + me.value_references(me.inputs, me.inputs, "in")
    nx, nu = me.nx, len(me.inputs)
    if coordinates == "raw":
        J = me.jacobian(unknowns, knowns)
        return J[:nx, :nx], J[:nx, nx:], J[nx:, :nx], J[nx:, nx:], xdot, me.nominals
    ch = chart(me.states, x0, frame)
    nz = len(ch.states)
    seeds = np.zeros((nx + nu, nz + nu))
    seeds[:nx, :nz], seeds[nx:, nz:] = ch.T, np.eye(nu)
    J = me.jacobian(unknowns, knowns, seeds)
    AT, B = J[:nx, :nz], J[:nx, nz:]
    # S applied to A_x T, ẋ₀ and B_x in one product (a matrix-vector product S ẋ₀ of its own
    # would sum in another order and round otherwise, by an ulp of its terms)
    SJ = ch.S @ np.column_stack((AT, xdot, B))
    zdot = SJ[:, nz]
    if ch.states[:3] == ATTITUDE:
        zdot[:3] -= ch.w0
    nominals = np.array([1.0 if s in ATTITUDE else me.nominals[me.states.index(s)] for s in ch.states])
    return SJ[:, :nz] + ch.turning, SJ[:, nz + 1 :], J[nx:, :nz], J[nx:, nz:], zdot, nominals


def same_bytes(a: np.ndarray, b: np.ndarray) -> bool:
    a, b = np.ascontiguousarray(a), np.ascontiguousarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


@pytest.mark.parametrize("scene", list_scenes())
def test_linearize_bits_are_the_formulas(fmus, scene):
    fmu = fmus[scene]
    start = start_point(fmu)
    with ModelExchange(fmu) as me:
        outs = [o for o in me.outputs if not o.startswith("euler_zxz[")]
        for point in (start, moved_point(start, me.nominals)):
            for coordinates, frame in (("attitude", "rotating"), ("attitude", "fixed"), ("raw", None)):
                m = linearize(fmu, point, coordinates=coordinates, frame=frame, instance=me)
                got = (m.A, m.B, m.C, m.D, m.drift, m.nominals)
                want = reference(me, point, coordinates, frame, outs)
                for name, g, w in zip(("A", "B", "C", "D", "drift", "nominals"), got, want):
                    assert same_bytes(g, w), (scene, point.source, coordinates, frame, name, np.abs(g - w).max())
