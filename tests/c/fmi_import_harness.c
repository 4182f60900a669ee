/* A minimal FMI 3.0 Co-Simulation importer for the platform tests: load a binary, step it, print values.
 *
 * Not part of any FMU. tests/platforms/test_platforms.py compiles it for the host (gcc) and for
 * the cross targets (zig cc) and runs it on each platform's binary of one FMU: natively,
 * under qemu-aarch64 (aarch64-linux) and under wine (x86_64-windows), like a C master
 * that knows nothing of rbfmu. Usage:
 *   fmi_import_harness LIBRARY TOKEN STEPS STEP_SIZE [VR=VALUE...] VR...
 * sets each VR=VALUE (Float64: an input or a parameter) before initialisation, then prints,
 * after initialisation and after every doStep, the time and the Float64 values of the
 * value references VR (%.17g: every bit of the double).
 */
#include <string.h>
#include <stdio.h>
#include <stdlib.h>

#include "fmi3Functions.h"

#ifdef _WIN32
#include <windows.h>
static void *open_library(const char *path) { return (void *)LoadLibraryA(path); }
static void *symbol(void *lib, const char *name) { return (void *)GetProcAddress((HMODULE)lib, name); }
#else
#include <dlfcn.h>
static void *open_library(const char *path) { return dlopen(path, RTLD_NOW | RTLD_LOCAL); }
static void *symbol(void *lib, const char *name) { return dlsym(lib, name); }
#endif

static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message) {
    (void)env;
    fprintf(stderr, "[%d %s] %s\n", (int)status, category, message);
}

#define LOOKUP(type, name)                                           \
    type name = (type)symbol(lib, #name);                           \
    if (!name) {                                                     \
        fprintf(stderr, "missing symbol %s\n", #name);               \
        return 3;                                                    \
    }

static void print_values(double t, const double *v, size_t n) {
    printf("%.17g", t);
    for (size_t k = 0; k < n; k++) printf(" %.17g", v[k]);
    printf("\n");
}

int main(int argc, char **argv) {
    if (argc < 6) {
        fprintf(stderr, "usage: %s LIBRARY TOKEN STEPS STEP_SIZE [VR=VALUE...] VR...\n", argv[0]);
        return 2;
    }
    void *lib = open_library(argv[1]);
    if (!lib) {
        fprintf(stderr, "cannot load %s\n", argv[1]);
        return 3;
    }
    LOOKUP(fmi3InstantiateCoSimulationTYPE *, fmi3InstantiateCoSimulation)
    LOOKUP(fmi3EnterInitializationModeTYPE *, fmi3EnterInitializationMode)
    LOOKUP(fmi3ExitInitializationModeTYPE *, fmi3ExitInitializationMode)
    LOOKUP(fmi3DoStepTYPE *, fmi3DoStep)
    LOOKUP(fmi3GetFloat64TYPE *, fmi3GetFloat64)
    LOOKUP(fmi3SetFloat64TYPE *, fmi3SetFloat64)
    LOOKUP(fmi3TerminateTYPE *, fmi3Terminate)
    LOOKUP(fmi3FreeInstanceTYPE *, fmi3FreeInstance)
    long steps = strtol(argv[3], NULL, 10);
    double h = strtod(argv[4], NULL);
    int first = 5; /* the first VR to print: after the VR=VALUE settings */
    while (first < argc && strchr(argv[first], '=')) first++;
    size_t n = (size_t)(argc - first);
    fmi3ValueReference *vrs = malloc((n > 0 ? n : 1) * sizeof *vrs);
    double *values = malloc((n > 0 ? n : 1) * sizeof *values);
    if (!vrs || !values) return 4;
    for (size_t k = 0; k < n; k++) vrs[k] = (fmi3ValueReference)strtoul(argv[first + k], NULL, 10);

    fmi3Instance inst = fmi3InstantiateCoSimulation("harness", argv[2], NULL, fmi3False, fmi3False, fmi3False,
                                                    fmi3False, NULL, 0, NULL, logger, NULL);
    if (!inst) return 5;
    for (int k = 5; k < first; k++) {
        fmi3ValueReference vr = (fmi3ValueReference)strtoul(argv[k], NULL, 10);
        fmi3Float64 value = strtod(strchr(argv[k], '=') + 1, NULL);
        if (fmi3SetFloat64(inst, &vr, 1, &value, 1) != fmi3OK) return 9;
    }
    if (fmi3EnterInitializationMode(inst, fmi3False, 0.0, 0.0, fmi3False, 0.0) != fmi3OK) return 6;
    if (fmi3ExitInitializationMode(inst) != fmi3OK) return 6;
    if (fmi3GetFloat64(inst, vrs, n, values, n) != fmi3OK) return 7;
    print_values(0.0, values, n);
    for (long i = 0; i < steps; i++) {
        fmi3Boolean event = fmi3False, terminate = fmi3False, early = fmi3False;
        fmi3Float64 last = 0.0;
        if (fmi3DoStep(inst, (double)i * h, h, fmi3True, &event, &terminate, &early, &last) != fmi3OK) return 8;
        if (fmi3GetFloat64(inst, vrs, n, values, n) != fmi3OK) return 7;
        print_values((double)(i + 1) * h, values, n);
    }
    fmi3Terminate(inst);
    fmi3FreeInstance(inst);
    free(vrs);
    free(values);
    return 0;
}
