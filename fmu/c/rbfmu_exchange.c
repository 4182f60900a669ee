/* Model Exchange in the FMU core: time, states, derivatives, nominals, directional derivatives.
 * The directional and adjoint derivatives come from the generated Jacobian (docs/fmi_layer.md). */
#include "rbfmu_core.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

RbStatus rb_set_time(Instance *c, const char *fn, double t) {
    if (!isfinite(t)) {
        RB_ERR(c, "%s: time must be finite, got %g", fn, t);
        return RB_ERROR;
    }
    c->persistent.buf[0] = t;
    return RB_OK;
}

/* The array of continuous states (or derivatives, nominals) has RB_NX elements and is given. */
static bool nx_array_given(const Instance *c, const char *fn, size_t n, const void *array) {
    if (n != RB_NX) {
        RB_ERR(c, "%s: this FMU has %d continuous states, got %zu", fn, RB_NX, n);
        return false;
    }
    return rb_arrays_given(c, fn, n, array, "the array", NULL, NULL);
}

RbStatus rb_set_states(Instance *c, const char *fn, const double x[], size_t n) {
    size_t i;
    if (!nx_array_given(c, fn, n, x)) return RB_ERROR;
    for (i = 0; i < n; i++) {
        if (!isfinite(x[i])) {
            RB_ERR(c, "%s: state '%s' must be finite, got %g", fn, rb_names[RB_OFF_X + i], x[i]);
            return RB_ERROR;
        }
    }
    /* the outputs use the projected state (q/|q|, docs/fmi_layer.md): it must exist and be
     * a unit quaternion, so projecting it once more stays finite (a norm of 0 gives NaN at
     * once; one that overflows gives q/|q| = 0, and NaN the second time) */
    rb_project(c, x, c->step.x_next);
    rb_project(c, c->step.x_next, c->step.x_start);
    for (i = 0; i < n; i++) {
        if (!isfinite(c->step.x_start[i])) {
            RB_ERR(c, "%s: state '%s' = %g has no finite projection: the orientation quaternion must have a "
                      "nonzero, finite norm", fn, rb_names[RB_OFF_X + i], x[i]);
            return RB_ERROR;
        }
    }
    /* the rule of docs/robustness.md (Values entering and leaving the FMU); Discard: FMI 3.0
     * §3.2.4 asks the importer's solver to try a smaller step at a state outside the domain */
    if (!rb_state_enters(c, fn, c->step.x_next)) return RB_DISCARD;
    memcpy(c->persistent.buf + RB_OFF_X, x, n * sizeof(double));
    return RB_OK;
}

RbStatus rb_get_states(Instance *c, const char *fn, double x[], size_t n) {
    if (!nx_array_given(c, fn, n, x)) return RB_ERROR;
    memcpy(x, c->persistent.buf + RB_OFF_X, n * sizeof(double));
    return RB_OK;
}

RbStatus rb_get_derivatives(Instance *c, const char *fn, double dx[], size_t n) {
    size_t i;
    if (!nx_array_given(c, fn, n, dx)) return RB_ERROR;
    rb_compute_derivatives(c, dx);
    for (i = 0; i < n; i++)
        if (!isfinite(dx[i])) return rb_refuse_non_finite(c, fn, (unsigned)(RB_OFF_DX + i), dx[i]);
    return RB_OK;
}

RbStatus rb_get_nominals(Instance *c, const char *fn, double nominals[], size_t n) {
    size_t i;
    if (!nx_array_given(c, fn, n, nominals)) return RB_ERROR;
    for (i = 0; i < n; i++) nominals[i] = rb_nominal[i]; /* modelsrc/nominals.py, the modelDescription's too */
    return RB_OK;
}

/* ---- directional and adjoint derivatives (the generated Jacobian, docs/fmi_layer.md) ---- */

static int jac_row(unsigned vr) {
    if (vr >= RB_OFF_X && vr < RB_OFF_X + RB_NX) return (int)(vr - RB_OFF_X);
    if (vr >= RB_OFF_DX && vr < RB_OFF_DX + RB_NX) return RB_NX + (int)(vr - RB_OFF_DX);
    if (vr >= RB_OFF_Y && vr < RB_OFF_Y + RB_NY) return 2 * RB_NX + (int)(vr - RB_OFF_Y);
    return -1;
}

static int jac_col(unsigned vr) {
    if (vr >= RB_OFF_X && vr < RB_OFF_X + RB_NX) return (int)(vr - RB_OFF_X);
    if (vr >= RB_OFF_U && vr < RB_OFF_U + RB_NU) return RB_NX + (int)(vr - RB_OFF_U);
    return -1;
}

