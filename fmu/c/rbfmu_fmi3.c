/* FMI 3.0 API (Co-Simulation and Model Exchange) over the generic core (rbfmu_core.c).
 *
 * Hand-written and model-agnostic. State machine in the style of the Modelica
 * Reference FMUs: every function checks that it may be called in the instance's
 * current state (docs/fmi_layer.md).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"
#include "rbfmu_core.h"

/* ---- Which instance states admit each call: the one table of these rules (the masks are
 * the state bits M_* of rbfmu_core.h). docs/fmi_layer.md §3 is generated from it
 * (fmu/fmi_rules.py) and tests/test_fmi_rules.py checks the fuzz model against it. ---- */
#define MASK_fmi3SetDebugLogging               (M_ANY | M_IUM)
#define MASK_fmi3EnterInitializationMode       M_INST
#define MASK_fmi3ExitInitializationMode        M_INIT
#define MASK_fmi3EnterEventMode                (M_CONT | M_EVENT)
#define MASK_fmi3Terminate                     (M_STEP | M_EVENT | M_CONT)
#define MASK_fmi3Reset                         M_ANY
#define MASK_fmi3SetFloat64                    (M_INST | M_INIT | M_STEP | M_EVENT | M_CONT | M_IUM)
#define MASK_fmi3GetFloat64                    (M_INIT | M_STEP | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi3GetInt64                      (M_INIT | M_STEP | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi3SetInt64                      (M_INST | M_INIT | M_STEP | M_EVENT)
#define MASK_fmi3DoStep                        M_STEP
#define MASK_fmi3EnterStepMode                 0
#define MASK_fmi3GetOutputDerivatives          (M_INIT | M_STEP | M_TERM | M_ERR)
#define MASK_fmi3EnterContinuousTimeMode       M_EVENT
#define MASK_fmi3CompletedIntegratorStep       M_CONT
#define MASK_fmi3SetTime                       (M_EVENT | M_CONT)
#define MASK_fmi3SetContinuousStates           M_CONT
#define MASK_fmi3GetContinuousStateDerivatives (M_INIT | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi3GetEventIndicators            (M_INIT | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi3GetContinuousStates           (M_INIT | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi3GetNominalsOfContinuousStates (M_INST | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi3GetNumberOfEventIndicators    M_ANY
#define MASK_fmi3GetNumberOfContinuousStates   M_ANY
#define MASK_fmi3UpdateDiscreteStates          M_EVENT
#define MASK_fmi3EvaluateDiscreteStates        (M_EVENT | M_CONT)
#define MASK_fmi3GetFMUState                   (M_INIT | M_STEP | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi3SetFMUState                   (M_INIT | M_STEP | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi3FreeFMUState                  M_ANY
#define MASK_fmi3SerializedFMUStateSize        M_ANY
#define MASK_fmi3SerializeFMUState             M_ANY
#define MASK_fmi3DeserializeFMUState           M_ANY
#define MASK_fmi3GetDirectionalDerivative      (M_INIT | M_STEP | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi3GetAdjointDerivative          (M_INIT | M_STEP | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi3GetClock                      (M_INIT | M_STEP | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi3SetClock                      (M_INST | M_INIT | M_STEP | M_EVENT | M_CONT)
#define MASK_fmi3GetBinary                     (M_INIT | M_STEP | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi3SetBinary                     (M_INST | M_INIT | M_STEP | M_EVENT | M_CONT)
#define MASK_fmi3GetFloat32                    (M_INIT | M_STEP | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi3SetFloat32                    (M_INST | M_INIT | M_STEP | M_EVENT | M_CONT)
#define MASK_fmi3GetInt8                       (M_INIT | M_STEP | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi3SetInt8                       (M_INST | M_INIT | M_STEP | M_EVENT | M_CONT)
#define MASK_fmi3GetUInt8                      (M_INIT | M_STEP | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi3SetUInt8                      (M_INST | M_INIT | M_STEP | M_EVENT | M_CONT)
#define MASK_fmi3GetInt16                      (M_INIT | M_STEP | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi3SetInt16                      (M_INST | M_INIT | M_STEP | M_EVENT | M_CONT)
#define MASK_fmi3GetUInt16                     (M_INIT | M_STEP | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi3SetUInt16                     (M_INST | M_INIT | M_STEP | M_EVENT | M_CONT)
#define MASK_fmi3GetInt32                      (M_INIT | M_STEP | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi3SetInt32                      (M_INST | M_INIT | M_STEP | M_EVENT | M_CONT)
#define MASK_fmi3GetUInt32                     (M_INIT | M_STEP | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi3SetUInt32                     (M_INST | M_INIT | M_STEP | M_EVENT | M_CONT)
#define MASK_fmi3GetUInt64                     (M_INIT | M_STEP | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi3SetUInt64                     (M_INST | M_INIT | M_STEP | M_EVENT | M_CONT)
#define MASK_fmi3GetBoolean                    (M_INIT | M_STEP | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi3SetBoolean                    (M_INST | M_INIT | M_STEP | M_EVENT | M_CONT)
#define MASK_fmi3GetString                     (M_INIT | M_STEP | M_EVENT | M_CONT | M_TERM | M_ERR)
#define MASK_fmi3SetString                     (M_INST | M_INIT | M_STEP | M_EVENT | M_CONT)

