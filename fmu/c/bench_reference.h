/* Definitions of the benchmark's hand-written reference kernel: its features, records, vector helpers and tableau.
 *
 * Included by bench_reference.c only (benchmark, never part of an FMU). The features are
 * compile-time macros set by fmu/bench/reference.py (`reference_features`); the parameters are read
 * in the order `reference_parameters` writes them, the inputs in that of `reference_inputs`. */
#ifndef BENCH_REFERENCE_H
#define BENCH_REFERENCE_H

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
#ifndef REF_FB_AXES /* bit i set: the body-frame forces may have a component along body axis i */
#define REF_FB_AXES 7
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
#define XT 7                         /* FMU state order: q, w, (x, v), the rotor rates, theta */
#define XR (7 + REF_NMOVE)           /* first torque-mode rotor rate */
#define XTH (7 + REF_NMOVE + REF_NTROT) /* orbit angle */
#ifdef REF_PRESCRIBED                /* the staged states: q, (w), the rotor rates, (a central field's x, v) */
#define NW 0
#else
#define NW 3
#endif
#define YW 4
#define YR (4 + NW)
#define YC (4 + NW + REF_NTROT)
#ifdef REF_CENTRAL
#define NY (YC + 6)
#else
#define NY YC
#endif
#define MAX1(n) ((n) > 0 ? (n) : 1)
/* the loops over the states straight-line code, as a hand-written kernel spells them out: the
 * compiler then keeps the states in registers and folds what is known at compile time */
#define UNROLLED _Pragma("GCC unroll 32")
#if defined(REF_TRANSLATION) && (defined(REF_FORCE_BODY) || (REF_POINT_WORLD != (1 << REF_NPOINTS) - 1) || \
                                 defined(REF_PROPELLERS))
#define REF_BODY_FORCES 1 /* forces given in the body frame: turned into the world's per stage */
#endif
#if defined(REF_TRANSLATION) && (defined(REF_FORCE_WORLD) || REF_POINT_WORLD != 0)
#define REF_WORLD_FORCES 1 /* forces given in the world frame */
#endif
#if defined(REF_TRANSLATION) && !defined(REF_CENTRAL) && !defined(REF_BODY_FORCES) && !defined(REF_WORLD_FORCES)
#define REF_CONSTANT_ACC 1 /* the centre of mass falls freely (or drifts): a = g */
#elif (defined(REF_TRANSLATION) && !defined(REF_CENTRAL)) || defined(REF_MOVING_PIVOT)
#define REF_CLOSED_FORM 1 /* x, v summed in closed form from the stage accelerations */
#endif
#if defined(REF_BODY_FORCES) || defined(REF_GRAVITY) || defined(REF_TAU_WORLD) || REF_POINT_WORLD != 0 || \
    defined(REF_GRAVITY_GRADIENT) || defined(REF_CENTRAL)
#define REF_ROTATES 1 /* something turns between the frames: 2/|q|^2 */
#endif
#if defined(REF_FULL_INERTIA) || defined(REF_HFORM)
#define REF_MOMENTUM 1 /* w x (I w + h) with h the rotors' momentum, not Euler's coefficients */
#endif

/* the inputs at one node */
typedef struct {
    double tau_b[3], tau_w[3], f_b[3], f_w[3], pt_f[MAX1(REF_NPOINTS)][3], a_piv[3];
    double u[MAX1(REF_NTROT)], Om[MAX1(REF_NSROT)], Omd[MAX1(REF_NSROT)];
} Inputs;

