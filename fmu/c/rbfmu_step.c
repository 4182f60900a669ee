/* The Co-Simulation step of the FMU core: the checks of a doStep, fixed sub-steps sized by the method's limits, retries.
 * Hand-written and model-agnostic; the rules are docs/theory.md §5.4. With tolerance > 0 and a
 * method that has an error estimate, the steps are chosen by the error control instead
 * (rbfmu_control.c, docs/theory.md §5.5). */
#include "rbfmu_core.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A doStep whose substeps fail the acceptance test is redone from its start state with
 * more substeps, at most this many times (each at least doubling the count). */
#define RB_MAX_RETRIES 10

/* The generated model_rate at x: r[0] = ||df/dx||_inf (1/s, stability), r[1] = |w| (rad/s, accuracy). */
void rb_eval_rate(Instance *c, const double *x, double r[2]) {
    c->arg[0] = x;
    c->arg[1] = c->buf + RB_OFF_U;
    c->arg[2] = c->buf + RB_OFF_P;
    c->arg[3] = c->d;
    c->res[0] = r;
    model_rate(c->arg, c->res, c->iw, c->w, 0);
}

/* ceil(H / h_cap) steps, less the rounding slack of the times (rb_time_slack): a ratio within
 * it of an integer n gives n, not n + 1 (the number of steps must not depend on how the
 * importer rounds its times). */
double rb_steps_in(double H, double h_cap, double t) {
    return ceil((H - rb_time_slack(H, t)) / h_cap);
}

/* Substeps needed over H for the rates r: h * r[0] <= stability limit, h * r[1] <= rotation limit. */
static double substeps_for(const Instance *c, double H, const double r[2]) {
    double n = 0, limit = rb_method_rate_limit[c->method], rot = rb_method_rotation_limit[c->method];
    if (isfinite(limit) && H * r[0] / limit > n) n = ceil(H * r[0] / limit);
    if (isfinite(rot) && H * r[1] / rot > n) n = ceil(H * r[1] / rot);
    return n;
}

int rb_all_finite(const double *x) {
    int i, finite = 1;
    for (i = 0; i < RB_NX; i++) finite &= isfinite(x[i]) ? 1 : 0;
    return finite;
}

void rb_bind_step(Instance *c) {
    c->step_arg[1] = c->U;
    c->step_arg[2] = c->buf + RB_OFF_P;
    c->step_arg[3] = &c->step_h;
    c->step_arg[4] = c->d;
    c->step_res[1] = &c->step_err;
    c->step_res[2] = &c->step_est;
    c->step_res[4] = c->dx;
}

double rb_call_step(Instance *c, int controlled, const double *x, const double *k, double h, double *x_next,
                    double *k_next, const double *comp, double *comp_out, double *est) {
    c->step_arg[0] = x;
    c->step_arg[5] = k;
    c->step_res[0] = x_next;
    c->step_res[3] = k_next;
    c->step_h = h;
    /* every variant writes err and est (0 where it has none: the fixed variants' est) */
    (controlled ? c->step_fns : c->fixed_step_fns)[c->method](c->step_arg, c->step_res, c->iw, c->w, 0);
    if (rb_method_increment[c->method]) {
        /* compensated summation (Kahan; Hairer-Lubich-Wanner §VIII.5) of x + dx for the
         * states but q (q is projected, and its rounding is not amplified): without it the
         * rounding of w + dw makes |L| and E random-walk by sqrt(N) eps over N steps, and a
         * fast spin W turns that into an attitude error sqrt(N) eps W T. comp_out may be
         * comp itself (element by element in place) */
        int i;
        for (i = RB_NQ; i < RB_NX; i++) {
            double inc = c->dx[i] + comp[i], y = x[i] + inc;
            comp_out[i] = inc - (y - x[i]);
            x_next[i] = y;
        }
    }
    *est = c->step_est;
    return c->step_err;
}

/* Up to n substeps of size h = H/n on the state in buf; returns how many it took. It stops
 * early once the attempt has failed: a Newton residual above the acceptance level, or a
 * non-finite state (checked every 64 substeps; NaN and Inf do not heal), so that a doomed
 * attempt does not spend its whole budget. *err_max: the largest residual (0: explicit). */
static long integrate(Instance *c, double t, long n, double H, double *err_max) {
    double *x = c->buf + RB_OFF_X, err, est, h = H / (double)n;
    long k;
    *err_max = 0.0;
    for (k = 0; k < n;) { /* ping-pong between the state and a scratch buffer: no copy per substep */
        int odd = (int)(k & 1);
        rb_inputs_for(c, t, (double)k * h, h);
        err = rb_call_step(c, 0, odd ? c->x_next : x, c->k[odd], h, odd ? x : c->x_next, c->k[!odd], c->comp,
                           c->comp, &est); /* every substep is kept: the compensation in place */
        if (!(err <= *err_max)) *err_max = err; /* also catches NaN */
        rb_inputs_accept(c);
        k++;
        if (!(*err_max <= RB_NEWTON_ACCEPT) || ((k & 63) == 0 && !rb_all_finite(odd ? x : c->x_next))) break;
    }
    if (k & 1) {
        memcpy(x, c->x_next, sizeof c->x_next);
        memcpy(c->k[0], c->k[1], sizeof c->k[0]);
    }
    return k;
}

