/* Test-only accessors (tests/harness/extreme_harness.py): the internal steps and the work of an instance's last fmi3DoStep.
 * Numbers the FMI API does not expose.
 *
 * Compiled into its own small shared library against the rbfmu_core.h / model_data.h of
 * a built FMU's sources/, so its `Instance` layout is that FMU's; it is called with an
 * instance handle returned by the FMU's own binary (which stays the code under test). */
#include "rbfmu_core.h"

__attribute__((visibility("default"))) long rbtest_last_substeps(const void *instance) {
    return instance ? ((const Instance *)instance)->step.last_substeps : -1;
}

/* Right-hand-side evaluations the last doStep was charged (rbfmu_budget.c). */
__attribute__((visibility("default"))) double rbtest_last_work(const void *instance) {
    return instance ? ((const Instance *)instance)->step.last_work : -1.0;
}