/* parameters and what is derived from them, once (fmu/bench/reference.py, reference_parameters) */
typedef struct {
    double I[9];    /* about the rotation point, body, row major */
    double Minv[9]; /* M^-1 = (I - sum_torque J g g^T)^-1 (I^-1 without rotors), row major; m_i = Minv[4 i] */
    double e[3];    /* diagonal: Euler's coefficients (I_2 - I_3) m_1, cyclic */
    double cI[3];   /* friction: c m_i (diagonal), c (full) */
    double mr[9];   /* heavy top: m_i r_j (diagonal), r in mr[0..2] (full); r: pivot -> centre of mass */
    double W[3];    /* heavy top: the weight m g (N, world) */
    double m;       /* moving pivot: the mass (m (g - a)) */
    double g[3];    /* free body: gravitational acceleration (world) */
    double inv_m;   /* free body: 1/m */
    double gg[9];   /* gravity gradient: 3 n^2 (I_3 - I_2) m_1 ... (diagonal), else 3 n^2 I */
    double n;       /* orbit rate */
    double adv[12][2]; /* orbit: sin, cos of the advances c h n of the method's nodes, once per h (main) */
    double mu, trI, c15m; /* central field: mu, tr I, 1.5/m */
    double gc[3];   /* central field, diagonal: 3 (I_3 - I_2) m_1, cyclic */
    double pt_r[MAX1(REF_NPOINTS)][3];
    double J[MAX1(REF_NTROT + REF_NSROT)], invJ[MAX1(REF_NTROT)];
    double mJ[3][MAX1(REF_NTROT)]; /* diagonal: m_i J_k of the torque-mode rotors */
    double kf[MAX1(REF_NSROT)], km[MAX1(REF_NSROT)], rpos[MAX1(REF_NSROT)][3];
} Params;

#if REF_NTROT > 0
static const int TAX[REF_NTROT] = {REF_TAX}; /* the torque-mode rotors' axes (body axis index) */
#else
static const int TAX[1] = {0};
#endif
#if REF_NSROT > 0
static const int SAX[REF_NSROT] = {REF_SAX}; /* the speed-mode rotors' axes */
#endif

#define CROSS_ADD(a, b, out)                           \
    do {                                               \
        (out)[0] += (a)[1] * (b)[2] - (a)[2] * (b)[1]; \
        (out)[1] += (a)[2] * (b)[0] - (a)[0] * (b)[2]; \
        (out)[2] += (a)[0] * (b)[1] - (a)[1] * (b)[0]; \
    } while (0)
/* v[ax] += val with a constant index whatever ax: the compiler keeps v in registers */
#define AXIS_ADD(v, ax, val)       \
    do {                           \
        const double val_ = (val); \
        if ((ax) == 0)             \
            (v)[0] += val_;        \
        else if ((ax) == 1)        \
            (v)[1] += val_;        \
        else                       \
            (v)[2] += val_;        \
    } while (0)
/* R^T v (world -> body) = v + s2 (u x t - w t), t = u x v, u = (qx, qy, qz), s2 = 2/|q|^2: the
 * model's R~(q)/|q|^2 (§1.1) for any q, in 30 operations instead of the 9 entries of R~ and 15 */
#define ROT_T(v, out)                                                                               \
    do {                                                                                            \
        const double t0_ = qy * (v)[2] - qz * (v)[1], t1_ = qz * (v)[0] - qx * (v)[2],              \
                     t2_ = qx * (v)[1] - qy * (v)[0];                                               \
        (out)[0] = (v)[0] + s2 * ((qy * t2_ - qz * t1_) - qw * t0_);                                \
        (out)[1] = (v)[1] + s2 * ((qz * t0_ - qx * t2_) - qw * t1_);                                \
        (out)[2] = (v)[2] + s2 * ((qx * t1_ - qy * t0_) - qw * t2_);                                \
    } while (0)
#define ROT(v, out) /* R v (body -> world): w -> -w */                                              \
    do {                                                                                            \
        const double t0_ = qy * (v)[2] - qz * (v)[1], t1_ = qz * (v)[0] - qx * (v)[2],              \
                     t2_ = qx * (v)[1] - qy * (v)[0];                                               \
        (out)[0] = (v)[0] + s2 * (qw * t0_ + (qy * t2_ - qz * t1_));                                \
        (out)[1] = (v)[1] + s2 * (qw * t1_ + (qz * t0_ - qx * t2_));                                \
        (out)[2] = (v)[2] + s2 * (qw * t2_ + (qx * t1_ - qy * t0_));                                \
    } while (0)
/* R e_a f for a force along body axis a alone: a column of R~, (R~ e_a)_a = w^2 + u_a^2 - u_b^2 - u_c^2,
 * (R~ e_a)_b = 2 (u_a u_b + w u_c), (R~ e_a)_c = 2 (u_a u_c - w u_b), b, c the next axes */
