/* Version-independent core of the FMU: see rbfmu_core.h and docs/fmi_layer.md. */
#include "rbfmu_core.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *const rb_state_names[] = {"Instantiated", "InitializationMode", "StepMode", "EventMode",
                                      "ContinuousTimeMode", "Terminated", "Error"};

/* A doStep whose substeps fail the acceptance test is redone from its start state with
 * more substeps, at most this many times (each at least doubling the count). */
#define RB_MAX_RETRIES 10

void rb_logf(const Instance *c, int status, const char *fmt, ...) {
    char msg[1024];
    va_list ap;
    if (!c || !c->log) return;
    if (!c->logging_on && status == RB_OK) return;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    c->log(c, status, status == RB_OK ? "logAll" : "logStatusError", msg);
}

int rb_allowed(const Instance *c, const char *fn, unsigned mask) {
    if (!c) return 0;
    if (mask & (1u << c->state)) return 1;
    RB_ERR(c, "%s: not allowed in state %s", fn, rb_state_names[c->state]);
    return 0;
}

/* ---- calls into the generated functions ---- */

static void compute_outputs(Instance *c) {
    if (RB_NY == 0) return;
    c->arg[0] = c->buf + RB_OFF_X;
    c->arg[1] = c->buf + RB_OFF_U;
    c->arg[2] = c->buf + RB_OFF_P;
    c->res[0] = c->buf + RB_OFF_Y;
    model_outputs(c->arg, c->res, c->iw, c->w, 0);
}

static void compute_derivatives(Instance *c, double *dx) {
    c->arg[0] = c->buf + RB_OFF_X;
    c->arg[1] = c->buf + RB_OFF_U;
    c->arg[2] = c->buf + RB_OFF_P;
    c->res[0] = dx;
    model_rhs(c->arg, c->res, c->iw, c->w, 0);
}

static void project_state(Instance *c) {
    c->arg[0] = c->buf + RB_OFF_X;
    c->res[0] = c->x_next;
    model_project(c->arg, c->res, c->iw, c->w, 0);
    memcpy(c->buf + RB_OFF_X, c->x_next, sizeof c->x_next);
}

/* Evaluates the generated validity checks; logs each violation with the values of all
 * parameters. Returns the number of violations. */
static int run_checks(Instance *c, const char *when) {
    int k, bad = 0;
    c->arg[0] = c->buf + RB_OFF_X;
    c->arg[1] = c->buf + RB_OFF_P;
    c->arg[2] = &c->method_value;
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
        for (i = RB_OFF_P; i < RB_OFF_P + RB_NP && len < sizeof line - 64; i++)
            len += (size_t)snprintf(line + len, sizeof line - len, "%s=%.17g ", rb_names[i], c->buf[i]);
        RB_ERR(c, "%s: parameter values: %s", when, line);
        len = 0;
        line[0] = '\0';
        for (i = RB_OFF_X; i < RB_OFF_X + RB_NX && len < sizeof line - 64; i++)
            len += (size_t)snprintf(line + len, sizeof line - len, "%s=%.17g ", rb_names[i], c->buf[i]);
        RB_ERR(c, "%s: state values: %s", when, line);
    }
    return bad;
}

static int method_index(long long value) {
    int i;
    for (i = 0; i < RB_NMETHODS; i++)
        if (rb_method_values[i] == value) return i;
    return -1;
}

static void select_method(Instance *c, int index) {
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
    free(c->name);
    free(c);
}

void rb_reset(Instance *c) {
    memcpy(c->buf, rb_start, sizeof c->buf);
    select_method(c, method_index(RB_DEFAULT_METHOD));
    c->state = ST_INSTANTIATED;
}

/* ---- variable access ---- */

static int settable(const Instance *c, unsigned char kind) {
    switch (kind) {
    case RB_KIND_INPUT:
        return c->state != ST_TERMINATED && c->state != ST_ERROR;
    case RB_KIND_PARAM_TUNABLE: /* in Model Exchange only at events, where FMI allows it */
        return c->state == ST_INSTANTIATED || c->state == ST_INITIALIZATION || c->state == ST_STEP ||
               c->state == ST_EVENT;
    case RB_KIND_STATE:
    case RB_KIND_PARAM_FIXED:
        return c->state == ST_INSTANTIATED || c->state == ST_INITIALIZATION;
    default:
        return 0;
    }
}

