/* Inputs that vary inside a communication step, and the outputs' time derivatives, in the FMU core.
 *
 * A generated step reads its inputs at the method's nodes t + c_k h (c->inputs.U, one column per
 * node, modelsrc/integrators.stage_nodes). Over a doStep they are, in this order of
 * preference (docs/fmi_layer.md, Inputs inside a step):
 *   RB_ASK  - FMI 3.0 intermediate update: the importer is asked at every node time (the
 *             API file's callback, IntermediateUpdateMode) and may set the inputs there;
 *   RB_POLY - FMI 2.0 input derivatives: u(t0 + s) = u + u' s + u'' s^2/2 + u''' s^3/6
 *             with the derivatives set before the doStep (fmi2SetRealInputDerivatives);
 *   RB_HELD - held at the values set before the doStep (zero-order hold).
 * A node shared by two steps (the end of one, the start of the next) is asked once. After
 * the doStep the inputs hold their values at its end (the polynomial's, or the last value
 * the importer set), so that the outputs there use them, and input derivatives are cleared:
 * they belong to the doStep they were set for. */
#include "rbfmu_core.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static double *node(Instance *c, int k) { return c->inputs.U + (size_t)k * RB_NU; }

/* The input polynomial at s seconds into the doStep (RB_POLY), written to u. */
static void poly_at(const Instance *c, double s, double *u) {
    int i, j;
    for (i = 0; i < RB_NU; i++) {
        double v = 0.0, term = 1.0;
        for (j = 0; j < RB_MAX_INPUT_ORDER; j++) {
            term *= s / (double)(j + 1);
            v += c->inputs.du[j][i] * term;
        }
        u[i] = c->inputs.u_start[i] + v;
    }
}

void rb_inputs_begin(Instance *c, bool controlled) {
    RbInputs *in = &c->inputs;
    int k, method = c->persistent.method;
    /* fixed steps skip the nodes only an estimate reads (rb_fixed_node_read) */
    in->node_read = controlled ? NULL : rb_fixed_node_read[method];
    memcpy(in->u_start, c->persistent.buf + RB_OFF_U, sizeof(double) * RB_NU);
    in->mode = (c->importer.ask && RB_NU > 0) ? RB_ASK : (in->du_set ? RB_POLY : RB_HELD);
    for (k = 0; k < rb_method_nnodes[method]; k++) memcpy(node(c, k), in->u_start, sizeof(double) * RB_NU);
}

void rb_inputs_nodes(Instance *c, double t0, double tau, double h) {
    const RbInputs *in = &c->inputs;
    int k, nn = rb_method_nnodes[c->persistent.method];
    const double *cs = rb_method_nodes[c->persistent.method];
    for (k = 1; k < nn; k++) { /* node 0 is the start of the step: set already */
        if (in->node_read && !in->node_read[k]) continue;
        if (in->mode == RB_POLY) {
            poly_at(c, tau + cs[k] * h, node(c, k));
        } else {
            c->importer.ask(c, t0 + tau + cs[k] * h);
            memcpy(node(c, k), c->persistent.buf + RB_OFF_U, sizeof(double) * RB_NU);
        }
    }
}

void rb_inputs_shift(Instance *c) {
    memcpy(node(c, 0), node(c, rb_method_nnodes[c->persistent.method] - 1), sizeof(double) * RB_NU);
}

void rb_inputs_restart(Instance *c) {
    if (c->inputs.mode != RB_HELD) memcpy(node(c, 0), c->inputs.u_start, sizeof(double) * RB_NU);
}

void rb_inputs_end(Instance *c, double H, bool ok) {
    RbInputs *in = &c->inputs;
    double *u = c->persistent.buf + RB_OFF_U;
    if (!ok) {
        memcpy(u, in->u_start, sizeof(double) * RB_NU);
    } else if (in->mode == RB_POLY) {
        poly_at(c, H, u);
    } else if (in->mode == RB_ASK) {
        memcpy(u, node(c, 0), sizeof(double) * RB_NU);
    }
    if (ok && in->mode == RB_POLY) {
        memset(in->du, 0, sizeof in->du);
        in->du_set = false;
    }
}

/* ---- FMI 3.0 intermediate inputs, FMI 2.0 input derivatives, output derivatives ---- */

/* The one test of "is an input" for the calls that may only name inputs. */
static bool is_input(unsigned vr) { return vr >= RB_OFF_U && vr < RB_OFF_U + RB_NU; }

bool rb_inputs_only(const char *what, const unsigned vrs[], size_t n, char *why, size_t len) {
    size_t i;
    if (n > 0 && !vrs) {
        snprintf(why, len, "%s is NULL while its count is %zu", what, n);
        return false;
    }
    for (i = 0; i < n; i++) {
        if (!is_input(vrs[i])) {
            snprintf(why, len, "%s names value reference %u, which is not an input: only the inputs (value "
                     "references %d..%d) can be set inside a doStep", what, vrs[i], RB_OFF_U, RB_OFF_U + RB_NU - 1);
            return false;
        }
    }
    return true;
}

