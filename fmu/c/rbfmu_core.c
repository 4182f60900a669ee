/* Version-independent core of the FMU: the instance, variable access, validity checks, initialisation.
 * See rbfmu_core.h and docs/fmi_layer.md; the lowest layer (rbfmu_core.h, Layers): it calls
 * only the generated functions. The step, Model Exchange and FMU state are in
 * rbfmu_dostep.c, rbfmu_exchange.c and rbfmu_snapshot.c. */
#include "rbfmu_core.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *const rb_state_names[] = {"Instantiated", "InitializationMode", "StepMode", "EventMode",
                                      "ContinuousTimeMode", "Terminated", "Error", "IntermediateUpdateMode"};

void rb_logf(const Instance *c, RbStatus status, const char *fmt, ...) {
    char msg[1024];
    va_list ap;
    if (!c || !c->importer.log) return;
    if (!c->importer.logging_on && status == RB_OK) return;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    c->importer.log(c, status,
                    status == RB_OK ? "logAll" : (status == RB_WARNING ? "logStatusWarning" : "logStatusError"), msg);
}

bool rb_allowed(const Instance *c, const char *fn, unsigned mask) {
    if (!c) return false;
    if (mask & (1u << c->persistent.state)) return true;
    RB_ERR(c, "%s: not allowed in state %s", fn, rb_state_names[c->persistent.state]);
    return false;
}

bool rb_arrays_given(const Instance *c, const char *fn, size_t n, const void *a, const char *a_name, const void *b,
                     const char *b_name) {
    const char *null = n == 0 ? NULL : !a ? a_name : (b_name && !b) ? b_name : NULL;
    if (!null) return true;
    RB_ERR(c, "%s: %s is NULL while the call's count is %zu", fn, null, n);
    return false;
}

RbStatus rb_put_count(const Instance *c, const char *fn, size_t *out, size_t value) {
    if (!out) {
        RB_ERR(c, "%s: the pointer for the result is NULL", fn);
        return RB_ERROR;
    }
    *out = value;
    return RB_OK;
}

/* ---- calls into the generated functions (by their arguments' names, rbfmu_core.h) ---- */

void rb_compute_outputs(Instance *c) {
    if (RB_NY == 0) return;
    RB_BIND_MODEL(c, model_outputs, c->persistent.buf + RB_OFF_X);
    RB_RES(c, model_outputs, y) = c->persistent.buf + RB_OFF_Y;
    RB_CALL(c, model_outputs);
}

void rb_compute_derivatives(Instance *c, double *dx) {
    RB_BIND_MODEL(c, model_rhs, c->persistent.buf + RB_OFF_X);
    RB_RES(c, model_rhs, xdot) = dx;
    RB_CALL(c, model_rhs);
}

/* What depends on the parameters only (inertia about the rotation point and its inverse,
 * m g, 1/m, the splitting's axis order) is computed here, once per parameter change, not in
 * every right-hand side (docs/theory.md §6). */
void rb_refresh_derived(Instance *c) {
    bool principal;
    RB_ARG(c, model_derived, p) = c->persistent.buf + RB_OFF_P;
    RB_RES(c, model_derived, d) = c->derived.d;
    RB_CALL(c, model_derived);
    /* an inertia about the rotation point that is diagonal as set takes the steps without
     * its off-diagonal products, where the model has them (model_functions.principal_steps) */
    principal = rb_principal(c->derived.d);
    c->derived.step_fns = principal ? rb_principal_step_fns : rb_step_fns;
    c->derived.fixed_step_fns = principal ? rb_principal_fixed_step_fns : rb_fixed_step_fns;
    c->derived.e_h = NAN; /* the fixed step's constants depend on p: computed again at the next step */
}

bool rb_principal(const double *d) {
    int k;
    for (k = 0; k < RB_NOFFDIAG; k++)
        if (d[rb_off_diagonal[k]] != 0.0) return false;
    return true;
}

void rb_project(Instance *c, const double *x, double *out) {
    RB_ARG(c, model_project, x) = x;
    RB_RES(c, model_project, x_projected) = out;
    RB_CALL(c, model_project);
}

static void project_state(Instance *c) {
    rb_project(c, c->persistent.buf + RB_OFF_X, c->step.x_next);
    memcpy(c->persistent.buf + RB_OFF_X, c->step.x_next, sizeof c->step.x_next);
}

/* Logs the values of all parameters p and states x (prefixed `when`): what a refusal of
 * them names. */
