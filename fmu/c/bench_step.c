/* Benchmark harness (not part of any FMU): times one method's generated step in C and via fmi3DoStep.
 * The generated step of one method called in a plain C loop, and the same work through
 * fmi3DoStep of the hand-written layer.
 * Built by fmu/benchmark.py against one scene's generated sources.
 * Usage: bench N [METHOD_VALUE [H [X[NX] U[NU]]]]: N steps of H seconds (default: h_max); METHOD_VALUE
 * is the method's enumeration value (modelDescription), default the FMU's first method. The raw
 * steps start from X with the inputs U held (default: the start values; the fmi3DoStep run takes
 * the start values). Prints raw ns, fmi3DoStep ns (fixed steps), the state after the raw steps. */
#define _POSIX_C_SOURCE 199309L /* clock_gettime under -std=c99 */
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "fmi3Functions.h"
#include "rbfmu_core.h" /* model_funcs.h, model_data.h and rb_principal */

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int main(int argc, char **argv) {
    long n = argc > 1 ? atol(argv[1]) : 10000000L, k;
    int rep, i;
    double buf[RB_NV], xa[RB_NX], xb[RB_NX], ka[RB_NX], kb[RB_NX], h, best_raw = 1e30, best_fmi = 1e30, t0, t;
    double err = 0.0, est = 0.0, d[RB_ND > 0 ? RB_ND : 1], U[(RB_NU > 0 ? RB_NU : 1) * RB_MAX_NODES], dx[RB_NX];
    const casadi_real *arg[RB_SZ_ARG];
    casadi_real *res[RB_SZ_RES];
    static casadi_int iw[RB_SZ_IW > 0 ? RB_SZ_IW : 1];
    static casadi_real w[RB_SZ_W > 0 ? RB_SZ_W : 1];
    fmi3Instance inst;
    fmi3Boolean b1, b2, b3;
    fmi3Float64 last;
    const rb_step_fn *fixed_fns;
    rb_step_fn step;
    double method = (double)rb_method_values[0];
    for (i = 0; i < RB_NV; i++) buf[i] = rb_start[i];
    /* the arguments by name (model_data.h: RB_ARG_<function>_<input>, RB_RES_<function>_<output>) */
    arg[RB_ARG_model_derived_p] = buf + RB_OFF_P; /* the derived parameters, once (as the FMU per parameter change) */
    res[RB_RES_model_derived_d] = d;
    model_derived(arg, res, iw, w, 0);
    /* fixed steps: the variant without error estimate, for a diagonal inertia where the FMU
     * takes that one (rb_refresh_derived) */
    fixed_fns = rb_principal(d) ? rb_principal_fixed_step_fns : rb_fixed_step_fns;
    step = fixed_fns[0];
    if (argc > 2 && atoll(argv[2]) != 0) { /* the method's enumeration value (the modelDescription's); 0: the first */
        long long value = atoll(argv[2]);
        for (i = 0; i < RB_NMETHODS && rb_method_values[i] != value; i++) {
        }
        if (i == RB_NMETHODS) {
            fprintf(stderr, "bench_step: no method with enumeration value %lld in this FMU\n", value);
            return 2;
        }
        step = fixed_fns[i];
        method = (double)rb_method_values[i];
    }
    h = argc > 3 ? atof(argv[3]) : buf[RB_VR_HMAX];
    if (argc > 4) { /* the raw steps' start state and held inputs */
        if (argc != 4 + RB_NX + RB_NU) {
            fprintf(stderr, "bench_step: give all %d states and %d inputs after H, got %d values\n", RB_NX, RB_NU,
                    argc - 4);
            return 2;
        }
        for (i = 0; i < RB_NX + RB_NU; i++) buf[RB_OFF_X + i] = atof(argv[4 + i]); /* u follows x in buf */
    }
    if (!(h > 0)) {
        fprintf(stderr, "bench_step: the step must be > 0, got %g (give H)\n", h);
        return 2;
    }
    for (i = 0; i < RB_NU * RB_MAX_NODES; i++) U[i] = buf[RB_OFF_U + i % (RB_NU > 0 ? RB_NU : 1)]; /* held inputs */
    for (rep = 0; rep < 5; rep++) { /* best of 5: the least disturbed run */
        for (i = 0; i < RB_NX; i++) xa[i] = buf[RB_OFF_X + i];
        arg[RB_ARG_model_rhs_x] = xa;
        arg[RB_ARG_model_rhs_u] = buf + RB_OFF_U;
        arg[RB_ARG_model_rhs_p] = buf + RB_OFF_P;
        arg[RB_ARG_model_rhs_d] = d;
        res[RB_RES_model_rhs_xdot] = ka;
        model_rhs(arg, res, iw, w, 0); /* k1 = f(x0): then each step returns the next one */
        arg[RB_ARG_model_step_U] = U;
        arg[RB_ARG_model_step_p] = buf + RB_OFF_P;
        arg[RB_ARG_model_step_h] = &h;
        arg[RB_ARG_model_step_d] = d;
        /* the step's Newton residual and error estimate, read by the FMI layer as well */
        res[RB_RES_model_step_err] = &err;
        res[RB_RES_model_step_est] = &est;
        res[RB_RES_model_step_dx] = dx;
        t0 = now();
        for (k = 0; k < n; k += 2) { /* ping-pong between two state buffers: no copies */
            arg[RB_ARG_model_step_x] = xa, arg[RB_ARG_model_step_k1] = ka;
            res[RB_RES_model_step_x_next] = xb, res[RB_RES_model_step_k_next] = kb;
            step(arg, res, iw, w, 0);
            arg[RB_ARG_model_step_x] = xb, arg[RB_ARG_model_step_k1] = kb;
            res[RB_RES_model_step_x_next] = xa, res[RB_RES_model_step_k_next] = ka;
            step(arg, res, iw, w, 0);
        }
        t = (now() - t0) / (double)n;
        if (t < best_raw) best_raw = t;

        inst = fmi3InstantiateCoSimulation("bench", RB_INSTANTIATION_TOKEN, NULL, fmi3False, fmi3False, fmi3False,
                                           fmi3False, NULL, 0, NULL, NULL, NULL);
        fmi3EnterInitializationMode(inst, fmi3False, 0.0, 0.0, fmi3False, 0.0);
        {
            fmi3ValueReference vr = RB_VR_METHOD, vrs[3] = {RB_VR_WORK_LIMIT, RB_VR_TOLERANCE, RB_VR_HMAX};
            fmi3Int64 m = (fmi3Int64)method;
            /* one doStep of n fixed internal steps of h; work_limit at its maximum (modelsrc/methods.py) */
            fmi3Float64 values[3] = {1e15, 0.0, h};
            fmi3SetInt64(inst, &vr, 1, &m, 1);
            fmi3SetFloat64(inst, vrs, 3, values, 3);
        }
        fmi3ExitInitializationMode(inst);
        t0 = now();
        if (fmi3DoStep(inst, 0.0, h * (double)n, fmi3True, &b1, &b2, &b3, &last) != fmi3OK) return 1;
        t = (now() - t0) / (double)n;
        if (t < best_fmi) best_fmi = t;
        fmi3FreeInstance(inst);
    }
    printf("%.3f %.3f", best_raw * 1e9, best_fmi * 1e9);
    for (i = 0; i < RB_NX; i++) printf(" %.17g", xa[i]);
    printf("\n");
    return 0;
}
