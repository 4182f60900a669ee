/* Version-independent core of a sampled-data controller FMU: instance, values, checks, sampling (rbctl_core.h).
 *
 * Hand-written and model-agnostic: the law is only the generated ctrl_output / ctrl_update /
 * ctrl_checks, bound by argument name (RB_ARG_<fn>_<name>, controller_data.h). */
#include "rbctl_core.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const STATE_NAMES[] = {"Instantiated", "InitializationMode", "StepMode", "Terminated", "Error"};

void rc_logf(const RcInstance *c, RcStatus status, const char *fmt, ...) {
    char msg[1024];
    va_list ap;
    if (!c || !c->log) return;
    if (status == RC_OK && !c->logging_on) return;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    c->log(c, status, status >= RC_ERROR ? "logStatusError" : status == RC_WARNING ? "logStatusWarning" : "logAll",
           msg);
}

void rc_reset(RcInstance *c) {
    memcpy(c->v, RC_START, sizeof c->v);
    memset(c->y_held, 0, sizeof c->y_held);
    c->t_start = 0.0;
    c->state = RC_INSTANTIATED;
}

RcInstance *rc_new(const char *name, RcLogFn log, void *env, void *logger) {
    RcInstance *c = (RcInstance *)calloc(1, sizeof(RcInstance));
    if (!c) return NULL;
    snprintf(c->name, sizeof c->name, "%s", name ? name : "");
    c->log = log;
    c->env = env;
    c->logger = logger;
    rc_reset(c);
    return c;
}

void rc_free(RcInstance *c) { free(c); }

RcStatus rc_state_allows(RcInstance *c, const char *fn, unsigned mask) {
    if (mask & RC_M(c->state)) return RC_OK;
    rc_logf(c, RC_ERROR, "%s: not allowed in state %s", fn, STATE_NAMES[c->state]);
    return RC_ERROR;
}

/* ---- the generated functions, bound by argument name ---- */
static void call_law(RcInstance *c, double y[RC_N_Y]) {
    c->arg[RB_ARG_ctrl_output_u] = c->v + RC_OFF_U;
    c->arg[RB_ARG_ctrl_output_p] = c->v + RC_OFF_P;
    c->arg[RB_ARG_ctrl_output_z] = c->v + RC_OFF_Z;
    c->res[RB_RES_ctrl_output_y] = y;
    ctrl_output(c->arg, c->res, c->iw, c->w, 0);
}

static void call_update(RcInstance *c, double z_next[RC_N_Z_ALLOC]) {
    c->arg[RB_ARG_ctrl_update_u] = c->v + RC_OFF_U;
    c->arg[RB_ARG_ctrl_update_p] = c->v + RC_OFF_P;
    c->arg[RB_ARG_ctrl_update_z] = c->v + RC_OFF_Z;
    c->res[RB_RES_ctrl_update_z_next] = z_next;
    ctrl_update(c->arg, c->res, c->iw, c->w, 0);
}

/* true when every condition of ctrl_checks holds; logs each violated one with the parameters */
static bool checks_pass(RcInstance *c, const char *fn) {
    double ok[RC_N_CHECKS_ALLOC];
    bool all = true;
    int i;
    c->arg[RB_ARG_ctrl_checks_p] = c->v + RC_OFF_P;
    c->res[RB_RES_ctrl_checks_ok] = ok;
    ctrl_checks(c->arg, c->res, c->iw, c->w, 0);
    for (i = 0; i < RC_N_CHECKS; i++) {
        if (ok[i] != 1.0) {
            all = false;
            rc_logf(c, RC_ERROR, "%s: parameter check violated: %s", fn, RC_CHECK_TEXTS[i]);
        }
    }
    if (!all) {
        for (i = RC_OFF_P; i < RC_OFF_P + RC_N_P; i++) rc_logf(c, RC_ERROR, "%s:   %s = %.17g", fn, RC_NAMES[i], c->v[i]);
    }
    return all;
}

/* ---- the sample grid t_start + k Ts ---- */
static double sample_tol(const RcInstance *c, double t) { return 1e-9 * fmax(c->v[RC_VR_TS], fabs(t - c->t_start)); }

/* whether t is a sample point; *next: the first sample point after t */
static bool at_sample(const RcInstance *c, double t, double *next) {
    double Ts = c->v[RC_VR_TS], s = (t - c->t_start) / Ts, k = floor(s + 0.5);
    bool at = fabs(t - c->t_start - k * Ts) <= sample_tol(c, t);
    *next = c->t_start + (at ? k + 1.0 : ceil(s)) * Ts;
    return at;
}

/* ---- values ---- */
static const char *kind_text(int kind) {
    static const char *const T[] = {"the independent variable", "an input", "a tunable parameter",
                                    "a fixed parameter", "an output", "a discrete state"};
    return (kind >= 0 && kind <= 5) ? T[kind] : "unknown";
}

static bool settable(const RcInstance *c, int kind) {
    if (kind == RC_KIND_INPUT || kind == RC_KIND_TUNABLE)
        return c->state == RC_INSTANTIATED || c->state == RC_INIT || c->state == RC_STEP;
    if (kind == RC_KIND_FIXED) return c->state == RC_INSTANTIATED || c->state == RC_INIT;
    return false;
}

