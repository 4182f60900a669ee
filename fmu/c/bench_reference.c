/* Minimal hand-written C RK4 of a scene's equations: the benchmark's reference for the generated step.
 *
 * Never part of an FMU (the FMU's physics is only CasADi-generated C): it exists so that
 * `rbfmu bench` can show how close the generated RK4 step comes to what a careful person
 * would write by hand for the same equations (docs/theory.md §2, §4, §7): Euler's
 * equations with the inverse inertia about the rotation point computed once, quaternion
 * kinematics, the torques and forces of the scene's features, and the projection of q
 * after each step. The features are compile-time macros set by fmu/benchmark.py from the
 * scene; the parameters and the start state come from the command line, so that the
 * compiler cannot fold them into constants (the generated code reads them from memory too).
 *
 * Usage: bench_reference N H X[NX] I[9] IINV[9] M RCM[3] G[3] C TAUB[3] TAUW[3] FB[3] FW[3]
 *        APIV[3] (R[3] F[3])*REF_NPOINTS. Prints ns per step (best of 5) and one state
 *        component (so the loop is not optimised away). */
#define _POSIX_C_SOURCE 199309L /* clock_gettime under -std=c99 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#if defined(REF_TRANSLATION) || defined(REF_MOVING_PIVOT)
#define REF_NX 13
#else
#define REF_NX 7
#endif
#ifndef REF_NPOINTS
#define REF_NPOINTS 0
#endif
#ifndef REF_POINT_WORLD /* bit k set: point k's force is given in the world frame */
#define REF_POINT_WORLD 0
#endif

typedef struct {
    double I[9], Iinv[9]; /* about the point the body turns about, body frame, row major */
    double m, r_cm[3], g[3], c;
    double tau_b[3], tau_w[3], f_b[3], f_w[3], a_piv[3];
    double pt_r[REF_NPOINTS > 0 ? REF_NPOINTS : 1][3], pt_f[REF_NPOINTS > 0 ? REF_NPOINTS : 1][3];
} RefParams;

static inline void cross(const double *a, const double *b, double *c) {
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

static inline void matvec(const double *M, const double *v, double *out) {
#ifdef REF_FULL_INERTIA
    out[0] = M[0] * v[0] + M[1] * v[1] + M[2] * v[2];
    out[1] = M[3] * v[0] + M[4] * v[1] + M[5] * v[2];
    out[2] = M[6] * v[0] + M[7] * v[1] + M[8] * v[2];
#else /* principal axes about the rotation point: a diagonal tensor */
    out[0] = M[0] * v[0];
    out[1] = M[4] * v[1];
    out[2] = M[8] * v[2];
#endif
}

static void rhs(const double *x, double *dx, const RefParams *P) {
    const double qw = x[0], qx = x[1], qy = x[2], qz = x[3];
    const double *w = x + 4;
    double tau[3] = {0.0, 0.0, 0.0}, Iw[3], wIw[3], t[3];
    /* q' = 1/2 q (x) (0, w) (docs/theory.md §1.2) */
    dx[0] = 0.5 * (-qx * w[0] - qy * w[1] - qz * w[2]);
    dx[1] = 0.5 * (qw * w[0] + qy * w[2] - qz * w[1]);
    dx[2] = 0.5 * (qw * w[1] + qz * w[0] - qx * w[2]);
    dx[3] = 0.5 * (qw * w[2] + qx * w[1] - qy * w[0]);
#if defined(REF_GRAVITY) || defined(REF_TAU_WORLD) || defined(REF_FORCE_BODY) || REF_NPOINTS > 0
    /* R body -> world of a unit q; Rt = R transposed */
    const double R[9] = {1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qw * qz), 2 * (qx * qz + qw * qy),
                         2 * (qx * qy + qw * qz), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qw * qx),
                         2 * (qx * qz - qw * qy), 2 * (qy * qz + qw * qx), 1 - 2 * (qx * qx + qy * qy)};