static const char *kind_text(unsigned char kind) {
    switch (kind) {
    case RB_KIND_INDEPENDENT: return "the independent variable";
    case RB_KIND_OUTPUT: return "a calculated output";
    case RB_KIND_DERIVATIVE: return "a state derivative";
    case RB_KIND_PARAM_FIXED: return "a fixed parameter (set it before or during initialisation)";
    case RB_KIND_STATE: return "a state (its start value is set before or during initialisation)";
    default: return "not settable now";
    }
}

int rb_set_reals(Instance *c, const char *fn, const unsigned vr[], size_t n, const double v[]) {
    size_t i;
    int tunable_changed = 0;
    double old[RB_NV];
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
        c->buf[vr[i]] = v[i];
        if (rb_kind[vr[i]] == RB_KIND_PARAM_TUNABLE) tunable_changed = 1;
    }
    if ((c->state == ST_STEP || c->state == ST_EVENT) && tunable_changed && run_checks(c, fn)) {
        memcpy(c->buf, old, sizeof old); /* refuse the change, keep the instance usable */
        return RB_ERROR;
    }
    return RB_OK;
}

int rb_get_reals(Instance *c, const char *fn, const unsigned vr[], size_t n, double v[]) {
    size_t i;
    int need_y = 0, need_dx = 0;
    for (i = 0; i < n; i++) {
        if (vr[i] >= RB_NV) {
            RB_ERR(c, "%s: unknown value reference %u (valid: 0..%d)", fn, vr[i], RB_NV - 1);
            return RB_ERROR;
        }
        need_y |= rb_kind[vr[i]] == RB_KIND_OUTPUT;
        need_dx |= rb_kind[vr[i]] == RB_KIND_DERIVATIVE;
    }
    /* outputs and derivatives always follow the current states, inputs and parameters */
    if (need_y) compute_outputs(c);
    if (need_dx) compute_derivatives(c, c->buf + RB_OFF_DX);
    for (i = 0; i < n; i++) v[i] = c->buf[vr[i]];
    return RB_OK;
}