/* The checks the input and output derivative calls share: a Co-Simulation instance, and
 * the arrays present for their count. `what`: "input" or "output". */
static bool derivative_call_ok(Instance *c, const char *fn, const char *what, size_t n, const unsigned vr[],
                               const int order[], const double *v) {
    if (c->importer.type != RB_CO_SIMULATION) {
        RB_ERR(c, "%s: %s derivatives are a Co-Simulation call; this is a Model Exchange instance", fn, what);
        return false;
    }
    return rb_arrays_given(c, fn, n, vr, "the value reference array", v, "the value array") &&
           rb_arrays_given(c, fn, n, order, "the order array", NULL, NULL);
}

RbStatus rb_set_input_derivatives(Instance *c, const char *fn, const unsigned vr[], size_t n, const int order[],
                             const double v[]) {
    size_t i;
    if (!derivative_call_ok(c, fn, "input", n, vr, order, v)) return RB_ERROR;
    for (i = 0; i < n; i++) { /* all-or-nothing */
        if (!is_input(vr[i])) {
            RB_ERR(c, "%s: value reference %u is not an input (inputs: %d..%d)", fn, vr[i], RB_OFF_U,
                   RB_OFF_U + RB_NU - 1);
            return RB_ERROR;
        }
        if (order[i] < 1 || order[i] > RB_MAX_INPUT_ORDER) {
            RB_ERR(c, "%s: derivative order %d of '%s' is not 1..%d", fn, order[i], rb_names[vr[i]],
                   RB_MAX_INPUT_ORDER);
            return RB_ERROR;
        }
        if (!isfinite(v[i])) {
            RB_ERR(c, "%s: derivative %d of '%s' must be finite, got %g", fn, order[i], rb_names[vr[i]], v[i]);
            return RB_ERROR;
        }
    }
    for (i = 0; i < n; i++) {
        c->inputs.du[order[i] - 1][vr[i] - RB_OFF_U] = v[i];
        if (v[i] != 0.0) c->inputs.du_set = true;
    }
    return RB_OK;
}

/* z = (states, outputs): the index of a value reference in model_output_rates' outputs, or -1. */
static int rate_row(unsigned vr) {
    if (vr >= RB_OFF_X && vr < RB_OFF_X + RB_NX) return (int)(vr - RB_OFF_X);
    if (vr >= RB_OFF_Y && vr < RB_OFF_Y + RB_NY) return RB_NX + (int)(vr - RB_OFF_Y);
    return -1;
}

RbStatus rb_output_derivatives(Instance *c, const char *fn, const unsigned vr[], size_t n, const int order[],
                          double v[]) {
    size_t i;
    if (!derivative_call_ok(c, fn, "output", n, vr, order, v)) return RB_ERROR;
    for (i = 0; i < n; i++) {
        if (vr[i] >= RB_NV || rate_row(vr[i]) < 0) {
            RB_ERR(c, "%s: value reference %u is not an output (a state or a calculated output)", fn, vr[i]);
            return RB_ERROR;
        }
        if (order[i] < 1 || order[i] > RB_MAX_OUTPUT_ORDER) {
            RB_ERR(c, "%s: derivative order %d of '%s' is not 1..%d (maxOutputDerivativeOrder)", fn, order[i],
                   rb_names[vr[i]], RB_MAX_OUTPUT_ORDER);
            return RB_ERROR;
        }
    }
    /* d/dt and d2/dt2 of every output at the current state, with the inputs' derivatives
     * as set (zero when the inputs are held) */
    RB_BIND_MODEL(c, model_output_rates, c->persistent.buf + RB_OFF_X);
    RB_ARG(c, model_output_rates, u1) = c->inputs.du[0];
    RB_ARG(c, model_output_rates, u2) = c->inputs.du[1];
    RB_RES(c, model_output_rates, z1) = c->work.z1;
    RB_RES(c, model_output_rates, z2) = c->work.z2;
    RB_CALL(c, model_output_rates);
    for (i = 0; i < n; i++) v[i] = (order[i] == 1 ? c->work.z1 : c->work.z2)[rate_row(vr[i])];
    for (i = 0; i < n; i++) /* the rule of docs/robustness.md (Values entering and leaving the FMU) */
        if (!isfinite(v[i]))
            return rb_refuse_non_finite_named(c, fn, order[i] == 1 ? "first derivative of" : "second derivative of",
                                              rb_names[vr[i]], v[i]);
    return RB_OK;
}
