/* Minimal hand-written C RK4 and RK8 of a scene's equations: the benchmark's reference for the generated step.
 *
 * Never part of an FMU (the FMU's physics is only CasADi-generated C): it exists so that
 * `rbfmu bench` can show how close the generated step comes to what an expert would write
 * by hand for the same equations (docs/theory.md §1-§9). What depends on the parameters
 * only is computed once, before the loop, by fmu/benchmark.py (`reference_parameters`):
 * the inverse inertia about the rotation point, or with rotors the inverse of the constant
 * matrix (I - sum J g g^T) (§8.1); for a diagonal one Euler's coefficients
 * (I_j - I_k) M^-1_i, so that the gyroscopic term is one product per axis; friction c I^-1;
 * the weight m g; g and 1/m of a free body; 3 n^2 (I_j - I_k) M^-1_i of the gravity gradient
 * (§9.2); 1/J of each torque-mode rotor. The step adds only what the state needs.
 *
 * Inputs: the step reads the inputs at its stage nodes t + c h (one column per node, as the
 * generated step does: a step that admits intermediate inputs (FMI 3 intermediate update)
 * must read them at every stage), here: RK4 the nodes 0, 1/2, 1 (stage 1 node 0, stages 2
 * and 3 node 1/2, stage 4 node 1); RK8 (DOP853, fmu's `rk8`, modelsrc/integrators.py) the
 * 12 distinct nodes of its 12 stages. Every input term (torques, forces, a_pivot, motor
 * torques, rotor speeds) is evaluated at every stage from that stage's column. The
 * benchmark holds them (equal columns), as the harness fmu/c/bench_step.c does.
 *
 * The rotation R(q) = R~(q)/|q|^2 is the model's (modelsrc/quaternion.py, Rotation): exact
 * for the q off the unit sphere that the stages visit, so the reference reproduces the
 * generated trajectory to rounding (tests/test_benchmark_reference.py); one division per
 * right-hand side that rotates something. After each step q is projected onto |q| = 1.
 *
 * The features are compile-time macros set by fmu/benchmark.py from the scene
 * (`reference_features`); rotor axes are body axes (REF_TAX_k, REF_SAX_k: 0, 1, 2), as in
 * every shipped scene. The parameters, start state and inputs come from the command line,
 * so that the compiler cannot fold them into constants (the generated step reads them from
 * memory too), and the step is a function of its own (noinline), called per step like the
 * generated one.
 *
 * Usage: bench_reference N METHOD H X[NX] P[NP] U[NU]: N steps of H seconds of METHOD (4:
 *        RK4, 8: RK8) from X, parameters P in the order of `reference_parameters`, inputs U
 *        held at every node. Prints ns per step (best of 5) and the final state. */
#define _POSIX_C_SOURCE 199309L /* clock_gettime under -std=c99 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#ifndef REF_NTROT /* torque-mode rotors (states Omega, inputs u) */
#define REF_NTROT 0
#endif
#ifndef REF_NSROT /* speed-mode rotors (inputs Omega, Omega_dot; propellers: thrust, drag) */
#define REF_NSROT 0
#endif
#ifndef REF_NPOINTS /* force points */
#define REF_NPOINTS 0
#endif
#ifndef REF_POINT_WORLD /* bit k set: point k's force is given in the world frame */
#define REF_POINT_WORLD 0
#endif
#if defined(REF_TRANSLATION) || defined(REF_MOVING_PIVOT)
#define REF_NMOVE 6
#else
#define REF_NMOVE 0
#endif
#ifdef REF_ORBIT
#define REF_NORBIT 1
#else
#define REF_NORBIT 0
#endif
#define REF_NX (7 + REF_NMOVE + REF_NTROT + REF_NORBIT)
#define IX_OMEGA (7 + REF_NMOVE) /* first rotor rate */
#define IX_THETA (7 + REF_NMOVE + REF_NTROT)
#define MAX1(n) ((n) > 0 ? (n) : 1)
/* the loops over the states straight-line code, as a hand-written kernel spells them out: the
 * compiler then keeps the states in registers and folds constant derivatives */