typedef struct {
    fmi3InstanceEnvironment env;
    fmi3LogMessageCallback log;
    fmi3IntermediateUpdateCallback update;
    bool free_requested; /* fmi3FreeInstance was called inside the callback: freed when doStep returns */
} Env3;

/* One environment per instance lives inside the instance's `callbacks` slot. */
static void log3(const Instance *c, RbStatus status, const char *category, const char *message) {
    const Env3 *e = (const Env3 *)c->importer.callbacks;
    if (e && e->log) e->log(e->env, (fmi3Status)status, category, message);
}

/* Intermediate update (FMI 3.0 §4.2.3): inside doStep, at a node time t of an internal step
 * (modelsrc/integrators.stage_nodes), the importer may set inputs in IntermediateUpdateMode.
 * Every such call is tentative (intermediateStepFinished = false: the step may still be
 * rejected and redone smaller, never before t of an earlier call's accepted step); no
 * outputs are offered (intermediateVariableGetAllowed = false) and no early return. */
static void ask3(Instance *c, double t) {
    const Env3 *e = (const Env3 *)c->importer.callbacks;
    fmi3Boolean early = fmi3False;
    fmi3Float64 early_time = t;
    if (e->free_requested) return; /* the importer let go of this instance: ask it nothing more */
    c->persistent.state = ST_INTERMEDIATE;
    e->update(e->env, t, fmi3True, fmi3False, fmi3False, fmi3False, &early, &early_time);
    c->persistent.state = ST_STEP;
}

/* Every function first checks that its instance's state admits it (table above); fn is its
 * name, for the core's messages. */
