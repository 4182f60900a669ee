/* Version-independent core of the FMU (hand-written, model-agnostic).
 *
 * The FMI 3.0 and FMI 2.0 API files (rbfmu_fmi3.c, rbfmu_fmi2.c) are thin adapters
 * around it. Everything model-specific comes from the generated model_data.h and
 * model_funcs.h (docs/fmi_layer.md).
 *
 * Value buffer layout (value reference of a Float64/Real variable = index):
 *   [ time | states x | inputs u | parameters p | step report l | outputs y | derivatives dx ]
 *
 * Layers: each file calls functions of the files in the layers below its own only, never
 * of its own layer's other files or of a layer above (tests/test_structure.py reads this
 * table; docs/fmi_layer.md, "Layers"):
 *   1 rbfmu_fmi3.c rbfmu_fmi3_absent.c rbfmu_fmi2.c   the FMI 3.0 and 2.0 API
 *   2 rbfmu_dostep.c                                  a doStep: its checks, start and end
 *   3 rbfmu_control.c                                 error-controlled internal steps
 *   4 rbfmu_step.c                                    fixed internal steps; one internal step
 *   5 rbfmu_inputs.c rbfmu_budget.c rbfmu_exchange.c rbfmu_snapshot.c
 *                                                     inputs in a step, work budget, Model Exchange, FMU states
 *   6 rbfmu_core.c                                    the instance, values, checks, logging
 */
#ifndef RBFMU_CORE_H
#define RBFMU_CORE_H

#include "rbfmu_build.h" /* first: what any compiler must do with these sources */
#include <float.h>
#include <math.h>
#include <stdbool.h>
#include <stddef.h>

#include "model_funcs.h"
#include "model_data.h"

#define UNUSED(x) (void)(x)

/* What a call that can fail returns: the FMI status numbering, identical in FMI 2.0 and 3.0
 * (OK, Warning, Discard, Error, Fatal), which the API files cast to fmi3Status / fmi2Status.
 * What only succeeds or fails is a bool predicate named for what it tests. */
typedef enum { RB_OK = 0, RB_WARNING = 1, RB_DISCARD = 2, RB_ERROR = 3, RB_FATAL = 4 } RbStatus;

/* Instance states; the API files decide which calls each state admits. IntermediateUpdateMode
 * (FMI 3.0) is entered only inside doStep, while the importer's intermediateUpdate callback runs. */
typedef enum {
    ST_INSTANTIATED, ST_INITIALIZATION, ST_STEP, ST_EVENT, ST_CONTINUOUS, ST_TERMINATED, ST_ERROR, ST_INTERMEDIATE
} InstanceState;

#define M_INST (1u << ST_INSTANTIATED)
#define M_INIT (1u << ST_INITIALIZATION)
#define M_STEP (1u << ST_STEP)
#define M_EVENT (1u << ST_EVENT)
#define M_CONT (1u << ST_CONTINUOUS)
#define M_TERM (1u << ST_TERMINATED)
#define M_ERR (1u << ST_ERROR)
#define M_IUM (1u << ST_INTERMEDIATE)
/* every state but IntermediateUpdateMode, where only the calls that name M_IUM are allowed */
#define M_ANY (M_INST | M_INIT | M_STEP | M_EVENT | M_CONT | M_TERM | M_ERR)

typedef enum { RB_CO_SIMULATION, RB_MODEL_EXCHANGE } InterfaceType;

struct Instance;
struct RbState; /* an FMU state snapshot (rbfmu_snapshot.c) */
/* The API file's logger adapter: forwards one finished message to the importer. */
typedef void (*rb_logger)(const struct Instance *c, RbStatus status, const char *category, const char *message);

#define RB_NJ_ROWS (2 * RB_NX + RB_NY) /* Jacobian rows: x, dx, y */
#define RB_NJ_COLS (RB_NX + RB_NU)     /* Jacobian columns: x, u */
#define RB_NU1 (RB_NU > 0 ? RB_NU : 1) /* array sizes: C99 has no empty arrays */
#define RB_ND1 (RB_ND > 0 ? RB_ND : 1)
#define RB_NE1 (RB_NE > 0 ? RB_NE : 1)
/* The step report (model_data.h: value references RB_VR_STEPS ...): what the last doStep did. */
#define RB_REPORT_STEPS 0    /* internal steps accepted */
#define RB_REPORT_REJECTED 1 /* internal steps rejected (or attempts retried) */
#define RB_REPORT_H_LAST 2   /* last internal step (s) */
#define RB_REPORT_H_NEXT 3   /* the error control's next step (s), 0 before its first */
#define RB_REPORT_TOL_EFFECTIVE 4 /* the tolerance (1/s) the last doStep's error control held (rbfmu_control.c) */
#define RB_REPORT_TOL_FLOOR 5     /* the lowest tolerance (1/s) the estimate resolved on this run, 0: no limit */

