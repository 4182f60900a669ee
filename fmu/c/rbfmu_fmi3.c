/* FMI 3.0 Co-Simulation layer: model-agnostic, hand-written.
 *
 * It knows nothing about rigid bodies. Everything model-specific comes from two
 * generated files: model_data.h (sizes, variable table, start values, the texts of
 * the validity checks; written by fmu/model_data.py) and model_funcs.h (the CasADi
 * generated functions model_step, model_outputs, model_checks, model_project).
 *
 * Value buffer layout (value reference = index):
 *   [ time | states x (RB_NX) | inputs u (RB_NU) | parameters p (RB_NP) | outputs y (RB_NY) ]
 *
 * State machine in the style of the Modelica Reference FMUs: every function checks
 * that it may be called in the instance's current state (docs/fmi_layer.md).
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"
#include "model_funcs.h"
#include "model_data.h"

#define UNUSED(x) (void)(x)

typedef enum { ST_INSTANTIATED, ST_INITIALIZATION, ST_STEP, ST_TERMINATED, ST_ERROR } InstanceState;

static const char *const state_names[] = {"Instantiated", "InitializationMode", "StepMode",
                                          "Terminated", "Error"};

/* Bit masks of the states a function may be called in. */
#define M_INST (1u << ST_INSTANTIATED)
#define M_INIT (1u << ST_INITIALIZATION)
#define M_STEP (1u << ST_STEP)
#define M_TERM (1u << ST_TERMINATED)
#define M_ERR (1u << ST_ERROR)

typedef struct {
    char *name;
    fmi3InstanceEnvironment env;
    fmi3LogMessageCallback log;
    int logging_on;
    InstanceState state;
    int method;          /* index into rb_step_fns / rb_method_values */
    double method_value; /* its enumeration value, as the generated checks take it */
    double buf[RB_NV];
    double x_next[RB_NX];
    double x_start[RB_NX]; /* state at the start of a doStep, for a retry */
    long last_substeps;    /* internal steps the last doStep took */
    double g[RB_NC];
    /* CasADi work arrays, sized at generation time: no heap use after instantiation */
    const casadi_real *arg[RB_SZ_ARG];
    casadi_real *res[RB_SZ_RES];
    casadi_int iw[RB_SZ_IW > 0 ? RB_SZ_IW : 1];
    casadi_real w[RB_SZ_W > 0 ? RB_SZ_W : 1];
} Instance;

static void logf_(Instance *c, fmi3Status status, const char *category, const char *fmt, ...) {
    char msg[1024];
    va_list ap;
    if (!c || !c->log) return;
    if (!c->logging_on && status == fmi3OK) return;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    c->log(c->env, status, category, msg);
}

#define ERR(c, ...) logf_((c), fmi3Error, "logStatusError", __VA_ARGS__)

/* Returns 0 and logs when `c` may not be called in its current state. */
static int allowed(Instance *c, const char *fn, unsigned mask) {
    if (!c) return 0;
    if (mask & (1u << c->state)) return 1;
    ERR(c, "%s: not allowed in state %s", fn, state_names[c->state]);
    return 0;
}

#define CHECK(fn, mask)                                        \
    Instance *c = (Instance *)instance;                        \
    if (!allowed(c, fn, mask)) return fmi3Error

/* ---- calls into the generated functions ---- */

static void compute_outputs(Instance *c) {
    if (RB_NY == 0) return;
    c->arg[0] = c->buf + RB_OFF_X;
    c->arg[1] = c->buf + RB_OFF_U;
    c->arg[2] = c->buf + RB_OFF_P;
    c->res[0] = c->buf + RB_OFF_Y;
    model_outputs(c->arg, c->res, c->iw, c->w, 0);
}

static void project_state(Instance *c) {
    c->arg[0] = c->buf + RB_OFF_X;
    c->res[0] = c->x_next;
    model_project(c->arg, c->res, c->iw, c->w, 0);
    memcpy(c->buf + RB_OFF_X, c->x_next, sizeof c->x_next);
}