#define CHECK(F)                        \
    Instance *c = (Instance *)instance; \
    const char *const fn = #F;          \
    if (!rb_allowed(c, fn, MASK_##F)) return fmi3Error

#define RET(expr) return (fmi3Status)(expr)

static fmi3Instance instantiate(const char *fn, fmi3String instanceName, fmi3String instantiationToken,
                                InterfaceType type, fmi3Boolean loggingOn,
                                fmi3InstanceEnvironment instanceEnvironment, fmi3LogMessageCallback logMessage,
                                fmi3IntermediateUpdateCallback update) {
    Env3 tmp_env, *env;
    Instance *c;
    tmp_env.env = instanceEnvironment;
    tmp_env.log = logMessage;
    tmp_env.update = update;
    tmp_env.free_requested = false;
    c = rb_instantiate(fn, instanceName, instantiationToken, type, loggingOn, log3, NULL, &tmp_env);
    if (!c) return NULL;
    env = (Env3 *)malloc(sizeof(Env3)); /* owned by the instance, freed in fmi3FreeInstance */
    if (!env) {
        rb_free(c);
        return NULL;
    }
    *env = tmp_env;
    c->importer.callbacks = env;
    return c;
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken,
                                         fmi3String resourcePath, fmi3Boolean visible,
                                         fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
                                         fmi3Boolean earlyReturnAllowed,
                                         const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables,
                                         fmi3InstanceEnvironment instanceEnvironment,
                                         fmi3LogMessageCallback logMessage,
                                         fmi3IntermediateUpdateCallback intermediateUpdate) {
    Instance *c;
    char why[200], what[80];
    UNUSED(resourcePath); UNUSED(visible); UNUSED(earlyReturnAllowed);
    if (eventModeUsed) {
        snprintf(why, sizeof why, "%s: eventModeUsed=true but this FMU has no event mode (hasEventMode=false)",
                 __func__);
        if (logMessage) logMessage(instanceEnvironment, fmi3Error, "logStatusError", why);
        return NULL;
    }
    snprintf(what, sizeof what, "%s: requiredIntermediateVariables", __func__);
    if (!rb_inputs_only(what, requiredIntermediateVariables, nRequiredIntermediateVariables, why, sizeof why)) {
        if (logMessage) logMessage(instanceEnvironment, fmi3Error, "logStatusError", why);
        return NULL;
    }
    c = (Instance *)instantiate(__func__, instanceName, instantiationToken, RB_CO_SIMULATION, loggingOn,
                                instanceEnvironment, logMessage, intermediateUpdate);
    /* asked only when the importer gave a callback and said which inputs it will set */
    if (c && intermediateUpdate && nRequiredIntermediateVariables > 0) c->importer.ask = ask3;
    return c;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible,
                                          fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage) {
    UNUSED(resourcePath); UNUSED(visible);
    return instantiate(__func__, instanceName, instantiationToken, RB_MODEL_EXCHANGE, loggingOn, instanceEnvironment,
                       logMessage, NULL);
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken,
                                               fmi3String resourcePath, fmi3Boolean visible,
                                               fmi3Boolean loggingOn,
                                               fmi3InstanceEnvironment instanceEnvironment,
                                               fmi3LogMessageCallback logMessage,
                                               fmi3ClockUpdateCallback clockUpdate,
                                               fmi3LockPreemptionCallback lockPreemption,
                                               fmi3UnlockPreemptionCallback unlockPreemption) {
    UNUSED(instanceName); UNUSED(instantiationToken); UNUSED(resourcePath); UNUSED(visible);
    UNUSED(loggingOn); UNUSED(clockUpdate); UNUSED(lockPreemption); UNUSED(unlockPreemption);
    if (logMessage) {
        char why[120];
        snprintf(why, sizeof why, "%s: this FMU provides Co-Simulation and Model Exchange only", __func__);
        logMessage(instanceEnvironment, fmi3Error, "logStatusError", why);
    }
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance) {
    Instance *c = (Instance *)instance;
    if (!c) return;
    if (c->persistent.state == ST_INTERMEDIATE) {
        /* Called from the intermediate-update callback, inside fmi3DoStep (a call FMI 3.0
         * does not admit there): freeing now would leave the doStep running on freed memory,
         * refusing would leak an instance the importer believes gone. Deferred: the doStep
         * asks nothing more, ends with fmi3Error and frees the instance before it returns
         * (docs/fmi_layer.md, Intermediate update). */
        ((Env3 *)c->importer.callbacks)->free_requested = true;
        RB_ERR(c, "%s: called in state IntermediateUpdateMode (from the intermediate-update "
                  "callback): the instance is freed when the running fmi3DoStep returns, with fmi3Error", __func__);
        return;
    }
    free((void *)c->importer.callbacks);
    rb_state_free_all(c); /* the FMU states the importer did not free, then the instance */
    rb_free(c);
}

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[]) {
    CHECK(fmi3SetDebugLogging);
    UNUSED(nCategories); UNUSED(categories);
    c->importer.logging_on = loggingOn;
    return fmi3OK;
}

/* ---- initialisation, termination ---- */

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined,
                                       fmi3Float64 tolerance, fmi3Float64 startTime,
                                       fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    RbStatus status;
    CHECK(fmi3EnterInitializationMode);
    status = rb_enter_initialization(c, fn, startTime, stopTimeDefined, stopTime);
    if (status != RB_OK) RET(status);
    RET(rb_importer_tolerance(c, fn, toleranceDefined, tolerance));
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    CHECK(fmi3ExitInitializationMode);
    RET(rb_exit_initialization(c, fn));
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
    CHECK(fmi3EnterEventMode);
    c->persistent.state = ST_EVENT;
    return fmi3OK;
}

