/* Benchmark harness (not part of any FMU): times one method's generated step in C and via fmi3DoStep.
 * The generated fixed step of one method called in a plain C loop, and the same work through
 * fmi3DoStep of the hand-written layer: one long doStep of N internal steps, and doSteps of 1
 * and of 10 internal steps called in a C loop, as a C master steps an FMU at its communication
 * step. Built by fmu/bench/benchmark.py against one scene's generated sources.
 * Usage: bench MODE N METHOD_VALUE H [X[NX] U[NU]]: N internal steps of H seconds of the method
 * with enumeration value METHOD_VALUE (the modelDescription's; 0: the FMU's first method).
 *   MODE time: best of 5 repeats of each; prints ns per raw step and per internal step of the
 *              long doStep, then the state after the raw steps;
 *   MODE loops: the same, and between them ns per doStep of 1 and per doStep of 10 internal steps
 *              (N/4 and N/40 doSteps: a doStep of one step costs a few raw steps);
 *   MODE raw | long | loop1 | loop10: one run of that part alone (for instruction counts:
 *              callgrind over N and 2N steps, fmu/bench/instructions.py), prints the final state.
 * The raw steps start from X with the inputs U held (default: the start values; the doSteps
 * take the start values).
 * Usage: bench cosim N METHOD_VALUE H TOLERANCE H_MAX REPEATS X[NX] U[NU]: a C master's run, N
 *        doSteps of H from X with the inputs U held, the FMU's tolerance and h_max as given
 *        (tools/basilisk_compare.py); prints the CPU seconds of the doSteps (best of REPEATS),
 *        the internal steps they took and the final state. */
#define _POSIX_C_SOURCE 199309L /* clock_gettime under -std=c99 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fmi3Functions.h"
#include "rbfmu_core.h" /* the generated functions and tables, rb_principal */

