/* FMI 3.0 Co-Simulation API of a sampled-data controller FMU over its core (rbctl_core.c).
 *
 * Hand-written and model-agnostic. Provides instantiation, initialisation, Float64 access and
 * doStep; every other function of the standard is exported (importers look them all up) and
 * returns fmi3Error with a message saying it is not provided. */
#include <stdio.h>
#include <string.h>

#include "fmi3Functions.h"
#include "rbctl_core.h"

#define CHECK(F, mask)                                                                   \
    RcInstance *c = (RcInstance *)instance;                                              \
    if (!c) return fmi3Error;                                                            \
    if (rc_state_allows(c, F, mask) != RC_OK) return fmi3Error

#define NOT_PROVIDED(inst)                                                                            \
    do {                                                                                              \
        RcInstance *c_ = (RcInstance *)(inst);                                                        \
        if (c_) rc_logf(c_, RC_ERROR, "%s: not provided by this controller FMU (Co-Simulation, Float64 " \
                        "variables only)", __func__);                                                 \
        return fmi3Error;                                                                             \
    } while (0)

static void log_fmi3(const RcInstance *c, RcStatus status, const char *category, const char *message) {
    fmi3LogMessageCallback cb = (fmi3LogMessageCallback)c->logger;
    if (cb) cb((fmi3InstanceEnvironment)c->env, (fmi3Status)status, category, message);
}

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[]) {
    RcInstance *c = (RcInstance *)instance;
    RC_UNUSED(nCategories); RC_UNUSED(categories);
    if (!c) return fmi3Error;
    c->logging_on = loggingOn;
    return fmi3OK;
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken,
                                         fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                         fmi3Boolean eventModeUsed, fmi3Boolean earlyReturnAllowed,
                                         const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables,
                                         fmi3InstanceEnvironment instanceEnvironment, fmi3LogMessageCallback logMessage,
                                         fmi3IntermediateUpdateCallback intermediateUpdate) {
    RcInstance *c;
    RC_UNUSED(resourcePath); RC_UNUSED(visible); RC_UNUSED(earlyReturnAllowed);
    RC_UNUSED(requiredIntermediateVariables); RC_UNUSED(nRequiredIntermediateVariables); RC_UNUSED(intermediateUpdate);
    if (!instantiationToken || strcmp(instantiationToken, RC_INSTANTIATION_TOKEN) != 0) {
        if (logMessage) logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                                   "fmi3InstantiateCoSimulation: instantiation token does not match this FMU's");
        return NULL;
    }
    if (eventModeUsed) {
        if (logMessage) logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                                   "fmi3InstantiateCoSimulation: event mode is not provided (hasEventMode=false)");
        return NULL;
    }
    c = rc_new(instanceName, log_fmi3, (void *)instanceEnvironment, (void *)logMessage);
    if (c) c->logging_on = loggingOn;
    return (fmi3Instance)c;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage) {
    RC_UNUSED(instanceName); RC_UNUSED(instantiationToken); RC_UNUSED(resourcePath); RC_UNUSED(visible);
    RC_UNUSED(loggingOn);
    if (logMessage) logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                               "fmi3InstantiateModelExchange: a controller FMU is Co-Simulation only");
    return NULL;
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken,
                                               fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                               fmi3InstanceEnvironment instanceEnvironment,
                                               fmi3LogMessageCallback logMessage,
                                               fmi3ClockUpdateCallback clockUpdate,
                                               fmi3LockPreemptionCallback lockPreemption,
                                               fmi3UnlockPreemptionCallback unlockPreemption) {
    RC_UNUSED(instanceName); RC_UNUSED(instantiationToken); RC_UNUSED(resourcePath); RC_UNUSED(visible);
    RC_UNUSED(loggingOn); RC_UNUSED(clockUpdate); RC_UNUSED(lockPreemption); RC_UNUSED(unlockPreemption);
    if (logMessage) logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                               "fmi3InstantiateScheduledExecution: a controller FMU is Co-Simulation only");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance) { rc_free((RcInstance *)instance); }

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined, fmi3Float64 tolerance,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    CHECK("fmi3EnterInitializationMode", RC_M(RC_INSTANTIATED));
    RC_UNUSED(toleranceDefined); RC_UNUSED(tolerance); RC_UNUSED(stopTimeDefined); RC_UNUSED(stopTime);
    return (fmi3Status)rc_enter_init(c, "fmi3EnterInitializationMode", startTime);
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    CHECK("fmi3ExitInitializationMode", RC_M(RC_INIT));
    return (fmi3Status)rc_exit_init(c, "fmi3ExitInitializationMode");
}