fmi3Status fmi3Terminate(fmi3Instance instance) {
    CHECK(fmi3Terminate); /* as the Reference FMUs: not in InitializationMode */
    c->persistent.state = ST_TERMINATED;
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance instance) {
    CHECK(fmi3Reset);
    rb_reset(c);
    return fmi3OK;
}

/* ---- variable access ---- */

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, const fmi3Float64 values[], size_t nValues) {
    CHECK(fmi3SetFloat64);
    if (nValues != nValueReferences) {
        RB_ERR(c, "%s: nValues (%zu) must equal nValueReferences (%zu) for scalar variables", fn,
               nValues, nValueReferences);
        return fmi3Error;
    }
    RET(rb_set_reals(c, fn, valueReferences, nValueReferences, values));
}

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, fmi3Float64 values[], size_t nValues) {
    CHECK(fmi3GetFloat64);
    if (nValues != nValueReferences) {
        RB_ERR(c, "%s: nValues (%zu) must equal nValueReferences (%zu) for scalar variables", fn,
               nValues, nValueReferences);
        return fmi3Error;
    }
    RET(rb_get_reals(c, fn, valueReferences, nValueReferences, values));
}

/* Int64: the one enumeration variable `method`. */
fmi3Status fmi3GetInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, fmi3Int64 values[], size_t nValues) {
    size_t i;
    long long v;
    CHECK(fmi3GetInt64);
    if (nValues != nValueReferences) {
        RB_ERR(c, "%s: nValues (%zu) must equal nValueReferences (%zu)", fn, nValues, nValueReferences);
        return fmi3Error;
    }
    if (!rb_arrays_given(c, fn, nValues, valueReferences, "valueReferences", values, "values")) return fmi3Error;
    for (i = 0; i < nValueReferences; i++) {
        if (rb_get_method(c, fn, valueReferences[i], &v) != RB_OK) return fmi3Error;
        values[i] = (fmi3Int64)v;
    }
    return fmi3OK;
}

fmi3Status fmi3SetInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, const fmi3Int64 values[], size_t nValues) {
    size_t i;
    long long buf[64];
    CHECK(fmi3SetInt64);
    if (nValues != nValueReferences) {
        RB_ERR(c, "%s: nValues (%zu) must equal nValueReferences (%zu)", fn, nValues, nValueReferences);
        return fmi3Error;
    }
    if (nValueReferences > 64) {
        RB_ERR(c, "%s: at most 64 values per call, got %zu", fn, nValueReferences);
        return fmi3Error;
    }
    if (!rb_arrays_given(c, fn, nValues, valueReferences, "valueReferences", values, "values")) return fmi3Error;
    for (i = 0; i < nValueReferences; i++) buf[i] = (long long)values[i];
    RET(rb_set_methods(c, fn, valueReferences, nValueReferences, buf));
}

/* Getters/setters of types this FMU has no variables of: a call with zero value
 * references is a no-op, any value reference is unknown for that type. */
#define NO_VARIABLES_OF_TYPE(F)                                                                       \
    do {                                                                                              \
        CHECK(F);                                                                                     \
        if (nValueReferences == 0) return fmi3OK;                                                     \
        if (!rb_arrays_given(c, fn, nValueReferences, valueReferences, "valueReferences", NULL, NULL)) \
            return fmi3Error;                                                                         \
        RB_ERR(c, "%s: value reference %u is not a variable of this type (the FMU has Float64 "       \
                  "variables and the Int64 enumeration 'method')", fn, valueReferences[0]);           \
        return fmi3Error;                                                                             \
    } while (0)