static void log_values(const Instance *c, const char *when, const double *x, const double *p) {
    char line[1024];
    size_t len = 0;
    int i;
    line[0] = '\0';
    for (i = 0; i < RB_NP && len < sizeof line - 64; i++)
        len += (size_t)snprintf(line + len, sizeof line - len, "%s=%.17g ", rb_names[RB_OFF_P + i], p[i]);
    RB_ERR(c, "%s: parameter values: %s", when, line);
    len = 0;
    line[0] = '\0';
    for (i = 0; i < RB_NX && len < sizeof line - 64; i++)
        len += (size_t)snprintf(line + len, sizeof line - len, "%s=%.17g ", rb_names[RB_OFF_X + i], x[i]);
    RB_ERR(c, "%s: state values: %s", when, line);
}

/* Evaluates the generated validity checks; logs each violation with the values of all
 * parameters and states. */
bool rb_checks_pass(Instance *c, const char *when, const double *x, const double *p, double method_value) {
    int k, bad = 0;
    const double *g = c->work.g;
    RB_ARG(c, model_checks, x) = x;
    RB_ARG(c, model_checks, p) = p;
    RB_ARG(c, model_checks, method) = &method_value;
    RB_RES(c, model_checks, g) = c->work.g;
    RB_CALL(c, model_checks);
    for (k = 0; k < RB_NC; k++) {
        bool ok = rb_check_strict[k] ? (g[k] > 0) : (g[k] >= 0);
        if (!ok) {
            RB_ERR(c, "%s: %s (check value %.17g)", when, rb_check_text[k], g[k]);
            bad++;
        }
    }
    if (bad) log_values(c, when, x, p);
    return bad == 0;
}

/* The checks of the instance's own state, parameters and method. */
static bool checks_pass(Instance *c, const char *when) {
    return rb_checks_pass(c, when, c->persistent.buf + RB_OFF_X, c->persistent.buf + RB_OFF_P,
                          c->derived.method_value);
}

static int method_index(long long value) {
    int i;
    for (i = 0; i < RB_NMETHODS; i++)
        if (rb_method_values[i] == value) return i;
    return -1;
}

void rb_select_method(Instance *c, int index) {
    c->persistent.method = index;
    c->derived.method_value = (double)rb_method_values[index];
}

/* ---- creation and destruction ---- */

Instance *rb_instantiate(const char *fn, const char *name, const char *token, InterfaceType type, bool logging_on,
                         rb_logger log, const void *env, const void *callbacks) {
    Instance tmp, *c;
    memset(&tmp, 0, sizeof tmp);
    tmp.importer.log = log;
    tmp.importer.env = env;
    tmp.importer.callbacks = callbacks;
    tmp.importer.name = (char *)(name ? name : "");
    if (!name || !name[0]) {
        RB_ERR(&tmp, "%s: instanceName must be a non-empty string", fn);
        return NULL;
    }
    if (!token || strcmp(token, RB_INSTANTIATION_TOKEN) != 0) {
        RB_ERR(&tmp, "%s: instantiation token / GUID '%s' does not match this FMU's '%s' "
                     "(modelDescription.xml and binary are from different builds)",
               fn, token ? token : "(null)", RB_INSTANTIATION_TOKEN);
        return NULL;
    }
    c = (Instance *)calloc(1, sizeof(Instance));
    if (!c) return NULL;
    c->importer.name = (char *)malloc(strlen(name) + 1);
    if (!c->importer.name) {
        free(c);
        return NULL;
    }
    strcpy(c->importer.name, name);
    c->importer.type = type;
    c->importer.log = log;
    c->importer.env = env;
    c->importer.callbacks = callbacks;
    c->importer.logging_on = logging_on;
    rb_reset(c);
    return c;
}

void rb_free(Instance *c) {
    if (!c) return;
    free(c->importer.name);
    free(c);
}

void rb_reset(Instance *c) {
    memcpy(c->persistent.buf, rb_start, sizeof c->persistent.buf);
    rb_select_method(c, method_index(RB_DEFAULT_METHOD));
    memset(c->inputs.du, 0, sizeof c->inputs.du);
    c->inputs.du_set = false;
    c->importer.tolerance_set = false;
    c->importer.tolerance_defined = false;
    c->importer.tolerance = 0.0;
    c->importer.tolerance_logged = 0.0;
    rb_refresh_derived(c);
    c->persistent.state = ST_INSTANTIATED;
}

/* ---- variable access ---- */

/* Which instance states let an importer set a variable of each kind (the kinds are RB_KIND_*
 * of model_data.h, the masks the state bits M_* of rbfmu_core.h): the one table of these
 * rules; docs/fmi_layer.md §3 is generated from it (fmu/fmi_rules.py). Tunable parameters
 * and the method change in Model Exchange only at events, where FMI allows it. */