/* Evaluates the validity checks of the generated model_checks; logs each violation
 * with the values of all parameters. Returns the number of violations. */
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
            ERR(c, "%s: %s (check value %.17g)", when, rb_check_text[k], c->g[k]);
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
        ERR(c, "%s: parameter values: %s", when, line);
    }
    return bad;
}

static int method_index(long long value) {
    int i;
    for (i = 0; i < RB_NMETHODS; i++)
        if (rb_method_values[i] == value) return i;
    return -1;
}

static void set_method(Instance *c, int index) {
    c->method = index;
    c->method_value = (double)rb_method_values[index];
}

static void load_start_values(Instance *c) {
    memcpy(c->buf, rb_start, sizeof c->buf);
    set_method(c, method_index(RB_DEFAULT_METHOD));
}

/* ---- creation and destruction ---- */

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken,
                                         fmi3String resourcePath, fmi3Boolean visible,
                                         fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
                                         fmi3Boolean earlyReturnAllowed,
                                         const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables,
                                         fmi3InstanceEnvironment instanceEnvironment,
                                         fmi3LogMessageCallback logMessage,
                                         fmi3IntermediateUpdateCallback intermediateUpdate) {
    Instance tmp, *c;
    UNUSED(resourcePath); UNUSED(visible); UNUSED(earlyReturnAllowed);
    UNUSED(requiredIntermediateVariables); UNUSED(nRequiredIntermediateVariables);
    UNUSED(intermediateUpdate);
    memset(&tmp, 0, sizeof tmp);
    tmp.env = instanceEnvironment;
    tmp.log = logMessage;
    if (!instanceName || !instanceName[0]) {
        ERR(&tmp, "fmi3InstantiateCoSimulation: instanceName must be a non-empty string");
        return NULL;
    }
    if (!instantiationToken || strcmp(instantiationToken, RB_INSTANTIATION_TOKEN) != 0) {
        ERR(&tmp, "fmi3InstantiateCoSimulation: instantiationToken '%s' does not match this FMU's '%s' "
                  "(modelDescription.xml and binary are from different builds)",
            instantiationToken ? instantiationToken : "(null)", RB_INSTANTIATION_TOKEN);
        return NULL;
    }
    if (eventModeUsed) {
        ERR(&tmp, "fmi3InstantiateCoSimulation: eventModeUsed=true but this FMU has no event mode "
                  "(hasEventMode=false)");
        return NULL;
    }
    c = (Instance *)calloc(1, sizeof(Instance));
    if (!c) return NULL;
    c->name = (char *)malloc(strlen(instanceName) + 1);
    if (!c->name) { free(c); return NULL; }
    strcpy(c->name, instanceName);
    c->env = instanceEnvironment;
    c->log = logMessage;
    c->logging_on = loggingOn ? 1 : 0;
    c->state = ST_INSTANTIATED;
    load_start_values(c);
    return c;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible,
                                          fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage) {
    Instance tmp;
    UNUSED(instanceName); UNUSED(instantiationToken); UNUSED(resourcePath); UNUSED(visible);
    UNUSED(loggingOn);
    memset(&tmp, 0, sizeof tmp);
    tmp.env = instanceEnvironment;
    tmp.log = logMessage;
    ERR(&tmp, "fmi3InstantiateModelExchange: this FMU provides Co-Simulation only");
    return NULL;
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken,
                                               fmi3String resourcePath, fmi3Boolean visible,
                                               fmi3Boolean loggingOn,
                                               fmi3InstanceEnvironment instanceEnvironment,
                                               fmi3LogMessageCallback logMessage,
                                               fmi3ClockUpdateCallback clockUpdate,
                                               fmi3LockPreemptionCallback lockPreemption,
                                               fmi3UnlockPreemptionCallback unlockPreemption) {
    Instance tmp;
    UNUSED(instanceName); UNUSED(instantiationToken); UNUSED(resourcePath); UNUSED(visible);
    UNUSED(loggingOn); UNUSED(clockUpdate); UNUSED(lockPreemption); UNUSED(unlockPreemption);
    memset(&tmp, 0, sizeof tmp);
    tmp.env = instanceEnvironment;
    tmp.log = logMessage;
    ERR(&tmp, "fmi3InstantiateScheduledExecution: this FMU provides Co-Simulation only");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance) {
    Instance *c = (Instance *)instance;
    if (!c) return;
    free(c->name);
    free(c);
}

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[]) {
    CHECK("fmi3SetDebugLogging", M_INST | M_INIT | M_STEP | M_TERM | M_ERR);
    UNUSED(nCategories); UNUSED(categories);
    c->logging_on = loggingOn ? 1 : 0;
    return fmi3OK;
}

