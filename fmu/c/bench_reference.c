/* Hand-written C RK4 and RK8 of a scene's equations, as an expert writes them: the benchmark's yardstick.
 *
 * Never part of an FMU (the FMU's physics is only CasADi-generated C): it exists so that
 * `rbfmu bench` can show how close the generated step comes to what an expert writes by
 * hand for the same equations and method (docs/theory.md §1-§9), compiled with the same
 * flags (no FMA, -O2, plain C99, no SIMD intrinsics). Same job as the generated fixed step:
 * one step of h from x with the inputs at the method's nodes, q projected onto |q| = 1 after
 * the step (as the generated step does); tests/report/test_benchmark_reference.py checks that both
 * reach the same state after 2000 steps. The generated step also writes the next step's k1
 * (first same as last) and the increment dx that the FMI layer sums with compensation; this
 * kernel evaluates f at the start of each step instead (the same number of evaluations) and
 * writes only x. What an expert does that a term-by-term transcription does not:
 * - parameter-only quantities once, before the loop (fmu/bench/reference.py, reference_parameters):
 *   M^-1 = (I - sum J g g^T)^-1, Euler's coefficients e_1 = (I_2 - I_3) M^-1_1 (cyclic) of a
 *   diagonal M, M^-1 times the friction, the pivot's lever arm and the gravity gradient's
 *   3 n^2 (I_3 - I_2), m g, 1/m, 1/J; the features and rotor axes are compile-time (§6); with
 *   rotors on all three axes w x (I w + h) is cheaper than Euler's coefficients (REF_HFORM);
 * - what depends on the inputs only, once per node instead of once per stage (RK4's stages 2
 *   and 3 share the node 1/2): M^-1 times the body torques, the propellers' thrust, moments,
 *   drag and momentum, u/J, the weight less m a_pivot, the forces over m;
 * - stages fused where the equations allow: the centre of mass (or a moving pivot) does not
 *   act back on the rotation, so its Runge-Kutta stages are summed in closed form from the
 *   stage accelerations, v+ = v + h sum b_i a_i, x+ = x + h v + h^2 sum beta_j a_j with
 *   beta_j = sum_i b_i a_ij (exact for x' = v, v' = a); the orbit angle is theta + c h n, its
 *   sine and cosine by the angle-addition formulas from sin theta, cos theta once per step and
 *   those of the advances c h n once per step size (main, as the FMU keeps them); a prescribed
 *   rate is not staged (w' = 0). Only a central field couples position and attitude: there all
 *   13 states are staged;
 * - vectors turned with the quaternion, R v = v + 2/|q|^2 (w (u x v) + u x (u x v)), u the
 *   vector part (the model's R = R~(q)/|q|^2, modelsrc/quaternion.py: exact off the unit
 *   sphere, where the stages are), a column of R~ for a force along one body axis, the full
 *   R~ where two vectors turn (central field); zero components left out at compile time.
 * The features are compile-time macros set by fmu/bench/reference.py (`reference_features`). The
 * parameters, start state and inputs come from the command line, so that the compiler cannot
 * fold them into constants (the generated step reads them from memory too), and the step is
 * a function of its own (noinline), called per step like the generated one.
 *
 * Usage: bench_reference METHOD N REPEATS H X[NX] P[NP] U[NU]: REPEATS runs of N steps of H
 *        seconds of METHOD (4: RK4, 8: RK8) from X, parameters P in the order of
 *        `reference_parameters`, inputs U held at every node. Prints ns of CPU time per step
 *        (best of the repeats) and the final state. */
#define _POSIX_C_SOURCE 199309L /* clock_gettime under -std=c99 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "bench_reference.h"

/* what depends on the inputs only, at one node (`node`) */
typedef struct {
    double mt[3];              /* M^-1 (body torques of the inputs) */
    double W[3];               /* heavy top: m (g - a_pivot), world */
    double tw[3];              /* world torque */
    double pw[MAX1(REF_NPOINTS)][3]; /* forces at world-frame points */
    double hs[3], mhs[3][3];   /* speed-mode rotors: h = sum J Omega g, and M^-1_i h_j (diagonal) */
    double uJ[MAX1(REF_NTROT)]; /* u / J */
    double fb[3], fw[3];       /* forces over m: body frame, world frame (with g) */
} Node;