/* The importer's side of FMI 3.0 intermediate update, set by the API file: asks the importer
 * for the inputs at time t inside a doStep (it may set them, in IntermediateUpdateMode). */
typedef void (*rb_ask_inputs)(struct Instance *c, double t);

/* Where the inputs over a communication step come from (rbfmu_inputs.c): held, polynomial
 * (FMI 2.0 input derivatives) or asked at the nodes (FMI 3.0 intermediate update). */
typedef enum { RB_HELD, RB_POLY, RB_ASK } InputMode;

/* ---- the instance, grouped by purpose ---- */

/* What an FMU state snapshot keeps: rbfmu_snapshot.c copies this group whole and restores it
 * whole (its serialized form writes its fields, the values up to RB_OFF_Y). Everything else
 * of an instance is fixed at instantiation, the importer's, derived from this group, or
 * scratch of one call. */
typedef struct {
    InstanceState state;
    int method;        /* index into the method tables (rb_step_fns, ...) and rb_method_values */
    double buf[RB_NV]; /* the values by value reference (layout above); the outputs and derivatives,
                        * from RB_OFF_Y on, are computed when read and are not serialized */
} RbPersistent;

/* What follows from the persistent group, recomputed whenever it changes (rb_select_method,
 * rb_refresh_derived): never saved, never set by the importer. */
typedef struct {
    double method_value; /* the method's enumeration value, as the generated checks take it */
    double d[RB_ND1];    /* derived parameters: model_derived(p) */
    const rb_step_fn *step_fns, *fixed_step_fns; /* the steps for these d */
    /* the fixed step's constants (rb_step_constants_fns: a clock's advances, functions of p, d
     * and h) and the step size and method they were computed for; e_h NaN: none yet */
    double e[RB_NE1];
    double e_h;
    int e_method;
} RbDerived;

/* The importer: who the instance is, how to reach the importer, and what it set or asked for
 * beyond the values (not part of an FMU state). */
typedef struct {
    char *name;
    InterfaceType type;
    rb_logger log;
    const void *env;       /* the importer's environment pointer(s), for the adapter */
    const void *callbacks; /* FMI 2.0: the callback functions struct; FMI 3.0: the adapter's */
    rb_ask_inputs ask;     /* FMI 3.0 intermediate update, NULL when the importer gave no callback */
    bool logging_on;
    bool tolerance_set;     /* the importer set the parameter `tolerance` (SetFloat64/SetReal) */
    bool tolerance_defined; /* EnterInitializationMode / SetupExperiment gave a tolerance ... */
    double tolerance;       /* ... this one (rb_importer_tolerance) */
    double tolerance_logged; /* the effective tolerance last reported through the logger (0: none) */
} RbImporter;

/* The inputs over the current doStep (rbfmu_inputs.c). */
typedef struct {
    double U[RB_NU1 * RB_MAX_NODES]; /* at the nodes of the current internal step (integrators.stage_nodes) */
    double u_start[RB_NU1];          /* when the doStep started */
    double du[RB_MAX_INPUT_ORDER][RB_NU1]; /* FMI 2.0 input derivatives for the next doStep */
    bool du_set;                     /* some input derivative is set (not all zero) */
    InputMode mode;                  /* over the current doStep */
    const unsigned char *node_read;  /* the nodes the doStep's steps read (NULL: all) */
} RbInputs;