/* ---- initialisation, termination ---- */

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined,
                                       fmi3Float64 tolerance, fmi3Float64 startTime,
                                       fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    CHECK("fmi3EnterInitializationMode", M_INST);
    UNUSED(toleranceDefined); UNUSED(tolerance);
    if (!isfinite(startTime)) {
        ERR(c, "fmi3EnterInitializationMode: startTime must be finite, got %g", startTime);
        return fmi3Error;
    }
    if (stopTimeDefined && !(stopTime >= startTime)) {
        ERR(c, "fmi3EnterInitializationMode: stopTime %.17g must be >= startTime %.17g", stopTime, startTime);
        return fmi3Error;
    }
    c->buf[0] = startTime;
    c->state = ST_INITIALIZATION;
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    CHECK("fmi3ExitInitializationMode", M_INIT);
    if (run_checks(c, "fmi3ExitInitializationMode")) {
        c->state = ST_ERROR;
        return fmi3Error;
    }
    project_state(c); /* a start quaternion within the tolerance of the checks is normalised */
    compute_outputs(c);
    c->state = ST_STEP;
    return fmi3OK;
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
    CHECK("fmi3EnterEventMode", 0);
    return fmi3Error;
}

fmi3Status fmi3Terminate(fmi3Instance instance) {
    CHECK("fmi3Terminate", M_STEP | M_INIT);
    c->state = ST_TERMINATED;
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance instance) {
    CHECK("fmi3Reset", M_INST | M_INIT | M_STEP | M_TERM | M_ERR);
    load_start_values(c);
    c->state = ST_INSTANTIATED;
    return fmi3OK;
}

/* ---- Float64 access ---- */

static int settable(Instance *c, unsigned char kind) {
    switch (kind) {
    case RB_KIND_INPUT:
    case RB_KIND_PARAM_TUNABLE:
        return c->state == ST_INSTANTIATED || c->state == ST_INITIALIZATION || c->state == ST_STEP;
    case RB_KIND_STATE:
    case RB_KIND_PARAM_FIXED:
        return c->state == ST_INSTANTIATED || c->state == ST_INITIALIZATION;
    default:
        return 0;
    }
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, const fmi3Float64 values[], size_t nValues) {
    size_t i;
    int tunable_changed = 0;
    double old[RB_NV];
    CHECK("fmi3SetFloat64", M_INST | M_INIT | M_STEP);
    if (nValues != nValueReferences) {
        ERR(c, "fmi3SetFloat64: nValues (%zu) must equal nValueReferences (%zu) for scalar variables",
            nValues, nValueReferences);
        return fmi3Error;
    }
    for (i = 0; i < nValueReferences; i++) { /* validate everything before changing anything */
        fmi3ValueReference vr = valueReferences[i];
        if (vr >= RB_NV) {
            ERR(c, "fmi3SetFloat64: unknown value reference %u (valid: 0..%d)", vr, RB_NV - 1);
            return fmi3Error;
        }
        if (!settable(c, rb_kind[vr])) {
            ERR(c, "fmi3SetFloat64: variable '%s' (vr %u) cannot be set in state %s", rb_names[vr], vr,
                state_names[c->state]);
            return fmi3Error;
        }
        if (!isfinite(values[i])) {
            ERR(c, "fmi3SetFloat64: variable '%s' (vr %u) must be finite, got %g", rb_names[vr], vr, values[i]);
            return fmi3Error;
        }
    }
    memcpy(old, c->buf, sizeof old);
    for (i = 0; i < nValueReferences; i++) {
        c->buf[valueReferences[i]] = values[i];
        if (rb_kind[valueReferences[i]] == RB_KIND_PARAM_TUNABLE) tunable_changed = 1;
    }
    if (c->state == ST_STEP && tunable_changed && run_checks(c, "fmi3SetFloat64")) {
        memcpy(c->buf, old, sizeof old); /* refuse the change, keep the instance usable */
        return fmi3Error;
    }
    return fmi3OK;
}

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, fmi3Float64 values[], size_t nValues) {
    size_t i;
    CHECK("fmi3GetFloat64", M_INIT | M_STEP | M_TERM | M_ERR);
    if (nValues != nValueReferences) {
        ERR(c, "fmi3GetFloat64: nValues (%zu) must equal nValueReferences (%zu) for scalar variables",
            nValues, nValueReferences);
        return fmi3Error;
    }
    if (c->state == ST_INITIALIZATION) compute_outputs(c); /* outputs follow start values set so far */
    for (i = 0; i < nValueReferences; i++) {
        if (valueReferences[i] >= RB_NV) {
            ERR(c, "fmi3GetFloat64: unknown value reference %u (valid: 0..%d)", valueReferences[i], RB_NV - 1);
            return fmi3Error;
        }
        values[i] = c->buf[valueReferences[i]];
    }
    return fmi3OK;
}