static const unsigned rb_set_mask[] = {
    [RB_KIND_INDEPENDENT] = 0,
    [RB_KIND_STATE] = M_INST | M_INIT,
    [RB_KIND_INPUT] = M_INST | M_INIT | M_STEP | M_EVENT | M_CONT | M_IUM,
    [RB_KIND_PARAM_FIXED] = M_INST | M_INIT,
    [RB_KIND_PARAM_TUNABLE] = M_INST | M_INIT | M_STEP | M_EVENT,
    [RB_KIND_OUTPUT] = 0,
    [RB_KIND_DERIVATIVE] = 0,
    [RB_KIND_LOCAL] = 0,
};

static bool settable(const Instance *c, unsigned char kind) {
    return kind < sizeof rb_set_mask / sizeof rb_set_mask[0] && (rb_set_mask[kind] & (1u << c->persistent.state)) != 0;
}

static const char *kind_text(unsigned char kind) {
    switch (kind) {
    case RB_KIND_INDEPENDENT: return "the independent variable";
    case RB_KIND_OUTPUT: return "a calculated output";
    case RB_KIND_DERIVATIVE: return "a state derivative";
    case RB_KIND_PARAM_FIXED: return "a fixed parameter (set it before or during initialisation)";
    case RB_KIND_STATE: return "a state (its start value is set before or during initialisation)";
    case RB_KIND_LOCAL: return "the step report, which doStep writes";
    default: return "not settable now";
    }
}

RbStatus rb_set_reals(Instance *c, const char *fn, const unsigned vr[], size_t n, const double v[]) {
    size_t i;
    bool tunable_changed = false, param_changed = false;
    double *buf = c->persistent.buf, old[RB_NV];
    if (!rb_arrays_given(c, fn, n, vr, "the value reference array", v, "the value array")) return RB_ERROR;
    for (i = 0; i < n; i++) { /* validate everything before changing anything */
        if (vr[i] >= RB_NV) {
            RB_ERR(c, "%s: unknown value reference %u (valid: 0..%d)", fn, vr[i], RB_NV - 1);
            return RB_ERROR;
        }
        if (!settable(c, rb_kind[vr[i]])) {
            RB_ERR(c, "%s: variable '%s' (vr %u) cannot be set in state %s: it is %s", fn, rb_names[vr[i]], vr[i],
                   rb_state_names[c->persistent.state], kind_text(rb_kind[vr[i]]));
            return RB_ERROR;
        }
        if (!isfinite(v[i])) {
            RB_ERR(c, "%s: variable '%s' (vr %u) must be finite, got %g", fn, rb_names[vr[i]], vr[i], v[i]);
            return RB_ERROR;
        }
    }
    memcpy(old, buf, sizeof old);
    for (i = 0; i < n; i++) {
        if (vr[i] == RB_VR_TOLERANCE && v[i] != buf[vr[i]]) /* a new tolerance: no floor found for it yet */
            buf[RB_OFF_L + RB_REPORT_TOL_FLOOR] = 0.0, c->importer.tolerance_logged = 0.0;
        buf[vr[i]] = v[i];
        if (rb_kind[vr[i]] == RB_KIND_PARAM_TUNABLE) tunable_changed = true;
        if (rb_kind[vr[i]] == RB_KIND_PARAM_TUNABLE || rb_kind[vr[i]] == RB_KIND_PARAM_FIXED) param_changed = true;
        if (vr[i] == RB_VR_TOLERANCE) c->importer.tolerance_set = true; /* it wins (rb_exit_initialization) */
    }
    if ((c->persistent.state == ST_STEP || c->persistent.state == ST_EVENT) && tunable_changed &&
        !checks_pass(c, fn)) {
        memcpy(buf, old, sizeof old); /* refuse the change, keep the instance usable */
        return RB_ERROR;
    }
    if (param_changed) rb_refresh_derived(c);
    return RB_OK;
}

RbStatus rb_get_reals(Instance *c, const char *fn, const unsigned vr[], size_t n, double v[]) {
    size_t i;
    bool need_y = false, need_dx = false;
    if (!rb_arrays_given(c, fn, n, vr, "the value reference array", v, "the value array")) return RB_ERROR;
    for (i = 0; i < n; i++) {
        if (vr[i] >= RB_NV) {
            RB_ERR(c, "%s: unknown value reference %u (valid: 0..%d)", fn, vr[i], RB_NV - 1);
            return RB_ERROR;
        }
        need_y |= rb_kind[vr[i]] == RB_KIND_OUTPUT;
        need_dx |= rb_kind[vr[i]] == RB_KIND_DERIVATIVE;
    }
    /* outputs and derivatives always follow the current states, inputs and parameters */
    if (need_y) rb_compute_outputs(c);
    if (need_dx) rb_compute_derivatives(c, c->persistent.buf + RB_OFF_DX);
    for (i = 0; i < n; i++) v[i] = c->persistent.buf[vr[i]];
    for (i = 0; i < n; i++) /* the rule of docs/robustness.md (Values entering and leaving the FMU) */
        if (!isfinite(v[i])) return rb_refuse_non_finite(c, fn, (unsigned)vr[i], v[i]);
    return RB_OK;
}

