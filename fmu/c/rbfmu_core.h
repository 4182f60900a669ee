/* Version-independent core of the FMU (hand-written, model-agnostic).
 *
 * The FMI 3.0 and FMI 2.0 API files (rbfmu_fmi3.c, rbfmu_fmi2.c) are thin adapters
 * around it. Everything model-specific comes from the generated model_data.h and
 * model_funcs.h (docs/fmi_layer.md).
 *
 * Value buffer layout (value reference of a Float64/Real variable = index):
 *   [ time | states x | inputs u | parameters p | outputs y | derivatives dx ]
 */
#ifndef RBFMU_CORE_H
#define RBFMU_CORE_H

#include <stddef.h>

#include "model_funcs.h"
#include "model_data.h"

#define UNUSED(x) (void)(x)

/* Status codes: identical numbering in FMI 2.0 and 3.0 (OK, Warning, Discard, Error, Fatal). */
enum { RB_OK = 0, RB_WARNING = 1, RB_DISCARD = 2, RB_ERROR = 3, RB_FATAL = 4 };

/* Instance states; the API files decide which calls each state admits. */
typedef enum {
    ST_INSTANTIATED, ST_INITIALIZATION, ST_STEP, ST_EVENT, ST_CONTINUOUS, ST_TERMINATED, ST_ERROR
} InstanceState;

#define M_INST (1u << ST_INSTANTIATED)
#define M_INIT (1u << ST_INITIALIZATION)
#define M_STEP (1u << ST_STEP)
#define M_EVENT (1u << ST_EVENT)
#define M_CONT (1u << ST_CONTINUOUS)
#define M_TERM (1u << ST_TERMINATED)
#define M_ERR (1u << ST_ERROR)
#define M_ANY (M_INST | M_INIT | M_STEP | M_EVENT | M_CONT | M_TERM | M_ERR)

typedef enum { RB_CO_SIMULATION, RB_MODEL_EXCHANGE } InterfaceType;

struct Instance;
struct RbState; /* an FMU state snapshot (rbfmu_snapshot.c) */
/* The API file's logger adapter: forwards one finished message to the importer. */
typedef void (*rb_logger)(const struct Instance *c, int status, const char *category, const char *message);

#define RB_NJ_ROWS (2 * RB_NX + RB_NY) /* Jacobian rows: x, dx, y */
#define RB_NJ_COLS (RB_NX + RB_NU)     /* Jacobian columns: x, u */

typedef struct Instance {
    char *name;
    InterfaceType type;
    InstanceState state;
    rb_logger log;
    const void *env;        /* the importer's environment pointer(s), for the adapter */
    const void *callbacks;  /* FMI 2.0: the callback functions struct */
    int logging_on;
    int method;             /* index into rb_step_fns / rb_method_values */
    double method_value;    /* its enumeration value, as the generated checks take it */
    double buf[RB_NV];
    double x_next[RB_NX];
    double x_start[RB_NX];  /* state at the start of a doStep, for a retry */
    long last_substeps;     /* internal steps the last doStep took */
    double last_work;       /* right-hand-side evaluations the last doStep spent, failed attempts included */
    struct RbState *states; /* the FMU states this instance made and has not freed (rbfmu_snapshot.c) */
    double g[RB_NC];
    double jac[RB_NJ_ROWS * RB_NJ_COLS]; /* column major, from the generated model_jac */
    /* CasADi work arrays, sized at generation time: no heap use after instantiation */
    const casadi_real *arg[RB_SZ_ARG];
    casadi_real *res[RB_SZ_RES];
    casadi_int iw[RB_SZ_IW > 0 ? RB_SZ_IW : 1];
    casadi_real w[RB_SZ_W > 0 ? RB_SZ_W : 1];
} Instance;

extern const char *const rb_state_names[];

/* Logging: errors are always forwarded; OK-level messages only with logging on. */
void rb_logf(const Instance *c, int status, const char *fmt, ...)
#ifdef __GNUC__
    __attribute__((format(printf, 3, 4)))
#endif
    ;
#define RB_ERR(c, ...) rb_logf((c), RB_ERROR, __VA_ARGS__)

/* 1 when `c` may be called in its state (mask of M_*), else logs and returns 0. */
int rb_allowed(const Instance *c, const char *fn, unsigned mask);
/* 1 when the arrays a call reads or writes are given (either may be NULL only when n = 0;
 * b_name NULL: only a), else logs which is NULL and returns 0. */
int rb_arrays(const Instance *c, const char *fn, size_t n, const void *a, const char *a_name, const void *b,
              const char *b_name);