/* model_jac at the instance's x, u, p and method, computed once per point: a linearisation
 * asks for one column per call, nz + nu calls at one point, and one dense Jacobian costs more
 * than two evaluations of the model (fmu/linear/bench.py). The key is the values themselves,
 * compared whole, so that whatever changes them (SetFloat64, SetContinuousStates,
 * SetFMUState, doStep, reset) leads to a new evaluation; d follows from p and the method. */
static const double *jacobian_at_point(Instance *c) {
    const double *at = c->persistent.buf + RB_OFF_X;
    if (!c->work.jac_valid || c->work.jac_method != c->persistent.method ||
        memcmp(c->work.jac_at, at, sizeof c->work.jac_at) != 0) {
        RB_BIND_MODEL(c, model_jac, c->persistent.buf + RB_OFF_X);
        RB_RES(c, model_jac, J) = c->work.jac;
        RB_CALL(c, model_jac);
        memcpy(c->work.jac_at, at, sizeof c->work.jac_at);
        c->work.jac_method = c->persistent.method;
        c->work.jac_valid = true;
    }
    return c->work.jac;
}

RbStatus rb_directional(Instance *c, const char *fn, const unsigned unknowns[], size_t n_unknowns,
                        const unsigned knowns[], size_t n_knowns, const double seed[], size_t n_seed,
                        double sensitivity[], size_t n_sensitivity, bool adjoint) {
    size_t i, j;
    const double *jac;
    if (n_seed != (adjoint ? n_unknowns : n_knowns) || n_sensitivity != (adjoint ? n_knowns : n_unknowns)) {
        RB_ERR(c, "%s: seed and sensitivity sizes (%zu, %zu) do not match the %zu unknowns and %zu knowns", fn,
               n_seed, n_sensitivity, n_unknowns, n_knowns);
        return RB_ERROR;
    }
    if (!rb_arrays_given(c, fn, n_unknowns, unknowns, "unknowns", adjoint ? seed : sensitivity,
                         adjoint ? "seed" : "sensitivity") ||
        !rb_arrays_given(c, fn, n_knowns, knowns, "knowns", adjoint ? sensitivity : seed,
                         adjoint ? "sensitivity" : "seed"))
        return RB_ERROR;
    for (i = 0; i < n_unknowns; i++) {
        if (unknowns[i] >= RB_NV || jac_row(unknowns[i]) < 0) {
            RB_ERR(c, "%s: value reference %u is not a state, state derivative or output", fn, unknowns[i]);
            return RB_ERROR;
        }
    }
    for (j = 0; j < n_knowns; j++) {
        if (knowns[j] >= RB_NV || jac_col(knowns[j]) < 0) {
            RB_ERR(c, "%s: value reference %u is not a state or input", fn, knowns[j]);
            return RB_ERROR;
        }
    }
    for (i = 0; i < n_seed; i++) { /* a seed of inf or NaN would make every sensitivity non-finite */
        if (!isfinite(seed[i])) {
            RB_ERR(c, "%s: seed[%zu] (of '%s') must be finite, got %g", fn, i,
                   rb_names[adjoint ? unknowns[i] : knowns[i]], seed[i]);
            return RB_ERROR;
        }
    }
    jac = jacobian_at_point(c);
    for (i = 0; i < n_sensitivity; i++) sensitivity[i] = 0.0;
    /* J·seed (or Jᵀ·seed) over the seed's nonzero entries only: a column of J asks for one.
     * A zero entry would add ±0, which leaves a finite sum as it is (only 0 × a non-finite
     * entry, NaN in the dense product, is left out); each sum takes its terms in the order
     * of the seed, as the dense product did, so finite results are bit-identical */
    if (adjoint) {
        for (i = 0; i < n_unknowns; i++) {
            const double *row = jac + jac_row(unknowns[i]);
            if (seed[i] == 0.0) continue;
            for (j = 0; j < n_knowns; j++)
                sensitivity[j] += row[(size_t)RB_NJ_ROWS * (size_t)jac_col(knowns[j])] * seed[i];
        }
    } else {
        for (j = 0; j < n_knowns; j++) {
            const double *col = jac + (size_t)RB_NJ_ROWS * (size_t)jac_col(knowns[j]);
            if (seed[j] == 0.0) continue;
            for (i = 0; i < n_unknowns; i++) sensitivity[i] += col[jac_row(unknowns[i])] * seed[j];
        }
    }
    /* the rule of docs/robustness.md (Values entering and leaving the FMU): the Jacobian of a
     * state at which the equations overflow (set in InitializationMode, or kept in Error) */
    for (i = 0; i < n_sensitivity; i++)
        if (!isfinite(sensitivity[i]))
            return rb_refuse_non_finite_named(c, fn, adjoint ? "adjoint derivative for" : "directional derivative of",
                                              rb_names[adjoint ? knowns[i] : unknowns[i]], sensitivity[i]);
    return RB_OK;
}