#define UNROLLED _Pragma("GCC unroll 32")
#ifndef REF_FB_AXES /* bit i set: the body-frame forces may have a component along body axis i */
#define REF_FB_AXES 7
#endif
#if defined(REF_FORCE_BODY) || (REF_POINT_WORLD != (1 << REF_NPOINTS) - 1) || \
    (defined(REF_PROPELLERS) && defined(REF_TRANSLATION))
#define REF_BODY_FORCES 1 /* forces given in the body frame: turned into the world's */
#endif
#if defined(REF_BODY_FORCES) || defined(REF_GRAVITY) || defined(REF_TAU_WORLD) || REF_POINT_WORLD != 0 || \
    defined(REF_GRAVITY_GRADIENT)
#define REF_ROTATES 1 /* something turns between the frames: R~(q) and 1/|q|^2 */
#endif

/* the inputs at one node */
typedef struct {
    double tau_b[3], tau_w[3], f_b[3], f_w[3], pt_f[MAX1(REF_NPOINTS)][3], a_piv[3];
    double u[MAX1(REF_NTROT)], Om[MAX1(REF_NSROT)], Omd[MAX1(REF_NSROT)];
} Inputs;

/* parameters and what is derived from them, once (fmu/benchmark.py, reference_parameters) */
typedef struct {
    double I[9];    /* about the rotation point, body, row major (full tensors: I w) */
    double Minv[9]; /* (I - sum_torque J g g^T)^-1, I^-1 without rotors; row major */
    double eul[3];  /* diagonal: (I_2 - I_3) Minv_1, cyclic */
    double cI[3];   /* friction: c Minv_i (diagonal) or c */
    double W[3];    /* heavy top: the weight m g (N, world); moving pivot: m g */
    double m;       /* moving pivot: the mass (r x R^T m (g - a)) */
    double r[3];    /* pivot -> centre of mass (body) */
    double g[3];    /* free body: gravitational acceleration (world) */
    double inv_m;   /* free body: 1/m */
    double pt_r[MAX1(REF_NPOINTS)][3];
    double gg[9];   /* gravity gradient: 3 n^2 (I_3 - I_2) Minv_1 ... (diagonal), else 3 n^2 I */
    double n;       /* orbit rate */
    double J[MAX1(REF_NTROT + REF_NSROT)], invJ[MAX1(REF_NTROT)];
    double kf[MAX1(REF_NSROT)], km[MAX1(REF_NSROT)], rpos[MAX1(REF_NSROT)][3];
} Params;

#if REF_NTROT > 0
static const int TAX[REF_NTROT] = {REF_TAX}; /* the torque-mode rotors' axes (body axis index) */
#endif
#if REF_NSROT > 0
static const int SAX[REF_NSROT] = {REF_SAX}; /* the speed-mode rotors' axes */
#endif

#define CROSS_ADD(a, b, out)                 \
    do {                                     \
        (out)[0] += (a)[1] * (b)[2] - (a)[2] * (b)[1]; \
        (out)[1] += (a)[2] * (b)[0] - (a)[0] * (b)[2]; \
        (out)[2] += (a)[0] * (b)[1] - (a)[1] * (b)[0]; \
    } while (0)

/* x' = f(x, u): docs/theory.md §1.2 (q), §2 (Euler), §4 (gravity, friction, prescribed rate),
 * §7 (free flight, force points, moving pivot), §8 (rotors), §9 (orbit, gravity gradient) */
