/* Heap-use harness for the FMU's C layer (tests/robustness/test_fuzz_fmi.py::test_no_heap_use_in_do_step).
 *
 * Linked with the sources/ of a built FMU (rbfmu_fmi3.c, rbfmu_core.c, model_funcs.c) and
 * -Wl,--wrap=malloc,--wrap=calloc,--wrap=realloc,--wrap=free, so every call the FMU's
 * code makes to these four functions goes through the counters below (calls made inside
 * the C library itself, e.g. by vsnprintf, are not seen). Prints one line per phase:
 *   phase=<name> malloc=<n> calloc=<n> realloc=<n> free=<n>
 * then `total_alloc=<n> total_free=<n>` (allocations and non-NULL frees over the whole run),
 * `messages=<n>` (log messages received) and `done`. Exit code 0 unless an FMI call
 * that must succeed fails (then it prints `fail=<what>` and exits 1).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"
#include "rbfmu_core.h"

static long n_malloc, n_calloc, n_realloc, n_free, n_messages;
static long total_alloc, total_free; /* over the whole run, never reset */

/* the C library's functions (--wrap renames them): default visibility, not the hidden one
 * rbfmu_build.h gives every later declaration */
#pragma GCC visibility push(default)
void *__real_malloc(size_t size);
void *__real_calloc(size_t n, size_t size);
void *__real_realloc(void *p, size_t size);
void __real_free(void *p);
#pragma GCC visibility pop

void *__wrap_malloc(size_t size) { n_malloc++; total_alloc++; return __real_malloc(size); }
void *__wrap_calloc(size_t n, size_t size) { n_calloc++; total_alloc++; return __real_calloc(n, size); }
void *__wrap_realloc(void *p, size_t size) { n_realloc++; return __real_realloc(p, size); }
void __wrap_free(void *p) {
    if (p) total_free++; /* free(NULL) releases nothing */
    n_free++;
    __real_free(p);
}

static void reset_counts(void) { n_malloc = n_calloc = n_realloc = n_free = 0; }

static void report(const char *phase) {
    printf("phase=%s malloc=%ld calloc=%ld realloc=%ld free=%ld\n", phase, n_malloc, n_calloc, n_realloc, n_free);
    reset_counts();
}

static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message) {
    (void)env; (void)status; (void)category; (void)message;
    n_messages++; /* no allocation here: the harness must not count its own */
}

static void must(int ok, const char *what) {
    if (!ok) {
        printf("fail=%s\n", what);
        exit(1);
    }
}

static fmi3Instance make(const char *name) {
    return fmi3InstantiateCoSimulation(name, RB_INSTANTIATION_TOKEN, NULL, fmi3False, fmi3True, fmi3False,
                                       fmi3False, NULL, 0, NULL, logger, NULL);
}

static fmi3Status step(fmi3Instance inst, double t, double h) {
    fmi3Boolean a, b, c;
    fmi3Float64 last;
    return fmi3DoStep(inst, t, h, fmi3False, &a, &b, &c, &last);
}