/* Scratch of one doStep (rbfmu_dostep.c, rbfmu_step.c, rbfmu_control.c), and what it reports. */
typedef struct {
    double x_next[RB_NX];  /* the other state of the ping-pong; also scratch of the projections */
    double x_start[RB_NX]; /* state at the start of a doStep, for a retry */
    double k[2][RB_NX];    /* f(x, u) at the state (first same as last: a step returns the next one) */
    double k_start[RB_NX]; /* f at the start of a doStep, for a retry */
    double dx[RB_NX];      /* the increment of the last step (before projection) */
    double comp[RB_NX], comp_next[RB_NX]; /* compensated summation of the states but q (rb_call_step) */
    /* the steps' own argument lists (rb_bind_step): bound once per doStep, since an importer
     * asked for inputs inside it may read outputs, which uses the work arrays */
    const casadi_real *arg[RB_SZ_ARG];
    casadi_real *res[RB_SZ_RES];
    double h, err, est;
    long last_substeps; /* internal steps the last doStep took */
    double last_work;   /* right-hand-side evaluations the last doStep spent, failed attempts included */
    /* model_rate and f at the end of the last fixed-step doStep (rb_step_fixed, one
     * model_rate_rhs), and what they were evaluated at: the states, inputs and parameters
     * (buf[RB_OFF_X .. RB_OFF_L)) and the method. The next doStep's start rate and k1 are
     * these while all of them are bit for bit the same (nothing set since, held inputs): one
     * evaluation per doStep instead of a model_rate at each end and a model_rhs at the start. */
    double rate_end[2];
    double k_end[RB_NX];
    double rate_H, rate_need; /* that doStep's length and the substeps its end rate asks (rb_step_fixed) */
    double rate_at[RB_OFF_L - RB_OFF_X];
    int rate_method;
    bool rate_valid; /* false in a new instance (calloc) and after a doStep with inputs not held */
} RbStepScratch;

/* CasADi work arrays, sized at generation time (no heap use after instantiation), and the
 * results of the generated calls outside the steps. */
typedef struct {
    const casadi_real *arg[RB_SZ_ARG];
    casadi_real *res[RB_SZ_RES];
    casadi_int iw[RB_SZ_IW > 0 ? RB_SZ_IW : 1];
    casadi_real w[RB_SZ_W > 0 ? RB_SZ_W : 1];
    double g[RB_NC];                     /* the validity checks (model_checks) */
    double jac[RB_NJ_ROWS * RB_NJ_COLS]; /* column major (model_jac) */
    /* the x, u, p and method jac was computed at (rbfmu_exchange.c, jacobian_at_point) */
    double jac_at[RB_OFF_L - RB_OFF_X];
    int jac_method;
    bool jac_valid;
    double z1[RB_NX + RB_NY], z2[RB_NX + RB_NY]; /* output derivatives (model_output_rates) */
} RbWork;

typedef struct Instance {
    RbPersistent persistent;
    RbDerived derived;
    RbImporter importer;
    RbInputs inputs;
    RbStepScratch step;
    RbWork work;
    struct RbState *snapshots; /* the FMU states this instance made and has not freed (rbfmu_snapshot.c) */
} Instance;

extern const char *const rb_state_names[];

/* ---- calling the generated functions by their arguments' names ----
 * model_data.h gives every argument's position: RB_ARG_<function>_<input>, RB_RES_<function>_<output>
 * (fmu/build/model_data.py, from the CasADi Functions' own names); the steps, called through one
 * table, as the family model_step. A function that takes other arguments than the layer
 * binds fails to compile here, one that takes them in another order is bound by name. */
#if RB_N_ARG_model_rhs != 4 || RB_N_ARG_model_rate != 4 || RB_N_ARG_model_outputs != 4 || RB_N_ARG_model_jac != 4
#error "model_rhs, model_rate, model_outputs and model_jac must take exactly x, u, p, d (in any order)"
#endif
#if RB_N_ARG_model_rate_rhs != 4 || RB_N_RES_model_rate_rhs != 2
#error "model_rate_rhs must take exactly x, u, p, d and return rate, xdot (in any order)"
#endif
#if RB_N_ARG_model_output_rates != 6
#error "model_output_rates must take exactly x, u, p, d, u1, u2 (in any order)"
#endif
#if RB_N_ARG_model_checks != 3 || RB_N_ARG_model_project != 1 || RB_N_ARG_model_derived != 1
#error "model_checks must take exactly x, p, method; model_project x; model_derived p (in any order)"
#endif
#if RB_N_ARG_model_step != 7 || RB_N_RES_model_step != 5
#error "the steps must take exactly x, U, p, h, d, k1, e and return x_next, err, est, k_next, dx (in any order)"
#endif
#if RB_N_ARG_model_step_constants != 3 || RB_N_RES_model_step_constants != 1
#error "the steps' constants must take exactly p, h, d and return e (in any order)"
#endif