fmi3Status fmi3Terminate(fmi3Instance instance) {
    CHECK("fmi3Terminate", RC_M(RC_STEP));
    c->state = RC_TERMINATED;
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance instance) {
    RcInstance *c = (RcInstance *)instance;
    if (!c) return fmi3Error;
    rc_reset(c);
    return fmi3OK;
}

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                          fmi3Float64 values[], size_t nValues) {
    CHECK("fmi3GetFloat64", RC_M_GET);
    if (nValues != nValueReferences) {
        rc_logf(c, RC_ERROR, "fmi3GetFloat64: nValues %zu differs from nValueReferences %zu (scalars only)", nValues,
                nValueReferences);
        return fmi3Error;
    }
    return (fmi3Status)rc_get_reals(c, "fmi3GetFloat64", valueReferences, nValueReferences, values);
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                          const fmi3Float64 values[], size_t nValues) {
    CHECK("fmi3SetFloat64", RC_M_SET);
    if (nValues != nValueReferences) {
        rc_logf(c, RC_ERROR, "fmi3SetFloat64: nValues %zu differs from nValueReferences %zu (scalars only)", nValues,
                nValueReferences);
        return fmi3Error;
    }
    return (fmi3Status)rc_set_reals(c, "fmi3SetFloat64", valueReferences, nValueReferences, values);
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint, fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint, fmi3Boolean *eventHandlingNeeded,
                      fmi3Boolean *terminateSimulation, fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime) {
    RcStatus s;
    CHECK("fmi3DoStep", RC_M(RC_STEP));
    RC_UNUSED(noSetFMUStatePriorToCurrentPoint);
    s = rc_do_step(c, "fmi3DoStep", currentCommunicationPoint, communicationStepSize);
    if (eventHandlingNeeded) *eventHandlingNeeded = fmi3False;
    if (terminateSimulation) *terminateSimulation = fmi3False;
    if (earlyReturn) *earlyReturn = fmi3False;
    if (lastSuccessfulTime) *lastSuccessfulTime = c->v[0];
    return (fmi3Status)s;
}

/* ---- not provided ---- */

fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
    NOT_PROVIDED(instance);
}

fmi3Status fmi3GetFloat32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Float32 values[], size_t nValues) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(values); RC_UNUSED(nValues); NOT_PROVIDED(instance);
}

fmi3Status fmi3GetInt8(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Int8 values[], size_t nValues) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(values); RC_UNUSED(nValues); NOT_PROVIDED(instance);
}

fmi3Status fmi3GetUInt8(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt8 values[], size_t nValues) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(values); RC_UNUSED(nValues); NOT_PROVIDED(instance);
}

fmi3Status fmi3GetInt16(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Int16 values[], size_t nValues) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(values); RC_UNUSED(nValues); NOT_PROVIDED(instance);
}

fmi3Status fmi3GetUInt16(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt16 values[], size_t nValues) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(values); RC_UNUSED(nValues); NOT_PROVIDED(instance);
}

fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Int32 values[], size_t nValues) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(values); RC_UNUSED(nValues); NOT_PROVIDED(instance);
}

fmi3Status fmi3GetUInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt32 values[], size_t nValues) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(values); RC_UNUSED(nValues); NOT_PROVIDED(instance);
}

fmi3Status fmi3GetInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Int64 values[], size_t nValues) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(values); RC_UNUSED(nValues); NOT_PROVIDED(instance);
}

fmi3Status fmi3GetUInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt64 values[], size_t nValues) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(values); RC_UNUSED(nValues); NOT_PROVIDED(instance);
}

fmi3Status fmi3GetBoolean(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Boolean values[], size_t nValues) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(values); RC_UNUSED(nValues); NOT_PROVIDED(instance);
}