/* ---- the step ---- */

/* A doStep whose substeps fail the acceptance test is redone from its start state with
 * more substeps, at most this many times (each at least doubling the count). */
#define RB_MAX_RETRIES 16

/* ||df/dx||_inf at x: a bound on the fastest time scale (1/s), from generated model_rate. */
static double eval_rate(Instance *c, const double *x) {
    double r = 0.0;
    c->arg[0] = x;
    c->arg[1] = c->buf + RB_OFF_U;
    c->arg[2] = c->buf + RB_OFF_P;
    c->res[0] = &r;
    model_rate(c->arg, c->res, c->iw, c->w, 0);
    return r;
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

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                      fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime) {
    double H = communicationStepSize, t = currentCommunicationPoint, h = 0, nd, tol, limit, rate, err = 0;
    double *x;
    long n = 0;
    int i, attempt, finite;
    CHECK("fmi3DoStep", M_STEP);
    UNUSED(noSetFMUStatePriorToCurrentPoint);
    if (eventHandlingNeeded) *eventHandlingNeeded = fmi3False;
    if (terminateSimulation) *terminateSimulation = fmi3False;
    if (earlyReturn) *earlyReturn = fmi3False;
    if (lastSuccessfulTime) *lastSuccessfulTime = c->buf[0];
    if (!(H > 0) || !isfinite(H)) {
        ERR(c, "fmi3DoStep: communicationStepSize must be finite and > 0, got %g", H);
        return fmi3Error;
    }
    tol = 1e-10 * (fabs(c->buf[0]) > 1.0 ? fabs(c->buf[0]) : 1.0);
    if (!(fabs(t - c->buf[0]) <= tol)) {
        ERR(c, "fmi3DoStep: currentCommunicationPoint %.17g is not the FMU's current time %.17g", t, c->buf[0]);
        return fmi3Error;
    }
    x = c->buf + RB_OFF_X;
    memcpy(c->x_start, x, sizeof c->x_start);
    limit = rb_method_rate_limit[c->method];
    /* substeps: h <= h_max, and for explicit methods h * rate <= limit (docs/theory.md 5.4) */
    nd = ceil(H / c->buf[RB_VR_HMAX] * (1.0 - 1e-12)); /* relative slack: H = n*h_max gives n, not n+1 */
    rate = eval_rate(c, x);
    if (isfinite(limit) && H * rate / limit > nd) nd = ceil(H * rate / limit);
    if (nd < 1) nd = 1;
    for (attempt = 0;; attempt++) {
        if (nd > RB_MAX_SUBSTEPS) {
            ERR(c, "fmi3DoStep: step %g from t=%.17g needs %.3g internal steps with method %s (h_max %g, "
                   "stiffness rate %g 1/s), more than the limit %.0f; shorten the communication step, "
                   "choose an implicit method, or raise h_max", H, t, nd, rb_method_names[c->method],
                c->buf[RB_VR_HMAX], rate, (double)RB_MAX_SUBSTEPS);
            memcpy(x, c->x_start, sizeof c->x_start);
            return fmi3Error;
        }
        n = (long)nd;
        h = H / (double)n;
        err = integrate(c, n, h);
        finite = 1;
        for (i = 0; i < RB_NX; i++) finite &= isfinite(x[i]) ? 1 : 0;
        rate = finite ? eval_rate(c, x) : NAN;
        /* accept: finite, Newton converged, and the rate at the end still within the limit
         * (torques can spin the body up during the step; 2x slack for the growth) */
        if (finite && err <= RB_NEWTON_ACCEPT && !(isfinite(limit) && h * rate > 2.0 * limit)) break;
        if (attempt == RB_MAX_RETRIES) {
            memcpy(x, c->x_start, sizeof c->x_start);
            ERR(c, "fmi3DoStep: step from t=%.17g (H=%g, method %s) failed after %d refinements down to %ld "
                   "substeps of %g: %s; the state is left at t=%.17g", t, H, rb_method_names[c->method],
                attempt, n, h, !finite ? "the state became non-finite" : "Newton did not converge",
                c->buf[0]);
            return fmi3Error;
        }
        memcpy(x, c->x_start, sizeof c->x_start); /* redo the whole step with more substeps */
        if (finite && isfinite(limit) && H * rate / limit > 2.0 * nd) nd = ceil(H * rate / limit);
        else nd *= 2.0;
    }
    c->last_substeps = n;
    c->buf[0] = t + H;
    if (lastSuccessfulTime) *lastSuccessfulTime = c->buf[0];
    compute_outputs(c);
    return fmi3OK;
}