/* The one binding of the model's arguments for every call site: a generated function's x, u,
 * p, d (at positions ix, iu, ip, id of arg) point at the state x, the inputs u and the
 * instance's parameters and derived parameters. */
static inline void rb_bind_model(const Instance *c, const casadi_real **arg, int ix, int iu, int ip, int id,
                                 const double *x, const double *u) {
    arg[ix] = x;
    arg[iu] = u;
    arg[ip] = c->persistent.buf + RB_OFF_P;
    arg[id] = c->derived.d;
}
/* The generated F's x, u, p, d in the work arrays, by name: state x and the current inputs. */
#define RB_BIND_MODEL(c, F, x)                                                                                    \
    rb_bind_model((c), (c)->work.arg, RB_ARG_##F##_x, RB_ARG_##F##_u, RB_ARG_##F##_p, RB_ARG_##F##_d, (x),        \
                  (c)->persistent.buf + RB_OFF_U)
/* F's argument or result NAME in the work arrays, by name. */
#define RB_ARG(c, F, NAME) ((c)->work.arg[RB_ARG_##F##_##NAME])
#define RB_RES(c, F, NAME) ((c)->work.res[RB_RES_##F##_##NAME])
/* Runs the generated F on the work arrays (its arguments bound first). */
#define RB_CALL(c, F) F((c)->work.arg, (c)->work.res, (c)->work.iw, (c)->work.w, 0)

/* ---- the core (rbfmu_core.c) ---- */

/* Logging: errors are always forwarded; OK-level messages only with logging on. */
void rb_logf(const Instance *c, RbStatus status, const char *fmt, ...)
#ifdef __GNUC__
    __attribute__((format(printf, 3, 4)))
#endif
    ;
#define RB_ERR(c, ...) rb_logf((c), RB_ERROR, __VA_ARGS__)

/* `c` may be called in its state (mask of M_*); else logs why. */
bool rb_allowed(const Instance *c, const char *fn, unsigned mask);
/* The arrays a call reads or writes are given (either may be NULL only when n = 0; b_name
 * NULL: only a); else logs which is NULL. */
bool rb_arrays_given(const Instance *c, const char *fn, size_t n, const void *a, const char *a_name, const void *b,
                     const char *b_name);
/* *out = value for the GetNumberOf... calls; a NULL out is refused. */
RbStatus rb_put_count(const Instance *c, const char *fn, size_t *out, size_t value);

/* Creation: checks the token against the build's; returns NULL (after logging through a
 * temporary instance) when it does not match. rb_free frees the instance only: its FMU
 * states go first (rb_state_free_all, a layer above). */
Instance *rb_instantiate(const char *fn, const char *name, const char *token, InterfaceType type, bool logging_on,
                         rb_logger log, const void *env, const void *callbacks);
void rb_free(Instance *c);
void rb_reset(Instance *c);

/* Float64/Real access by value reference; all-or-nothing validation. */
RbStatus rb_set_reals(Instance *c, const char *fn, const unsigned vr[], size_t n, const double v[]);
RbStatus rb_get_reals(Instance *c, const char *fn, const unsigned vr[], size_t n, double v[]);
/* The method enumeration (value reference RB_VR_METHOD). */
RbStatus rb_set_method(Instance *c, const char *fn, unsigned vr, long long value);
RbStatus rb_set_methods(Instance *c, const char *fn, const unsigned vr[], size_t n, const long long values[]);
RbStatus rb_get_method(const Instance *c, const char *fn, unsigned vr, long long *value);

/* Shared between the core's files: the generated outputs and derivatives at the current
 * state, the derived parameters, the method by index, the validity checks. */
void rb_compute_outputs(Instance *c);
void rb_compute_derivatives(Instance *c, double *dx);
void rb_refresh_derived(Instance *c); /* c->derived from p and the method: after any change of them */
bool rb_principal(const double *d);   /* d's off-diagonal inertia entries are all 0 (rb_off_diagonal) */
void rb_select_method(Instance *c, int index);
/* x projected by the generated model_project (q/|q|) into out. */
void rb_project(Instance *c, const double *x, double *out);
/* The generated validity checks of states x, parameters p and a method value all pass; logs
 * each violation (prefixed `when`) with the parameter and state values. */
