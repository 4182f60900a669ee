"""One evaluation per distinct subexpression in a generated function (CasADi's cse).

A model's expressions are built feature by feature, and the same term is often built more than
once: R(q) for each rotated vector, sin θ in the right-hand side and again in its Jacobian
(∂ sin θ/∂θ = cos θ beside the cos θ of the nadir), the stages' h/2. CasADi's SX graph keeps
every node it was given, so the generated C evaluates each copy. `ca.cse` merges the nodes
that apply the same operation to the same operands: the same numbers, evaluated once
(a libm sin or sincos is ~140 instructions; measured on the shipped scenes, model_rate_rhs
loses 10-20 % of its operations, model_jac 5-20 %).
"""

from __future__ import annotations

import casadi as ca


def merged_outputs(outs: list) -> list:
    """The SX expressions `outs` with their repeated subexpressions merged across all of them,
    each reshaped as it was."""
    outs = [ca.SX(o) for o in outs]
    merged = ca.cse(ca.vertcat(*[ca.vec(o) for o in outs]))
    parts, k = [], 0
    for o in outs:
        parts.append(ca.reshape(merged[k : k + o.numel()], o.shape[0], o.shape[1]))
        k += o.numel()
    return parts


def merged(f: ca.Function) -> ca.Function:
    """f (an SX Function) with its repeated subexpressions merged (`merged_outputs`): the same
    name, arguments and values, fewer operations. Other Functions are returned as they are."""
    if not f.is_a("SXFunction"):
        return f
    args = f.sx_in()
    return ca.Function(f.name(), args, merged_outputs(f.call(args)), f.name_in(), f.name_out())
