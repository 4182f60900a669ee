/* FMI 2.0 API (Co-Simulation and Model Exchange) over the generic core (rbfmu_core.c).
 *
 * Hand-written and model-agnostic; the same core and state rules as the FMI 3.0 file
 * (docs/fmi_layer.md). FMI 2.0 specifics: fmi2SetupExperiment before initialisation,
 * the GUID in place of the instantiation token, Integer access for the enumeration
 * `method`, and a printf-style logger (messages are passed through "%s").
 */
#include <string.h>

#include "fmi2Functions.h"
#include "rbfmu_core.h"

/* ---- Which instance states admit each call: the one table of these rules (the masks are
 * the state bits M_* of rbfmu_core.h). docs/fmi_layer.md §3 is generated from it
 * (fmu/fmi_rules.py) and tests/test_fmi_rules.py checks the fuzz model against it. ---- */
#define MASK_fmi2SetDebugLogging               M_ANY
#define MASK_fmi2SetupExperiment               M_INST
#define MASK_fmi2EnterInitializationMode       M_INST
#define MASK_fmi2ExitInitializationMode        M_INIT
#define MASK_fmi2Terminate                     (M_STEP | M_EVENT | M_CONT)
#define MASK_fmi2Reset                         M_ANY
#define MASK_fmi2SetReal                       (M_INST | M_INIT | M_STEP | M_EVENT | M_CONT)
#define MASK_fmi2GetReal                       (M_INIT | M_STEP | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi2SetInteger                    (M_INST | M_INIT | M_STEP | M_EVENT)
#define MASK_fmi2GetInteger                    (M_INIT | M_STEP | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi2GetFMUstate                   (M_INIT | M_STEP | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi2SetFMUstate                   (M_INIT | M_STEP | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi2FreeFMUstate                  M_ANY
#define MASK_fmi2SerializedFMUstateSize        M_ANY
#define MASK_fmi2SerializeFMUstate             M_ANY
#define MASK_fmi2DeSerializeFMUstate           M_ANY
#define MASK_fmi2GetDirectionalDerivative      (M_INIT | M_STEP | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi2EnterEventMode                (M_EVENT | M_CONT)
#define MASK_fmi2NewDiscreteStates             M_EVENT
#define MASK_fmi2EnterContinuousTimeMode       M_EVENT
#define MASK_fmi2CompletedIntegratorStep       M_CONT
#define MASK_fmi2SetTime                       (M_EVENT | M_CONT)
#define MASK_fmi2SetContinuousStates           M_CONT
#define MASK_fmi2GetDerivatives                (M_INIT | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi2GetEventIndicators            (M_INIT | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi2GetContinuousStates           (M_INIT | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi2GetNominalsOfContinuousStates (M_INST | M_INIT | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi2SetRealInputDerivatives       (M_INST | M_INIT | M_STEP)
#define MASK_fmi2GetRealOutputDerivatives      (M_INIT | M_STEP | M_TERM | M_ERR)
#define MASK_fmi2DoStep                        M_STEP
#define MASK_fmi2CancelStep                    M_STEP
#define MASK_fmi2GetStatus                     (M_STEP | M_TERM | M_ERR)
#define MASK_fmi2GetRealStatus                 (M_STEP | M_TERM | M_ERR)
#define MASK_fmi2GetIntegerStatus              (M_STEP | M_TERM | M_ERR)
#define MASK_fmi2GetBooleanStatus              (M_STEP | M_TERM | M_ERR)
#define MASK_fmi2GetStringStatus               (M_STEP | M_TERM | M_ERR)
#define MASK_fmi2GetBoolean                    (M_INIT | M_STEP | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi2GetString                     (M_INIT | M_STEP | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi2SetBoolean                    (M_INST | M_INIT | M_STEP | M_EVENT | M_CONT)
#define MASK_fmi2SetString                     (M_INST | M_INIT | M_STEP | M_EVENT | M_CONT)

static void log2_(const Instance *c, RbStatus status, const char *category, const char *message) {
    const fmi2CallbackFunctions *f = (const fmi2CallbackFunctions *)c->importer.callbacks;
    if (f && f->logger)
        f->logger(f->componentEnvironment, c->importer.name, (fmi2Status)status, category, "%s", message);
}

/* Every function first checks that its instance's state admits it (table above); fn is its
 * name, for the core's messages. */