bool rb_checks_pass(Instance *c, const char *when, const double *x, const double *p, double method_value);

RbStatus rb_enter_initialization(Instance *c, const char *fn, double start_time, bool stop_defined,
                                 double stop_time);
/* The importer's tolerance (FMI 3.0 EnterInitializationMode, FMI 2.0 SetupExperiment): kept
 * for rb_exit_initialization, which applies it to the error control unless the importer set
 * the parameter `tolerance` (docs/fmi_layer.md, Tolerance). */
RbStatus rb_importer_tolerance(Instance *c, const char *fn, bool defined, double tolerance);
RbStatus rb_exit_initialization(Instance *c, const char *fn); /* checks, normalises q, computes outputs */
/* The rule of docs/robustness.md (Values entering and leaving the FMU): a state x entering the
 * instance (start values at exitInitializationMode, SetContinuousStates, SetFMUState,
 * DeserializeFMUState) passes the generated checks with the instance's parameters and method,
 * and the state derivatives and outputs at it are finite; else logs the first failure with
 * the parameter and state values. The instance's state is unchanged. */
bool rb_state_enters(Instance *c, const char *fn, const double *x);
/* Logs that the output or state derivative of value reference vr would be `value` (non-finite), with the parameter and state
 * values; returns RB_ERROR. A Get never returns a non-finite value with status OK. */
RbStatus rb_refuse_non_finite(Instance *c, const char *fn, unsigned vr, double value);
/* The same for any computed value: `what` 'name' would be `value` (e.g. "directional derivative", "E_kin"). */
RbStatus rb_refuse_non_finite_named(Instance *c, const char *fn, const char *what, const char *name, double value);

/* ---- a Co-Simulation step ---- */

/* A step of length H from t (rbfmu_dostep.c): fixed steps (rbfmu_step.c), or error-controlled
 * ones (rbfmu_control.c) when tolerance > 0 and the method has an estimate. */
RbStatus rb_do_step(Instance *c, const char *fn, double t, double H);
typedef struct RbBudget RbBudget;
RbStatus rb_step_controlled(Instance *c, const char *fn, double t, double H, RbBudget *budget);
RbStatus rb_step_fixed(Instance *c, const char *fn, double t, double H, RbBudget *budget);
/* Shared by the two kinds of stepping (rbfmu_step.c). */
void rb_eval_rate(Instance *c, const double *x, double r[2]);
/* The rounding slack never lets a step exceed its cap by more than this (relative): times
 * so coarse that H is uncertain beyond it decide nothing finer. */
#define RB_GUARD_MAX 1e-6
/* The rounding slack (s) of a span H starting at time t: an importer's H = t_(k+1) - t_k
 * differs from the step it meant by up to eps (|t_k| + |t_(k+1)|)/2, and a division by H
 * adds one rounding of 2 eps H, at most RB_GUARD_MAX H (docs/theory.md §5.4). Inline: the
 * error control asks for it at every internal step. */
static inline double rb_time_slack(double H, double t) {
    double slack = 2.0 * DBL_EPSILON * (fabs(t) + fabs(t + H) + 2.0 * H);
    return slack < RB_GUARD_MAX * H ? slack : RB_GUARD_MAX * H;
}
double rb_steps_in(double H, double h_cap, double t); /* ceil(H/h_cap), robust to the times' rounding */
bool rb_all_finite(const double *x);
/* One internal step of size h from state x with derivative k (f at x): writes x_next, its
 * derivative k_next; returns the Newton residual (0 for explicit methods), *est the
 * estimated relative error (0 without an estimate). Inputs come from c->inputs.U. The states
 * but q are summed with compensation `comp`; comp_out receives its value after the step (the
 * same array under fixed steps, where every step is kept; the other of two under error
 * control, which swaps them when it accepts the step). Needs rb_bind_step once per doStep.
 * controlled false: fixed stepping, which calls the method's variant without error estimate
 * where there is one (rb_fixed_step_fns; *est is then 0). */
double rb_call_step(Instance *c, bool controlled, const double *x, const double *k, double h, double *x_next,
                    double *k_next, const double *comp, double *comp_out, double *est);
void rb_bind_step(Instance *c); /* the arguments of rb_call_step that stay over a doStep */

