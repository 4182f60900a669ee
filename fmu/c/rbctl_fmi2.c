/* FMI 2.0 Co-Simulation API of a sampled-data controller FMU over its core (rbctl_core.c).
 *
 * Hand-written and model-agnostic. Provides instantiation, initialisation, Real access and
 * doStep; every other function of the standard is exported and returns fmi2Error with a
 * message saying it is not provided. */
#include <stdio.h>
#include <math.h>
#include <string.h>

#include "fmi2Functions.h"
#include "rbctl_core.h"

#define CHECK(F, mask)                                                                   \
    RcInstance *c = (RcInstance *)instance;                                              \
    if (!c) return fmi2Error;                                                            \
    if (rc_state_allows(c, F, mask) != RC_OK) return fmi2Error

#define NOT_PROVIDED(inst)                                                                            \
    do {                                                                                              \
        RcInstance *c_ = (RcInstance *)(inst);                                                        \
        if (c_) rc_logf(c_, RC_ERROR, "%s: not provided by this controller FMU (Co-Simulation, Real " \
                        "variables only)", __func__);                                                 \
        return fmi2Error;                                                                             \
    } while (0)

static void log_fmi2(const RcInstance *c, RcStatus status, const char *category, const char *message) {
    const fmi2CallbackFunctions *f = (const fmi2CallbackFunctions *)c->env;
    if (f && f->logger) f->logger(f->componentEnvironment, c->name, (fmi2Status)status, category, "%s", message);
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component instance, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    RcInstance *c = (RcInstance *)instance;
    RC_UNUSED(nCategories); RC_UNUSED(categories);
    if (!c) return fmi2Error;
    c->logging_on = loggingOn;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    RcInstance *c;
    RC_UNUSED(fmuResourceLocation); RC_UNUSED(visible);
    if (!functions) return NULL; /* a NULL logger is tolerated: messages are then dropped */
    if (fmuType != fmi2CoSimulation) {
        if (functions->logger)
            functions->logger(functions->componentEnvironment, instanceName, fmi2Error, "logStatusError",
                              "fmi2Instantiate: a controller FMU is Co-Simulation only");
        return NULL;
    }
    if (!fmuGUID || strcmp(fmuGUID, RC_INSTANTIATION_TOKEN) != 0) {
        if (functions->logger)
            functions->logger(functions->componentEnvironment, instanceName, fmi2Error, "logStatusError",
                              "fmi2Instantiate: GUID does not match this FMU's");
        return NULL;
    }
    c = rc_new(instanceName, log_fmi2, (void *)functions, NULL);
    if (c) c->logging_on = loggingOn;
    return (fmi2Component)c;
}

void fmi2FreeInstance(fmi2Component instance) { rc_free((RcInstance *)instance); }

fmi2Status fmi2SetupExperiment(fmi2Component instance, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    CHECK("fmi2SetupExperiment", RC_M(RC_INSTANTIATED));
    RC_UNUSED(toleranceDefined); RC_UNUSED(tolerance); RC_UNUSED(stopTimeDefined); RC_UNUSED(stopTime);
    if (!isfinite(startTime)) {
        rc_logf(c, RC_ERROR, "fmi2SetupExperiment: start time %g is not finite", startTime);
        return fmi2Error;
    }
    c->t_start = startTime;
    c->v[0] = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component instance) {
    CHECK("fmi2EnterInitializationMode", RC_M(RC_INSTANTIATED));
    return (fmi2Status)rc_enter_init(c, "fmi2EnterInitializationMode", c->t_start);
}

fmi2Status fmi2ExitInitializationMode(fmi2Component instance) {
    CHECK("fmi2ExitInitializationMode", RC_M(RC_INIT));
    return (fmi2Status)rc_exit_init(c, "fmi2ExitInitializationMode");
}

fmi2Status fmi2Terminate(fmi2Component instance) {
    CHECK("fmi2Terminate", RC_M(RC_STEP));
    c->state = RC_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component instance) {
    RcInstance *c = (RcInstance *)instance;
    if (!c) return fmi2Error;
    rc_reset(c);
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component instance, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    CHECK("fmi2GetReal", RC_M_GET);
    return (fmi2Status)rc_get_reals(c, "fmi2GetReal", vr, nvr, value);
}

fmi2Status fmi2SetReal(fmi2Component instance, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    CHECK("fmi2SetReal", RC_M_SET);
    return (fmi2Status)rc_set_reals(c, "fmi2SetReal", vr, nvr, value);
}