RbStatus rb_refuse_non_finite(Instance *c, const char *fn, unsigned vr, double value) {
    return rb_refuse_non_finite_named(c, fn, rb_kind[vr] == RB_KIND_OUTPUT ? "output" : "state derivative",
                                      rb_names[vr], value);
}

RbStatus rb_refuse_non_finite_named(Instance *c, const char *fn, const char *what, const char *name, double value) {
    const double *buf = c->persistent.buf;
    RB_ERR(c, "%s: %s '%s' would be %g at t=%.17g in state %s: the parameters and states overflow the model's "
              "equations or leave their domain (keep them in the ranges of docs/user_guide.md §2.3)",
           fn, what, name, value, buf[0], rb_state_names[c->persistent.state]);
    log_values(c, fn, buf + RB_OFF_X, buf + RB_OFF_P);
    return RB_ERROR;
}

bool rb_state_enters(Instance *c, const char *fn, const double *x) {
    double saved[RB_NX];
    int i;
    bool ok = true;
    if (!rb_checks_pass(c, fn, x, c->persistent.buf + RB_OFF_P, c->derived.method_value)) return false;
    memcpy(saved, c->persistent.buf + RB_OFF_X, sizeof saved);
    memcpy(c->persistent.buf + RB_OFF_X, x, sizeof saved);
    rb_compute_derivatives(c, c->work.z1);
    for (i = 0; i < RB_NX && ok; i++)
        if (!isfinite(c->work.z1[i]))
            ok = rb_refuse_non_finite(c, fn, (unsigned)(RB_OFF_DX + i), c->work.z1[i]) == RB_OK;
    if (ok) {
        rb_compute_outputs(c);
        for (i = 0; i < RB_NY && ok; i++)
            if (!isfinite(c->persistent.buf[RB_OFF_Y + i]))
                ok = rb_refuse_non_finite(c, fn, (unsigned)(RB_OFF_Y + i), c->persistent.buf[RB_OFF_Y + i]) == RB_OK;
    }
    memcpy(c->persistent.buf + RB_OFF_X, saved, sizeof saved);
    if (!ok) rb_compute_outputs(c);
    return ok;
}

RbStatus rb_set_methods(Instance *c, const char *fn, const unsigned vr[], size_t n, const long long values[]) {
    size_t i;
    int old = c->persistent.method;
    if (!rb_arrays_given(c, fn, n, vr, "the value reference array", values, "the value array")) return RB_ERROR;
    for (i = 0; i < n; i++) { /* all-or-nothing: every entry must be valid before any takes effect */
        if (rb_set_method(c, fn, vr[i], values[i]) != RB_OK) {
            rb_select_method(c, old);
            return RB_ERROR;
        }
    }
    return RB_OK;
}

RbStatus rb_set_method(Instance *c, const char *fn, unsigned vr, long long value) {
    int idx, old;
    if (vr != RB_VR_METHOD) {
        RB_ERR(c, "%s: value reference %u is not an integer/enumeration variable (only %d: method)", fn, vr,
               RB_VR_METHOD);
        return RB_ERROR;
    }
    if (!settable(c, RB_KIND_PARAM_TUNABLE)) { /* the method is a tunable parameter */
        RB_ERR(c, "%s: 'method' cannot be set in state %s", fn, rb_state_names[c->persistent.state]);
        return RB_ERROR;
    }
    idx = method_index(value);
    if (idx < 0) {
        char allowed[256];
        size_t len = 0;
        int k;
        allowed[0] = '\0';
        for (k = 0; k < RB_NMETHODS && len < sizeof allowed - 40; k++)
            len += (size_t)snprintf(allowed + len, sizeof allowed - len, "%s%lld=%s", k ? ", " : "",
                                    rb_method_values[k], rb_method_names[k]);
        RB_ERR(c, "%s: method %lld is not compiled into this FMU; allowed: %s", fn, value, allowed);
        return RB_ERROR;
    }
    old = c->persistent.method;
    rb_select_method(c, idx);
    if ((c->persistent.state == ST_STEP || c->persistent.state == ST_EVENT) && !checks_pass(c, fn)) {
        rb_select_method(c, old); /* e.g. splitting without principal axes */
        return RB_ERROR;
    }
    if (idx != old) /* another estimate: the floor the last one showed does not hold for it */
        c->persistent.buf[RB_OFF_L + RB_REPORT_TOL_FLOOR] = 0.0, c->importer.tolerance_logged = 0.0;
    return RB_OK;
}