/* Fixed stepping: n equal substeps, n = max(ceil(H/h_max), the stability and rotation
 * limits) (docs/theory.md §5.4), redone with more when an attempt fails. */
static int step_fixed(Instance *c, const char *fn, double t, double H, RbBudget *budget) {
    double nd, need, rate[2] = {0, 0}, err = 0, rejected = 0;
    double *x = c->buf + RB_OFF_X, h_max = c->buf[RB_VR_HMAX];
    long n = 0, done;
    int attempt, finite, converged, stiff;
    const char *failure = "";
    char context[200];
    nd = h_max > 0 ? rb_steps_in(H, h_max, t) : 1;
    rb_eval_rate(c, x, rate);
    need = substeps_for(c, H, rate);
    if (need > nd) nd = need;
    if (nd < 1) nd = 1;
    for (attempt = 0;; attempt++) {
        if (!rb_budget_allows(budget, c, nd)) { /* refused before the work is done */
            stiff = ceil(H * rate[0] / rb_method_rate_limit[c->method]) >= nd; /* an implicit method takes fewer */
            if (attempt == 0)
                snprintf(context, sizeof context, "the step %g from t=%.17g (h_max %g, stiffness rate %g 1/s, spin "
                         "%g rad/s%s)", H, t, h_max, rate[0], rate[1], stiff ? "; choose an implicit method" : "");
            else
                snprintf(context, sizeof context, "refining the step %g from t=%.17g, in which %s with %ld substeps,",
                         H, t, failure, n);
            rb_budget_refuse(c, fn, budget, nd, context);
            return RB_ERROR;
        }
        n = (long)nd;
        done = integrate(c, t, n, H, &err);
        rb_budget_charge(budget, c, done);
        finite = rb_all_finite(x);
        converged = err <= RB_NEWTON_ACCEPT;
        if (finite && converged) rb_eval_rate(c, x, rate);
        need = finite && converged ? substeps_for(c, H, rate) : NAN;
        /* accept: finite, Newton converged, and the limits still met at the end of the step
         * within a factor 2 (torques can spin the body up during the step) */
        if (done == n && finite && converged && need <= 2.0 * nd) break;
        rejected += (double)done;
        failure = !finite ? "the state became non-finite"
                          : (!converged ? "Newton did not converge" : "the spin rate kept growing");
        memcpy(x, c->x_start, sizeof c->x_start); /* redo the whole step with more substeps */
        memcpy(c->k[0], c->k_start, sizeof c->k_start);
        memset(c->comp, 0, sizeof c->comp);
        rb_inputs_restart(c);
        if (attempt == RB_MAX_RETRIES) {
            RB_ERR(c, "%s: step from t=%.17g (H=%g, method %s) failed after %d refinements down to %ld "
                      "substeps of %g: %s; the state is left at t=%.17g", fn, t, H, rb_method_names[c->method],
                   attempt, n, H / (double)n, failure, c->buf[0]);
            return RB_ERROR;
        }
        nd = need > 2.0 * nd ? need : 2.0 * nd; /* false for NaN */
    }
    c->last_substeps = n;
    c->buf[RB_OFF_L + RB_REPORT_STEPS] = (double)n;
    c->buf[RB_OFF_L + RB_REPORT_REJECTED] = rejected;
    c->buf[RB_OFF_L + RB_REPORT_H_LAST] = H / (double)n;
    return RB_OK;
}

int rb_do_step(Instance *c, const char *fn, double t, double H) {
    double tol, tolerance = c->buf[RB_VR_TOLERANCE];
    double *x = c->buf + RB_OFF_X;
    int status, controlled;
    RbBudget budget;
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
    controlled = tolerance > 0 && rb_method_estimate_order[c->method] > 0;
    rb_inputs_begin(c, controlled);
    rb_bind_step(c);
    rb_compute_derivatives(c, c->k[0]); /* f at the start: the first step's k1 */
    memcpy(c->k_start, c->k[0], sizeof c->k_start);
    memset(c->comp, 0, sizeof c->comp); /* a doStep starts from its state as stored: reproducible */
    c->buf[RB_OFF_L + RB_REPORT_STEPS] = 0.0;
    c->buf[RB_OFF_L + RB_REPORT_REJECTED] = 0.0;
    c->buf[RB_OFF_L + RB_REPORT_TOL_EFFECTIVE] = 0.0; /* fixed stepping holds no tolerance */
    if (controlled)
        status = rb_step_controlled(c, fn, t, H, &budget);
    else
        status = step_fixed(c, fn, t, H, &budget);
    if (status == RB_OK) { /* the outputs at t + H (its inputs), checked once per doStep (rb_outputs_finite) */
        rb_inputs_end(c, H, 1);
        c->buf[0] = t + H;
        if (!rb_outputs_finite(c, fn)) {
            c->buf[0] = t; /* back to the start, inputs too (below) */
            status = RB_ERROR;
        }
    }
    if (status != RB_OK) {
        memcpy(x, c->x_start, sizeof c->x_start);
        rb_inputs_end(c, H, 0);
        return status;
    }
    return RB_OK;
}
