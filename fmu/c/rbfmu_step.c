/* Fixed internal steps of the FMU core, sized by the method's limits and retried; the internal step both kinds take.
 * Hand-written and model-agnostic; the rules are docs/theory.md §5.4. rb_do_step
 * (rbfmu_dostep.c) takes these fixed steps, or the error control's (rbfmu_control.c,
 * docs/theory.md §5.5), which calls the internal step, the rates and the counts here. */
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
    RB_BIND_MODEL(c, model_rate, x);
    RB_RES(c, model_rate, rate) = r;
    RB_CALL(c, model_rate);
}

/* The generated model_rate_rhs at x: the rate r (rb_eval_rate) and f = f(x) in one call, the
 * same values bit for bit as model_rate's and model_rhs's (the same expressions). */
static void eval_rate_rhs(Instance *c, const double *x, double r[2], double *f) {
    RB_BIND_MODEL(c, model_rate_rhs, x);
    RB_RES(c, model_rate_rhs, rate) = r;
    RB_RES(c, model_rate_rhs, xdot) = f;
    RB_CALL(c, model_rate_rhs);
}

/* ceil(H / h_cap) steps, less the rounding slack of the times (rb_time_slack): a ratio within
 * it of an integer n gives n, not n + 1 (the number of steps must not depend on how the
 * importer rounds its times). */
double rb_steps_in(double H, double h_cap, double t) {
    return ceil((H - rb_time_slack(H, t)) / h_cap);
}

/* Substeps needed over H for the rates r: h * r[0] <= stability limit, h * r[1] <= rotation limit. */
static double substeps_for(const Instance *c, double H, const double r[2]) {
    int method = c->persistent.method;
    double n = 0, limit = rb_method_rate_limit[method], rot = rb_method_rotation_limit[method];
    if (isfinite(limit) && H * r[0] / limit > n) n = ceil(H * r[0] / limit);
    if (isfinite(rot) && H * r[1] / rot > n) n = ceil(H * r[1] / rot);
    return n;
}

/* The start rate r of a fixed-step doStep of length H, the substeps it asks (substeps_for)
 * and *k1 = f(x): the previous doStep's end values (k_end) where they were taken at the same
 * states, inputs, parameters and method (bit for bit: the values model_rate_rhs and
 * substeps_for would return; the substeps also at the same H), else computed at x (into
 * k_start). Either way the kept values are spent: an attempt overwrites k_end, and only an
 * accepted doStep keeps new ones (keep_rate). */
static double start_rate(Instance *c, const double *x, double H, double r[2], const double **k1) {
    RbStepScratch *s = &c->step;
    bool kept = s->rate_valid && s->rate_method == c->persistent.method &&
                memcmp(s->rate_at, c->persistent.buf + RB_OFF_X, sizeof s->rate_at) == 0;
    s->rate_valid = false;
    if (kept) {
        r[0] = s->rate_end[0];
        r[1] = s->rate_end[1];
        *k1 = s->k_end;
        return H == s->rate_H ? s->rate_need : substeps_for(c, H, r);
    }
    eval_rate_rhs(c, x, r, s->k_start);
    *k1 = s->k_start;
    return substeps_for(c, H, r);
}

/* Keeps the rate r at the end of an accepted fixed-step doStep of length H, and the substeps
 * need it asks, for the next doStep's start (start_rate), with f there in k_end (end_rate).
 * Only with held inputs: otherwise the inputs in buf after the doStep (rb_inputs_end) are
 * not the ones r and f were evaluated with. */
static void keep_rate(Instance *c, double H, const double r[2], double need) {
    RbStepScratch *s = &c->step;
    s->rate_valid = c->inputs.mode == RB_HELD;
    if (!s->rate_valid) return;
    s->rate_end[0] = r[0];
    s->rate_end[1] = r[1];
    s->rate_H = H;
    s->rate_need = need;
    s->rate_method = c->persistent.method;
    memcpy(s->rate_at, c->persistent.buf + RB_OFF_X, sizeof s->rate_at);
}

/* The rate r at the end state x of an attempt (the acceptance test of rb_step_fixed); with
 * held inputs also f(x) into k_end, in the same call, for the next doStep (keep_rate). */
static void end_rate(Instance *c, const double *x, double r[2]) {
    if (c->inputs.mode == RB_HELD)
        eval_rate_rhs(c, x, r, c->step.k_end);
    else
        rb_eval_rate(c, x, r);
}