#define RT_TIMES(v, out)                                          \
    do {                                                          \
        (out)[0] = R[0] * (v)[0] + R[3] * (v)[1] + R[6] * (v)[2]; \
        (out)[1] = R[1] * (v)[0] + R[4] * (v)[1] + R[7] * (v)[2]; \
        (out)[2] = R[2] * (v)[0] + R[5] * (v)[1] + R[8] * (v)[2]; \
    } while (0)
#define R_TIMES(v, out)                                           \
    do {                                                          \
        (out)[0] = R[0] * (v)[0] + R[1] * (v)[1] + R[2] * (v)[2]; \
        (out)[1] = R[3] * (v)[0] + R[4] * (v)[1] + R[5] * (v)[2]; \
        (out)[2] = R[6] * (v)[0] + R[7] * (v)[1] + R[8] * (v)[2]; \
    } while (0)
#endif
#ifdef REF_GRAVITY /* heavy top: r_cm x R^T m (g - a_pivot) (docs/theory.md §4.1, §7.3) */
    {
        double mg[3], fb[3];
#ifdef REF_MOVING_PIVOT
        mg[0] = P->m * (P->g[0] - P->a_piv[0]);
        mg[1] = P->m * (P->g[1] - P->a_piv[1]);
        mg[2] = P->m * (P->g[2] - P->a_piv[2]);
#else
        mg[0] = P->m * P->g[0];
        mg[1] = P->m * P->g[1];
        mg[2] = P->m * P->g[2];
#endif
        RT_TIMES(mg, fb);
        cross(P->r_cm, fb, tau);
    }
#endif
#ifdef REF_FRICTION
    tau[0] -= P->c * w[0];
    tau[1] -= P->c * w[1];
    tau[2] -= P->c * w[2];
#endif
#ifdef REF_TAU_BODY
    tau[0] += P->tau_b[0];
    tau[1] += P->tau_b[1];
    tau[2] += P->tau_b[2];
#endif
#ifdef REF_TAU_WORLD
    RT_TIMES(P->tau_w, t);
    tau[0] += t[0];
    tau[1] += t[1];
    tau[2] += t[2];
#endif
#ifdef REF_TRANSLATION
    double F[3] = {0.0, 0.0, 0.0}; /* world frame */
#ifdef REF_FREE_GRAVITY
    F[0] = P->m * P->g[0];
    F[1] = P->m * P->g[1];
    F[2] = P->m * P->g[2];
#endif
#ifdef REF_FORCE_BODY
    R_TIMES(P->f_b, t);
    F[0] += t[0];
    F[1] += t[1];
    F[2] += t[2];
#endif
#ifdef REF_FORCE_WORLD
    F[0] += P->f_w[0];
    F[1] += P->f_w[1];
    F[2] += P->f_w[2];
#endif
#if REF_NPOINTS > 0
    for (int k = 0; k < REF_NPOINTS; k++) { /* force at a point: F and r x F (docs/theory.md §7.1) */
        double fb[3], fw[3], mom[3];
        if (REF_POINT_WORLD & (1 << k)) {
            fw[0] = P->pt_f[k][0];
            fw[1] = P->pt_f[k][1];
            fw[2] = P->pt_f[k][2];
            RT_TIMES(fw, fb);
        } else {
            fb[0] = P->pt_f[k][0];
            fb[1] = P->pt_f[k][1];
            fb[2] = P->pt_f[k][2];
            R_TIMES(fb, fw);
        }
        cross(P->pt_r[k], fb, mom);
        tau[0] += mom[0];
        tau[1] += mom[1];
        tau[2] += mom[2];
        F[0] += fw[0];
        F[1] += fw[1];
        F[2] += fw[2];
    }
#endif
#endif
#ifdef REF_PRESCRIBED /* held at a constant rate about a fixed axis: w' = 0 (docs/theory.md §4.4) */
    (void)Iw;
    (void)wIw;
    (void)t;
    (void)tau;
    (void)P;
    dx[4] = dx[5] = dx[6] = 0.0;