fmi3Status fmi3GetString(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3String values[], size_t nValues) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(values); RC_UNUSED(nValues); NOT_PROVIDED(instance);
}

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, size_t valueSizes[], fmi3Binary values[], size_t nValues) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(valueSizes); RC_UNUSED(values); RC_UNUSED(nValues); NOT_PROVIDED(instance);
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Clock values[]) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(values); NOT_PROVIDED(instance);
}

fmi3Status fmi3SetFloat32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Float32 values[], size_t nValues) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(values); RC_UNUSED(nValues); NOT_PROVIDED(instance);
}

fmi3Status fmi3SetInt8(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Int8 values[], size_t nValues) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(values); RC_UNUSED(nValues); NOT_PROVIDED(instance);
}

fmi3Status fmi3SetUInt8(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt8 values[], size_t nValues) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(values); RC_UNUSED(nValues); NOT_PROVIDED(instance);
}

fmi3Status fmi3SetInt16(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Int16 values[], size_t nValues) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(values); RC_UNUSED(nValues); NOT_PROVIDED(instance);
}

fmi3Status fmi3SetUInt16(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt16 values[], size_t nValues) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(values); RC_UNUSED(nValues); NOT_PROVIDED(instance);
}

fmi3Status fmi3SetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Int32 values[], size_t nValues) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(values); RC_UNUSED(nValues); NOT_PROVIDED(instance);
}

fmi3Status fmi3SetUInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt32 values[], size_t nValues) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(values); RC_UNUSED(nValues); NOT_PROVIDED(instance);
}

fmi3Status fmi3SetInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Int64 values[], size_t nValues) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(values); RC_UNUSED(nValues); NOT_PROVIDED(instance);
}

fmi3Status fmi3SetUInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt64 values[], size_t nValues) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(values); RC_UNUSED(nValues); NOT_PROVIDED(instance);
}

fmi3Status fmi3SetBoolean(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Boolean values[], size_t nValues) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(values); RC_UNUSED(nValues); NOT_PROVIDED(instance);
}

fmi3Status fmi3SetString(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3String values[], size_t nValues) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(values); RC_UNUSED(nValues); NOT_PROVIDED(instance);
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const size_t valueSizes[], const fmi3Binary values[], size_t nValues) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(valueSizes); RC_UNUSED(values); RC_UNUSED(nValues); NOT_PROVIDED(instance);
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Clock values[]) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(values); NOT_PROVIDED(instance);
}

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference valueReference, size_t* nDependencies) {
    RC_UNUSED(valueReference); RC_UNUSED(nDependencies); NOT_PROVIDED(instance);
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent, size_t elementIndicesOfDependent[], fmi3ValueReference independents[], size_t elementIndicesOfIndependents[], fmi3DependencyKind dependencyKinds[], size_t nDependencies) {
    RC_UNUSED(dependent); RC_UNUSED(elementIndicesOfDependent); RC_UNUSED(independents); RC_UNUSED(elementIndicesOfIndependents); RC_UNUSED(dependencyKinds); RC_UNUSED(nDependencies); NOT_PROVIDED(instance);
}

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState* FMUState) {
    RC_UNUSED(FMUState); NOT_PROVIDED(instance);
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState) {
    RC_UNUSED(FMUState); NOT_PROVIDED(instance);
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState* FMUState) {
    RC_UNUSED(FMUState); NOT_PROVIDED(instance);
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t* size) {
    RC_UNUSED(FMUState); RC_UNUSED(size); NOT_PROVIDED(instance);
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState, fmi3Byte serializedState[], size_t size) {
    RC_UNUSED(FMUState); RC_UNUSED(serializedState); RC_UNUSED(size); NOT_PROVIDED(instance);
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[], size_t size, fmi3FMUState* FMUState) {
    RC_UNUSED(serializedState); RC_UNUSED(size); RC_UNUSED(FMUState); NOT_PROVIDED(instance);
}

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns, const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    RC_UNUSED(unknowns); RC_UNUSED(nUnknowns); RC_UNUSED(knowns); RC_UNUSED(nKnowns); RC_UNUSED(seed); RC_UNUSED(nSeed); RC_UNUSED(sensitivity); RC_UNUSED(nSensitivity); NOT_PROVIDED(instance);
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns, const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    RC_UNUSED(unknowns); RC_UNUSED(nUnknowns); RC_UNUSED(knowns); RC_UNUSED(nKnowns); RC_UNUSED(seed); RC_UNUSED(nSeed); RC_UNUSED(sensitivity); RC_UNUSED(nSensitivity); NOT_PROVIDED(instance);
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance) {
    NOT_PROVIDED(instance);
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance) {
    NOT_PROVIDED(instance);
}

fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Float64 intervals[], fmi3IntervalQualifier qualifiers[]) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(intervals); RC_UNUSED(qualifiers); NOT_PROVIDED(instance);
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[], fmi3IntervalQualifier qualifiers[]) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(counters); RC_UNUSED(resolutions); RC_UNUSED(qualifiers); NOT_PROVIDED(instance);
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Float64 shifts[]) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(shifts); NOT_PROVIDED(instance);
}

fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[]) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(counters); RC_UNUSED(resolutions); NOT_PROVIDED(instance);
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Float64 intervals[]) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(intervals); NOT_PROVIDED(instance);
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt64 counters[], const fmi3UInt64 resolutions[]) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(counters); RC_UNUSED(resolutions); NOT_PROVIDED(instance);
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Float64 shifts[]) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(shifts); NOT_PROVIDED(instance);
}

fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt64 counters[], const fmi3UInt64 resolutions[]) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(counters); RC_UNUSED(resolutions); NOT_PROVIDED(instance);
}

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) {
    NOT_PROVIDED(instance);
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean* discreteStatesNeedUpdate, fmi3Boolean* terminateSimulation, fmi3Boolean* nominalsOfContinuousStatesChanged, fmi3Boolean* valuesOfContinuousStatesChanged, fmi3Boolean* nextEventTimeDefined, fmi3Float64* nextEventTime) {
    RC_UNUSED(discreteStatesNeedUpdate); RC_UNUSED(terminateSimulation); RC_UNUSED(nominalsOfContinuousStatesChanged); RC_UNUSED(valuesOfContinuousStatesChanged); RC_UNUSED(nextEventTimeDefined); RC_UNUSED(nextEventTime); NOT_PROVIDED(instance);
}

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) {
    NOT_PROVIDED(instance);
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint, fmi3Boolean* enterEventMode, fmi3Boolean* terminateSimulation) {
    RC_UNUSED(noSetFMUStatePriorToCurrentPoint); RC_UNUSED(enterEventMode); RC_UNUSED(terminateSimulation); NOT_PROVIDED(instance);
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) {
    RC_UNUSED(time); NOT_PROVIDED(instance);
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[], size_t nContinuousStates) {
    RC_UNUSED(continuousStates); RC_UNUSED(nContinuousStates); NOT_PROVIDED(instance);
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[], size_t nContinuousStates) {
    RC_UNUSED(derivatives); RC_UNUSED(nContinuousStates); NOT_PROVIDED(instance);
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[], size_t nEventIndicators) {
    RC_UNUSED(eventIndicators); RC_UNUSED(nEventIndicators); NOT_PROVIDED(instance);
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[], size_t nContinuousStates) {
    RC_UNUSED(continuousStates); RC_UNUSED(nContinuousStates); NOT_PROVIDED(instance);
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[], size_t nContinuousStates) {
    RC_UNUSED(nominals); RC_UNUSED(nContinuousStates); NOT_PROVIDED(instance);
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t* nEventIndicators) {
    RC_UNUSED(nEventIndicators); NOT_PROVIDED(instance);
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t* nContinuousStates) {
    RC_UNUSED(nContinuousStates); NOT_PROVIDED(instance);
}

fmi3Status fmi3EnterStepMode(fmi3Instance instance) {
    NOT_PROVIDED(instance);
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Int32 orders[], fmi3Float64 values[], size_t nValues) {
    RC_UNUSED(valueReferences); RC_UNUSED(nValueReferences); RC_UNUSED(orders); RC_UNUSED(values); RC_UNUSED(nValues); NOT_PROVIDED(instance);
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference, fmi3Float64 activationTime) {
    RC_UNUSED(clockReference); RC_UNUSED(activationTime); NOT_PROVIDED(instance);
}