int rb_set_methods(Instance *c, const char *fn, const unsigned vr[], size_t n, const long long values[]) {
    size_t i;
    int old = c->method;
    for (i = 0; i < n; i++) { /* all-or-nothing: every entry must be valid before any takes effect */
        if (rb_set_method(c, fn, vr[i], values[i]) != RB_OK) {
            select_method(c, old);
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
    if (!(c->state == ST_INSTANTIATED || c->state == ST_INITIALIZATION || c->state == ST_STEP ||
          c->state == ST_EVENT)) {
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
    select_method(c, idx);
    if ((c->state == ST_STEP || c->state == ST_EVENT) && run_checks(c, fn)) {
        select_method(c, old); /* e.g. splitting without principal axes */
        return RB_ERROR;
    }
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

int rb_exit_initialization(Instance *c, const char *fn) {
    if (run_checks(c, fn)) {
        c->state = ST_ERROR;
        return RB_ERROR;
    }
    project_state(c); /* a start quaternion within the tolerance of the checks is normalised */
    c->state = c->type == RB_CO_SIMULATION ? ST_STEP : ST_EVENT;
    return RB_OK;
}

/* ---- the Co-Simulation step ---- */

/* The generated model_rate at x: r[0] = ||df/dx||_inf (1/s, stability), r[1] = |w| (rad/s, accuracy). */
static void eval_rate(Instance *c, const double *x, double r[2]) {
    c->arg[0] = x;
    c->arg[1] = c->buf + RB_OFF_U;
    c->arg[2] = c->buf + RB_OFF_P;
    c->res[0] = r;
    model_rate(c->arg, c->res, c->iw, c->w, 0);
}

/* Substeps needed over H for the rates r: h * r[0] <= stability limit, h * r[1] <= rotation limit. */
static double substeps_for(const Instance *c, double H, const double r[2]) {
    double n = 0, limit = rb_method_rate_limit[c->method], rot = rb_method_rotation_limit[c->method];
    if (isfinite(limit) && H * r[0] / limit > n) n = ceil(H * r[0] / limit);
    if (isfinite(rot) && H * r[1] / rot > n) n = ceil(H * r[1] / rot);
    return n;
}

/* n substeps of size h on the state in buf; returns the largest Newton residual the
 * method reported (0 for explicit methods). */
static double integrate(Instance *c, long n, double h) {
    double *x = c->buf + RB_OFF_X, err = 0.0, err_max = 0.0;
    long k;
    rb_step_fn step = rb_step_fns[c->method];
    c->arg[1] = c->buf + RB_OFF_U;
    c->arg[2] = c->buf + RB_OFF_P;
    c->arg[3] = &h;
    c->res[1] = &err;
    for (k = 0; k < n; k++) { /* ping-pong between the state and a scratch buffer: no copy per substep */
        c->arg[0] = (k & 1) ? c->x_next : x;
        c->res[0] = (k & 1) ? x : c->x_next;
        step(c->arg, c->res, c->iw, c->w, 0);
        if (!(err <= err_max)) err_max = err; /* also catches NaN */
    }
    if (n & 1) memcpy(x, c->x_next, sizeof c->x_next);
    return err_max;
}

int rb_do_step(Instance *c, const char *fn, double t, double H) {
    double h = 0, nd, need, tol, rate[2] = {0, 0}, err = 0;
    double *x = c->buf + RB_OFF_X;
    long n = 0;
    int i, attempt, finite;
    if (!(H > 0) || !isfinite(H)) {
        RB_ERR(c, "%s: communicationStepSize must be finite and > 0, got %g", fn, H);
        return RB_ERROR;
    }
    tol = 1e-10 * (fabs(c->buf[0]) > 1.0 ? fabs(c->buf[0]) : 1.0);
    if (!(fabs(t - c->buf[0]) <= tol)) {
        RB_ERR(c, "%s: currentCommunicationPoint %.17g is not the FMU's current time %.17g", fn, t, c->buf[0]);
        return RB_ERROR;
    }
    memcpy(c->x_start, x, sizeof c->x_start);
    /* substeps: h <= h_max, and the method's stability and rotation limits (docs/theory.md 5.4) */
    nd = ceil(H / c->buf[RB_VR_HMAX] * (1.0 - 1e-12)); /* relative slack: H = n*h_max gives n, not n+1 */
    eval_rate(c, x, rate);
    need = substeps_for(c, H, rate);
    if (need > nd) nd = need;
    if (nd < 1) nd = 1;
    for (attempt = 0;; attempt++) {
        if (nd > RB_MAX_SUBSTEPS) {
            RB_ERR(c, "%s: step %g from t=%.17g needs %.3g internal steps with method %s (h_max %g, "
                      "stiffness rate %g 1/s, spin %g rad/s), more than the limit %.0f; shorten the communication "
                      "step, choose an implicit method, or raise h_max", fn, H, t, nd, rb_method_names[c->method],
                   c->buf[RB_VR_HMAX], rate[0], rate[1], (double)RB_MAX_SUBSTEPS);
            memcpy(x, c->x_start, sizeof c->x_start);
            return RB_ERROR;
        }
        n = (long)nd;
        h = H / (double)n;
        err = integrate(c, n, h);
        finite = 1;
        for (i = 0; i < RB_NX; i++) finite &= isfinite(x[i]) ? 1 : 0;
        if (finite) eval_rate(c, x, rate);
        need = finite ? substeps_for(c, H, rate) : NAN;
        /* accept: finite, Newton converged, and the limits still met at the end of the step
         * within a factor 2 (torques can spin the body up during the step) */
        if (finite && err <= RB_NEWTON_ACCEPT && need <= 2.0 * nd) break;
        if (attempt == RB_MAX_RETRIES) {
            memcpy(x, c->x_start, sizeof c->x_start);
            RB_ERR(c, "%s: step from t=%.17g (H=%g, method %s) failed after %d refinements down to %ld "
                      "substeps of %g: %s; the state is left at t=%.17g", fn, t, H, rb_method_names[c->method],
                   attempt, n, h,
                   !finite ? "the state became non-finite"
                           : (err > RB_NEWTON_ACCEPT ? "Newton did not converge" : "the spin rate kept growing"),
                   c->buf[0]);
            return RB_ERROR;
        }
        memcpy(x, c->x_start, sizeof c->x_start); /* redo the whole step with more substeps */
        nd = (finite && need > 2.0 * nd) ? need : 2.0 * nd;
    }
    c->last_substeps = n;
    c->buf[0] = t + H; /* outputs are evaluated when they are read (rb_get_reals) */
    return RB_OK;
}

/* ---- Model Exchange ---- */

int rb_set_time(Instance *c, const char *fn, double t) {
    if (!isfinite(t)) {
        RB_ERR(c, "%s: time must be finite, got %g", fn, t);
        return RB_ERROR;
    }
    c->buf[0] = t;
    return RB_OK;
}

static int check_nx(const Instance *c, const char *fn, size_t n) {
    if (n == RB_NX) return 1;
    RB_ERR(c, "%s: this FMU has %d continuous states, got %zu", fn, RB_NX, n);
    return 0;
}

int rb_set_states(Instance *c, const char *fn, const double x[], size_t n) {
    size_t i;
    if (!check_nx(c, fn, n)) return RB_ERROR;
    for (i = 0; i < n; i++) {
        if (!isfinite(x[i])) {
            RB_ERR(c, "%s: state '%s' must be finite, got %g", fn, rb_names[RB_OFF_X + i], x[i]);
            return RB_ERROR;
        }
    }
    memcpy(c->buf + RB_OFF_X, x, n * sizeof(double));
    return RB_OK;
}

int rb_get_states(Instance *c, const char *fn, double x[], size_t n) {
    if (!check_nx(c, fn, n)) return RB_ERROR;
    memcpy(x, c->buf + RB_OFF_X, n * sizeof(double));
    return RB_OK;
}

int rb_get_derivatives(Instance *c, const char *fn, double dx[], size_t n) {
    if (!check_nx(c, fn, n)) return RB_ERROR;
    compute_derivatives(c, dx);
    return RB_OK;
}

int rb_get_nominals(Instance *c, const char *fn, double nominals[], size_t n) {
    size_t i;
    if (!check_nx(c, fn, n)) return RB_ERROR;
    for (i = 0; i < n; i++) nominals[i] = 1.0;
    return RB_OK;
}

/* ---- FMU state ---- */

#define RB_STATE_MAGIC 0x52424653u /* "RBFS" */

struct RbState {
    unsigned magic;
    unsigned nv;
    int type; /* the interface the snapshot was taken from */
    int state;
    int method;
    double buf[RB_NV];
};

size_t rb_state_size(void) { return sizeof(struct RbState) + sizeof(RB_INSTANTIATION_TOKEN); }

int rb_state_get(Instance *c, const char *fn, void **state) {
    struct RbState *s;
    if (!state) {
        RB_ERR(c, "%s: FMUState pointer is NULL", fn);
        return RB_ERROR;
    }
    s = (struct RbState *)(*state ? *state : malloc(sizeof(struct RbState)));
    if (!s) {
        RB_ERR(c, "%s: out of memory", fn);
        return RB_ERROR;
    }
    s->magic = RB_STATE_MAGIC;
    s->nv = RB_NV;
    s->type = (int)c->type;
    s->state = (int)c->state;
    s->method = c->method;
    memcpy(s->buf, c->buf, sizeof s->buf);
    *state = s;
    return RB_OK;
}

static int valid_state(const Instance *c, const char *fn, const struct RbState *s) {
    if (!s || s->magic != RB_STATE_MAGIC || s->nv != RB_NV || s->method < 0 || s->method >= RB_NMETHODS ||
        s->state < ST_INSTANTIATED || s->state > ST_ERROR) {
        RB_ERR(c, "%s: not an FMU state of this FMU", fn);
        return 0;
    }
    return 1;
}

int rb_state_set(Instance *c, const char *fn, const void *state) {
    const struct RbState *s = (const struct RbState *)state;
    if (!valid_state(c, fn, s)) return RB_ERROR;
    if (s->type != (int)c->type) {
        RB_ERR(c, "%s: the FMU state was taken from a %s instance; this one is %s", fn,
               s->type == RB_MODEL_EXCHANGE ? "Model Exchange" : "Co-Simulation",
               c->type == RB_MODEL_EXCHANGE ? "Model Exchange" : "Co-Simulation");
        return RB_ERROR;
    }
    c->state = (InstanceState)s->state;
    select_method(c, s->method);
    memcpy(c->buf, s->buf, sizeof c->buf);
    return RB_OK;
}

int rb_state_free(Instance *c, const char *fn, void **state) {
    UNUSED(c);
    UNUSED(fn);
    if (state && *state) {
        free(*state);
        *state = NULL;
    }
    return RB_OK;
}

int rb_state_serialize(Instance *c, const char *fn, const void *state, unsigned char *out, size_t size) {
    if (!valid_state(c, fn, (const struct RbState *)state)) return RB_ERROR;
    if (size != rb_state_size() || !out) {
        RB_ERR(c, "%s: buffer of %zu bytes, the serialized state has %zu", fn, size, rb_state_size());
        return RB_ERROR;
    }
    /* the token first: a state only deserializes into the same build */
    memcpy(out, RB_INSTANTIATION_TOKEN, sizeof(RB_INSTANTIATION_TOKEN));
    memcpy(out + sizeof(RB_INSTANTIATION_TOKEN), state, sizeof(struct RbState));
    return RB_OK;
}

int rb_state_deserialize(Instance *c, const char *fn, const unsigned char *in, size_t size, void **state) {
    struct RbState tmp;
    if (!in || !state || size != rb_state_size() ||
        memcmp(in, RB_INSTANTIATION_TOKEN, sizeof(RB_INSTANTIATION_TOKEN)) != 0) {
        RB_ERR(c, "%s: %zu bytes are not a serialized state of this FMU build (expected %zu bytes starting "
                  "with its instantiation token)", fn, size, rb_state_size());
        return RB_ERROR;
    }
    memcpy(&tmp, in + sizeof(RB_INSTANTIATION_TOKEN), sizeof tmp);
    if (!valid_state(c, fn, &tmp)) return RB_ERROR;
    if (!*state) *state = malloc(sizeof(struct RbState));
    if (!*state) {
        RB_ERR(c, "%s: out of memory", fn);
        return RB_ERROR;
    }
    memcpy(*state, &tmp, sizeof tmp);
    return RB_OK;
}

/* ---- directional derivatives ---- */

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

int rb_directional(Instance *c, const char *fn, const unsigned unknowns[], size_t n_unknowns,
                   const unsigned knowns[], size_t n_knowns, const double seed[], size_t n_seed,
                   double sensitivity[], size_t n_sensitivity, int adjoint) {
    size_t i, j;
    if (n_seed != (adjoint ? n_unknowns : n_knowns) || n_sensitivity != (adjoint ? n_knowns : n_unknowns)) {
        RB_ERR(c, "%s: seed and sensitivity sizes (%zu, %zu) do not match the %zu unknowns and %zu knowns", fn,
               n_seed, n_sensitivity, n_unknowns, n_knowns);
        return RB_ERROR;
    }
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
    c->arg[0] = c->buf + RB_OFF_X;
    c->arg[1] = c->buf + RB_OFF_U;
    c->arg[2] = c->buf + RB_OFF_P;
    c->res[0] = c->jac;
    model_jac(c->arg, c->res, c->iw, c->w, 0);
    for (i = 0; i < n_sensitivity; i++) sensitivity[i] = 0.0;
    for (i = 0; i < n_unknowns; i++) {
        for (j = 0; j < n_knowns; j++) {
            double d = c->jac[jac_row(unknowns[i]) + RB_NJ_ROWS * jac_col(knowns[j])];
            if (adjoint)
                sensitivity[j] += d * seed[i];
            else
                sensitivity[i] += d * seed[j];
        }
    }
    return RB_OK;
}