#define GETTER(T, CT)                                                                          \
    fmi3Status fmi3Get##T(fmi3Instance instance, const fmi3ValueReference valueReferences[],   \
                          size_t nValueReferences, CT values[], size_t nValues) {              \
        UNUSED(values); UNUSED(nValues);                                                       \
        NO_VARIABLES_OF_TYPE(fmi3Get##T);                                           \
    }
#define SETTER(T, CT)                                                                          \
    fmi3Status fmi3Set##T(fmi3Instance instance, const fmi3ValueReference valueReferences[],   \
                          size_t nValueReferences, const CT values[], size_t nValues) {        \
        UNUSED(values); UNUSED(nValues);                                                       \
        NO_VARIABLES_OF_TYPE(fmi3Set##T);                                           \
    }

GETTER(Float32, fmi3Float32) SETTER(Float32, fmi3Float32)
GETTER(Int8, fmi3Int8) SETTER(Int8, fmi3Int8)
GETTER(UInt8, fmi3UInt8) SETTER(UInt8, fmi3UInt8)
GETTER(Int16, fmi3Int16) SETTER(Int16, fmi3Int16)
GETTER(UInt16, fmi3UInt16) SETTER(UInt16, fmi3UInt16)
GETTER(Int32, fmi3Int32) SETTER(Int32, fmi3Int32)
GETTER(UInt32, fmi3UInt32) SETTER(UInt32, fmi3UInt32)
GETTER(UInt64, fmi3UInt64) SETTER(UInt64, fmi3UInt64)
GETTER(Boolean, fmi3Boolean) SETTER(Boolean, fmi3Boolean)
GETTER(String, fmi3String) SETTER(String, fmi3String)

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, fmi3Clock values[]) {
    UNUSED(values);
    NO_VARIABLES_OF_TYPE(fmi3GetClock);
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, const fmi3Clock values[]) {
    UNUSED(values);
    NO_VARIABLES_OF_TYPE(fmi3SetClock);
}

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, size_t valueSizes[], fmi3Binary values[], size_t nValues) {
    UNUSED(valueSizes); UNUSED(values); UNUSED(nValues);
    NO_VARIABLES_OF_TYPE(fmi3GetBinary);
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, const size_t valueSizes[], const fmi3Binary values[],
                         size_t nValues) {
    UNUSED(valueSizes); UNUSED(values); UNUSED(nValues);
    NO_VARIABLES_OF_TYPE(fmi3SetBinary);
}

/* ---- Co-Simulation ---- */

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                      fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime) {
    RbStatus status;
    CHECK(fmi3DoStep);
    UNUSED(noSetFMUStatePriorToCurrentPoint);
    if (eventHandlingNeeded) *eventHandlingNeeded = fmi3False;
    if (terminateSimulation) *terminateSimulation = fmi3False;
    if (earlyReturn) *earlyReturn = fmi3False;
    status = rb_do_step(c, fn, currentCommunicationPoint, communicationStepSize);
    if (lastSuccessfulTime) *lastSuccessfulTime = c->persistent.buf[0];
    if (((const Env3 *)c->importer.callbacks)->free_requested) { /* fmi3FreeInstance inside the callback */
        fmi3FreeInstance(instance);
        return fmi3Error;
    }
    RET(status);
}

fmi3Status fmi3EnterStepMode(fmi3Instance instance) {
    CHECK(fmi3EnterStepMode); /* no event mode in Co-Simulation: exitInitializationMode enters step mode */
    return fmi3Error;
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                    size_t nValueReferences, const fmi3Int32 orders[], fmi3Float64 values[],
                                    size_t nValues) {
    CHECK(fmi3GetOutputDerivatives);
    if (nValues != nValueReferences) {
        RB_ERR(c, "%s: nValues (%zu) must equal nValueReferences (%zu) for scalar variables", fn,
               nValues, nValueReferences);
        return fmi3Error;
    }
    RET(rb_output_derivatives(c, fn, valueReferences, nValueReferences, orders, values));
}