static double now(void) { /* CPU time of the process: what another job on the machine does not add */
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double buf[RB_NV], d[RB_ND > 0 ? RB_ND : 1], U[(RB_NU > 0 ? RB_NU : 1) * RB_MAX_NODES];
static casadi_int iw[RB_SZ_IW > 0 ? RB_SZ_IW : 1];
static casadi_real w[RB_SZ_W > 0 ? RB_SZ_W : 1];

/* n raw steps of h from buf's state with the inputs U held; the state after them in xa */
static void raw_steps(rb_step_fn step, rb_step_fn constants, long n, double h, double *xa) {
    double xb[RB_NX], ka[RB_NX], kb[RB_NX], err = 0.0, est = 0.0, dx[RB_NX], e[RB_NE > 0 ? RB_NE : 1];
    const casadi_real *arg[RB_SZ_ARG];
    casadi_real *res[RB_SZ_RES];
    long k;
    int i;
    for (i = 0; i < RB_NX; i++) xa[i] = buf[RB_OFF_X + i];
    /* the arguments by name (model_data.h: RB_ARG_<function>_<input>, RB_RES_<function>_<output>) */
    arg[RB_ARG_model_rhs_x] = xa;
    arg[RB_ARG_model_rhs_u] = buf + RB_OFF_U;
    arg[RB_ARG_model_rhs_p] = buf + RB_OFF_P;
    arg[RB_ARG_model_rhs_d] = d;
    res[RB_RES_model_rhs_xdot] = ka;
    model_rhs(arg, res, iw, w, 0); /* k1 = f(x0): then each step returns the next one */
    if (constants) { /* the step's constants for h, once (as the FMU per step size) */
        arg[RB_ARG_model_step_constants_p] = buf + RB_OFF_P;
        arg[RB_ARG_model_step_constants_h] = &h;
        arg[RB_ARG_model_step_constants_d] = d;
        res[RB_RES_model_step_constants_e] = e;
        constants(arg, res, iw, w, 0);
    }
    arg[RB_ARG_model_step_e] = e;
    arg[RB_ARG_model_step_U] = U;
    arg[RB_ARG_model_step_p] = buf + RB_OFF_P;
    arg[RB_ARG_model_step_h] = &h;
    arg[RB_ARG_model_step_d] = d;
    /* the step's Newton residual and error estimate, read by the FMI layer as well */
    res[RB_RES_model_step_err] = &err;
    res[RB_RES_model_step_est] = &est;
    res[RB_RES_model_step_dx] = dx;
    for (k = 0; k < n; k += 2) { /* ping-pong between two state buffers: no copies */
        arg[RB_ARG_model_step_x] = xa, arg[RB_ARG_model_step_k1] = ka;
        res[RB_RES_model_step_x_next] = xb, res[RB_RES_model_step_k_next] = kb;
        step(arg, res, iw, w, 0);
        arg[RB_ARG_model_step_x] = xb, arg[RB_ARG_model_step_k1] = kb;
        res[RB_RES_model_step_x_next] = xa, res[RB_RES_model_step_k_next] = ka;
        step(arg, res, iw, w, 0);
    }
}

/* An instance in step mode with fixed internal steps of h of the method (work_limit at its
 * maximum, modelsrc/methods.py) */
static fmi3Instance step_instance(double method, double h) {
    fmi3Instance inst = fmi3InstantiateCoSimulation("bench", RB_INSTANTIATION_TOKEN, NULL, fmi3False, fmi3False,
                                                    fmi3False, fmi3False, NULL, 0, NULL, NULL, NULL);
    fmi3ValueReference vr = RB_VR_METHOD, vrs[3] = {RB_VR_WORK_LIMIT, RB_VR_TOLERANCE, RB_VR_HMAX};
    fmi3Int64 m = (fmi3Int64)method;
    fmi3Float64 values[3] = {1e15, 0.0, h};
    if (inst == NULL) {
        fprintf(stderr, "bench_step: fmi3InstantiateCoSimulation failed\n");
        exit(1);
    }
    fmi3EnterInitializationMode(inst, fmi3False, 0.0, 0.0, fmi3False, 0.0);
    fmi3SetInt64(inst, &vr, 1, &m, 1);
    fmi3SetFloat64(inst, vrs, 3, values, 3);
    fmi3ExitInitializationMode(inst);
    return inst;
}

/* n internal steps of h through doSteps of `per` internal steps each (per = n: one long
 * doStep), from t = 0 at the times k H (H = per h) a master computes; the seconds they took */
static double do_steps(double method, long n, long per, double h) {
    fmi3Instance inst = step_instance(method, h);
    fmi3Boolean b1, b2, b3;
    fmi3Float64 last;
    const double H = h * (double)per;
    const long calls = n / per;
    long k;
    double t0 = now();
    for (k = 0; k < calls; k++)
        if (fmi3DoStep(inst, H * (double)k, H, fmi3True, &b1, &b2, &b3, &last) != fmi3OK) {
            fprintf(stderr, "bench_step: fmi3DoStep failed at t = %.17g\n", H * (double)k);
            exit(1);
        }
    t0 = now() - t0;
    fmi3FreeInstance(inst);
    return t0;
}

/* `bench cosim ...` (usage above) */
static int cosim(int argc, char **argv) {
    const long n = atol(argv[2]), repeats = atol(argv[7]);
    const double H = atof(argv[4]);
    const fmi3Float64 settings[3] = {1e15, atof(argv[5]), atof(argv[6])}; /* work_limit, tolerance, h_max */
    const fmi3ValueReference vrs[3] = {RB_VR_WORK_LIMIT, RB_VR_TOLERANCE, RB_VR_HMAX}, vm = RB_VR_METHOD;
    const fmi3Int64 method = atoll(argv[3]);
    fmi3ValueReference vx[RB_NX + RB_NU], vsteps = RB_OFF_L + RB_REPORT_STEPS;
    fmi3Float64 v[RB_NX + RB_NU], x[RB_NX], steps = 0.0, count;
    fmi3Boolean b1, b2, b3;
    fmi3Float64 last;
    double best = 1e30, t;
    long k, rep;
    int i;
    if (argc != 8 + RB_NX + RB_NU || n < 1 || repeats < 1 || !(H > 0)) {
        fprintf(stderr, "usage: bench cosim N METHOD_VALUE H TOLERANCE H_MAX REPEATS X[%d] U[%d]\n", RB_NX, RB_NU);
        return 2;
    }
    for (i = 0; i < RB_NX + RB_NU; i++) { /* the state's and the inputs' value references: buf indices */
        vx[i] = (fmi3ValueReference)(RB_OFF_X + i);
        v[i] = atof(argv[8 + i]);
    }
    for (rep = 0; rep <= repeats; rep++) { /* the last pass, untimed, counts the internal steps */
        fmi3Instance inst = fmi3InstantiateCoSimulation("bench", RB_INSTANTIATION_TOKEN, NULL, fmi3False, fmi3False,
                                                        fmi3False, fmi3False, NULL, 0, NULL, NULL, NULL);
        if (inst == NULL || fmi3EnterInitializationMode(inst, fmi3False, 0.0, 0.0, fmi3False, 0.0) != fmi3OK ||
            fmi3SetInt64(inst, &vm, 1, &method, 1) != fmi3OK || fmi3SetFloat64(inst, vrs, 3, settings, 3) != fmi3OK ||
            fmi3SetFloat64(inst, vx, RB_NX + RB_NU, v, RB_NX + RB_NU) != fmi3OK ||
            fmi3ExitInitializationMode(inst) != fmi3OK) {
            fprintf(stderr, "bench_step: the FMU refused the settings of the cosim run\n");
            return 1;
        }
        t = now();
        for (k = 0; k < n; k++) {
            if (fmi3DoStep(inst, H * (double)k, H, fmi3True, &b1, &b2, &b3, &last) != fmi3OK) {
                fprintf(stderr, "bench_step: fmi3DoStep failed at t = %.17g\n", H * (double)k);
                return 1;
            }
            if (rep == repeats) {
                fmi3GetFloat64(inst, &vsteps, 1, &count, 1);
                steps += count;
            }
        }
        t = now() - t;
        if (rep < repeats && t < best) best = t;
        fmi3GetFloat64(inst, vx, RB_NX, x, RB_NX);
        fmi3FreeInstance(inst);
    }
    printf("%.9e %.0f", best, steps);
    for (i = 0; i < RB_NX; i++) printf(" %.17g", x[i]);
    printf("\n");
    return 0;
}

int main(int argc, char **argv) {
    long n;
    int rep, i;
    double xa[RB_NX], h, best[4] = {1e30, 1e30, 1e30, 1e30}, t;
    const rb_step_fn *fixed_fns;
    rb_step_fn step, constants;
    double method;
    const char *mode;
    const casadi_real *arg[RB_SZ_ARG];
    casadi_real *res[RB_SZ_RES];
    if (argc < 5) {
        fprintf(stderr, "usage: bench MODE N METHOD_VALUE H [X[%d] U[%d]]\n", RB_NX, RB_NU);
        return 2;
    }
    mode = argv[1];
    if (strcmp(mode, "cosim") == 0) return cosim(argc, argv);
    n = atol(argv[2]);
    n += n % 2; /* the raw loop takes two steps per iteration */
    for (i = 0; i < RB_NV; i++) buf[i] = rb_start[i];
    arg[RB_ARG_model_derived_p] = buf + RB_OFF_P; /* the derived parameters, once (as the FMU per parameter change) */
    res[RB_RES_model_derived_d] = d;
    model_derived(arg, res, iw, w, 0);
    /* fixed steps: the variant without error estimate, for a diagonal inertia where the FMU
     * takes that one (rb_refresh_derived) */
    fixed_fns = rb_principal(d) ? rb_principal_fixed_step_fns : rb_fixed_step_fns;
    step = fixed_fns[0];
    constants = rb_step_constants_fns[0];
    method = (double)rb_method_values[0];
    if (atoll(argv[3]) != 0) { /* the method's enumeration value (the modelDescription's); 0: the first */
        long long value = atoll(argv[3]);
        for (i = 0; i < RB_NMETHODS && rb_method_values[i] != value; i++) {
        }
        if (i == RB_NMETHODS) {
            fprintf(stderr, "bench_step: no method with enumeration value %lld in this FMU\n", value);
            return 2;
        }
        step = fixed_fns[i];
        constants = rb_step_constants_fns[i];
        method = (double)rb_method_values[i];
    }
    h = atof(argv[4]);
    if (argc > 5) { /* the raw steps' start state and held inputs */
        if (argc != 5 + RB_NX + RB_NU) {
            fprintf(stderr, "bench_step: give all %d states and %d inputs after H, got %d values\n", RB_NX, RB_NU,
                    argc - 5);
            return 2;
        }
        for (i = 0; i < RB_NX + RB_NU; i++) buf[RB_OFF_X + i] = atof(argv[5 + i]); /* u follows x in buf */
    }
    if (!(h > 0) || n < 10) {
        fprintf(stderr, "bench_step: H must be > 0 and N >= 10, got H = %g, N = %ld\n", h, n);
        return 2;
    }
    for (i = 0; i < RB_NU * RB_MAX_NODES; i++) U[i] = buf[RB_OFF_U + i % (RB_NU > 0 ? RB_NU : 1)]; /* held inputs */
    for (i = 0; i < RB_NX; i++) xa[i] = buf[RB_OFF_X + i];
    if (strcmp(mode, "raw") == 0)
        raw_steps(step, constants, n, h, xa);
    else if (strcmp(mode, "long") == 0)
        do_steps(method, n, n, h);
    else if (strcmp(mode, "loop1") == 0)
        do_steps(method, n, 1, h);
    else if (strcmp(mode, "loop10") == 0)
        do_steps(method, n - n % 10, 10, h);
    else if (strcmp(mode, "time") == 0 || strcmp(mode, "loops") == 0) {
        const int loops = strcmp(mode, "loops") == 0;
        for (rep = 0; rep < 5; rep++) { /* best of 5: the least disturbed run */
            t = now();
            raw_steps(step, constants, n, h, xa);
            t = (now() - t) / (double)n;
            if (t < best[0]) best[0] = t;
            t = do_steps(method, n, n, h) / (double)n;
            if (t < best[1]) best[1] = t;
            if (!loops) continue;
            t = do_steps(method, n / 4, 1, h) / (double)(n / 4);
            if (t < best[2]) best[2] = t;
            t = do_steps(method, n / 4 - (n / 4) % 10, 10, h) / (double)((n / 4) / 10);
            if (t < best[3]) best[3] = t;
        }
        printf("%.3f %.3f", best[0] * 1e9, best[1] * 1e9);
        if (loops) printf(" %.3f %.3f", best[2] * 1e9, best[3] * 1e9);
    } else {
        fprintf(stderr, "bench_step: MODE must be time, loops, raw, long, loop1 or loop10, got %s\n", mode);
        return 2;
    }
    for (i = 0; i < RB_NX; i++) printf(" %.17g", xa[i]);
    printf("\n");
    return 0;
}