fmi2Status fmi2DoStep(fmi2Component instance, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentCommunicationPoint) {
    CHECK("fmi2DoStep", RC_M(RC_STEP));
    RC_UNUSED(noSetFMUStatePriorToCurrentCommunicationPoint);
    return (fmi2Status)rc_do_step(c, "fmi2DoStep", currentCommunicationPoint, communicationStepSize);
}

/* ---- not provided ---- */

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    RC_UNUSED(vr); RC_UNUSED(nvr); RC_UNUSED(value); NOT_PROVIDED(c);
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    RC_UNUSED(vr); RC_UNUSED(nvr); RC_UNUSED(value); NOT_PROVIDED(c);
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    RC_UNUSED(vr); RC_UNUSED(nvr); RC_UNUSED(value); NOT_PROVIDED(c);
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    RC_UNUSED(vr); RC_UNUSED(nvr); RC_UNUSED(value); NOT_PROVIDED(c);
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    RC_UNUSED(vr); RC_UNUSED(nvr); RC_UNUSED(value); NOT_PROVIDED(c);
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    RC_UNUSED(vr); RC_UNUSED(nvr); RC_UNUSED(value); NOT_PROVIDED(c);
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate* FMUstate) {
    RC_UNUSED(FMUstate); NOT_PROVIDED(c);
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
    RC_UNUSED(FMUstate); NOT_PROVIDED(c);
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* FMUstate) {
    RC_UNUSED(FMUstate); NOT_PROVIDED(c);
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t* size) {
    RC_UNUSED(FMUstate); RC_UNUSED(size); NOT_PROVIDED(c);
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[], size_t size) {
    RC_UNUSED(FMUstate); RC_UNUSED(serializedState); RC_UNUSED(size); NOT_PROVIDED(c);
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size, fmi2FMUstate* FMUstate) {
    RC_UNUSED(serializedState); RC_UNUSED(size); RC_UNUSED(FMUstate); NOT_PROVIDED(c);
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[], size_t nUnknown, const fmi2ValueReference vKnown_ref[], size_t nKnown, const fmi2Real dvKnown[], fmi2Real dvUnknown[]) {
    RC_UNUSED(vUnknown_ref); RC_UNUSED(nUnknown); RC_UNUSED(vKnown_ref); RC_UNUSED(nKnown); RC_UNUSED(dvKnown); RC_UNUSED(dvUnknown); NOT_PROVIDED(c);
}

fmi2Status fmi2EnterEventMode(fmi2Component c) {
    NOT_PROVIDED(c);
}

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo* fmi2eventInfo) {
    RC_UNUSED(fmi2eventInfo); NOT_PROVIDED(c);
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) {
    NOT_PROVIDED(c);
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint, fmi2Boolean* enterEventMode, fmi2Boolean* terminateSimulation) {
    RC_UNUSED(noSetFMUStatePriorToCurrentPoint); RC_UNUSED(enterEventMode); RC_UNUSED(terminateSimulation); NOT_PROVIDED(c);
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) {
    RC_UNUSED(time); NOT_PROVIDED(c);
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    RC_UNUSED(x); RC_UNUSED(nx); NOT_PROVIDED(c);
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx) {
    RC_UNUSED(derivatives); RC_UNUSED(nx); NOT_PROVIDED(c);
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni) {
    RC_UNUSED(eventIndicators); RC_UNUSED(ni); NOT_PROVIDED(c);
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    RC_UNUSED(x); RC_UNUSED(nx); NOT_PROVIDED(c);
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx) {
    RC_UNUSED(x_nominal); RC_UNUSED(nx); NOT_PROVIDED(c);
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer order[], const fmi2Real value[]) {
    RC_UNUSED(vr); RC_UNUSED(nvr); RC_UNUSED(order); RC_UNUSED(value); NOT_PROVIDED(c);
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer order[], fmi2Real value[]) {
    RC_UNUSED(vr); RC_UNUSED(nvr); RC_UNUSED(order); RC_UNUSED(value); NOT_PROVIDED(c);
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    NOT_PROVIDED(c);
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status* value) {
    RC_UNUSED(s); RC_UNUSED(value); NOT_PROVIDED(c);
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real* value) {
    RC_UNUSED(s); RC_UNUSED(value); NOT_PROVIDED(c);
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer* value) {
    RC_UNUSED(s); RC_UNUSED(value); NOT_PROVIDED(c);
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean* value) {
    RC_UNUSED(s); RC_UNUSED(value); NOT_PROVIDED(c);
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String* value) {
    RC_UNUSED(s); RC_UNUSED(value); NOT_PROVIDED(c);
}

