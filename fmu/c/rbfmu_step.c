/* The Co-Simulation step of the FMU core: sub-steps sized by the method's limits, retries, acceptance.
 * Hand-written and model-agnostic; the rules are docs/theory.md §5.4. */
#include "rbfmu_core.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A doStep whose substeps fail the acceptance test is redone from its start state with
 * more substeps, at most this many times (each at least doubling the count). */
#define RB_MAX_RETRIES 10

/* The generated model_rate at x: r[0] = ||df/dx||_inf (1/s, stability), r[1] = |w| (rad/s, accuracy). */
static void eval_rate(Instance *c, const double *x, double r[2]) {
    c->arg[0] = x;
    c->arg[1] = c->buf + RB_OFF_U;
    c->arg[2] = c->buf + RB_OFF_P;
    c->res[0] = r;
    model_rate(c->arg, c->res, c->iw, c->w, 0);
}

/* Substeps needed over H for the rates r: h * r[0] <= stability limit, h * r[1] <= rotation limit. */
static double substeps_for(const Instance *c, double H, const double r[2]) {
    double n = 0, limit = rb_method_rate_limit[c->method], rot = rb_method_rotation_limit[c->method];
    if (isfinite(limit) && H * r[0] / limit > n) n = ceil(H * r[0] / limit);
    if (isfinite(rot) && H * r[1] / rot > n) n = ceil(H * r[1] / rot);
    return n;
}

static int all_finite(const double *x) {
    int i, finite = 1;
    for (i = 0; i < RB_NX; i++) finite &= isfinite(x[i]) ? 1 : 0;
    return finite;
}

/* Up to n substeps of size h on the state in buf; returns how many it took. It stops
 * early once the attempt has failed: a Newton residual above the acceptance level, or a
 * non-finite state (checked every 64 substeps; NaN and Inf do not heal), so that a doomed
 * attempt does not spend its whole budget. *err_max: the largest residual (0: explicit). */
static long integrate(Instance *c, long n, double h, double *err_max) {
    double *x = c->buf + RB_OFF_X, err = 0.0;
    long k;
    rb_step_fn step = rb_step_fns[c->method];
    c->arg[1] = c->buf + RB_OFF_U;
    c->arg[2] = c->buf + RB_OFF_P;
    c->arg[3] = &h;
    c->res[1] = &err;
    *err_max = 0.0;
    for (k = 0; k < n;) { /* ping-pong between the state and a scratch buffer: no copy per substep */
        c->arg[0] = (k & 1) ? c->x_next : x;
        c->res[0] = (k & 1) ? x : c->x_next;
        step(c->arg, c->res, c->iw, c->w, 0);
        if (!(err <= *err_max)) *err_max = err; /* also catches NaN */
        k++;
        if (!(*err_max <= RB_NEWTON_ACCEPT) || ((k & 63) == 0 && !all_finite(c->res[0]))) break;
    }
    if (k & 1) memcpy(x, c->x_next, sizeof c->x_next);
    return k;
}

int rb_do_step(Instance *c, const char *fn, double t, double H) {
    double h = 0, nd, need, tol, rate[2] = {0, 0}, err = 0;
    double *x = c->buf + RB_OFF_X;
    long n = 0, done;
    int attempt, finite, converged, stiff;
    const char *failure = "";
    RbBudget budget;
    char context[200];
    if (!(H > 0) || !isfinite(H)) {
        RB_ERR(c, "%s: communicationStepSize must be finite and > 0, got %g", fn, H);
        return RB_ERROR;
    }
    tol = 1e-10 * (fabs(c->buf[0]) > 1.0 ? fabs(c->buf[0]) : 1.0);
    if (!(fabs(t - c->buf[0]) <= tol)) {
        RB_ERR(c, "%s: currentCommunicationPoint %.17g is not the FMU's current time %.17g", fn, t, c->buf[0]);
        return RB_ERROR;
    }
    if (!isfinite(t + H) || !(t + H > t)) { /* time must stay finite and advance */
        RB_ERR(c, "%s: currentCommunicationPoint %.17g + communicationStepSize %.17g = %.17g: %s", fn, t, H, t + H,
               isfinite(t + H) ? "the step is below the resolution of the time, it would not advance"
                               : "the time overflows");
        return RB_ERROR;
    }
    memcpy(c->x_start, x, sizeof c->x_start);
    rb_budget_start(&budget, c);
    /* substeps: h <= h_max, and the method's stability and rotation limits (docs/theory.md 5.4) */
    nd = ceil(H / c->buf[RB_VR_HMAX] * (1.0 - 1e-12)); /* relative slack: H = n*h_max gives n, not n+1 */
    eval_rate(c, x, rate);
    need = substeps_for(c, H, rate);
    if (need > nd) nd = need;
    if (nd < 1) nd = 1;
    for (attempt = 0;; attempt++) {
        if (!rb_budget_allows(&budget, c, nd)) { /* refused before the work is done */
            stiff = ceil(H * rate[0] / rb_method_rate_limit[c->method]) >= nd; /* an implicit method takes fewer */
            if (attempt == 0)
                snprintf(context, sizeof context, "the step %g from t=%.17g (h_max %g, stiffness rate %g 1/s, spin "
                         "%g rad/s%s)", H, t, c->buf[RB_VR_HMAX], rate[0], rate[1],
                         stiff ? "; choose an implicit method" : "");
            else
                snprintf(context, sizeof context, "refining the step %g from t=%.17g, in which %s with %ld substeps,",
                         H, t, failure, n);
            rb_budget_refuse(c, fn, &budget, nd, context);
            memcpy(x, c->x_start, sizeof c->x_start);
            return RB_ERROR;
        }
        n = (long)nd;
        h = H / (double)n;
        done = integrate(c, n, h, &err);
        rb_budget_charge(&budget, c, done);
        finite = all_finite(x);
        converged = err <= RB_NEWTON_ACCEPT;
        if (finite && converged) eval_rate(c, x, rate);
        need = finite && converged ? substeps_for(c, H, rate) : NAN;
        /* accept: finite, Newton converged, and the limits still met at the end of the step
         * within a factor 2 (torques can spin the body up during the step) */
        if (done == n && finite && converged && need <= 2.0 * nd) break;
        failure = !finite ? "the state became non-finite"
                          : (!converged ? "Newton did not converge" : "the spin rate kept growing");
        if (attempt == RB_MAX_RETRIES) {
            memcpy(x, c->x_start, sizeof c->x_start);
            RB_ERR(c, "%s: step from t=%.17g (H=%g, method %s) failed after %d refinements down to %ld "
                      "substeps of %g: %s; the state is left at t=%.17g", fn, t, H, rb_method_names[c->method],
                   attempt, n, h, failure, c->buf[0]);
            return RB_ERROR;
        }
        memcpy(x, c->x_start, sizeof c->x_start); /* redo the whole step with more substeps */
        nd = need > 2.0 * nd ? need : 2.0 * nd; /* false for NaN */
    }
    c->last_substeps = n;
    c->buf[0] = t + H; /* outputs are evaluated when they are read (rb_get_reals) */
    return RB_OK;
}