static inline __attribute__((always_inline)) void node(const Inputs *U, const Params *P, Node *N) {
    double t[3] = {0.0, 0.0, 0.0}; /* body torque of the inputs */
    int ts[3] = {0, 0, 0}, f[3], k, i;
    (void)P, (void)i, (void)k, (void)U, (void)f, (void)t, (void)ts;
#ifdef REF_TAU_BODY
    UNROLLED for (i = 0; i < 3; i++) PUT(t, ts, i, U->tau_b[i]);
#endif
#ifdef REF_TAU_WORLD
    UNROLLED for (i = 0; i < 3; i++) N->tw[i] = U->tau_w[i];
#endif
#ifdef REF_MOVING_PIVOT /* the weight less m a_pivot (§7.3) */
    UNROLLED for (i = 0; i < 3; i++) N->W[i] = P->W[i] - P->m * U->a_piv[i];
#endif
#ifdef REF_TRANSLATION /* forces over m (§7.1); body-frame forces turn per stage */
    double fb[3] = {0.0, 0.0, 0.0}, fw[3] = {0.0, 0.0, 0.0};
    int bs[3] = {0, 0, 0}, ws[3] = {0, 0, 0};
    (void)bs, (void)ws, (void)fb, (void)fw;
#ifdef REF_FORCE_BODY
    UNROLLED for (i = 0; i < 3; i++) PUT(fb, bs, i, U->f_b[i]);
#endif
#ifdef REF_FORCE_WORLD
    UNROLLED for (i = 0; i < 3; i++) PUT(fw, ws, i, U->f_w[i]);
#endif
    UNROLLED for (k = 0; k < REF_NPOINTS; k++) {
        if (REF_POINT_WORLD & (1 << k)) {
            UNROLLED for (i = 0; i < 3; i++) PUT(fw, ws, i, U->pt_f[k][i]);
        } else {
            UNROLLED for (i = 0; i < 3; i++) PUT(fb, bs, i, U->pt_f[k][i]);
        }
    }
#endif
    UNROLLED for (k = 0; k < REF_NPOINTS; k++) { /* r x F of a body-frame force; world ones turn per stage */
        if (REF_POINT_WORLD & (1 << k)) {
            UNROLLED for (i = 0; i < 3; i++) N->pw[k][i] = U->pt_f[k][i];
        } else {
            const double *r = P->pt_r[k], *F = U->pt_f[k];
            PUT(t, ts, 0, r[1] * F[2] - r[2] * F[1]);
            PUT(t, ts, 1, r[2] * F[0] - r[0] * F[2]);
            PUT(t, ts, 2, r[0] * F[1] - r[1] * F[0]);
        }
    }
    UNROLLED for (k = 0; k < REF_NTROT; k++) { /* the body feels -u g; J Omega' = u - J g.w' (§8.1) */
        PUT(t, ts, TAX[k], -U->u[k]);
        N->uJ[k] = U->u[k] * P->invJ[k];
    }
#if REF_NSROT > 0 /* speed mode (§8.5, §8.6): -J Omega' g - k_m Omega|Omega| g, thrust k_f Omega^2 g at r */
    {
        int hs[3] = {0, 0, 0};
        UNROLLED for (k = 0; k < REF_NSROT; k++) {
            const double Om = U->Om[k], J = P->J[REF_NTROT + k];
            const int a = SAX[k], b = (a + 1) % 3, c = (a + 2) % 3;
            PUT(N->hs, hs, a, J * Om);
            PUT(t, ts, a, -(J * U->Omd[k] + P->km[k] * Om * fabs(Om)));
#ifdef REF_PROPELLERS
            {
                const double thrust = P->kf[k] * Om * Om; /* (r x f e_a)_b = r_c f, (r x f e_a)_c = -r_b f */
                PUT(t, ts, b, P->rpos[k][c] * thrust);
                PUT(t, ts, c, -(P->rpos[k][b] * thrust));
#ifdef REF_TRANSLATION
                PUT(fb, bs, a, thrust);
#endif
            }
#endif
            (void)b, (void)c;
        }
#ifndef REF_MOMENTUM
        UNROLLED for (k = 0; k < 3; k++) /* M^-1_i h_k for the gyroscopic term (euler) */
            if (hs[k]) N->mhs[(k + 1) % 3][k] = P->Minv[4 * ((k + 1) % 3)] * N->hs[k],
                       N->mhs[(k + 2) % 3][k] = P->Minv[4 * ((k + 2) % 3)] * N->hs[k];
#endif
    }
#endif
#ifdef REF_TRANSLATION
    UNROLLED for (i = 0; i < 3; i++) {
        if (bs[i]) N->fb[i] = fb[i] * P->inv_m;
#if defined(REF_FREE_GRAVITY)
        N->fw[i] = ws[i] ? P->g[i] + fw[i] * P->inv_m : P->g[i];
#else
        if (ws[i]) N->fw[i] = fw[i] * P->inv_m;
#endif
    }
#endif
    torque_axes(f);
#ifdef REF_FULL_INERTIA
    UNROLLED for (i = 0; i < 3; i++) { /* M^-1 t over the axes t has */
        int first = 1;
        UNROLLED for (k = 0; k < 3; k++)
            if (f[k]) N->mt[i] = first ? P->Minv[3 * i + k] * t[k] : N->mt[i] + P->Minv[3 * i + k] * t[k], first = 0;
    }
#else
    UNROLLED for (i = 0; i < 3; i++)
        if (f[i]) N->mt[i] = P->Minv[4 * i] * t[i];
#endif
}