static inline __attribute__((always_inline)) void rhs(const double *x, const Inputs *U, const Params *P,
                                                      double *dx) {
    const double qw = x[0], qx = x[1], qy = x[2], qz = x[3];
    const double w0 = x[4], w1 = x[5], w2 = x[6];
    const double hw0 = 0.5 * w0, hw1 = 0.5 * w1, hw2 = 0.5 * w2;
    double tau[3] = {0.0, 0.0, 0.0}; /* body torque, before the inertia */
    (void)U;
    (void)P;
    /* q' = 1/2 q (x) (0, w) (§1.2) */
    dx[0] = -qx * hw0 - qy * hw1 - qz * hw2;
    dx[1] = qw * hw0 + qy * hw2 - qz * hw1;
    dx[2] = qw * hw1 + qz * hw0 - qx * hw2;
    dx[3] = qw * hw2 + qx * hw1 - qy * hw0;
#ifdef REF_ROTATES
    /* R~ = |q|^2 R (§1.1); R v = (R~ v) s, R^T v = (R~^T v) s with s = 1/|q|^2 */
    const double xx = qx * qx, yy = qy * qy, zz = qz * qz, ww = qw * qw;
    const double xy = qx * qy, xz = qx * qz, yz = qy * qz, wx = qw * qx, wy = qw * qy, wz = qw * qz;
    const double s = 1.0 / (ww + xx + yy + zz);
    const double R[9] = {ww + xx - yy - zz, 2 * (xy - wz),     2 * (xz + wy),
                         2 * (xy + wz),     ww - xx + yy - zz, 2 * (yz - wx),
                         2 * (xz - wy),     2 * (yz + wx),     ww - xx - yy + zz};
#define RT_TIMES(v, out)                                                \
    do {                                                                \
        (out)[0] = (R[0] * (v)[0] + R[3] * (v)[1] + R[6] * (v)[2]) * s; \
        (out)[1] = (R[1] * (v)[0] + R[4] * (v)[1] + R[7] * (v)[2]) * s; \
        (out)[2] = (R[2] * (v)[0] + R[5] * (v)[1] + R[8] * (v)[2]) * s; \
    } while (0)
#define R_TIMES(v, out)                                                 \
    do {                                                                \
        (out)[0] = (R[0] * (v)[0] + R[1] * (v)[1] + R[2] * (v)[2]) * s; \
        (out)[1] = (R[3] * (v)[0] + R[4] * (v)[1] + R[5] * (v)[2]) * s; \
        (out)[2] = (R[6] * (v)[0] + R[7] * (v)[1] + R[8] * (v)[2]) * s; \
    } while (0)
#endif
#ifdef REF_GRAVITY /* heavy top: r_cm x R^T m (g - a_pivot) (§4.1, §7.3) */
    {
        double fb[3];
#ifdef REF_MOVING_PIVOT
        const double wt[3] = {P->W[0] - P->m * U->a_piv[0], P->W[1] - P->m * U->a_piv[1],
                              P->W[2] - P->m * U->a_piv[2]};
        RT_TIMES(wt, fb);
#else
        RT_TIMES(P->W, fb);
#endif
        CROSS_ADD(P->r, fb, tau);
    }
#endif
#ifdef REF_TAU_BODY
    tau[0] += U->tau_b[0];
    tau[1] += U->tau_b[1];
    tau[2] += U->tau_b[2];
#endif
#ifdef REF_TAU_WORLD
    {
        double t[3];
        RT_TIMES(U->tau_w, t);
        tau[0] += t[0];
        tau[1] += t[1];
        tau[2] += t[2];
    }
#endif
#ifdef REF_TRANSLATION
    double Fb[3] = {0.0, 0.0, 0.0}, Fw[3] = {0.0, 0.0, 0.0}; /* forces given in the body, in the world */
    (void)Fb;
    (void)Fw;
#ifdef REF_FORCE_BODY
    Fb[0] += U->f_b[0];
    Fb[1] += U->f_b[1];
    Fb[2] += U->f_b[2];
#endif
#ifdef REF_FORCE_WORLD
    Fw[0] += U->f_w[0];
    Fw[1] += U->f_w[1];
    Fw[2] += U->f_w[2];
#endif
#if REF_NPOINTS > 0
    UNROLLED for (int k = 0; k < REF_NPOINTS; k++) { /* force at a point: F and r x F (§7.1) */
        if (REF_POINT_WORLD & (1 << k)) {
            double fb[3];
            RT_TIMES(U->pt_f[k], fb);
            CROSS_ADD(P->pt_r[k], fb, tau);
            Fw[0] += U->pt_f[k][0];
            Fw[1] += U->pt_f[k][1];
            Fw[2] += U->pt_f[k][2];
        } else {
            CROSS_ADD(P->pt_r[k], U->pt_f[k], tau);
            Fb[0] += U->pt_f[k][0];
            Fb[1] += U->pt_f[k][1];
            Fb[2] += U->pt_f[k][2];
        }
    }
#endif
#endif
    double h[3] = {0.0, 0.0, 0.0}; /* the rotors' relative momentum sum J Omega g (§8.1) */
    (void)h;
    /* v[ax] += val with a constant index whatever ax: the compiler keeps v in registers (an index
     * known only once the rotor loop is unrolled would leave v in memory, a store-to-load chain) */
#define AXIS_ADD(v, ax, val)         \
    do {                             \
        const double val_ = (val);   \
        if ((ax) == 0)               \
            (v)[0] += val_;          \
        else if ((ax) == 1)          \
            (v)[1] += val_;          \
        else                         \
            (v)[2] += val_;          \
    } while (0)
#if REF_NTROT > 0
    UNROLLED for (int k = 0; k < REF_NTROT; k++) {
        AXIS_ADD(h, TAX[k], P->J[k] * x[IX_OMEGA + k]);
        AXIS_ADD(tau, TAX[k], -U->u[k]); /* the body feels -u g */
    }
#endif
#if REF_NSROT > 0
    UNROLLED for (int k = 0; k < REF_NSROT; k++) { /* speed mode: Omega, Omega' inputs; propellers (§8.5, §8.6) */
        const double Om = U->Om[k], J = P->J[REF_NTROT + k];
        AXIS_ADD(h, SAX[k], J * Om);
        AXIS_ADD(tau, SAX[k], -(J * U->Omd[k] + P->km[k] * Om * fabs(Om)));
#ifdef REF_PROPELLERS /* every speed-mode rotor: thrust k_f Omega^2 along the axis at its position */
        {
            const double f = P->kf[k] * Om * Om;
            const int a = SAX[k], b = (a + 1) % 3, c = (a + 2) % 3;
            /* (r x f e_a)_b = r_c f, (r x f e_a)_c = -r_b f */
            AXIS_ADD(tau, b, P->rpos[k][c] * f);
            AXIS_ADD(tau, c, -(P->rpos[k][b] * f));
#ifdef REF_TRANSLATION
            AXIS_ADD(Fb, a, f);
#endif
        }
#endif
    }
#endif
#ifdef REF_ORBIT /* gravity gradient: 3 n^2 c x (I c), c = R^T (-sin th, 0, cos th) (§9.2) */
    const double sth = sin(x[IX_THETA]), cth = cos(x[IX_THETA]);
#ifdef REF_GRAVITY_GRADIENT
    const double c0 = (-R[0] * sth + R[6] * cth) * s, c1 = (-R[1] * sth + R[7] * cth) * s,
                 c2 = (-R[2] * sth + R[8] * cth) * s;
#endif
#endif
#ifdef REF_PRESCRIBED /* held at a constant rate about a fixed axis: w' = 0 (§4.4) */
    dx[4] = dx[5] = dx[6] = 0.0;
    (void)tau;
#elif defined(REF_FULL_INERTIA) /* w' = M^-1 (tau - w x (I w + h)) (§2, §8.1) */
    {
        const double *I = P->I, *M = P->Minv;
        double L[3] = {I[0] * w0 + I[1] * w1 + I[2] * w2 + h[0], I[3] * w0 + I[4] * w1 + I[5] * w2 + h[1],
                       I[6] * w0 + I[7] * w1 + I[8] * w2 + h[2]};
        double t[3];
#ifdef REF_FRICTION
        tau[0] -= P->cI[0] * w0;
        tau[1] -= P->cI[0] * w1;
        tau[2] -= P->cI[0] * w2;
#endif
#ifdef REF_GRAVITY_GRADIENT
        {
            const double *G = P->gg, c[3] = {c0, c1, c2};
            const double Gc[3] = {G[0] * c0 + G[1] * c1 + G[2] * c2, G[3] * c0 + G[4] * c1 + G[5] * c2,
                                  G[6] * c0 + G[7] * c1 + G[8] * c2};
            CROSS_ADD(c, Gc, tau);
        }
#endif
        t[0] = tau[0] - (w1 * L[2] - w2 * L[1]);
        t[1] = tau[1] - (w2 * L[0] - w0 * L[2]);
        t[2] = tau[2] - (w0 * L[1] - w1 * L[0]);
        dx[4] = M[0] * t[0] + M[1] * t[1] + M[2] * t[2];
        dx[5] = M[3] * t[0] + M[4] * t[1] + M[5] * t[2];
        dx[6] = M[6] * t[0] + M[7] * t[1] + M[8] * t[2];
    }
#else /* diagonal: w'_1 = (I_2 - I_3) M_1 w_2 w_3 + M_1 (tau_1 - (w x h)_1) - c M_1 w_1, cyclic */
    {
        const double *M = P->Minv;
        double t[3] = {tau[0], tau[1], tau[2]};
#if REF_NTROT + REF_NSROT > 0
        t[0] -= w1 * h[2] - w2 * h[1];
        t[1] -= w2 * h[0] - w0 * h[2];
        t[2] -= w0 * h[1] - w1 * h[0];
#endif
        dx[4] = P->eul[0] * (w1 * w2) + M[0] * t[0];
        dx[5] = P->eul[1] * (w2 * w0) + M[4] * t[1];
        dx[6] = P->eul[2] * (w0 * w1) + M[8] * t[2];
#ifdef REF_FRICTION
        dx[4] -= P->cI[0] * w0;
        dx[5] -= P->cI[1] * w1;
        dx[6] -= P->cI[2] * w2;
#endif
#ifdef REF_GRAVITY_GRADIENT
        dx[4] += P->gg[0] * (c1 * c2);
        dx[5] += P->gg[1] * (c2 * c0);
        dx[6] += P->gg[2] * (c0 * c1);
#endif
    }
#endif
#ifdef REF_TRANSLATION /* x' = v, v' = g + (R F_body + F_world) / m (§7.1) */
    {
        double a[3] = {0.0, 0.0, 0.0};
#if defined(REF_BODY_FORCES) && REF_FB_AXES == 4 /* body forces along body z only (propellers): R's column 3 */
        a[0] = R[2] * Fb[2] * s;
        a[1] = R[5] * Fb[2] * s;
        a[2] = R[8] * Fb[2] * s;
#elif defined(REF_BODY_FORCES)
        R_TIMES(Fb, a);
#endif
        dx[7] = x[10];
        dx[8] = x[11];
        dx[9] = x[12];
#if !(defined(REF_FORCE_BODY) || defined(REF_FORCE_WORLD) || REF_NPOINTS > 0 || defined(REF_PROPELLERS))
        (void)a; /* no force but gravity: the parabola */
#ifdef REF_FREE_GRAVITY
        dx[10] = P->g[0];
        dx[11] = P->g[1];
        dx[12] = P->g[2];
#else
        dx[10] = dx[11] = dx[12] = 0.0;
#endif
#elif defined(REF_FREE_GRAVITY)
        dx[10] = P->g[0] + P->inv_m * (a[0] + Fw[0]);
        dx[11] = P->g[1] + P->inv_m * (a[1] + Fw[1]);
        dx[12] = P->g[2] + P->inv_m * (a[2] + Fw[2]);
#else
        dx[10] = P->inv_m * (a[0] + Fw[0]);
        dx[11] = P->inv_m * (a[1] + Fw[1]);
        dx[12] = P->inv_m * (a[2] + Fw[2]);
#endif
    }
#endif
#ifdef REF_MOVING_PIVOT /* x' = v, v' = a_pivot (§7.3) */
    dx[7] = x[10];
    dx[8] = x[11];
    dx[9] = x[12];
    dx[10] = U->a_piv[0];
    dx[11] = U->a_piv[1];
    dx[12] = U->a_piv[2];
#endif
#if REF_NTROT > 0 /* J Omega' = u - J g.w' (§8.1) */
    UNROLLED for (int k = 0; k < REF_NTROT; k++) {
        const double wd = TAX[k] == 0 ? dx[4] : TAX[k] == 1 ? dx[5] : dx[6];
        dx[IX_OMEGA + k] = U->u[k] * P->invJ[k] - wd;
    }
#endif
#ifdef REF_ORBIT
    dx[IX_THETA] = P->n; /* theta' = n (§9.1) */
#endif
}

