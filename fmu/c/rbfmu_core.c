/* Version-independent core of the FMU: the instance, variable access, validity checks, initialisation.
 * See rbfmu_core.h and docs/fmi_layer.md; the step, Model Exchange and FMU state are in
 * rbfmu_step.c, rbfmu_exchange.c and rbfmu_snapshot.c. */
#include "rbfmu_core.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *const rb_state_names[] = {"Instantiated", "InitializationMode", "StepMode", "EventMode",
                                      "ContinuousTimeMode", "Terminated", "Error", "IntermediateUpdateMode"};

void rb_logf(const Instance *c, int status, const char *fmt, ...) {
    char msg[1024];
    va_list ap;
    if (!c || !c->log) return;
    if (!c->logging_on && status == RB_OK) return;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    c->log(c, status, status == RB_OK ? "logAll" : (status == RB_WARNING ? "logStatusWarning" : "logStatusError"), msg);
}

int rb_allowed(const Instance *c, const char *fn, unsigned mask) {
    if (!c) return 0;
    if (mask & (1u << c->state)) return 1;
    RB_ERR(c, "%s: not allowed in state %s", fn, rb_state_names[c->state]);
    return 0;
}

int rb_arrays(const Instance *c, const char *fn, size_t n, const void *a, const char *a_name, const void *b,
              const char *b_name) {
    const char *null = n == 0 ? NULL : !a ? a_name : (b_name && !b) ? b_name : NULL;
    if (!null) return 1;
    RB_ERR(c, "%s: %s is NULL while the call's count is %zu", fn, null, n);
    return 0;
}

int rb_put_count(const Instance *c, const char *fn, size_t *out, size_t value) {
    if (!out) {
        RB_ERR(c, "%s: the pointer for the result is NULL", fn);
        return RB_ERROR;
    }
    *out = value;
    return RB_OK;
}

/* ---- calls into the generated functions ---- */

void rb_compute_outputs(Instance *c) {
    if (RB_NY == 0) return;
    c->arg[0] = c->buf + RB_OFF_X;
    c->arg[1] = c->buf + RB_OFF_U;
    c->arg[2] = c->buf + RB_OFF_P;
    c->arg[3] = c->d;
    c->res[0] = c->buf + RB_OFF_Y;
    model_outputs(c->arg, c->res, c->iw, c->w, 0);
}

void rb_compute_derivatives(Instance *c, double *dx) {
    c->arg[0] = c->buf + RB_OFF_X;
    c->arg[1] = c->buf + RB_OFF_U;
    c->arg[2] = c->buf + RB_OFF_P;
    c->arg[3] = c->d;
    c->res[0] = dx;
    model_rhs(c->arg, c->res, c->iw, c->w, 0);
}

/* What depends on the parameters only (inertia about the rotation point and its inverse,
 * m g, 1/m, the splitting's axis order) is computed here, once per parameter change, not in
 * every right-hand side (docs/theory.md §6). */
void rb_refresh_derived(Instance *c) {
    int principal;
    c->arg[0] = c->buf + RB_OFF_P;
    c->res[0] = c->d;
    model_derived(c->arg, c->res, c->iw, c->w, 0);
    /* an inertia about the rotation point that is diagonal as set takes the steps without
     * its off-diagonal products, where the model has them (model_functions.principal_steps) */
    principal = rb_principal(c->d);
    c->step_fns = principal ? rb_principal_step_fns : rb_step_fns;
    c->fixed_step_fns = principal ? rb_principal_fixed_step_fns : rb_fixed_step_fns;
}

int rb_principal(const double *d) {
    int k;
    for (k = 0; k < RB_NOFFDIAG; k++)
        if (d[rb_off_diagonal[k]] != 0.0) return 0;
    return 1;
}

static void project_state(Instance *c) {
    c->arg[0] = c->buf + RB_OFF_X;
    c->res[0] = c->x_next;
    model_project(c->arg, c->res, c->iw, c->w, 0);
    memcpy(c->buf + RB_OFF_X, c->x_next, sizeof c->x_next);
}