/* w' (§2, §4, §8.1): M^-1 (tau - w x (I w + h)) with tau the node's input torques (N->mt, already
 * times M^-1) and the state-dependent ones (tau: times M^-1 on a diagonal M), h the rotors'
 * momentum; on a diagonal M with rotors on at most two axes in Euler's form,
 * w'_1 = e_1 w_2 w_3 - m_1 (w x h)_1 + ..., else with H = I w + h, w'_1 = m_1 (w_3 H_2 - w_2 H_3) + ... */
static inline __attribute__((always_inline)) void euler(const double *w, const double *y, const double *tau, int tq,
                                                        const Node *N, const Params *P, double *dw) {
    int i, k;
    (void)tau, (void)tq, (void)N, (void)k, (void)y;
#ifdef REF_MOMENTUM
    double H[3]; /* H = I w + h */
#ifdef REF_FULL_INERTIA
    UNROLLED for (i = 0; i < 3; i++) H[i] = P->I[3 * i] * w[0] + P->I[3 * i + 1] * w[1] + P->I[3 * i + 2] * w[2];
#else
    UNROLLED for (i = 0; i < 3; i++) H[i] = P->I[4 * i] * w[i];
#endif
    UNROLLED for (k = 0; k < REF_NTROT; k++) AXIS_ADD(H, TAX[k], P->J[k] * y[YR + k]);
#if REF_NSROT > 0
    {
        double hf[3] = {0, 0, 0}; /* the axes the speed-mode rotors' h has */
        UNROLLED for (k = 0; k < REF_NSROT; k++) AXIS_ADD(hf, SAX[k], 1.0);
        UNROLLED for (i = 0; i < 3; i++)
            if (hf[i] != 0.0) H[i] += N->hs[i];
    }
#endif
    const double t[3] = {w[2] * H[1] - w[1] * H[2], w[0] * H[2] - w[2] * H[0], w[1] * H[0] - w[0] * H[1]};
#ifdef REF_FULL_INERTIA
    double T[3];
    UNROLLED for (i = 0; i < 3; i++) {
        T[i] = t[i];
        if (tq) T[i] += tau[i];
#ifdef REF_FRICTION
        T[i] -= P->cI[0] * w[i];
#endif
    }
    UNROLLED for (i = 0; i < 3; i++) dw[i] = P->Minv[3 * i] * T[0] + P->Minv[3 * i + 1] * T[1] + P->Minv[3 * i + 2] * T[2];
#else
    UNROLLED for (i = 0; i < 3; i++) dw[i] = P->Minv[4 * i] * t[i];
#endif
#else /* Euler's coefficients */
    dw[0] = P->e[0] * (w[1] * w[2]);
    dw[1] = P->e[1] * (w[2] * w[0]);
    dw[2] = P->e[2] * (w[0] * w[1]);
    UNROLLED for (k = 0; k < REF_NTROT; k++) { /* -m_i (w x J Omega e_a)_i */
        const int a = TAX[k], b = (a + 1) % 3, c = (a + 2) % 3;
        const double Om = y[YR + k];
        AXIS_ADD(dw, b, -(w[c] * (P->mJ[b][k] * Om))); /* (w x e_a)_b = w_c, (w x e_a)_c = -w_b */
        AXIS_ADD(dw, c, w[b] * (P->mJ[c][k] * Om));
    }
#if REF_NSROT > 0
    {
        double hf[3] = {0, 0, 0};
        UNROLLED for (k = 0; k < REF_NSROT; k++) AXIS_ADD(hf, SAX[k], 1.0);
        UNROLLED for (k = 0; k < 3; k++) /* the speed-mode rotors' h on axis k (inputs) */
            if (hf[k] != 0.0) {
                const int b = (k + 1) % 3, c = (k + 2) % 3;
                AXIS_ADD(dw, b, -(w[c] * N->mhs[b][k]));
                AXIS_ADD(dw, c, w[b] * N->mhs[c][k]);
            }
    }
#endif
#endif
#ifndef REF_FULL_INERTIA
    UNROLLED for (i = 0; i < 3; i++) {
        if (tq) dw[i] += tau[i];
#ifdef REF_FRICTION
        dw[i] -= P->cI[i] * w[i];
#endif
    }
#endif
    {
        int f[3];
        torque_axes(f);
        UNROLLED for (i = 0; i < 3; i++)
#ifdef REF_FULL_INERTIA
            if (f[0] || f[1] || f[2]) dw[i] += N->mt[i]; /* M^-1 mixes the axes */
#else
            if (f[i]) dw[i] += N->mt[i];
#endif
    }
}