static void project(double *x) { /* q onto |q| = 1 */
    const double n = 1.0 / sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2] + x[3] * x[3]);
    x[0] *= n;
    x[1] *= n;
    x[2] *= n;
    x[3] *= n;
}

/* One classic RK4 step (Hairer-Norsett-Wanner I §II.1); U: the inputs at the nodes 0, 1/2, 1. */
__attribute__((noinline)) static void rk4(double *x, double h, const Inputs *U, const Params *P) {
    double k1[REF_NX], k2[REF_NX], k3[REF_NX], k4[REF_NX], y[REF_NX];
    const double h2 = 0.5 * h, h6 = h * (1.0 / 6.0), h3 = h * (1.0 / 3.0);
    int i;
    rhs(x, U, P, k1);
    UNROLLED for (i = 0; i < REF_NX; i++) y[i] = x[i] + h2 * k1[i];
    rhs(y, U + 1, P, k2);
    UNROLLED for (i = 0; i < REF_NX; i++) y[i] = x[i] + h2 * k2[i];
    rhs(y, U + 1, P, k3);
    UNROLLED for (i = 0; i < REF_NX; i++) y[i] = x[i] + h * k3[i];
    rhs(y, U + 2, P, k4);
    UNROLLED for (i = 0; i < REF_NX; i++) x[i] += h6 * (k1[i] + k4[i]) + h3 * (k2[i] + k3[i]);
    project(x);
}