RbStatus rb_get_method(const Instance *c, const char *fn, unsigned vr, long long *value) {
    if (vr != RB_VR_METHOD) {
        RB_ERR(c, "%s: value reference %u is not an integer/enumeration variable (only %d: method)", fn, vr,
               RB_VR_METHOD);
        return RB_ERROR;
    }
    *value = rb_method_values[c->persistent.method];
    return RB_OK;
}

/* ---- initialisation ---- */

RbStatus rb_enter_initialization(Instance *c, const char *fn, double start_time, bool stop_defined,
                                 double stop_time) {
    if (!isfinite(start_time)) {
        RB_ERR(c, "%s: startTime must be finite, got %g", fn, start_time);
        return RB_ERROR;
    }
    if (stop_defined && !(stop_time >= start_time)) {
        RB_ERR(c, "%s: stopTime %.17g must be >= startTime %.17g", fn, stop_time, start_time);
        return RB_ERROR;
    }
    c->persistent.buf[0] = start_time;
    c->persistent.state = ST_INITIALIZATION;
    return RB_OK;
}

RbStatus rb_importer_tolerance(Instance *c, const char *fn, bool defined, double tolerance) {
    c->importer.tolerance_defined = false;
    if (!defined) return RB_OK;
    if (!(tolerance > 0) || !isfinite(tolerance)) { /* refused, not an error: the FMU keeps its own */
        rb_logf(c, RB_WARNING, "%s: the importer's tolerance %g is not applied: a tolerance must be finite and > 0; "
                "the FMU keeps tolerance = %g", fn, tolerance, c->persistent.buf[RB_VR_TOLERANCE]);
        return RB_WARNING;
    }
    c->importer.tolerance_defined = true;
    c->importer.tolerance = tolerance;
    return RB_OK;
}

/* The rule of docs/fmi_layer.md (Tolerance): in Co-Simulation the importer's tolerance sets
 * the parameter `tolerance` (the error control's, per second of simulated time), unless the
 * importer set that parameter itself or the FMU takes fixed steps (tolerance 0); in Model
 * Exchange it is the importer's own solver's. Every outcome is logged. */
static void apply_importer_tolerance(Instance *c, const char *fn) {
    double own = c->persistent.buf[RB_VR_TOLERANCE], tol = c->importer.tolerance;
    int method = c->persistent.method;
    if (!c->importer.tolerance_defined) return;
    if (c->importer.type == RB_MODEL_EXCHANGE)
        rb_logf(c, RB_OK, "%s: Model Exchange: the importer's tolerance %g is its own solver's; the parameter "
                "tolerance (%g) acts only in Co-Simulation", fn, tol, own);
    else if (c->importer.tolerance_set)
        rb_logf(c, RB_WARNING, "%s: the importer's tolerance %g is not applied: the parameter tolerance was set "
                "to %g, which wins", fn, tol, own);
    else if (!(own > 0))
        rb_logf(c, RB_WARNING, "%s: the importer's tolerance %g is not applied: this FMU takes fixed steps "
                "(tolerance = 0); set the parameter tolerance > 0 for error control", fn, tol);
    else {
        bool fixed = rb_method_estimate_order[method] == 0;
        c->persistent.buf[RB_VR_TOLERANCE] = tol;
        rb_logf(c, RB_OK, "%s: tolerance = %g from the importer (the FMU's default was %g)%s%s", fn, tol, own,
                fixed ? "; it acts once method is one with error control: now fixed steps under " : "",
                fixed ? rb_method_names[method] : "");
    }
}

RbStatus rb_exit_initialization(Instance *c, const char *fn) {
    apply_importer_tolerance(c, fn);
    rb_refresh_derived(c);
    if (!checks_pass(c, fn)) {
        c->persistent.state = ST_ERROR;
        return RB_ERROR;
    }
    project_state(c); /* a start quaternion within the tolerance of the checks is normalised */
    if (!rb_state_enters(c, fn, c->persistent.buf + RB_OFF_X)) {
        c->persistent.state = ST_ERROR;
        return RB_ERROR;
    }
    c->persistent.state = c->importer.type == RB_CO_SIMULATION ? ST_STEP : ST_EVENT;
    return RB_OK;
}