/* the staged states' rates dy = f(y) at one stage, and the translation's acceleration (world)
 * there; y: q, w (not with a prescribed rate: w0 instead), the torque-mode rotor rates, a
 * central field's x and v. cs: the orbit angle's sine and cosine at the stage's node */
static inline __attribute__((always_inline)) void rhs(const double *y, const double *w0, const Node *N,
                                                      const Params *P, const double *cs, double *dy, double *acc) {
    const double qw = y[0], qx = y[1], qy = y[2], qz = y[3];
#ifdef REF_PRESCRIBED
    const double w[3] = {w0[0], w0[1], w0[2]};
#else
    const double w[3] = {y[YW], y[YW + 1], y[YW + 2]};
    (void)w0;
#endif
    const double hw0 = 0.5 * w[0], hw1 = 0.5 * w[1], hw2 = 0.5 * w[2];
    double tau[3] = {0.0, 0.0, 0.0}; /* state-dependent torques (times M^-1 on a diagonal M) */
    int i, tq = 0; /* tq: tau holds a term (known at compile time: the code is straight) */
    (void)cs, (void)acc, (void)i, (void)P, (void)N, (void)tau, (void)tq;
    /* q' = 1/2 q (x) (0, w) (§1.2) */
    dy[0] = -qx * hw0 - qy * hw1 - qz * hw2;
    dy[1] = qw * hw0 + qy * hw2 - qz * hw1;
    dy[2] = qw * hw1 + qz * hw0 - qx * hw2;
    dy[3] = qw * hw2 + qx * hw1 - qy * hw0;
#ifdef REF_ROTATES
    const double s2 = 2.0 / (qw * qw + qx * qx + qy * qy + qz * qz); /* R = R~/|q|^2 (§1.1) */
#endif
#ifdef REF_FULL_INERTIA
#define TQ(i, v) (tau[i] = tq ? tau[i] + (v) : (v))
#define TQ_SCALED(i, v) TQ(i, v)       /* raw torque: M^-1 applied in euler */
#else
#define TQ(i, v) (tau[i] = tq ? tau[i] + (v) : (v)) /* v already times m_i */
#define TQ_SCALED(i, v) TQ(i, P->Minv[4 * (i)] * (v))
#endif
#ifdef REF_GRAVITY /* heavy top: r x R^T m (g - a_pivot) (§4.1, §7.3) */
    {
        double b[3];
#ifdef REF_MOVING_PIVOT
        ROT_T(N->W, b);
#else
        ROT_T(P->W, b);
#endif
#ifdef REF_FULL_INERTIA
        const double *r = P->mr;
        TQ(0, r[1] * b[2] - r[2] * b[1]), TQ(1, r[2] * b[0] - r[0] * b[2]), TQ(2, r[0] * b[1] - r[1] * b[0]);
#else
        const double *r = P->mr; /* m_i r_j */
        TQ(0, r[1] * b[2] - r[2] * b[1]), TQ(1, r[5] * b[0] - r[3] * b[2]), TQ(2, r[6] * b[1] - r[7] * b[0]);
#endif
        tq = 1;
    }
#endif
#ifdef REF_TAU_WORLD
    {
        double b[3];
        ROT_T(N->tw, b);
        TQ_SCALED(0, b[0]), TQ_SCALED(1, b[1]), TQ_SCALED(2, b[2]);
        tq = 1;
    }
#endif
#if REF_POINT_WORLD != 0
    UNROLLED for (i = 0; i < REF_NPOINTS; i++) {
        if (REF_POINT_WORLD & (1 << i)) {
            double b[3], c[3] = {0.0, 0.0, 0.0};
            ROT_T(N->pw[i], b);
            CROSS_ADD(P->pt_r[i], b, c);
            TQ_SCALED(0, c[0]), TQ_SCALED(1, c[1]), TQ_SCALED(2, c[2]);
            tq = 1;
        }
    }
#endif
#ifdef REF_GRAVITY_GRADIENT /* 3 n^2 c x (I c), c = R^T (-sin th, 0, cos th) (§9.2) */
    {
        const double v0 = -cs[0], v2 = cs[1]; /* ROT_T with v1 = 0 */
        const double t0 = qy * v2, t1 = qz * v0 - qx * v2, t2 = -(qy * v0);
        const double c0 = v0 + s2 * ((qy * t2 - qz * t1) - qw * t0), c1 = s2 * ((qz * t0 - qx * t2) - qw * t1),
                     c2 = v2 + s2 * ((qx * t1 - qy * t0) - qw * t2);
#ifdef REF_FULL_INERTIA
        const double *G = P->gg, c[3] = {c0, c1, c2};
        const double Gc[3] = {G[0] * c0 + G[1] * c1 + G[2] * c2, G[3] * c0 + G[4] * c1 + G[5] * c2,
                              G[6] * c0 + G[7] * c1 + G[8] * c2};
        TQ(0, c[1] * Gc[2] - c[2] * Gc[1]), TQ(1, c[2] * Gc[0] - c[0] * Gc[2]), TQ(2, c[0] * Gc[1] - c[1] * Gc[0]);
#else
        TQ(0, P->gg[0] * (c1 * c2)), TQ(1, P->gg[1] * (c2 * c0)), TQ(2, P->gg[2] * (c0 * c1));
#endif
        tq = 1;
    }
#endif
#ifdef REF_CENTRAL /* central field (§9.7): rho = R^T x, tau = 3 k/r^2 rho x (I rho), k = mu/r^3 */
    const double *xc = y + YC, *vc = y + YC + 3, s = 0.5 * s2;
    const double ww = qw * qw, xx = qx * qx, yy = qy * qy, zz = qz * qz;
    const double xy = qx * qy, xz = qx * qz, yz = qy * qz, wx = qw * qx, wy = qw * qy, wz = qw * qz;
    const double R[9] = {ww + xx - yy - zz, 2 * (xy - wz),     2 * (xz + wy),
                         2 * (xy + wz),     ww - xx + yy - zz, 2 * (yz - wx),
                         2 * (xz - wy),     2 * (yz + wx),     ww - xx - yy + zz};
    const double rho[3] = {(R[0] * xc[0] + R[3] * xc[1] + R[6] * xc[2]) * s,
                           (R[1] * xc[0] + R[4] * xc[1] + R[7] * xc[2]) * s,
                           (R[2] * xc[0] + R[5] * xc[1] + R[8] * xc[2]) * s};
    const double r2 = xc[0] * xc[0] + xc[1] * xc[1] + xc[2] * xc[2], ir = 1.0 / sqrt(r2), ir2 = ir * ir;
    const double k = P->mu * ir2 * ir, k2 = k * ir2;
#ifdef REF_FULL_INERTIA
    const double *I = P->I;
    const double Ir[3] = {I[0] * rho[0] + I[1] * rho[1] + I[2] * rho[2], I[3] * rho[0] + I[4] * rho[1] + I[5] * rho[2],
                          I[6] * rho[0] + I[7] * rho[1] + I[8] * rho[2]};
    const double k3 = 3.0 * k2;
    TQ(0, k3 * (rho[1] * Ir[2] - rho[2] * Ir[1])), TQ(1, k3 * (rho[2] * Ir[0] - rho[0] * Ir[2])),
        TQ(2, k3 * (rho[0] * Ir[1] - rho[1] * Ir[0]));
#else
    const double Ir[3] = {P->I[0] * rho[0], P->I[4] * rho[1], P->I[8] * rho[2]};
    TQ(0, k2 * (P->gc[0] * (rho[1] * rho[2]))), TQ(1, k2 * (P->gc[1] * (rho[2] * rho[0]))),
        TQ(2, k2 * (P->gc[2] * (rho[0] * rho[1])));
#endif
    tq = 1;
#endif
#undef TQ
#undef TQ_SCALED
#ifndef REF_PRESCRIBED
    euler(w, y, tau, tq, N, P, dy + YW);
    UNROLLED for (i = 0; i < REF_NTROT; i++) /* J Omega' = u - J g.w' (§8.1) */
        dy[YR + i] = N->uJ[i] - dy[YW + TAX[i]];
#endif
#if defined(REF_BODY_FORCES) || defined(REF_WORLD_FORCES) /* (R F_body + F_world) / m (+ g) (§7.1) */
    double af[3];
#ifdef REF_BODY_FORCES
    ROT_FB(N->fb, af);
#if defined(REF_WORLD_FORCES) || defined(REF_FREE_GRAVITY)
    UNROLLED for (i = 0; i < 3; i++) af[i] += N->fw[i];
#endif
#else
    UNROLLED for (i = 0; i < 3; i++) af[i] = N->fw[i];
#endif
#endif
#ifdef REF_CENTRAL /* x' = v, v' = -k x - 1.5 k/(m r^2) ((tr I - 5 rho.I rho/r^2) x + 2 R I rho) (§9.7) */
    {
        const double RI[3] = {(R[0] * Ir[0] + R[1] * Ir[1] + R[2] * Ir[2]) * s,
                              (R[3] * Ir[0] + R[4] * Ir[1] + R[5] * Ir[2]) * s,
                              (R[6] * Ir[0] + R[7] * Ir[1] + R[8] * Ir[2]) * s};
        const double f = P->c15m * k2, c = P->trI - 5.0 * ir2 * (rho[0] * Ir[0] + rho[1] * Ir[1] + rho[2] * Ir[2]);
        UNROLLED for (i = 0; i < 3; i++) {
            dy[YC + i] = vc[i];
            dy[YC + 3 + i] = -(k * xc[i]) - f * (c * xc[i] + 2.0 * RI[i]);
#if defined(REF_BODY_FORCES) || defined(REF_WORLD_FORCES)
            dy[YC + 3 + i] += af[i];
#endif
        }
    }
#elif defined(REF_BODY_FORCES) /* summed in closed form by the step (REF_CLOSED_FORM) */
    UNROLLED for (i = 0; i < 3; i++) acc[i] = af[i];
#endif
}