/* DOP853's 8th-order solution with its 12 stages (Hairer-Norsett-Wanner I §II.10; the
 * coefficients of scipy's dop853_coefficients, which modelsrc/integrators.py uses: the FMU's
 * rk8 without its error estimate); only the nonzero a_ij and b_i enter. */
#define A21 0.05260015195876773
#define A31 0.0197250569845379
#define A32 0.0591751709536137
#define A41 0.02958758547680685
#define A43 0.08876275643042054
#define A51 0.2413651341592667
#define A53 (-0.8845494793282861)
#define A54 0.924834003261792
#define A61 0.037037037037037035
#define A64 0.17082860872947386
#define A65 0.12546768756682242
#define A71 0.037109375
#define A74 0.17025221101954405
#define A75 0.06021653898045596
#define A76 (-0.017578125)
#define A81 0.03709200011850479
#define A84 0.17038392571223998
#define A85 0.10726203044637328
#define A86 (-0.015319437748624402)
#define A87 0.008273789163814023
#define A91 0.6241109587160757
#define A94 (-3.3608926294469414)
#define A95 (-0.868219346841726)
#define A96 27.59209969944671
#define A97 20.154067550477894
#define A98 (-43.48988418106996)
#define A101 0.47766253643826434
#define A104 (-2.4881146199716677)
#define A105 (-0.590290826836843)
#define A106 21.230051448181193
#define A107 15.279233632882423
#define A108 (-33.28821096898486)
#define A109 (-0.020331201708508627)
#define A111 (-0.9371424300859873)
#define A114 5.186372428844064
#define A115 1.0914373489967295
#define A116 (-8.149787010746927)
#define A117 (-18.52006565999696)
#define A118 22.739487099350505
#define A119 2.4936055526796523
#define A1110 (-3.0467644718982196)
#define A121 2.273310147516538
#define A124 (-10.53449546673725)
#define A125 (-2.0008720582248625)
#define A126 (-17.9589318631188)
#define A127 27.94888452941996
#define A128 (-2.8589982771350235)
#define A129 (-8.87285693353063)
#define A1210 12.360567175794303
#define A1211 0.6433927460157636
#define B1 0.054293734116568765
#define B6 4.450312892752409
#define B7 1.8915178993145003
#define B8 (-5.801203960010585)
#define B9 0.3111643669578199
#define B10 (-0.1521609496625161)
#define B11 0.20136540080403034
#define B12 0.04471061572777259