/* Evaluates the generated validity checks; logs each violation with the values of all
 * parameters and states. Returns the number of violations. */
int rb_run_checks(Instance *c, const char *when, const double *x, const double *p, double method_value) {
    int k, bad = 0;
    c->arg[0] = x;
    c->arg[1] = p;
    c->arg[2] = &method_value;
    c->res[0] = c->g;
    model_checks(c->arg, c->res, c->iw, c->w, 0);
    for (k = 0; k < RB_NC; k++) {
        int ok = rb_check_strict[k] ? (c->g[k] > 0) : (c->g[k] >= 0);
        if (!ok) {
            RB_ERR(c, "%s: %s (check value %.17g)", when, rb_check_text[k], c->g[k]);
            bad++;
        }
    }
    if (bad) {
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
    return bad;
}

static int run_checks(Instance *c, const char *when) {
    return rb_run_checks(c, when, c->buf + RB_OFF_X, c->buf + RB_OFF_P, c->method_value);
}

static int method_index(long long value) {
    int i;
    for (i = 0; i < RB_NMETHODS; i++)
        if (rb_method_values[i] == value) return i;
    return -1;
}

void rb_select_method(Instance *c, int index) {
    c->method = index;
    c->method_value = (double)rb_method_values[index];
}

/* ---- creation and destruction ---- */

Instance *rb_instantiate(const char *fn, const char *name, const char *token, InterfaceType type,
                         int logging_on, rb_logger log, const void *env, const void *callbacks) {
    Instance tmp, *c;
    memset(&tmp, 0, sizeof tmp);
    tmp.log = log;
    tmp.env = env;
    tmp.callbacks = callbacks;
    tmp.name = (char *)(name ? name : "");
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
    c->name = (char *)malloc(strlen(name) + 1);
    if (!c->name) {
        free(c);
        return NULL;
    }
    strcpy(c->name, name);
    c->type = type;
    c->log = log;
    c->env = env;
    c->callbacks = callbacks;
    c->logging_on = logging_on ? 1 : 0;
    rb_reset(c);
    return c;
}

void rb_free(Instance *c) {
    if (!c) return;
    rb_state_free_all(c);
    free(c->name);
    free(c);
}

void rb_reset(Instance *c) {
    memcpy(c->buf, rb_start, sizeof c->buf);
    rb_select_method(c, method_index(RB_DEFAULT_METHOD));
    memset(c->du, 0, sizeof c->du);
    c->du_set = 0;
    c->tolerance_set = 0;
    c->importer_tolerance_defined = 0;
    c->importer_tolerance = 0.0;
    c->tolerance_logged = 0.0;
    rb_refresh_derived(c);
    c->state = ST_INSTANTIATED;
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

static int settable(const Instance *c, unsigned char kind) {
    return kind < sizeof rb_set_mask / sizeof rb_set_mask[0] && (rb_set_mask[kind] & (1u << c->state)) != 0;
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

int rb_set_reals(Instance *c, const char *fn, const unsigned vr[], size_t n, const double v[]) {
    size_t i;
    int tunable_changed = 0, param_changed = 0;
    double old[RB_NV];
    if (!rb_arrays(c, fn, n, vr, "the value reference array", v, "the value array")) return RB_ERROR;
    for (i = 0; i < n; i++) { /* validate everything before changing anything */
        if (vr[i] >= RB_NV) {
            RB_ERR(c, "%s: unknown value reference %u (valid: 0..%d)", fn, vr[i], RB_NV - 1);
            return RB_ERROR;
        }
        if (!settable(c, rb_kind[vr[i]])) {
            RB_ERR(c, "%s: variable '%s' (vr %u) cannot be set in state %s: it is %s", fn, rb_names[vr[i]], vr[i],
                   rb_state_names[c->state], kind_text(rb_kind[vr[i]]));
            return RB_ERROR;
        }
        if (!isfinite(v[i])) {
            RB_ERR(c, "%s: variable '%s' (vr %u) must be finite, got %g", fn, rb_names[vr[i]], vr[i], v[i]);
            return RB_ERROR;
        }
    }
    memcpy(old, c->buf, sizeof old);
    for (i = 0; i < n; i++) {
        if (vr[i] == RB_VR_TOLERANCE && v[i] != c->buf[vr[i]]) /* a new tolerance: no floor found for it yet */
            c->buf[RB_OFF_L + RB_REPORT_TOL_FLOOR] = 0.0, c->tolerance_logged = 0.0;
        c->buf[vr[i]] = v[i];
        if (rb_kind[vr[i]] == RB_KIND_PARAM_TUNABLE) tunable_changed = 1;
        if (rb_kind[vr[i]] == RB_KIND_PARAM_TUNABLE || rb_kind[vr[i]] == RB_KIND_PARAM_FIXED) param_changed = 1;
        if (vr[i] == RB_VR_TOLERANCE) c->tolerance_set = 1; /* the importer's own value wins (rb_exit_initialization) */
    }
    if ((c->state == ST_STEP || c->state == ST_EVENT) && tunable_changed && run_checks(c, fn)) {
        memcpy(c->buf, old, sizeof old); /* refuse the change, keep the instance usable */
        return RB_ERROR;
    }
    if (param_changed) rb_refresh_derived(c);
    return RB_OK;
}

int rb_get_reals(Instance *c, const char *fn, const unsigned vr[], size_t n, double v[]) {
    size_t i;
    int need_y = 0, need_dx = 0;
    if (!rb_arrays(c, fn, n, vr, "the value reference array", v, "the value array")) return RB_ERROR;
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
    if (need_dx) rb_compute_derivatives(c, c->buf + RB_OFF_DX);
    for (i = 0; i < n; i++) v[i] = c->buf[vr[i]];
    return RB_OK;
}

int rb_set_methods(Instance *c, const char *fn, const unsigned vr[], size_t n, const long long values[]) {
    size_t i;
    int old = c->method;
    if (!rb_arrays(c, fn, n, vr, "the value reference array", values, "the value array")) return RB_ERROR;
    for (i = 0; i < n; i++) { /* all-or-nothing: every entry must be valid before any takes effect */
        if (rb_set_method(c, fn, vr[i], values[i]) != RB_OK) {
            rb_select_method(c, old);
            return RB_ERROR;
        }
    }
    return RB_OK;
}

int rb_set_method(Instance *c, const char *fn, unsigned vr, long long value) {
    int idx, old;
    if (vr != RB_VR_METHOD) {
        RB_ERR(c, "%s: value reference %u is not an integer/enumeration variable (only %d: method)", fn, vr,
               RB_VR_METHOD);
        return RB_ERROR;
    }
    if (!settable(c, RB_KIND_PARAM_TUNABLE)) { /* the method is a tunable parameter */
        RB_ERR(c, "%s: 'method' cannot be set in state %s", fn, rb_state_names[c->state]);
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
    old = c->method;
    rb_select_method(c, idx);
    if ((c->state == ST_STEP || c->state == ST_EVENT) && run_checks(c, fn)) {
        rb_select_method(c, old); /* e.g. splitting without principal axes */
        return RB_ERROR;
    }
    if (idx != old) /* another estimate: the floor the last one showed does not hold for it */
        c->buf[RB_OFF_L + RB_REPORT_TOL_FLOOR] = 0.0, c->tolerance_logged = 0.0;
    return RB_OK;
}

int rb_get_method(const Instance *c, const char *fn, unsigned vr, long long *value) {
    if (vr != RB_VR_METHOD) {
        RB_ERR(c, "%s: value reference %u is not an integer/enumeration variable (only %d: method)", fn, vr,
               RB_VR_METHOD);
        return RB_ERROR;
    }
    *value = rb_method_values[c->method];
    return RB_OK;
}

/* ---- initialisation ---- */

int rb_enter_initialization(Instance *c, const char *fn, double start_time, int stop_defined, double stop_time) {
    if (!isfinite(start_time)) {
        RB_ERR(c, "%s: startTime must be finite, got %g", fn, start_time);
        return RB_ERROR;
    }
    if (stop_defined && !(stop_time >= start_time)) {
        RB_ERR(c, "%s: stopTime %.17g must be >= startTime %.17g", fn, stop_time, start_time);
        return RB_ERROR;
    }
    c->buf[0] = start_time;
    c->state = ST_INITIALIZATION;
    return RB_OK;
}

int rb_importer_tolerance(Instance *c, const char *fn, int defined, double tolerance) {
    c->importer_tolerance_defined = 0;
    if (!defined) return RB_OK;
    if (!(tolerance > 0) || !isfinite(tolerance)) { /* refused, not an error: the FMU keeps its own */
        rb_logf(c, RB_WARNING, "%s: the importer's tolerance %g is not applied: a tolerance must be finite and > 0; "
                "the FMU keeps tolerance = %g", fn, tolerance, c->buf[RB_VR_TOLERANCE]);
        return RB_WARNING;
    }
    c->importer_tolerance_defined = 1;
    c->importer_tolerance = tolerance;
    return RB_OK;
}

/* The rule of docs/fmi_layer.md (Tolerance): in Co-Simulation the importer's tolerance sets
 * the parameter `tolerance` (the error control's, per second of simulated time), unless the
 * importer set that parameter itself or the FMU takes fixed steps (tolerance 0); in Model
 * Exchange it is the importer's own solver's. Every outcome is logged. */
static void apply_importer_tolerance(Instance *c, const char *fn) {
    double own = c->buf[RB_VR_TOLERANCE], tol = c->importer_tolerance;
    if (!c->importer_tolerance_defined) return;
    if (c->type == RB_MODEL_EXCHANGE)
        rb_logf(c, RB_OK, "%s: Model Exchange: the importer's tolerance %g is its own solver's; the parameter "
                "tolerance (%g) acts only in Co-Simulation", fn, tol, own);
    else if (c->tolerance_set)
        rb_logf(c, RB_WARNING, "%s: the importer's tolerance %g is not applied: the parameter tolerance was set "
                "to %g, which wins", fn, tol, own);
    else if (!(own > 0))
        rb_logf(c, RB_WARNING, "%s: the importer's tolerance %g is not applied: this FMU takes fixed steps "
                "(tolerance = 0); set the parameter tolerance > 0 for error control", fn, tol);
    else {
        int fixed = rb_method_estimate_order[c->method] == 0;
        c->buf[RB_VR_TOLERANCE] = tol;
        rb_logf(c, RB_OK, "%s: tolerance = %g from the importer (the FMU's default was %g)%s%s", fn, tol, own,
                fixed ? "; it acts once method is one with error control: now fixed steps under " : "",
                fixed ? rb_method_names[c->method] : "");
    }
}

/* An output never becomes non-finite with status OK (issue 23.11): the parameter checks
 * bound each parameter, not every product the equations form with the states, so the
 * outputs are checked where they are made available, after initialisation and at the end
 * of a doStep (once per doStep, not per internal step). Logs the first non-finite one. */
int rb_outputs_finite(Instance *c, const char *fn) {
    int i;
    rb_compute_outputs(c);
    for (i = 0; i < RB_NY; i++) {
        double y = c->buf[RB_OFF_Y + i];
        if (!isfinite(y)) {
            RB_ERR(c, "%s: output '%s' would be %g at t=%.17g: the parameters and states overflow the model's "
                      "equations (keep them in the ranges of docs/user_guide.md §2.3, Parameter ranges)",
                   fn, rb_names[RB_OFF_Y + i], y, c->buf[0]);
            return 0;
        }
    }
    return 1;
}

int rb_exit_initialization(Instance *c, const char *fn) {
    apply_importer_tolerance(c, fn);
    if (run_checks(c, fn)) {
        c->state = ST_ERROR;
        return RB_ERROR;
    }
    rb_refresh_derived(c);
    project_state(c); /* a start quaternion within the tolerance of the checks is normalised */
    if (!rb_outputs_finite(c, fn)) {
        c->state = ST_ERROR;
        return RB_ERROR;
    }
    c->state = c->type == RB_CO_SIMULATION ? ST_STEP : ST_EVENT;
    return RB_OK;
}