/* ---- inputs over a communication step (rbfmu_inputs.c) ---- */

void rb_inputs_begin(Instance *c, bool controlled); /* controlled: the doStep steps under error control */
void rb_inputs_nodes(Instance *c, double t0, double tau, double h); /* the nodes of [t0+tau, t0+tau+h] */
void rb_inputs_shift(Instance *c); /* the step was accepted: its end is the next one's start */
/* Called around every internal step; held inputs (the usual case) need neither call. */
static inline void rb_inputs_for(Instance *c, double t0, double tau, double h) {
    if (c->inputs.mode != RB_HELD) rb_inputs_nodes(c, t0, tau, h);
}
static inline void rb_inputs_accept(Instance *c) {
    if (c->inputs.mode != RB_HELD) rb_inputs_shift(c);
}
void rb_inputs_restart(Instance *c);                              /* back to the doStep's start */
void rb_inputs_end(Instance *c, double H, bool ok);
/* The value references are all inputs (FMI 3.0 requiredIntermediateVariables); else writes
 * why (naming `what`). */
bool rb_inputs_only(const char *what, const unsigned vrs[], size_t n, char *why, size_t len);
RbStatus rb_set_input_derivatives(Instance *c, const char *fn, const unsigned vr[], size_t n, const int order[],
                                  const double v[]);
RbStatus rb_output_derivatives(Instance *c, const char *fn, const unsigned vr[], size_t n, const int order[],
                               double v[]);

/* ---- the work budget of one doStep (rbfmu_budget.c) ----
 * Work counted in right-hand-side evaluations, rb_method_cost[method] per internal step,
 * against the tunable work_limit. A step controller starts a budget per doStep, asks before
 * each batch of internal steps (rb_budget_allows; rb_budget_refuse logs the refusal) and
 * charges the steps it took. */
struct RbBudget {
    double limit; /* work_limit when the doStep started */
    double used;  /* evaluations charged so far in this doStep */
};
void rb_budget_start(RbBudget *b, Instance *c);
bool rb_budget_allows(const RbBudget *b, const Instance *c, double steps);
void rb_budget_refuse(const Instance *c, const char *fn, const RbBudget *b, double steps, const char *context);
long rb_budget_steps_left(const RbBudget *b, const Instance *c);
void rb_budget_charge(RbBudget *b, Instance *c, long steps);

/* ---- Model Exchange (rbfmu_exchange.c) ---- */

RbStatus rb_set_time(Instance *c, const char *fn, double t);
RbStatus rb_set_states(Instance *c, const char *fn, const double x[], size_t n);
RbStatus rb_get_states(Instance *c, const char *fn, double x[], size_t n);
RbStatus rb_get_derivatives(Instance *c, const char *fn, double dx[], size_t n);
RbStatus rb_get_nominals(Instance *c, const char *fn, double nominals[], size_t n);
/* Directional (adjoint false) or adjoint (adjoint true) derivatives of unknowns (states,
 * derivatives, outputs) with respect to knowns (states, inputs), from the generated
 * Jacobian (CasADi AD). */
RbStatus rb_directional(Instance *c, const char *fn, const unsigned unknowns[], size_t n_unknowns,
                        const unsigned knowns[], size_t n_knowns, const double seed[], size_t n_seed,
                        double sensitivity[], size_t n_sensitivity, bool adjoint);

/* ---- FMU state snapshots (rbfmu_snapshot.c) ----
 * On the heap: allowed outside doStep. A state belongs to the instance that made it
 * (GetFMUState, DeserializeFMUState); every call checks that it does, and the values of a
 * state (set or deserialized) pass the checks of values set through the API. */
typedef struct RbState RbState;
RbStatus rb_state_get(Instance *c, const char *fn, void **state);
RbStatus rb_state_set(Instance *c, const char *fn, const void *state);
RbStatus rb_state_free(Instance *c, const char *fn, void **state);
void rb_state_free_all(Instance *c); /* at FreeInstance: the states the importer did not free */
RbStatus rb_state_size(Instance *c, const char *fn, const void *state, size_t *size);
RbStatus rb_state_serialize(Instance *c, const char *fn, const void *state, unsigned char *out, size_t size);
RbStatus rb_state_deserialize(Instance *c, const char *fn, const unsigned char *in, size_t size, void **state);

#endif