/* k1 of a retry that started from the kept k_end: f at the start state (back in buf) with
 * the inputs at the doStep's start (an importer asked inside the doStep may have set others),
 * into k_start. */
static const double *retry_k1(Instance *c) {
    rb_bind_model(c, c->work.arg, RB_ARG_model_rhs_x, RB_ARG_model_rhs_u, RB_ARG_model_rhs_p, RB_ARG_model_rhs_d,
                  c->persistent.buf + RB_OFF_X, c->inputs.u_start);
    RB_RES(c, model_rhs, xdot) = c->step.k_start;
    RB_CALL(c, model_rhs);
    return c->step.k_start;
}

bool rb_all_finite(const double *x) {
    /* x - x is 0 for a finite x and NaN for an infinite or NaN one, and a NaN stays in the
     * sum: one subtraction and one addition per state, no branch (a third of the
     * instructions of an isfinite test per state, run once per doStep) */
    double z = 0.0;
    int i;
    for (i = 0; i < RB_NX; i++) z += x[i] - x[i];
    return z == 0.0;
}

void rb_bind_step(Instance *c) {
    RbStepScratch *s = &c->step;
    rb_bind_model(c, s->arg, RB_ARG_model_step_x, RB_ARG_model_step_U, RB_ARG_model_step_p, RB_ARG_model_step_d,
                  c->persistent.buf + RB_OFF_X, c->inputs.U);
    s->arg[RB_ARG_model_step_h] = &s->h;
    s->res[RB_RES_model_step_err] = &s->err;
    s->res[RB_RES_model_step_est] = &s->est;
    s->res[RB_RES_model_step_dx] = s->dx;
    s->arg[RB_ARG_model_step_e] = c->derived.e;
}

/* The fixed step's constants for step size h (modelsrc/integrators.py, step_constants: the
 * sines and cosines of a clock's advances), computed when h, the method or the parameters
 * changed since the last ones: once per run at a constant step, not once per step; the
 * fixed steps of `integrate` take them (the steps under error control have none). */
static void step_constants(Instance *c, double h) {
    RbDerived *dv = &c->derived;
    int m = c->persistent.method;
    rb_step_fn fn = rb_step_constants_fns[m];
    if (fn == 0 || (h == dv->e_h && m == dv->e_method)) return;
    c->work.arg[RB_ARG_model_step_constants_p] = c->persistent.buf + RB_OFF_P;
    c->work.arg[RB_ARG_model_step_constants_h] = &h;
    c->work.arg[RB_ARG_model_step_constants_d] = dv->d;
    c->work.res[RB_RES_model_step_constants_e] = dv->e;
    fn(c->work.arg, c->work.res, c->work.iw, c->work.w, 0);
    dv->e_h = h;
    dv->e_method = m;
}

double rb_call_step(Instance *c, bool controlled, const double *x, const double *k, double h, double *x_next,
                    double *k_next, const double *comp, double *comp_out, double *est) {
    RbStepScratch *s = &c->step;
    s->arg[RB_ARG_model_step_x] = x;
    s->arg[RB_ARG_model_step_k1] = k;
    s->res[RB_RES_model_step_x_next] = x_next;
    s->res[RB_RES_model_step_k_next] = k_next;
    s->h = h;
    /* every variant writes err and est (0 where it has none: the fixed variants' est) */
    (controlled ? c->derived.step_fns : c->derived.fixed_step_fns)[c->persistent.method](s->arg, s->res, c->work.iw,
                                                                                          c->work.w, 0);
    if (rb_method_increment[c->persistent.method]) { /* read after the call: no register kept across it */
        /* compensated summation (Kahan; Hairer-Lubich-Wanner §VIII.5) of x + dx for the
         * states but q (q is projected, and its rounding is not amplified): without it the
         * rounding of w + dw makes |L| and E random-walk by sqrt(N) eps over N steps, and a
         * fast spin W turns that into an attitude error sqrt(N) eps W T. comp_out may be
         * comp itself (element by element in place) */
        int i;
        for (i = RB_NQ; i < RB_NX; i++) {
            double inc = s->dx[i] + comp[i], y = x[i] + inc;
            comp_out[i] = inc - (y - x[i]);
            x_next[i] = y;
        }
    }
    *est = s->est;
    return s->err;
}

/* Up to n substeps of size h = H/n on the state in buf, the first with k1 = f there; returns
 * how many it took (the state in buf; s->k not kept: the next doStep starts afresh). It stops
 * early once the attempt has failed: a Newton residual above the acceptance level, or a
 * non-finite state (checked every 64 substeps; NaN and Inf do not heal), so that a doomed
 * attempt does not spend its whole budget. *err_max: the largest residual (0: explicit). */