/* ---- everything this FMU does not provide: fmi3Error with a message ---- */

#define NOT_PROVIDED(fn, why)                                      \
    do {                                                           \
        Instance *c_ = (Instance *)instance;                       \
        if (c_) ERR(c_, "%s: not provided by this FMU (%s)", fn, why); \
        return fmi3Error;                                          \
    } while (0)

/* Getters/setters of types this FMU has no variables of: a call with zero value
 * references is a no-op, any value reference is unknown for that type. */
#define NO_VARIABLES_OF_TYPE(fn, mask)                                                          \
    do {                                                                                        \
        CHECK(fn, mask);                                                                        \
        if (nValueReferences == 0) return fmi3OK;                                               \
        ERR(c, "%s: value reference %u is not a variable of this type (the FMU has Float64 "    \
               "variables only)", fn, valueReferences[0]);                                      \
        return fmi3Error;                                                                       \
    } while (0)

#define GETTER(T, CT)                                                                          \
    fmi3Status fmi3Get##T(fmi3Instance instance, const fmi3ValueReference valueReferences[],   \
                          size_t nValueReferences, CT values[], size_t nValues) {              \
        UNUSED(values); UNUSED(nValues);                                                       \
        NO_VARIABLES_OF_TYPE("fmi3Get" #T, M_INIT | M_STEP | M_TERM | M_ERR);                   \
    }
#define SETTER(T, CT)                                                                          \
    fmi3Status fmi3Set##T(fmi3Instance instance, const fmi3ValueReference valueReferences[],   \
                          size_t nValueReferences, const CT values[], size_t nValues) {        \
        UNUSED(values); UNUSED(nValues);                                                       \
        NO_VARIABLES_OF_TYPE("fmi3Set" #T, M_INST | M_INIT | M_STEP);                          \
    }

GETTER(Float32, fmi3Float32) SETTER(Float32, fmi3Float32)
GETTER(Int8, fmi3Int8) SETTER(Int8, fmi3Int8)
GETTER(UInt8, fmi3UInt8) SETTER(UInt8, fmi3UInt8)
GETTER(Int16, fmi3Int16) SETTER(Int16, fmi3Int16)
GETTER(UInt16, fmi3UInt16) SETTER(UInt16, fmi3UInt16)
GETTER(Int32, fmi3Int32) SETTER(Int32, fmi3Int32)
GETTER(UInt32, fmi3UInt32) SETTER(UInt32, fmi3UInt32)
/* Int64: the one enumeration variable `method` (value reference RB_VR_METHOD). */
fmi3Status fmi3GetInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, fmi3Int64 values[], size_t nValues) {
    size_t i;
    CHECK("fmi3GetInt64", M_INIT | M_STEP | M_TERM | M_ERR);
    if (nValues != nValueReferences) {
        ERR(c, "fmi3GetInt64: nValues (%zu) must equal nValueReferences (%zu)", nValues, nValueReferences);
        return fmi3Error;
    }
    for (i = 0; i < nValueReferences; i++) {
        if (valueReferences[i] != RB_VR_METHOD) {
            ERR(c, "fmi3GetInt64: value reference %u is not an Int64/Enumeration variable (only %d: method)",
                valueReferences[i], RB_VR_METHOD);
            return fmi3Error;
        }
        values[i] = rb_method_values[c->method];
    }
    return fmi3OK;
}