/* one classic RK4 step (Hairer-Norsett-Wanner I §II.1); U: the inputs at the nodes 0, 1/2, 1 */
__attribute__((noinline)) static void rk4(double *x, double h, const Inputs *U, const Params *P) {
    double y[NY], z[NY], k1[NY], k2[NY], k3[NY], k4[NY], a[4][3];
    double cs[3][2] = {{0.0, 0.0}, {0.0, 0.0}, {0.0, 0.0}};
    const double h2 = 0.5 * h, h6 = h * (1.0 / 6.0), h3 = h * (1.0 / 3.0);
    Node N[3];
    int i;
    (void)a, (void)cs, (void)h3;
    UNROLLED for (i = 0; i < 3; i++) node(U + i, P, N + i);
#ifdef REF_ORBIT /* sin, cos of theta + c h n, c = 0, 1/2, 1 (angle addition; the advances' in P) */
    cs[0][0] = sin(x[XTH]), cs[0][1] = cos(x[XTH]);
    UNROLLED for (i = 1; i < 3; i++) {
        cs[i][0] = cs[0][0] * P->adv[i][1] + cs[0][1] * P->adv[i][0];
        cs[i][1] = cs[0][1] * P->adv[i][1] - cs[0][0] * P->adv[i][0];
    }
#endif
    gather(x, y);
    rhs(y, x + 4, N, P, cs[0], k1, a[0]);
    UNROLLED for (i = 0; i < NY; i++) z[i] = y[i] + h2 * k1[i];
    rhs(z, x + 4, N + 1, P, cs[1], k2, a[1]);
    UNROLLED for (i = 0; i < NY; i++) z[i] = y[i] + h2 * k2[i];
    rhs(z, x + 4, N + 1, P, cs[1], k3, a[2]);
    UNROLLED for (i = 0; i < NY; i++) z[i] = y[i] + h * k3[i];
    rhs(z, x + 4, N + 2, P, cs[2], k4, a[3]);
    UNROLLED for (i = 0; i < NY; i++) y[i] += h6 * (k1[i] + k4[i]) + h3 * (k2[i] + k3[i]);
#if defined(REF_CONSTANT_ACC) /* x+ = x + h v + h^2/2 g, v+ = v + h g (no force but gravity) */
    UNROLLED for (i = 0; i < 3; i++) {
        const double v = x[XT + 3 + i];
#ifdef REF_FREE_GRAVITY
        x[XT + i] += h * v + (h * h2) * P->g[i];
        x[XT + 3 + i] = v + h * P->g[i];
#else
        x[XT + i] += h * v;
#endif
    }
#elif defined(REF_CLOSED_FORM) /* x+ = x + h v + h^2/6 (a_1 + a_2 + a_3), v+ = v + h/6 (a_1 + 2 a_2 + 2 a_3 + a_4) */
    UNROLLED for (i = 0; i < 3; i++) {
#if defined(REF_MOVING_PIVOT) /* x' = v, v' = a_pivot (§7.3) */
#define ACC(s, node) U[node].a_piv[i]
#elif defined(REF_BODY_FORCES)
#define ACC(s, node) a[s][i]
#else
#define ACC(s, node) N[node].fw[i]
#endif
        const double v = x[XT + 3 + i];
        x[XT + i] += h * v + (h * h6) * (ACC(0, 0) + ACC(1, 1) + ACC(2, 1));
        x[XT + 3 + i] = v + (h6 * (ACC(0, 0) + ACC(3, 2)) + h3 * (ACC(1, 1) + ACC(2, 1)));
#undef ACC
    }
#endif
#ifdef REF_ORBIT
    x[XTH] += h * P->n; /* theta' = n (§9.1) */
#endif
    scatter(y, x);
}