/* *out = value for the GetNumberOf... calls; a NULL out is refused. */
int rb_put_count(const Instance *c, const char *fn, size_t *out, size_t value);

/* Creation: checks the token against the build's; returns NULL (after logging through a
 * temporary instance) when it does not match. */
Instance *rb_instantiate(const char *fn, const char *name, const char *token, InterfaceType type,
                         int logging_on, rb_logger log, const void *env, const void *callbacks);
void rb_free(Instance *c);
void rb_reset(Instance *c);

/* Float64/Real access by value reference; all-or-nothing validation. */
int rb_set_reals(Instance *c, const char *fn, const unsigned vr[], size_t n, const double v[]);
int rb_get_reals(Instance *c, const char *fn, const unsigned vr[], size_t n, double v[]);
/* The method enumeration (value reference RB_VR_METHOD). */
int rb_set_method(Instance *c, const char *fn, unsigned vr, long long value);
int rb_set_methods(Instance *c, const char *fn, const unsigned vr[], size_t n, const long long values[]);
int rb_get_method(const Instance *c, const char *fn, unsigned vr, long long *value);

/* Shared between the core's files: the generated outputs and derivatives at the current
 * state, the method by index, the validity checks (returns the number violated). */
void rb_compute_outputs(Instance *c);
void rb_compute_derivatives(Instance *c, double *dx);
void rb_select_method(Instance *c, int index);
/* The generated validity checks of states x, parameters p and a method value; logs each
 * violation (prefixed `when`) with the parameter and state values; returns how many failed. */
int rb_run_checks(Instance *c, const char *when, const double *x, const double *p, double method_value);

int rb_enter_initialization(Instance *c, const char *fn, double start_time, int stop_defined, double stop_time);
int rb_exit_initialization(Instance *c, const char *fn); /* checks, normalises q, computes outputs */

/* Co-Simulation step of length H from t. */
int rb_do_step(Instance *c, const char *fn, double t, double H);

/* The work budget of one doStep (rbfmu_budget.c): work counted in right-hand-side
 * evaluations, rb_method_cost[method] per internal step, against the tunable work_limit.
 * A step controller starts a budget per doStep, asks before each batch of internal steps
 * (rb_budget_allows; rb_budget_refuse logs the refusal) and charges the steps it took. */
typedef struct {
    double limit; /* work_limit when the doStep started */
    double used;  /* evaluations charged so far in this doStep */
} RbBudget;
void rb_budget_start(RbBudget *b, Instance *c);
int rb_budget_allows(const RbBudget *b, const Instance *c, double steps);
void rb_budget_refuse(const Instance *c, const char *fn, const RbBudget *b, double steps, const char *context);
void rb_budget_charge(RbBudget *b, Instance *c, long steps);

/* Model Exchange. */
int rb_set_time(Instance *c, const char *fn, double t);
int rb_set_states(Instance *c, const char *fn, const double x[], size_t n);
int rb_get_states(Instance *c, const char *fn, double x[], size_t n);
int rb_get_derivatives(Instance *c, const char *fn, double dx[], size_t n);
int rb_get_nominals(Instance *c, const char *fn, double nominals[], size_t n);

/* FMU state snapshots (heap: allowed outside doStep). A state belongs to the instance that
 * made it (GetFMUState, DeserializeFMUState); every call checks that it does, and the
 * values of a state (set or deserialized) pass the checks of values set through the API. */
typedef struct RbState RbState;
int rb_state_get(Instance *c, const char *fn, void **state);
int rb_state_set(Instance *c, const char *fn, const void *state);
int rb_state_free(Instance *c, const char *fn, void **state);
void rb_state_free_all(Instance *c); /* at FreeInstance: the states the importer did not free */
int rb_state_size(Instance *c, const char *fn, const void *state, size_t *size);
int rb_state_serialize(Instance *c, const char *fn, const void *state, unsigned char *out, size_t size);
int rb_state_deserialize(Instance *c, const char *fn, const unsigned char *in, size_t size, void **state);

/* Directional (adjoint = 0) or adjoint (adjoint = 1) derivatives of unknowns (states,
 * derivatives, outputs) with respect to knowns (states, inputs), from the generated
 * Jacobian (CasADi AD). */
int rb_directional(Instance *c, const char *fn, const unsigned unknowns[], size_t n_unknowns,
                   const unsigned knowns[], size_t n_knowns, const double seed[], size_t n_seed,
                   double sensitivity[], size_t n_sensitivity, int adjoint);

#endif