#define ROT_AXIS(a, f, out)                                                                         \
    do {                                                                                            \
        const double u_[3] = {qx, qy, qz}, sf_ = s2 * (f);                                          \
        const int b_ = ((a) + 1) % 3, c_ = ((a) + 2) % 3;                                           \
        (out)[a] = (0.5 * sf_) * ((qw * qw + u_[a] * u_[a]) - (u_[b_] * u_[b_] + u_[c_] * u_[c_])); \
        (out)[b_] = sf_ * (u_[a] * u_[b_] + qw * u_[c_]);                                           \
        (out)[c_] = sf_ * (u_[a] * u_[c_] - qw * u_[b_]);                                           \
    } while (0)
#if defined(REF_BODY_FORCES) && (REF_FB_AXES == 1 || REF_FB_AXES == 2 || REF_FB_AXES == 4)
#define ROT_FB(v, out) ROT_AXIS(REF_FB_AXES == 1 ? 0 : REF_FB_AXES == 2 ? 1 : 2, (v)[REF_FB_AXES == 1 ? 0 : REF_FB_AXES == 2 ? 1 : 2], out)
#else
#define ROT_FB(v, out) ROT(v, out)
#endif

/* the body axes that the inputs' torques reach (f[a] = 1), known at compile time */
static inline __attribute__((always_inline)) void torque_axes(int f[3]) {
    int k;
    f[0] = f[1] = f[2] = 0;
#if defined(REF_TAU_BODY) || (REF_NPOINTS > 0 && REF_POINT_WORLD != (1 << REF_NPOINTS) - 1)
    f[0] = f[1] = f[2] = 1;
#endif
    UNROLLED for (k = 0; k < REF_NTROT; k++) f[TAX[k]] = 1;
#if REF_NSROT > 0
    UNROLLED for (k = 0; k < REF_NSROT; k++) {
        f[SAX[k]] = 1;
#ifdef REF_PROPELLERS
        f[(SAX[k] + 1) % 3] = f[(SAX[k] + 2) % 3] = 1;
#endif
    }
#endif
    (void)k;
}

/* v[ax] = val for the first term on that axis, v[ax] += val after (set[ax]: known at compile time) */
#define PUT(v, set, ax, val)                                                   \
    do {                                                                       \
        const double pv_ = (val);                                              \
        const int ax_ = (ax);                                                  \
        if (ax_ == 0)                                                          \
            (v)[0] = (set)[0] ? (v)[0] + pv_ : pv_, (set)[0] = 1;              \
        else if (ax_ == 1)                                                     \
            (v)[1] = (set)[1] ? (v)[1] + pv_ : pv_, (set)[1] = 1;              \
        else                                                                   \
            (v)[2] = (set)[2] ? (v)[2] + pv_ : pv_, (set)[2] = 1;              \
    } while (0)

/* the state x (FMU order) <-> the staged states y */
static inline __attribute__((always_inline)) void gather(const double *x, double *y) {
    int i;
    UNROLLED for (i = 0; i < 4 + NW; i++) y[i] = x[i];
    UNROLLED for (i = 0; i < REF_NTROT; i++) y[YR + i] = x[XR + i];
#ifdef REF_CENTRAL
    UNROLLED for (i = 0; i < 6; i++) y[YC + i] = x[XT + i];
#endif
}

static inline __attribute__((always_inline)) void scatter(const double *y, double *x) {
    int i;
    const double n = 1.0 / sqrt(y[0] * y[0] + y[1] * y[1] + y[2] * y[2] + y[3] * y[3]); /* q onto |q| = 1 */
    UNROLLED for (i = 0; i < 4; i++) x[i] = y[i] * n;
    UNROLLED for (i = 4; i < 4 + NW; i++) x[i] = y[i];
    UNROLLED for (i = 0; i < REF_NTROT; i++) x[XR + i] = y[YR + i];
#ifdef REF_CENTRAL
    UNROLLED for (i = 0; i < 6; i++) x[XT + i] = y[YC + i];
#endif
}

/* DOP853 (scipy's dop853_coefficients): the nonzero a_ij and b_i of its 12 stages */
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
/* beta_j = sum_i b_i a_ij (numpy: B @ A of the same coefficients), the weights of x+ = x + h v +
 * h^2 sum beta_j a_j for x' = v, v' = a; beta_2, beta_3, beta_12 are 0 and beta_4, beta_5 are 0 to
 * 1e-16 (b_j (1 - c_j): the simplifying assumption D(1)) */