static long integrate(Instance *c, double t, long n, double H, const double *k1, double *err_max) {
    RbStepScratch *s = &c->step;
    double *x = c->persistent.buf + RB_OFF_X, err, est, h = H / (double)n;
    long k;
    *err_max = 0.0;
    step_constants(c, h); /* once per attempt: every substep has this h */
    for (k = 0; k < n;) { /* ping-pong between the state and a scratch buffer: no copy per substep */
        int odd = (int)(k & 1);
        rb_inputs_for(c, t, (double)k * h, h);
        err = rb_call_step(c, false, odd ? s->x_next : x, k1, h, odd ? x : s->x_next, s->k[!odd], s->comp, s->comp,
                           &est); /* every substep is kept: the compensation in place */
        k1 = s->k[!odd];
        if (!(err <= *err_max)) *err_max = err; /* also catches NaN */
        rb_inputs_accept(c);
        k++;
        if (!(*err_max <= RB_NEWTON_ACCEPT) || ((k & 63) == 0 && !rb_all_finite(odd ? x : s->x_next))) break;
    }
    if (k & 1) memcpy(x, s->x_next, sizeof s->x_next);
    return k;
}

/* Fixed stepping: n equal substeps, n = max(ceil(H/h_max), the stability and rotation
 * limits) (docs/theory.md §5.4), redone with more when an attempt fails. */
RbStatus rb_step_fixed(Instance *c, const char *fn, double t, double H, RbBudget *budget) {
    RbStepScratch *s = &c->step;
    double *buf = c->persistent.buf, *x = buf + RB_OFF_X, h_max = buf[RB_VR_HMAX];
    double nd, need, rate[2] = {0, 0}, err = 0, rejected = 0;
    const double *k1;
    int method = c->persistent.method, attempt;
    long n = 0, done;
    bool finite, converged, stiff;
    const char *failure = "";
    char context[200];
    nd = h_max > 0 ? rb_steps_in(H, h_max, t) : 1;
    need = start_rate(c, x, H, rate, &k1); /* and f at the start: the first step's k1 */
    if (need > nd) nd = need;
    if (nd < 1) nd = 1;
    for (attempt = 0;; attempt++) {
        if (!rb_budget_allows(budget, c, nd)) { /* refused before the work is done */
            stiff = ceil(H * rate[0] / rb_method_rate_limit[method]) >= nd; /* an implicit method takes fewer */
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
        done = integrate(c, t, n, H, k1, &err);
        rb_budget_charge(budget, c, done);
        finite = rb_all_finite(x);
        converged = err <= RB_NEWTON_ACCEPT;
        if (finite && converged) end_rate(c, x, rate);
        need = finite && converged ? substeps_for(c, H, rate) : NAN;
        /* accept: finite, Newton converged, and the limits still met at the end of the step
         * within a factor 2 (torques can spin the body up during the step) */
        if (done == n && finite && converged && need <= 2.0 * nd) break;
        rejected += (double)done;
        failure = !finite ? "the state became non-finite"
                          : (!converged ? "Newton did not converge" : "the spin rate kept growing");
        memcpy(x, s->x_start, sizeof s->x_start); /* redo the whole step with more substeps */
        if (k1 != s->k_start) k1 = retry_k1(c); /* the kept k_end: overwritten by the attempt's end_rate */
        memset(s->comp, 0, sizeof s->comp);
        rb_inputs_restart(c);
        if (attempt == RB_MAX_RETRIES) {
            RB_ERR(c, "%s: step from t=%.17g (H=%g, method %s) failed after %d refinements down to %ld "
                      "substeps of %g: %s; the state is left at t=%.17g", fn, t, H, rb_method_names[method],
                   attempt, n, H / (double)n, failure, buf[0]);
            return RB_ERROR;
        }
        nd = need > 2.0 * nd ? need : 2.0 * nd; /* false for NaN */
    }
    keep_rate(c, H, rate, need); /* both taken at the accepted end state (the test above) */
    s->last_substeps = n;
    buf[RB_OFF_L + RB_REPORT_STEPS] = (double)n;
    buf[RB_OFF_L + RB_REPORT_REJECTED] = rejected;
    buf[RB_OFF_L + RB_REPORT_H_LAST] = H / (double)n;
    return RB_OK;
}