#else /* Euler's equations w' = I^-1 (tau - w x I w) (docs/theory.md §2) */
    matvec(P->I, w, Iw);
    cross(w, Iw, wIw);
    t[0] = tau[0] - wIw[0];
    t[1] = tau[1] - wIw[1];
    t[2] = tau[2] - wIw[2];
    matvec(P->Iinv, t, dx + 4);
#endif
#ifdef REF_TRANSLATION /* x' = v, v' = F / m (docs/theory.md §7.1) */
    dx[7] = x[10];
    dx[8] = x[11];
    dx[9] = x[12];
    dx[10] = F[0] / P->m;
    dx[11] = F[1] / P->m;
    dx[12] = F[2] / P->m;
#endif
#ifdef REF_MOVING_PIVOT
    dx[7] = x[10];
    dx[8] = x[11];
    dx[9] = x[12];
    dx[10] = P->a_piv[0];
    dx[11] = P->a_piv[1];
    dx[12] = P->a_piv[2];
#endif
}

/* One classic RK4 step (Hairer-Norsett-Wanner I §II.1), then q projected onto |q| = 1. */
static void rk4(double *x, double h, const RefParams *P) {
    double k1[REF_NX], k2[REF_NX], k3[REF_NX], k4[REF_NX], y[REF_NX], n;
    int i;
    rhs(x, k1, P);
    for (i = 0; i < REF_NX; i++) y[i] = x[i] + 0.5 * h * k1[i];
    rhs(y, k2, P);
    for (i = 0; i < REF_NX; i++) y[i] = x[i] + 0.5 * h * k2[i];
    rhs(y, k3, P);
    for (i = 0; i < REF_NX; i++) y[i] = x[i] + h * k3[i];
    rhs(y, k4, P);
    for (i = 0; i < REF_NX; i++) x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    n = 1.0 / sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2] + x[3] * x[3]);
    for (i = 0; i < 4; i++) x[i] *= n;
}

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int main(int argc, char **argv) {
    RefParams P;
    double x0[REF_NX], x[REF_NX], h, best = 1e30, t0;
    long n, k;
    int a = 1, i, rep;
    const int need = 3 + REF_NX + 9 + 9 + 1 + 3 + 3 + 1 + 5 * 3 + 6 * REF_NPOINTS;
    if (argc != need) {
        fprintf(stderr, "bench_reference: expected %d arguments, got %d\n", need - 1, argc - 1);
        return 2;
    }
    n = atol(argv[a++]);
    h = atof(argv[a++]);
    for (i = 0; i < REF_NX; i++) x0[i] = atof(argv[a++]);
    for (i = 0; i < 9; i++) P.I[i] = atof(argv[a++]);
    for (i = 0; i < 9; i++) P.Iinv[i] = atof(argv[a++]);
    P.m = atof(argv[a++]);
    for (i = 0; i < 3; i++) P.r_cm[i] = atof(argv[a++]);
    for (i = 0; i < 3; i++) P.g[i] = atof(argv[a++]);
    P.c = atof(argv[a++]);
    for (i = 0; i < 3; i++) P.tau_b[i] = atof(argv[a++]);
    for (i = 0; i < 3; i++) P.tau_w[i] = atof(argv[a++]);
    for (i = 0; i < 3; i++) P.f_b[i] = atof(argv[a++]);
    for (i = 0; i < 3; i++) P.f_w[i] = atof(argv[a++]);
    for (i = 0; i < 3; i++) P.a_piv[i] = atof(argv[a++]);
    for (k = 0; k < REF_NPOINTS; k++) {
        for (i = 0; i < 3; i++) P.pt_r[k][i] = atof(argv[a++]);
        for (i = 0; i < 3; i++) P.pt_f[k][i] = atof(argv[a++]);
    }
    for (rep = 0; rep < 5; rep++) { /* best of 5: the least disturbed run */
        for (i = 0; i < REF_NX; i++) x[i] = x0[i];
        t0 = now();
        for (k = 0; k < n; k++) rk4(x, h, &P);
        t0 = (now() - t0) / (double)n;
        if (t0 < best) best = t0;
    }
    printf("%.3f %g\n", best * 1e9, x[REF_NX - 1]);
    return 0;
}