RcStatus rc_set_reals(RcInstance *c, const char *fn, const unsigned vr[], size_t n, const double x[]) {
    double saved[RC_N_VARS];
    size_t i;
    bool tunable_changed = false;
    if (n > 0 && (!vr || !x)) {
        rc_logf(c, RC_ERROR, "%s: %s is NULL with %zu values", fn, !vr ? "the value references" : "the values", n);
        return RC_ERROR;
    }
    for (i = 0; i < n; i++) { /* all-or-nothing: check every one first */
        if (vr[i] >= RC_N_VARS) {
            rc_logf(c, RC_ERROR, "%s: unknown value reference %u (this FMU has 0..%d)", fn, vr[i], RC_N_VARS - 1);
            return RC_ERROR;
        }
        if (!settable(c, RC_KIND[vr[i]])) {
            rc_logf(c, RC_ERROR, "%s: variable '%s' is %s and cannot be set in state %s", fn, RC_NAMES[vr[i]],
                    kind_text(RC_KIND[vr[i]]), STATE_NAMES[c->state]);
            return RC_ERROR;
        }
        if (!isfinite(x[i])) {
            rc_logf(c, RC_ERROR, "%s: variable '%s': value %g is not finite", fn, RC_NAMES[vr[i]], x[i]);
            return RC_ERROR;
        }
    }
    memcpy(saved, c->v, sizeof saved);
    for (i = 0; i < n; i++) {
        c->v[vr[i]] = x[i];
        if (RC_KIND[vr[i]] == RC_KIND_TUNABLE) tunable_changed = true;
    }
    if (tunable_changed && c->state == RC_STEP && !checks_pass(c, fn)) {
        memcpy(c->v, saved, sizeof saved); /* refused: undone */
        return RC_ERROR;
    }
    return RC_OK;
}

RcStatus rc_get_reals(RcInstance *c, const char *fn, const unsigned vr[], size_t n, double x[]) {
    double y[RC_N_Y], next;
    size_t i;
    int k;
    if (n > 0 && (!vr || !x)) {
        rc_logf(c, RC_ERROR, "%s: %s is NULL with %zu values", fn, !vr ? "the value references" : "the values", n);
        return RC_ERROR;
    }
    for (i = 0; i < n; i++) {
        if (vr[i] >= RC_N_VARS) {
            rc_logf(c, RC_ERROR, "%s: unknown value reference %u (this FMU has 0..%d)", fn, vr[i], RC_N_VARS - 1);
            return RC_ERROR;
        }
    }
    /* at a sample point the outputs are the law at the current inputs; between samples, held */
    if (at_sample(c, c->v[0], &next) && c->state != RC_FAILED) {
        call_law(c, y);
        for (k = 0; k < RC_N_Y; k++) {
            if (!isfinite(y[k])) {
                rc_logf(c, RC_ERROR, "%s: output '%s' would be %g at t=%.17g", fn, RC_NAMES[RC_OFF_Y + k], y[k], c->v[0]);
                return RC_ERROR;
            }
        }
        memcpy(c->v + RC_OFF_Y, y, sizeof y);
    } else {
        memcpy(c->v + RC_OFF_Y, c->y_held, sizeof c->y_held);
    }
    for (i = 0; i < n; i++) x[i] = c->v[vr[i]];
    return RC_OK;
}

RcStatus rc_enter_init(RcInstance *c, const char *fn, double t_start) {
    if (!isfinite(t_start)) {
        rc_logf(c, RC_ERROR, "%s: start time %g is not finite", fn, t_start);
        return RC_ERROR;
    }
    c->t_start = t_start;
    c->v[0] = t_start;
    c->state = RC_INIT;
    return RC_OK;
}

RcStatus rc_exit_init(RcInstance *c, const char *fn) {
    if (!checks_pass(c, fn)) {
        c->state = RC_FAILED;
        return RC_ERROR;
    }
    call_law(c, c->y_held);
    c->state = RC_STEP;
    return RC_OK;
}

RcStatus rc_do_step(RcInstance *c, const char *fn, double t, double h) {
    double next, y[RC_N_Y], z[RC_N_Z_ALLOC], t_end = t + h;
    bool at;
    int k;
    if (!(isfinite(h) && h > 0)) {
        rc_logf(c, RC_ERROR, "%s: communication step size %g must be finite and > 0", fn, h);
        return RC_ERROR;
    }
    if (!isfinite(t) || fabs(t - c->v[0]) > 1e-10 * fmax(1.0, fabs(t))) {
        rc_logf(c, RC_ERROR, "%s: currentCommunicationPoint %.17g differs from the FMU's time %.17g", fn, t, c->v[0]);
        return RC_ERROR;
    }
    at = at_sample(c, c->v[0], &next);
    if (t_end > next + sample_tol(c, next)) {
        rc_logf(c, RC_ERROR,
                "%s: the step from t=%.17g with H=%.17g would cross the sample point t=%.17g inside it: every sample "
                "point must be a communication point (sample period Ts=%.17g s must be a multiple m*H of the step H)",
                fn, t, h, next, c->v[RC_VR_TS]);
        return RC_ERROR;
    }
    if (at) { /* leaving a sample point: latch the outputs, update the discrete states */
        call_law(c, y);
        call_update(c, z);
        for (k = 0; k < RC_N_Y; k++) {
            if (!isfinite(y[k])) {
                rc_logf(c, RC_ERROR, "%s: output '%s' would be %g at t=%.17g", fn, RC_NAMES[RC_OFF_Y + k], y[k], t);
                return RC_ERROR;
            }
        }
        for (k = 0; k < RC_N_Z; k++) {
            if (!isfinite(z[k])) {
                rc_logf(c, RC_ERROR, "%s: discrete state '%s' would be %g at t=%.17g", fn, RC_NAMES[RC_OFF_Z + k], z[k], t);
                return RC_ERROR;
            }
        }
        memcpy(c->y_held, y, sizeof y);
        memcpy(c->v + RC_OFF_Z, z, RC_N_Z * sizeof(double));
    }
    c->v[0] = t_end;
    return RC_OK;
}