/* U: the inputs at the 12 sorted nodes 0, c2, c3, c4, 1/4, c5, 4/13, 1/3, 3/5, c9, 6/7, 1
 * (modelsrc.integrators.stage_nodes("rk8")); stage i reads node NODE_i */
__attribute__((noinline)) static void rk8(double *x, double h, const Inputs *U, const Params *P) {
    double k[12][REF_NX], y[REF_NX];
    int i;
#define STAGE(s, node, sum)                                   \
    do {                                                      \
        UNROLLED for (i = 0; i < REF_NX; i++) y[i] = x[i] + sum;        \
        rhs(y, U + (node), P, k[s]);                          \
    } while (0)
#define K(j) k[j - 1][i]
    rhs(x, U, P, k[0]);
    STAGE(1, 1, h * A21 * K(1));
    STAGE(2, 2, h * A31 * K(1) + h * A32 * K(2));
    STAGE(3, 3, h * A41 * K(1) + h * A43 * K(3));
    STAGE(4, 5, h * A51 * K(1) + h * A53 * K(3) + h * A54 * K(4));
    STAGE(5, 7, h * A61 * K(1) + h * A64 * K(4) + h * A65 * K(5));
    STAGE(6, 4, h * A71 * K(1) + h * A74 * K(4) + h * A75 * K(5) + h * A76 * K(6));
    STAGE(7, 6, h * A81 * K(1) + h * A84 * K(4) + h * A85 * K(5) + h * A86 * K(6) + h * A87 * K(7));
    STAGE(8, 9, h * A91 * K(1) + h * A94 * K(4) + h * A95 * K(5) + h * A96 * K(6) + h * A97 * K(7) + h * A98 * K(8));
    STAGE(9, 8, h * A101 * K(1) + h * A104 * K(4) + h * A105 * K(5) + h * A106 * K(6) + h * A107 * K(7) +
                    h * A108 * K(8) + h * A109 * K(9));
    STAGE(10, 10, h * A111 * K(1) + h * A114 * K(4) + h * A115 * K(5) + h * A116 * K(6) + h * A117 * K(7) +
                      h * A118 * K(8) + h * A119 * K(9) + h * A1110 * K(10));
    STAGE(11, 11, h * A121 * K(1) + h * A124 * K(4) + h * A125 * K(5) + h * A126 * K(6) + h * A127 * K(7) +
                      h * A128 * K(8) + h * A129 * K(9) + h * A1210 * K(10) + h * A1211 * K(11));
    UNROLLED for (i = 0; i < REF_NX; i++)
        x[i] += h * (B1 * K(1) + B6 * K(6) + B7 * K(7) + B8 * K(8) + B9 * K(9) + B10 * K(10) + B11 * K(11) +
                     B12 * K(12));
#undef K
#undef STAGE
    project(x);
}

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* the parameters in the order fmu/benchmark.py (reference_parameters) writes them */
static int read_params(Params *P, char **argv, int a) {
    int i, k;
    for (i = 0; i < 9; i++) P->I[i] = atof(argv[a++]);
    for (i = 0; i < 9; i++) P->Minv[i] = atof(argv[a++]);
    for (i = 0; i < 3; i++) P->eul[i] = atof(argv[a++]);
    for (i = 0; i < 3; i++) P->cI[i] = atof(argv[a++]);
    for (i = 0; i < 3; i++) P->W[i] = atof(argv[a++]);
    P->m = atof(argv[a++]);
    for (i = 0; i < 3; i++) P->r[i] = atof(argv[a++]);
    for (i = 0; i < 3; i++) P->g[i] = atof(argv[a++]);
    P->inv_m = atof(argv[a++]);
    for (i = 0; i < 9; i++) P->gg[i] = atof(argv[a++]);
    P->n = atof(argv[a++]);
    for (k = 0; k < REF_NPOINTS; k++)
        for (i = 0; i < 3; i++) P->pt_r[k][i] = atof(argv[a++]);
    for (k = 0; k < REF_NTROT + REF_NSROT; k++) P->J[k] = atof(argv[a++]);
    for (k = 0; k < REF_NTROT; k++) P->invJ[k] = atof(argv[a++]);
    for (k = 0; k < REF_NSROT; k++) {
        P->kf[k] = atof(argv[a++]);
        P->km[k] = atof(argv[a++]);
        for (i = 0; i < 3; i++) P->rpos[k][i] = atof(argv[a++]);
    }
    return a;
}