/* ---- Model Exchange ---- */

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) {
    CHECK(fmi3EnterContinuousTimeMode);
    c->persistent.state = ST_CONTINUOUS;
    return fmi3OK;
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation) {
    CHECK(fmi3CompletedIntegratorStep);
    UNUSED(noSetFMUStatePriorToCurrentPoint);
    if (enterEventMode) *enterEventMode = fmi3False;
    if (terminateSimulation) *terminateSimulation = fmi3False;
    return fmi3OK;
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) {
    CHECK(fmi3SetTime);
    RET(rb_set_time(c, fn, time));
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates) {
    CHECK(fmi3SetContinuousStates);
    RET(rb_set_states(c, fn, continuousStates, nContinuousStates));
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                             size_t nContinuousStates) {
    CHECK(fmi3GetContinuousStateDerivatives);
    RET(rb_get_derivatives(c, fn, derivatives, nContinuousStates));
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[],
                                  size_t nEventIndicators) {
    CHECK(fmi3GetEventIndicators);
    UNUSED(eventIndicators);
    if (nEventIndicators == 0) return fmi3OK;
    RB_ERR(c, "%s: this FMU has no event indicators, got nEventIndicators=%zu", fn,
           nEventIndicators);
    return fmi3Error;
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[],
                                   size_t nContinuousStates) {
    CHECK(fmi3GetContinuousStates);
    RET(rb_get_states(c, fn, continuousStates, nContinuousStates));
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[],
                                             size_t nContinuousStates) {
    CHECK(fmi3GetNominalsOfContinuousStates);
    RET(rb_get_nominals(c, fn, nominals, nContinuousStates));
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *nEventIndicators) {
    CHECK(fmi3GetNumberOfEventIndicators);
    RET(rb_put_count(c, fn, nEventIndicators, 0));
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates) {
    CHECK(fmi3GetNumberOfContinuousStates);
    RET(rb_put_count(c, fn, nContinuousStates, RB_NX));
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation,
                                    fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged,
                                    fmi3Boolean *nextEventTimeDefined, fmi3Float64 *nextEventTime) {
    CHECK(fmi3UpdateDiscreteStates);
    if (discreteStatesNeedUpdate) *discreteStatesNeedUpdate = fmi3False;
    if (terminateSimulation) *terminateSimulation = fmi3False;
    if (nominalsOfContinuousStatesChanged) *nominalsOfContinuousStatesChanged = fmi3False;
    if (valuesOfContinuousStatesChanged) *valuesOfContinuousStatesChanged = fmi3False;
    if (nextEventTimeDefined) *nextEventTimeDefined = fmi3False;
    if (nextEventTime) *nextEventTime = 0.0;
    return fmi3OK;
}

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) {
    CHECK(fmi3EvaluateDiscreteStates);
    return fmi3OK; /* no discrete states */
}

/* ---- FMU state ---- */

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    CHECK(fmi3GetFMUState);
    RET(rb_state_get(c, fn, (void **)FMUState));
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState) {
    CHECK(fmi3SetFMUState);
    RET(rb_state_set(c, fn, FMUState));
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    CHECK(fmi3FreeFMUState);
    RET(rb_state_free(c, fn, (void **)FMUState));
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t *size) {
    CHECK(fmi3SerializedFMUStateSize);
    RET(rb_state_size(c, fn, FMUState, size));
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState, fmi3Byte serializedState[],
                                 size_t size) {
    CHECK(fmi3SerializeFMUState);
    RET(rb_state_serialize(c, fn, FMUState, serializedState, size));
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[], size_t size,
                                   fmi3FMUState *FMUState) {
    CHECK(fmi3DeserializeFMUState);
    RET(rb_state_deserialize(c, fn, serializedState, size, (void **)FMUState));
}

/* ---- derivatives (generated CasADi Jacobian) ---- */

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                        size_t nUnknowns, const fmi3ValueReference knowns[], size_t nKnowns,
                                        const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[],
                                        size_t nSensitivity) {
    CHECK(fmi3GetDirectionalDerivative);
    RET(rb_directional(c, fn, unknowns, nUnknowns, knowns, nKnowns, seed, nSeed,
                       sensitivity, nSensitivity, false));
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                    size_t nUnknowns, const fmi3ValueReference knowns[], size_t nKnowns,
                                    const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[],
                                    size_t nSensitivity) {
    CHECK(fmi3GetAdjointDerivative);
    RET(rb_directional(c, fn, unknowns, nUnknowns, knowns, nKnowns, seed, nSeed,
                       sensitivity, nSensitivity, true));
}