#define BETA1 0.05429373411656877
#define BETA6 2.96687526183494
#define BETA7 1.4186384244858754
#define BETA8 (-4.016218126161175)
#define BETA9 0.10850859975965002
#define BETA10 (-0.060864379865006424)
#define BETA11 0.028766485829147193
/* the node each stage reads: stage s at c_s, the 12 sorted nodes 0, c2, c3, c4, 1/4, c5, 4/13,
 * 1/3, 3/5, c9, 6/7, 1 (modelsrc.integrators.stage_nodes("rk8")) */
static const int RK8_NODE[12] = {0, 1, 2, 3, 5, 7, 4, 6, 9, 8, 10, 11};
static const double RK8_C[12] = {0.0, 0.05260015195876773, 0.0789002279381516, 0.1183503419072274,
                                 0.2816496580927726, 0.3333333333333333, 0.25, 0.3076923076923077,
                                 0.6512820512820513, 0.6, 0.8571428571428571, 1.0};

#define NPARAM                                                                                     \
    (9 + 9 + 3 + 3 + 9 + 3 + 1 + 3 + 1 + 9 + 1 + 3 + 3 + 3 * REF_NPOINTS + REF_NTROT + REF_NSROT + \
     REF_NTROT + 3 * REF_NTROT + 5 * REF_NSROT)
#define NINPUT (12 + 3 * REF_NPOINTS + 3 + REF_NTROT + 2 * REF_NSROT)

static double arg_(char **argv, int *a) { return atof(argv[(*a)++]); }

/* the parameters in the order fmu/bench/reference.py (reference_parameters) writes them */
static int read_params(Params *P, char **argv, int a) {
    int i, k;
    for (i = 0; i < 9; i++) P->I[i] = arg_(argv, &a);
    for (i = 0; i < 9; i++) P->Minv[i] = arg_(argv, &a);
    for (i = 0; i < 3; i++) P->e[i] = arg_(argv, &a);
    for (i = 0; i < 3; i++) P->cI[i] = arg_(argv, &a);
    for (i = 0; i < 9; i++) P->mr[i] = arg_(argv, &a);
    for (i = 0; i < 3; i++) P->W[i] = arg_(argv, &a);
    P->m = arg_(argv, &a);
    for (i = 0; i < 3; i++) P->g[i] = arg_(argv, &a);
    P->inv_m = arg_(argv, &a);
    for (i = 0; i < 9; i++) P->gg[i] = arg_(argv, &a);
    P->n = arg_(argv, &a);
    P->mu = arg_(argv, &a), P->trI = arg_(argv, &a), P->c15m = arg_(argv, &a);
    for (i = 0; i < 3; i++) P->gc[i] = arg_(argv, &a);
    for (k = 0; k < REF_NPOINTS; k++)
        for (i = 0; i < 3; i++) P->pt_r[k][i] = arg_(argv, &a);
    for (k = 0; k < REF_NTROT + REF_NSROT; k++) P->J[k] = arg_(argv, &a);
    for (k = 0; k < REF_NTROT; k++) P->invJ[k] = arg_(argv, &a);
    for (i = 0; i < 3; i++)
        for (k = 0; k < REF_NTROT; k++) P->mJ[i][k] = arg_(argv, &a);
    for (k = 0; k < REF_NSROT; k++) {
        P->kf[k] = arg_(argv, &a);
        P->km[k] = arg_(argv, &a);
        for (i = 0; i < 3; i++) P->rpos[k][i] = arg_(argv, &a);
    }
    return a;
}

/* one node's inputs, in the order of reference_inputs */
static int read_inputs(Inputs *U, char **argv, int a) {
    int i, k;
    for (i = 0; i < 3; i++) U->tau_b[i] = arg_(argv, &a);
    for (i = 0; i < 3; i++) U->tau_w[i] = arg_(argv, &a);
    for (i = 0; i < 3; i++) U->f_b[i] = arg_(argv, &a);
    for (i = 0; i < 3; i++) U->f_w[i] = arg_(argv, &a);
    for (k = 0; k < REF_NPOINTS; k++)
        for (i = 0; i < 3; i++) U->pt_f[k][i] = arg_(argv, &a);
    for (i = 0; i < 3; i++) U->a_piv[i] = arg_(argv, &a);
    for (k = 0; k < REF_NTROT; k++) U->u[k] = arg_(argv, &a);
    for (k = 0; k < REF_NSROT; k++) {
        U->Om[k] = arg_(argv, &a);
        U->Omd[k] = arg_(argv, &a);
    }
    return a;
}

#endif