/* DOP853's 8th-order solution with its 12 stages (Hairer-Norsett-Wanner I §II.10; the
 * coefficients of scipy's dop853_coefficients, which modelsrc/integrators.py uses: the FMU's
 * rk8 without its error estimate); only the nonzero a_ij and b_i enter. U: the inputs at the 12
 * sorted nodes (modelsrc.integrators.stage_nodes("rk8")); stage s reads node RK8_NODE[s] */
__attribute__((noinline)) static void rk8(double *x, double h, const Inputs *U, const Params *P) {
    double y[NY], z[NY], k[12][NY], a[12][3], cs[12][2];
    Node N[12];
    int i, s;
    (void)a, (void)cs;
    UNROLLED for (s = 0; s < 12; s++) node(U + s, P, N + s);
#ifdef REF_ORBIT /* sin, cos of theta + c_s h n (angle addition; the advances' in P) */
    cs[0][0] = sin(x[XTH]), cs[0][1] = cos(x[XTH]);
    UNROLLED for (s = 1; s < 12; s++) {
        cs[s][0] = cs[0][0] * P->adv[s][1] + cs[0][1] * P->adv[s][0];
        cs[s][1] = cs[0][1] * P->adv[s][1] - cs[0][0] * P->adv[s][0];
    }
#endif
    gather(x, y);
#define STAGE(s, sum)                                                 \
    do {                                                              \
        UNROLLED for (i = 0; i < NY; i++) z[i] = y[i] + (sum);        \
        rhs(z, x + 4, N + RK8_NODE[s], P, cs[s], k[s], a[s]);         \
    } while (0)
#define K(j) k[j - 1][i]
    rhs(y, x + 4, N, P, cs[0], k[0], a[0]);
    STAGE(1, h * A21 * K(1));
    STAGE(2, h * A31 * K(1) + h * A32 * K(2));
    STAGE(3, h * A41 * K(1) + h * A43 * K(3));
    STAGE(4, h * A51 * K(1) + h * A53 * K(3) + h * A54 * K(4));
    STAGE(5, h * A61 * K(1) + h * A64 * K(4) + h * A65 * K(5));
    STAGE(6, h * A71 * K(1) + h * A74 * K(4) + h * A75 * K(5) + h * A76 * K(6));
    STAGE(7, h * A81 * K(1) + h * A84 * K(4) + h * A85 * K(5) + h * A86 * K(6) + h * A87 * K(7));
    STAGE(8, h * A91 * K(1) + h * A94 * K(4) + h * A95 * K(5) + h * A96 * K(6) + h * A97 * K(7) + h * A98 * K(8));
    STAGE(9, h * A101 * K(1) + h * A104 * K(4) + h * A105 * K(5) + h * A106 * K(6) + h * A107 * K(7) +
                 h * A108 * K(8) + h * A109 * K(9));
    STAGE(10, h * A111 * K(1) + h * A114 * K(4) + h * A115 * K(5) + h * A116 * K(6) + h * A117 * K(7) +
                  h * A118 * K(8) + h * A119 * K(9) + h * A1110 * K(10));
    STAGE(11, h * A121 * K(1) + h * A124 * K(4) + h * A125 * K(5) + h * A126 * K(6) + h * A127 * K(7) +
                  h * A128 * K(8) + h * A129 * K(9) + h * A1210 * K(10) + h * A1211 * K(11));
    UNROLLED for (i = 0; i < NY; i++)
        y[i] += h * (B1 * K(1) + B6 * K(6) + B7 * K(7) + B8 * K(8) + B9 * K(9) + B10 * K(10) + B11 * K(11) +
                     B12 * K(12));
#undef K
#undef STAGE
#if defined(REF_CONSTANT_ACC)
    UNROLLED for (i = 0; i < 3; i++) {
        const double v = x[XT + 3 + i];
#ifdef REF_FREE_GRAVITY
        x[XT + i] += h * v + (0.5 * h * h) * P->g[i];
        x[XT + 3 + i] = v + h * P->g[i];
#else
        x[XT + i] += h * v;
#endif
    }
#elif defined(REF_CLOSED_FORM)
    UNROLLED for (i = 0; i < 3; i++) { /* v+ = v + h sum b_s a_s, x+ = x + h v + h^2 sum beta_s a_s */
#if defined(REF_MOVING_PIVOT)
#define ACC(s) U[RK8_NODE[s]].a_piv[i]
#elif defined(REF_BODY_FORCES)
#define ACC(s) a[s][i]
#else
#define ACC(s) N[RK8_NODE[s]].fw[i]
#endif
        const double v = x[XT + 3 + i];
        x[XT + i] += h * v + (h * h) * (BETA1 * ACC(0) + BETA6 * ACC(5) + BETA7 * ACC(6) + BETA8 * ACC(7) +
                                        BETA9 * ACC(8) + BETA10 * ACC(9) + BETA11 * ACC(10));
        x[XT + 3 + i] = v + h * (B1 * ACC(0) + B6 * ACC(5) + B7 * ACC(6) + B8 * ACC(7) + B9 * ACC(8) +
                                 B10 * ACC(9) + B11 * ACC(10) + B12 * ACC(11));
#undef ACC
    }
#endif
#ifdef REF_ORBIT
    x[XTH] += h * P->n;
#endif
    scatter(y, x);
}