fmi3Status fmi3SetInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, const fmi3Int64 values[], size_t nValues) {
    size_t i;
    int idx, old;
    CHECK("fmi3SetInt64", M_INST | M_INIT | M_STEP);
    if (nValues != nValueReferences) {
        ERR(c, "fmi3SetInt64: nValues (%zu) must equal nValueReferences (%zu)", nValues, nValueReferences);
        return fmi3Error;
    }
    for (i = 0; i < nValueReferences; i++) {
        if (valueReferences[i] != RB_VR_METHOD) {
            ERR(c, "fmi3SetInt64: value reference %u is not an Int64/Enumeration variable (only %d: method)",
                valueReferences[i], RB_VR_METHOD);
            return fmi3Error;
        }
        idx = method_index(values[i]);
        if (idx < 0) {
            char allowed[256];
            size_t len = 0;
            int k;
            allowed[0] = '\0';
            for (k = 0; k < RB_NMETHODS && len < sizeof allowed - 40; k++)
                len += (size_t)snprintf(allowed + len, sizeof allowed - len, "%s%lld=%s", k ? ", " : "",
                                        rb_method_values[k], rb_method_names[k]);
            ERR(c, "fmi3SetInt64: method %lld is not compiled into this FMU; allowed: %s", (long long)values[i],
                allowed);
            return fmi3Error;
        }
        old = c->method;
        set_method(c, idx);
        if (c->state == ST_STEP && run_checks(c, "fmi3SetInt64")) { /* e.g. splitting without principal axes */
            set_method(c, old);
            return fmi3Error;
        }
    }
    return fmi3OK;
}
GETTER(UInt64, fmi3UInt64) SETTER(UInt64, fmi3UInt64)
GETTER(Boolean, fmi3Boolean) SETTER(Boolean, fmi3Boolean)
GETTER(String, fmi3String) SETTER(String, fmi3String)

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, fmi3Clock values[]) {
    UNUSED(values);
    NO_VARIABLES_OF_TYPE("fmi3GetClock", M_INIT | M_STEP | M_TERM | M_ERR);
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, const fmi3Clock values[]) {
    UNUSED(values);
    NO_VARIABLES_OF_TYPE("fmi3SetClock", M_INST | M_INIT | M_STEP);
}

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, size_t valueSizes[], fmi3Binary values[], size_t nValues) {
    UNUSED(valueSizes); UNUSED(values); UNUSED(nValues);
    NO_VARIABLES_OF_TYPE("fmi3GetBinary", M_INIT | M_STEP | M_TERM | M_ERR);
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, const size_t valueSizes[], const fmi3Binary values[],
                         size_t nValues) {
    UNUSED(valueSizes); UNUSED(values); UNUSED(nValues);
    NO_VARIABLES_OF_TYPE("fmi3SetBinary", M_INST | M_INIT | M_STEP);
}

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference valueReference,
                                               size_t *nDependencies) {
    UNUSED(valueReference); UNUSED(nDependencies);
    NOT_PROVIDED("fmi3GetNumberOfVariableDependencies", "no dependency information");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[], fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[],
                                       fmi3DependencyKind dependencyKinds[], size_t nDependencies) {
    UNUSED(dependent); UNUSED(elementIndicesOfDependent); UNUSED(independents);
    UNUSED(elementIndicesOfIndependents); UNUSED(dependencyKinds); UNUSED(nDependencies);
    NOT_PROVIDED("fmi3GetVariableDependencies", "no dependency information");
}

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    UNUSED(FMUState);
    NOT_PROVIDED("fmi3GetFMUState", "canGetAndSetFMUState=false");
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState) {
    UNUSED(FMUState);
    NOT_PROVIDED("fmi3SetFMUState", "canGetAndSetFMUState=false");
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    UNUSED(FMUState);
    NOT_PROVIDED("fmi3FreeFMUState", "canGetAndSetFMUState=false");
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t *size) {
    UNUSED(FMUState); UNUSED(size);
    NOT_PROVIDED("fmi3SerializedFMUStateSize", "canSerializeFMUState=false");
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState, fmi3Byte serializedState[],
                                 size_t size) {
    UNUSED(FMUState); UNUSED(serializedState); UNUSED(size);
    NOT_PROVIDED("fmi3SerializeFMUState", "canSerializeFMUState=false");
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[], size_t size,
                                   fmi3FMUState *FMUState) {
    UNUSED(serializedState); UNUSED(size); UNUSED(FMUState);
    NOT_PROVIDED("fmi3DeserializeFMUState", "canSerializeFMUState=false");
}

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                        size_t nUnknowns, const fmi3ValueReference knowns[], size_t nKnowns,
                                        const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[],
                                        size_t nSensitivity) {
    UNUSED(unknowns); UNUSED(nUnknowns); UNUSED(knowns); UNUSED(nKnowns); UNUSED(seed); UNUSED(nSeed);
    UNUSED(sensitivity); UNUSED(nSensitivity);
    NOT_PROVIDED("fmi3GetDirectionalDerivative", "providesDirectionalDerivatives=false");
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                    size_t nUnknowns, const fmi3ValueReference knowns[], size_t nKnowns,
                                    const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[],
                                    size_t nSensitivity) {
    UNUSED(unknowns); UNUSED(nUnknowns); UNUSED(knowns); UNUSED(nKnowns); UNUSED(seed); UNUSED(nSeed);
    UNUSED(sensitivity); UNUSED(nSensitivity);
    NOT_PROVIDED("fmi3GetAdjointDerivative", "providesAdjointDerivatives=false");
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance) {
    NOT_PROVIDED("fmi3EnterConfigurationMode", "no structural parameters");
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance) {
    NOT_PROVIDED("fmi3ExitConfigurationMode", "no structural parameters");
}

fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, fmi3Float64 intervals[],
                                  fmi3IntervalQualifier qualifiers[]) {
    UNUSED(valueReferences); UNUSED(nValueReferences); UNUSED(intervals); UNUSED(qualifiers);
    NOT_PROVIDED("fmi3GetIntervalDecimal", "no clocks");
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[],
                                   fmi3IntervalQualifier qualifiers[]) {
    UNUSED(valueReferences); UNUSED(nValueReferences); UNUSED(counters); UNUSED(resolutions);
    UNUSED(qualifiers);
    NOT_PROVIDED("fmi3GetIntervalFraction", "no clocks");
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, fmi3Float64 shifts[]) {
    UNUSED(valueReferences); UNUSED(nValueReferences); UNUSED(shifts);
    NOT_PROVIDED("fmi3GetShiftDecimal", "no clocks");
}

fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[]) {
    UNUSED(valueReferences); UNUSED(nValueReferences); UNUSED(counters); UNUSED(resolutions);
    NOT_PROVIDED("fmi3GetShiftFraction", "no clocks");
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, const fmi3Float64 intervals[]) {
    UNUSED(valueReferences); UNUSED(nValueReferences); UNUSED(intervals);
    NOT_PROVIDED("fmi3SetIntervalDecimal", "no clocks");
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, const fmi3UInt64 counters[],
                                   const fmi3UInt64 resolutions[]) {
    UNUSED(valueReferences); UNUSED(nValueReferences); UNUSED(counters); UNUSED(resolutions);
    NOT_PROVIDED("fmi3SetIntervalFraction", "no clocks");
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, const fmi3Float64 shifts[]) {
    UNUSED(valueReferences); UNUSED(nValueReferences); UNUSED(shifts);
    NOT_PROVIDED("fmi3SetShiftDecimal", "no clocks");
}

fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, const fmi3UInt64 counters[],
                                const fmi3UInt64 resolutions[]) {
    UNUSED(valueReferences); UNUSED(nValueReferences); UNUSED(counters); UNUSED(resolutions);
    NOT_PROVIDED("fmi3SetShiftFraction", "no clocks");
}

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) {
    NOT_PROVIDED("fmi3EvaluateDiscreteStates", "no discrete states");
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation,
                                    fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged,
                                    fmi3Boolean *nextEventTimeDefined, fmi3Float64 *nextEventTime) {
    UNUSED(discreteStatesNeedUpdate); UNUSED(terminateSimulation); UNUSED(nominalsOfContinuousStatesChanged);
    UNUSED(valuesOfContinuousStatesChanged); UNUSED(nextEventTimeDefined); UNUSED(nextEventTime);
    NOT_PROVIDED("fmi3UpdateDiscreteStates", "no event mode");
}

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) {
    NOT_PROVIDED("fmi3EnterContinuousTimeMode", "Co-Simulation only");
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation) {
    UNUSED(noSetFMUStatePriorToCurrentPoint); UNUSED(enterEventMode); UNUSED(terminateSimulation);
    NOT_PROVIDED("fmi3CompletedIntegratorStep", "Co-Simulation only");
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) {
    UNUSED(time);
    NOT_PROVIDED("fmi3SetTime", "Co-Simulation only");
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates) {
    UNUSED(continuousStates); UNUSED(nContinuousStates);
    NOT_PROVIDED("fmi3SetContinuousStates", "Co-Simulation only");
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                             size_t nContinuousStates) {
    UNUSED(derivatives); UNUSED(nContinuousStates);
    NOT_PROVIDED("fmi3GetContinuousStateDerivatives", "Co-Simulation only");
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[],
                                  size_t nEventIndicators) {
    UNUSED(eventIndicators); UNUSED(nEventIndicators);
    NOT_PROVIDED("fmi3GetEventIndicators", "Co-Simulation only");
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[],
                                   size_t nContinuousStates) {
    UNUSED(continuousStates); UNUSED(nContinuousStates);
    NOT_PROVIDED("fmi3GetContinuousStates", "Co-Simulation only");
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[],
                                             size_t nContinuousStates) {
    UNUSED(nominals); UNUSED(nContinuousStates);
    NOT_PROVIDED("fmi3GetNominalsOfContinuousStates", "Co-Simulation only");
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *nEventIndicators) {
    UNUSED(nEventIndicators);
    NOT_PROVIDED("fmi3GetNumberOfEventIndicators", "Co-Simulation only");
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates) {
    UNUSED(nContinuousStates);
    NOT_PROVIDED("fmi3GetNumberOfContinuousStates", "Co-Simulation only");
}

fmi3Status fmi3EnterStepMode(fmi3Instance instance) {
    NOT_PROVIDED("fmi3EnterStepMode", "no event mode: the FMU enters step mode at exitInitializationMode");
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                    size_t nValueReferences, const fmi3Int32 orders[], fmi3Float64 values[],
                                    size_t nValues) {
    UNUSED(valueReferences); UNUSED(nValueReferences); UNUSED(orders); UNUSED(values); UNUSED(nValues);
    NOT_PROVIDED("fmi3GetOutputDerivatives", "maxOutputDerivativeOrder=0");
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime) {
    UNUSED(clockReference); UNUSED(activationTime);
    NOT_PROVIDED("fmi3ActivateModelPartition", "Co-Simulation only");
}
