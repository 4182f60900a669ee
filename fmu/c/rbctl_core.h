/* Version-independent core of a sampled-data controller FMU (hand-written, model-agnostic).
 *
 * The FMI 3.0 and 2.0 API files (rbctl_fmi3.c, rbctl_fmi2.c) are thin adapters around it;
 * everything controller-specific comes from the generated controller_data.h (sizes,
 * variable table, start values, check texts, the generated functions' argument names) and
 * ctrl_funcs.c/.h (CasADi: ctrl_output, ctrl_update, ctrl_checks). docs/theory.md §12.
 *
 * Value buffer (value reference of a Float64/Real variable = index):
 *   [ time | inputs u | parameters p (tunable, fixed) | outputs y | discrete states z ]
 *
 * Sampled-data semantics: samples at t_k = t_start + k Ts. At a sample point the outputs are
 * the law at the current inputs (direct feedthrough); a doStep from a sample point latches
 * them (held, zero-order hold, until the next sample point) and updates the discrete states;
 * a doStep that would cross a sample point inside it is refused (Ts = m H).
 */
#ifndef RBCTL_CORE_H
#define RBCTL_CORE_H

#include "rbfmu_build.h" /* first: hidden symbols, no FP contraction */
#include <stdbool.h>
#include <stddef.h>

#include "ctrl_funcs.h"
#include "controller_data.h"

#define RC_UNUSED(x) (void)(x)

/* FMI status numbering (identical in FMI 2.0 and 3.0). */
typedef enum { RC_OK = 0, RC_WARNING = 1, RC_DISCARD = 2, RC_ERROR = 3, RC_FATAL = 4 } RcStatus;
typedef enum { RC_INSTANTIATED = 0, RC_INIT = 1, RC_STEP = 2, RC_TERMINATED = 3, RC_FAILED = 4 } RcState;

struct RcInstance;
/* The API file's logger: forwards one formatted message to the importer's callback. */
typedef void (*RcLogFn)(const struct RcInstance *c, RcStatus status, const char *category, const char *message);

typedef struct RcInstance {
    RcState state;
    double v[RC_N_VARS];   /* the value buffer */
    double y_held[RC_N_Y]; /* the outputs latched at the last sample point */
    double t_start;        /* the sample grid's origin (s) */
    bool logging_on;
    char name[128];
    RcLogFn log;
    void *env;    /* the importer's instance environment (FMI 3) or callbacks (FMI 2) */
    void *logger; /* the importer's log callback, as the API file stores it */
    const double *arg[RC_SZ_ARG];
    double *res[RC_SZ_RES];
    casadi_int iw[RC_SZ_IW + 1];
    double w[RC_SZ_W + 1];
} RcInstance;

RcInstance *rc_new(const char *name, RcLogFn log, void *env, void *logger);
void rc_free(RcInstance *c);
void rc_reset(RcInstance *c);
void rc_logf(const RcInstance *c, RcStatus status, const char *fmt, ...);
RcStatus rc_state_allows(RcInstance *c, const char *fn, unsigned mask);
RcStatus rc_set_reals(RcInstance *c, const char *fn, const unsigned vr[], size_t n, const double x[]);
RcStatus rc_get_reals(RcInstance *c, const char *fn, const unsigned vr[], size_t n, double x[]);
RcStatus rc_enter_init(RcInstance *c, const char *fn, double t_start);
RcStatus rc_exit_init(RcInstance *c, const char *fn);
RcStatus rc_do_step(RcInstance *c, const char *fn, double t, double h);

/* state bits for rc_state_allows */
#define RC_M(s) (1u << (s))
#define RC_M_GET (RC_M(RC_INIT) | RC_M(RC_STEP) | RC_M(RC_TERMINATED) | RC_M(RC_FAILED))
#define RC_M_SET (RC_M(RC_INSTANTIATED) | RC_M(RC_INIT) | RC_M(RC_STEP))

#endif