static double now(void) { /* CPU time of the process, as the harness fmu/c/bench_step.c */
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int main(int argc, char **argv) {
    static Params P;
    static Inputs U[12]; /* one column per node (RK4: 3, RK8: 12), all equal: held inputs */
    double x0[REF_NX], x[REF_NX], h, best = 1e30, t0;
    long n, k, repeats, rep;
    int a = 1, i, method;
    const int need = 1 + 4 + REF_NX + NPARAM + NINPUT;
    if (argc != need) {
        fprintf(stderr, "bench_reference: expected %d arguments, got %d\n", need - 1, argc - 1);
        return 2;
    }
    method = atoi(argv[a++]);
    n = atol(argv[a++]);
    repeats = atol(argv[a++]);
    h = atof(argv[a++]);
    if ((method != 4 && method != 8) || n < 1 || repeats < 1) {
        fprintf(stderr, "bench_reference: METHOD must be 4 or 8, N and REPEATS >= 1; got %d, %ld, %ld\n", method, n,
                repeats);
        return 2;
    }
    for (i = 0; i < REF_NX; i++) x0[i] = atof(argv[a++]);
    a = read_params(&P, argv, a);
    a = read_inputs(&U[0], argv, a);
    for (i = 1; i < 12; i++) U[i] = U[0];
    for (i = 0; i < 12; i++) { /* the orbit's advances c h n at the nodes, once per step size */
        const double c = method == 4 ? 0.5 * (double)i : RK8_C[i], adv = (c * h) * P.n;
        P.adv[i][0] = sin(adv), P.adv[i][1] = cos(adv);
    }
    for (rep = 0; rep < repeats; rep++) { /* best of the repeats: the least disturbed run */
        for (i = 0; i < REF_NX; i++) x[i] = x0[i];
        t0 = now();
        if (method == 4)
            for (k = 0; k < n; k++) rk4(x, h, U, &P);
        else
            for (k = 0; k < n; k++) rk8(x, h, U, &P);
        t0 = (now() - t0) / (double)n;
        if (t0 < best) best = t0;
    }
    printf("%.3f", best * 1e9);
    for (i = 0; i < REF_NX; i++) printf(" %.17g", x[i]);
    printf("\n");
    return 0;
}