#define CHECK(F)                        \
    Instance *c = (Instance *)instance; \
    const char *const fn = #F;          \
    if (!rb_allowed(c, fn, MASK_##F)) return fmi2Error

#define RET(expr) return (fmi2Status)(expr)

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    UNUSED(fmuResourceLocation); UNUSED(visible);
    if (!functions || !functions->logger) return NULL; /* FMI 2.0 requires a logger */
    if (fmuType != fmi2CoSimulation && fmuType != fmi2ModelExchange) {
        Instance tmp;
        memset(&tmp, 0, sizeof tmp);
        tmp.importer.log = log2_;
        tmp.importer.callbacks = functions;
        tmp.importer.name = (char *)(instanceName ? instanceName : "");
        RB_ERR(&tmp, "%s: fmuType %d is neither fmi2ModelExchange (0) nor fmi2CoSimulation (1)", __func__,
               (int)fmuType);
        return NULL;
    }
    return rb_instantiate(__func__, instanceName, fmuGUID,
                          fmuType == fmi2CoSimulation ? RB_CO_SIMULATION : RB_MODEL_EXCHANGE, loggingOn, log2_,
                          functions->componentEnvironment, functions);
}

void fmi2FreeInstance(fmi2Component instance) {
    Instance *c = (Instance *)instance;
    if (!c) return;
    rb_state_free_all(c); /* the FMU states the importer did not free, then the instance */
    rb_free(c);
}

fmi2Status fmi2SetDebugLogging(fmi2Component instance, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    CHECK(fmi2SetDebugLogging);
    UNUSED(nCategories); UNUSED(categories);
    c->importer.logging_on = loggingOn;
    return fmi2OK;
}

/* ---- initialisation, termination ---- */

fmi2Status fmi2SetupExperiment(fmi2Component instance, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    RbStatus status;
    CHECK(fmi2SetupExperiment);
    /* FMI 2.0 sets the times here; initialisation mode starts at EnterInitializationMode */
    status = rb_enter_initialization(c, fn, startTime, stopTimeDefined, stopTime);
    c->persistent.state = ST_INSTANTIATED;
    if (status != RB_OK) RET(status);
    RET(rb_importer_tolerance(c, fn, toleranceDefined, tolerance));
}

fmi2Status fmi2EnterInitializationMode(fmi2Component instance) {
    CHECK(fmi2EnterInitializationMode);
    c->persistent.state = ST_INITIALIZATION;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component instance) {
    CHECK(fmi2ExitInitializationMode);
    RET(rb_exit_initialization(c, fn));
}

fmi2Status fmi2Terminate(fmi2Component instance) {
    CHECK(fmi2Terminate);
    c->persistent.state = ST_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component instance) {
    CHECK(fmi2Reset);
    rb_reset(c);
    return fmi2OK;
}

/* ---- variable access ---- */

fmi2Status fmi2SetReal(fmi2Component instance, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    CHECK(fmi2SetReal);
    RET(rb_set_reals(c, fn, vr, nvr, value));
}

fmi2Status fmi2GetReal(fmi2Component instance, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    CHECK(fmi2GetReal);
    RET(rb_get_reals(c, fn, vr, nvr, value));
}

/* Integer access: the enumeration `method`. */
fmi2Status fmi2SetInteger(fmi2Component instance, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[]) {
    size_t i;
    long long buf[64];
    CHECK(fmi2SetInteger);
    if (nvr > 64) {
        RB_ERR(c, "%s: at most 64 values per call, got %zu", fn, nvr);
        return fmi2Error;
    }
    if (!rb_arrays_given(c, fn, nvr, vr, "vr", value, "value")) return fmi2Error;
    for (i = 0; i < nvr; i++) buf[i] = (long long)value[i];
    RET(rb_set_methods(c, fn, vr, nvr, buf));
}

fmi2Status fmi2GetInteger(fmi2Component instance, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    size_t i;
    long long v;
    CHECK(fmi2GetInteger);
    if (!rb_arrays_given(c, fn, nvr, vr, "vr", value, "value")) return fmi2Error;
    for (i = 0; i < nvr; i++) {
        if (rb_get_method(c, fn, vr[i], &v) != RB_OK) return fmi2Error;
        value[i] = (fmi2Integer)v;
    }
    return fmi2OK;
}

#define NO_VARIABLES_OF_TYPE(F)                                                                  \
    do {                                                                                         \
        CHECK(F);                                                                                \
        if (nvr == 0) return fmi2OK;                                                             \
        if (!rb_arrays_given(c, fn, nvr, vr, "vr", NULL, NULL)) return fmi2Error;                \
        RB_ERR(c, "%s: value reference %u is not a variable of this type (the FMU has Real "     \
                  "variables and the Integer enumeration 'method')", fn, vr[0]);                 \
        return fmi2Error;                                                                        \
    } while (0)

fmi2Status fmi2GetBoolean(fmi2Component instance, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    UNUSED(value);
    NO_VARIABLES_OF_TYPE(fmi2GetBoolean);
}

fmi2Status fmi2GetString(fmi2Component instance, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    UNUSED(value);
    NO_VARIABLES_OF_TYPE(fmi2GetString);
}

fmi2Status fmi2SetBoolean(fmi2Component instance, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[]) {
    UNUSED(value);
    NO_VARIABLES_OF_TYPE(fmi2SetBoolean);
}

fmi2Status fmi2SetString(fmi2Component instance, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[]) {
    UNUSED(value);
    NO_VARIABLES_OF_TYPE(fmi2SetString);
}

/* ---- FMU state ---- */

fmi2Status fmi2GetFMUstate(fmi2Component instance, fmi2FMUstate *FMUstate) {
    CHECK(fmi2GetFMUstate);
    RET(rb_state_get(c, fn, (void **)FMUstate));
}

fmi2Status fmi2SetFMUstate(fmi2Component instance, fmi2FMUstate FMUstate) {
    CHECK(fmi2SetFMUstate);
    RET(rb_state_set(c, fn, FMUstate));
}

fmi2Status fmi2FreeFMUstate(fmi2Component instance, fmi2FMUstate *FMUstate) {
    CHECK(fmi2FreeFMUstate);
    RET(rb_state_free(c, fn, (void **)FMUstate));
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component instance, fmi2FMUstate FMUstate, size_t *size) {
    CHECK(fmi2SerializedFMUstateSize);
    RET(rb_state_size(c, fn, FMUstate, size));
}

fmi2Status fmi2SerializeFMUstate(fmi2Component instance, fmi2FMUstate FMUstate, fmi2Byte serializedState[],
                                 size_t size) {
    CHECK(fmi2SerializeFMUstate);
    RET(rb_state_serialize(c, fn, FMUstate, (unsigned char *)serializedState, size));
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component instance, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate) {
    CHECK(fmi2DeSerializeFMUstate);
    RET(rb_state_deserialize(c, fn, (const unsigned char *)serializedState, size,
                             (void **)FMUstate));
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component instance, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[], size_t nKnown,
                                        const fmi2Real dvKnown[], fmi2Real dvUnknown[]) {
    CHECK(fmi2GetDirectionalDerivative);
    RET(rb_directional(c, fn, vUnknown_ref, nUnknown, vKnown_ref, nKnown, dvKnown,
                       nKnown, dvUnknown, nUnknown, false));
}

/* ---- Model Exchange ---- */

fmi2Status fmi2EnterEventMode(fmi2Component instance) {
    CHECK(fmi2EnterEventMode);
    c->persistent.state = ST_EVENT;
    return fmi2OK;
}

fmi2Status fmi2NewDiscreteStates(fmi2Component instance, fmi2EventInfo *eventInfo) {
    CHECK(fmi2NewDiscreteStates);
    if (eventInfo) {
        eventInfo->newDiscreteStatesNeeded = fmi2False;
        eventInfo->terminateSimulation = fmi2False;
        eventInfo->nominalsOfContinuousStatesChanged = fmi2False;
        eventInfo->valuesOfContinuousStatesChanged = fmi2False;
        eventInfo->nextEventTimeDefined = fmi2False;
        eventInfo->nextEventTime = 0.0;
    }
    return fmi2OK;
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component instance) {
    CHECK(fmi2EnterContinuousTimeMode);
    c->persistent.state = ST_CONTINUOUS;
    return fmi2OK;
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component instance, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation) {
    CHECK(fmi2CompletedIntegratorStep);
    UNUSED(noSetFMUStatePriorToCurrentPoint);
    if (enterEventMode) *enterEventMode = fmi2False;
    if (terminateSimulation) *terminateSimulation = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2SetTime(fmi2Component instance, fmi2Real time) {
    CHECK(fmi2SetTime);
    RET(rb_set_time(c, fn, time));
}

fmi2Status fmi2SetContinuousStates(fmi2Component instance, const fmi2Real x[], size_t nx) {
    CHECK(fmi2SetContinuousStates);
    RET(rb_set_states(c, fn, x, nx));
}

fmi2Status fmi2GetDerivatives(fmi2Component instance, fmi2Real derivatives[], size_t nx) {
    CHECK(fmi2GetDerivatives);
    RET(rb_get_derivatives(c, fn, derivatives, nx));
}

fmi2Status fmi2GetEventIndicators(fmi2Component instance, fmi2Real eventIndicators[], size_t ni) {
    CHECK(fmi2GetEventIndicators);
    UNUSED(eventIndicators);
    if (ni == 0) return fmi2OK;
    RB_ERR(c, "%s: this FMU has no event indicators, got ni=%zu", fn, ni);
    return fmi2Error;
}

fmi2Status fmi2GetContinuousStates(fmi2Component instance, fmi2Real x[], size_t nx) {
    CHECK(fmi2GetContinuousStates);
    RET(rb_get_states(c, fn, x, nx));
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component instance, fmi2Real x_nominal[], size_t nx) {
    CHECK(fmi2GetNominalsOfContinuousStates);
    RET(rb_get_nominals(c, fn, x_nominal, nx));
}

/* ---- Co-Simulation ---- */

/* canInterpolateInputs: derivatives of orders 1..3 set here make the inputs a polynomial
 * over the next doStep (rbfmu_inputs.c, docs/fmi_layer.md). */
fmi2Status fmi2SetRealInputDerivatives(fmi2Component instance, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    CHECK(fmi2SetRealInputDerivatives);
    RET(rb_set_input_derivatives(c, fn, vr, nvr, order, value));
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component instance, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    CHECK(fmi2GetRealOutputDerivatives);
    RET(rb_output_derivatives(c, fn, vr, nvr, order, value));
}

fmi2Status fmi2DoStep(fmi2Component instance, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    CHECK(fmi2DoStep);
    UNUSED(noSetFMUStatePriorToCurrentPoint);
    RET(rb_do_step(c, fn, currentCommunicationPoint, communicationStepSize));
}

fmi2Status fmi2CancelStep(fmi2Component instance) {
    CHECK(fmi2CancelStep);
    RB_ERR(c, "%s: doStep never returns fmi2Pending, so there is nothing to cancel", fn);
    return fmi2Error;
}

/* The status getters: a NULL result pointer is named as what is wrong, before the kind. */
static bool value_pointer_given(const Instance *c, const char *fn, const void *value) {
    if (value) return true;
    RB_ERR(c, "%s: the pointer for the value (argument 'value') is NULL", fn);
    return false;
}

fmi2Status fmi2GetStatus(fmi2Component instance, const fmi2StatusKind s, fmi2Status *value) {
    CHECK(fmi2GetStatus);
    if (!value_pointer_given(c, fn, value)) return fmi2Error;
    if (s == fmi2DoStepStatus) {
        *value = fmi2OK; /* doStep is synchronous */
        return fmi2OK;
    }
    RB_ERR(c, "%s: status kind %d not provided (only fmi2DoStepStatus)", fn, (int)s);
    return fmi2Discard;
}

fmi2Status fmi2GetRealStatus(fmi2Component instance, const fmi2StatusKind s, fmi2Real *value) {
    CHECK(fmi2GetRealStatus);
    if (!value_pointer_given(c, fn, value)) return fmi2Error;
    if (s == fmi2LastSuccessfulTime) {
        *value = c->persistent.buf[0];
        return fmi2OK;
    }
    RB_ERR(c, "%s: status kind %d not provided (only fmi2LastSuccessfulTime)", fn, (int)s);
    return fmi2Discard;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component instance, const fmi2StatusKind s, fmi2Integer *value) {
    CHECK(fmi2GetIntegerStatus);
    if (!value_pointer_given(c, fn, value)) return fmi2Error;
    RB_ERR(c, "%s: status kind %d not provided", fn, (int)s);
    return fmi2Discard;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component instance, const fmi2StatusKind s, fmi2Boolean *value) {
    CHECK(fmi2GetBooleanStatus);
    if (!value_pointer_given(c, fn, value)) return fmi2Error;
    if (s == fmi2Terminated) {
        *value = fmi2False; /* the FMU never asks to terminate */
        return fmi2OK;
    }
    RB_ERR(c, "%s: status kind %d not provided (only fmi2Terminated)", fn, (int)s);
    return fmi2Discard;
}

fmi2Status fmi2GetStringStatus(fmi2Component instance, const fmi2StatusKind s, fmi2String *value) {
    CHECK(fmi2GetStringStatus);
    if (!value_pointer_given(c, fn, value)) return fmi2Error;
    RB_ERR(c, "%s: status kind %d not provided", fn, (int)s);
    return fmi2Discard;
}