/* one node's inputs, in the order of reference_inputs */
static int read_inputs(Inputs *U, char **argv, int a) {
    int i, k;
    for (i = 0; i < 3; i++) U->tau_b[i] = atof(argv[a++]);
    for (i = 0; i < 3; i++) U->tau_w[i] = atof(argv[a++]);
    for (i = 0; i < 3; i++) U->f_b[i] = atof(argv[a++]);
    for (i = 0; i < 3; i++) U->f_w[i] = atof(argv[a++]);
    for (k = 0; k < REF_NPOINTS; k++)
        for (i = 0; i < 3; i++) U->pt_f[k][i] = atof(argv[a++]);
    for (i = 0; i < 3; i++) U->a_piv[i] = atof(argv[a++]);
    for (k = 0; k < REF_NTROT; k++) U->u[k] = atof(argv[a++]);
    for (k = 0; k < REF_NSROT; k++) {
        U->Om[k] = atof(argv[a++]);
        U->Omd[k] = atof(argv[a++]);
    }
    return a;
}

#define NPARAM (9 + 9 + 3 + 3 + 3 + 1 + 3 + 3 + 1 + 9 + 1 + 3 * REF_NPOINTS + 2 * REF_NTROT + REF_NSROT + 5 * REF_NSROT)
#define NINPUT (12 + 3 * REF_NPOINTS + 3 + REF_NTROT + 2 * REF_NSROT)

int main(int argc, char **argv) {
    static Params P;
    static Inputs U[12]; /* one column per node (RK4: 3, RK8: 12), all equal: held inputs */
    double x0[REF_NX], x[REF_NX], h, best = 1e30, t0;
    long n, k;
    int a = 1, i, rep, method;
    const int need = 1 + 3 + REF_NX + NPARAM + NINPUT;
    if (argc != need) {
        fprintf(stderr, "bench_reference: expected %d arguments, got %d\n", need - 1, argc - 1);
        return 2;
    }
    n = atol(argv[a++]);
    method = atoi(argv[a++]);
    h = atof(argv[a++]);
    if (method != 4 && method != 8) {
        fprintf(stderr, "bench_reference: METHOD must be 4 (RK4) or 8 (RK8), got %d\n", method);
        return 2;
    }
    for (i = 0; i < REF_NX; i++) x0[i] = atof(argv[a++]);
    a = read_params(&P, argv, a);
    a = read_inputs(&U[0], argv, a);
    for (i = 1; i < 12; i++) U[i] = U[0];
    for (rep = 0; rep < 5; rep++) { /* best of 5: the least disturbed run */
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
