/* FMI 3.0 functions this FMU does not provide: clocks, Scheduled Execution, configuration mode, dependencies.
 *
 * Hand-written and model-agnostic, beside the FMI 3.0 API file rbfmu_fmi3.c: every one
 * returns fmi3Error in every state with a message saying why (docs/fmi_layer.md), and is
 * exported, since importers such as fmpy look up every symbol of the standard. */
#include "fmi3Functions.h"
#include "rbfmu_core.h"

/* Logs and returns the refusal; the function's name from __func__. */
#define NOT_PROVIDED(why)                                                         \
    do {                                                                          \
        Instance *c_ = (Instance *)instance;                                      \
        if (c_) RB_ERR(c_, "%s: not provided by this FMU (%s)", __func__, why);   \
        return fmi3Error;                                                         \
    } while (0)

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference valueReference,
                                               size_t *nDependencies) {
    UNUSED(valueReference); UNUSED(nDependencies);
    NOT_PROVIDED("no dependency information");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[], fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[],
                                       fmi3DependencyKind dependencyKinds[], size_t nDependencies) {
    UNUSED(dependent); UNUSED(elementIndicesOfDependent); UNUSED(independents);
    UNUSED(elementIndicesOfIndependents); UNUSED(dependencyKinds); UNUSED(nDependencies);
    NOT_PROVIDED("no dependency information");
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance) {
    NOT_PROVIDED("no structural parameters");
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance) {
    NOT_PROVIDED("no structural parameters");
}

fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, fmi3Float64 intervals[],
                                  fmi3IntervalQualifier qualifiers[]) {
    UNUSED(valueReferences); UNUSED(nValueReferences); UNUSED(intervals); UNUSED(qualifiers);
    NOT_PROVIDED("no clocks");
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[],
                                   fmi3IntervalQualifier qualifiers[]) {
    UNUSED(valueReferences); UNUSED(nValueReferences); UNUSED(counters); UNUSED(resolutions);
    UNUSED(qualifiers); NOT_PROVIDED("no clocks");
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, fmi3Float64 shifts[]) {
    UNUSED(valueReferences); UNUSED(nValueReferences); UNUSED(shifts); NOT_PROVIDED("no clocks");
}

fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[]) {
    UNUSED(valueReferences); UNUSED(nValueReferences); UNUSED(counters); UNUSED(resolutions);
    NOT_PROVIDED("no clocks");
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, const fmi3Float64 intervals[]) {
    UNUSED(valueReferences); UNUSED(nValueReferences); UNUSED(intervals);
    NOT_PROVIDED("no clocks");
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, const fmi3UInt64 counters[],
                                   const fmi3UInt64 resolutions[]) {
    UNUSED(valueReferences); UNUSED(nValueReferences); UNUSED(counters); UNUSED(resolutions);
    NOT_PROVIDED("no clocks");
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, const fmi3Float64 shifts[]) {
    UNUSED(valueReferences); UNUSED(nValueReferences); UNUSED(shifts); NOT_PROVIDED("no clocks");
}

fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, const fmi3UInt64 counters[],
                                const fmi3UInt64 resolutions[]) {
    UNUSED(valueReferences); UNUSED(nValueReferences); UNUSED(counters); UNUSED(resolutions);
    NOT_PROVIDED("no clocks");
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime) {
    UNUSED(clockReference); UNUSED(activationTime);
    NOT_PROVIDED("no Scheduled Execution");
}