int main(void) {
    fmi3Instance inst, other;
    fmi3FMUState state = NULL, copy = NULL;
    fmi3ValueReference vr_all[RB_NV], vr_method = RB_VR_METHOD, vr_hmax = RB_VR_HMAX, vr_u0 = RB_OFF_U;
    fmi3Float64 values[RB_NV], x;
    fmi3Int64 method;
    unsigned char bytes[4096];
    size_t size = 0;
    double t;
    int i, k, m;
    for (i = 0; i < RB_NV; i++) vr_all[i] = (fmi3ValueReference)i;

    /* creation and destruction, Co-Simulation and Model Exchange; a refused instantiation */
    reset_counts();
    inst = make("a");
    must(inst != NULL, "instantiate");
    fmi3FreeInstance(inst);
    inst = fmi3InstantiateModelExchange("me", RB_INSTANTIATION_TOKEN, NULL, fmi3False, fmi3False, NULL, logger);
    must(inst != NULL, "instantiate ME");
    fmi3FreeInstance(inst);
    report("lifecycle");
    must(fmi3InstantiateCoSimulation("b", "{wrong}", NULL, fmi3False, fmi3False, fmi3False, fmi3False, NULL, 0,
                                     NULL, logger, NULL) == NULL, "wrong token refused");
    report("refused_instantiation");

    /* every method: the step loop with everything an importer does between steps */
    for (m = 0; m < RB_NMETHODS; m++) {
        inst = make("s");
        method = rb_method_values[m];
        must(fmi3SetInt64(inst, &vr_method, 1, &method, 1) == fmi3OK, "set method");
        must(fmi3EnterInitializationMode(inst, fmi3False, 0.0, 0.0, fmi3False, 0.0) == fmi3OK, "enter init");
        must(fmi3ExitInitializationMode(inst) == fmi3OK, "exit init");
        reset_counts();
        t = 0.0;
        for (k = 0; k < 200; k++) {
            if (RB_NU > 0) {
                x = (k & 1) ? 0.5 : -0.5; /* a torque switching sign every step */
                must(fmi3SetFloat64(inst, &vr_u0, 1, &x, 1) == fmi3OK, "set input");
            }
            must(step(inst, t, 1e-2) == fmi3OK, "doStep");
            t += 1e-2;
            must(fmi3GetFloat64(inst, vr_all, RB_NV, values, RB_NV) == fmi3OK, "get all");
        }
        must(fmi3GetInt64(inst, &vr_method, 1, &method, 1) == fmi3OK, "get method");
        /* refused calls log a message: no allocation on the error paths either */
        must(step(inst, t, 0.0) == fmi3Error, "zero step refused");
        must(step(inst, t + 1.0, 1e-2) == fmi3Error, "wrong time refused");
        x = -1.0;
        must(fmi3SetFloat64(inst, &vr_hmax, 1, &x, 1) == fmi3Error, "bad h_max refused");
        x = 1e-12; /* valid, but the next step would need > 1e8 substeps */
        must(fmi3SetFloat64(inst, &vr_hmax, 1, &x, 1) == fmi3OK, "tiny h_max");
        must(step(inst, t, 1.0) == fmi3Error, "too many substeps refused");
        x = 1e-3;
        must(fmi3SetFloat64(inst, &vr_hmax, 1, &x, 1) == fmi3OK, "h_max back");
        if (RB_NU > 0 && rb_method_values[m] == 1) { /* rk4: a step whose state overflows: 10 refinements */
            x = 1e200;
            must(fmi3SetFloat64(inst, &vr_u0, 1, &x, 1) == fmi3OK, "huge torque");
            must(step(inst, t, 1e-2) == fmi3Error, "overflow refused");
        }
        {
            char phase[64];
            snprintf(phase, sizeof phase, "step_%s", rb_method_names[m]);
            report(phase);
        }
        must(fmi3Terminate(inst) == fmi3OK, "terminate");
        must(fmi3Reset(inst) == fmi3OK, "reset");
        report("terminate_reset");
        fmi3FreeInstance(inst);
        reset_counts();
    }

    /* FMU state: allocates by design (docs/fmi_layer.md); must be balanced */
    inst = make("f");
    other = make("g");
    must(fmi3EnterInitializationMode(inst, fmi3False, 0.0, 0.0, fmi3False, 0.0) == fmi3OK, "enter init");
    must(fmi3ExitInitializationMode(inst) == fmi3OK, "exit init");
    must(fmi3EnterInitializationMode(other, fmi3False, 0.0, 0.0, fmi3False, 0.0) == fmi3OK, "enter init");
    must(fmi3ExitInitializationMode(other) == fmi3OK, "exit init");
    reset_counts();
    must(fmi3GetFMUState(inst, &state) == fmi3OK, "get state");
    must(fmi3GetFMUState(inst, &state) == fmi3OK, "get state again (overwrite)");
    must(step(inst, 0.0, 1e-2) == fmi3OK, "doStep");
    must(fmi3SetFMUState(inst, state) == fmi3OK, "set state");
    must(fmi3SerializedFMUStateSize(inst, state, &size) == fmi3OK && size <= sizeof bytes, "size");
    must(fmi3SerializeFMUState(inst, state, bytes, size) == fmi3OK, "serialize");
    must(fmi3DeserializeFMUState(other, bytes, size, &copy) == fmi3OK, "deserialize");
    must(fmi3SetFMUState(other, copy) == fmi3OK, "set copy");
    bytes[0] ^= 0x5A;
    {
        fmi3FMUState bad = NULL;
        must(fmi3DeserializeFMUState(other, bytes, size, &bad) == fmi3Error && bad == NULL, "corrupt refused");
    }
    must(fmi3FreeFMUState(inst, &state) == fmi3OK && state == NULL, "free state");
    must(fmi3FreeFMUState(other, &copy) == fmi3OK && copy == NULL, "free copy");
    report("fmu_state");
    fmi3FreeInstance(inst);
    fmi3FreeInstance(other);
    report("free");
    printf("total_alloc=%ld total_free=%ld\nmessages=%ld\ndone\n", total_alloc, total_free, n_messages);
    return 0;
}
