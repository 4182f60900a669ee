/* Error-controlled internal steps of the FMU core: step sizes from the embedded estimates, rejections, the work budget.
 *
 * Hand-written and model-agnostic; the rules are docs/theory.md §5.5. Each internal step of
 * size h returns an estimate `est` of its relative error (the generated steps,
 * modelsrc/integrators.py); the step is accepted when est <= max(tolerance h / 1 s,
 * RB_ESTIMATE_FLOOR): an error per unit step (Shampine, Numerical Solution of ODEs §7.1),
 * so the error after T seconds is about tolerance T whatever the communication step, with a
 * floor where the estimate is round-off. The next step follows the elementary controller
 * h_new = h min(FAC_MAX, max(FAC_MIN, SAFETY rho^(-1/q))) with rho = est / target and q the
 * estimate's order (Hairer, Norsett, Wanner I §II.4), q + 1 where the floor is the target.
 * A rejected step is redone from its start state (its inputs, k1 and all) with the smaller
 * step, and no step grows right after a rejection. The last step lands exactly on the
 * communication point; the steps before it are spread evenly. Every attempt, a rejected one
 * included, counts against the doStep's work budget (rbfmu_budget.c). */
#include "rbfmu_core.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#define SAFETY 0.9   /* the usual margin below the step the estimate allows */
#define FAC_MIN 0.2  /* at most a factor 5 smaller per step ... */
#define FAC_MAX 5.0  /* ... or larger (DOP853 uses 1/3 and 6, HNW I §II.10) */
#define FAC_FAIL 0.25 /* after a non-finite state or a Newton failure */

/* The first step of a run: as large as the communication step, the cap and the method's
 * stability and rotation limits allow; the controller shrinks it if the estimate says so. */
static double first_step(const Instance *c, double H, double cap, const double rate[2]) {
    double h = H < cap ? H : cap, limit = rb_method_rate_limit[c->method], rot = rb_method_rotation_limit[c->method];
    if (isfinite(limit) && rate[0] * h > limit) h = limit / rate[0];
    if (isfinite(rot) && rate[1] * h > rot) h = rot / rate[1];
    return h;
}

static void refuse(Instance *c, const char *fn, RbBudget *budget, double t, double H, double tau, double h,
                   long accepted, long rejected, double steps) {
    char context[240];
    snprintf(context, sizeof context, "the error-controlled step %g from t=%.17g (tolerance %g, h_max %g; at t=%.17g "
             "after %ld accepted and %ld rejected steps, step %g)", H, t, c->buf[RB_VR_TOLERANCE],
             c->buf[RB_VR_HMAX], t + tau, accepted, rejected, h);
    rb_budget_refuse(c, fn, budget, steps, context);
}

int rb_step_controlled(Instance *c, const char *fn, double t, double H, RbBudget *budget) {
    double *x = c->buf + RB_OFF_X, *report = c->buf + RB_OFF_L;
    double tol = c->buf[RB_VR_TOLERANCE], h_max = c->buf[RB_VR_HMAX], rate[2] = {0, 0};
    double cap = h_max > 0 ? h_max : INFINITY, q = (double)rb_method_estimate_order[c->method];
    double tau = 0.0, h, h_try, est, err, target, rho, fac, n, stab = INFINITY;
    double h_min = 16.0 * DBL_EPSILON * (fabs(t) + H);
    long accepted = 0, rejected = 0;
    int cur = 0, grow = 1, ok;
    rb_eval_rate(c, x, rate);
    if (isfinite(rb_method_rate_limit[c->method]) && rate[0] > 0) stab = rb_method_rate_limit[c->method] / rate[0];
    if (stab < cap) cap = stab; /* explicit methods: inside the stability interval, like fixed steps */
    n = rb_steps_in(H, cap, t); /* the cap alone needs this many steps: refuse at once if too many */
    if (!rb_budget_allows(budget, c, n)) {
        refuse(c, fn, budget, t, H, 0.0, H / n, 0, 0, n);
        return RB_ERROR;
    }
    h = report[RB_REPORT_H_NEXT];
    if (!(h > 0) || !isfinite(h)) h = first_step(c, H, cap, rate);
    while (tau < H) {
        double remaining = H - tau, tau_next;
        if (h > cap) h = cap;
        n = rb_steps_in(remaining, h, t + tau); /* spread evenly, the last one ends on t + H */
        tau_next = n <= 1 ? H : tau + remaining / n;
        /* the step is the exact difference of the two times (Sterbenz), so the steps add up to
         * H exactly: a rounding of tau per step would otherwise shift the time the body
         * turns for by N ulps, an attitude error of W times that at a fast spin W */
        h_try = tau_next - tau;
        if (h_try < h_min) {
            RB_ERR(c, "%s: the error control needs a step below %g s at t=%.17g (method %s, tolerance %g): the "
                      "tolerance cannot be met there; loosen it or choose another method", fn, h_min, t + tau,
                   rb_method_names[c->method], tol);
            return RB_ERROR;
        }
        if (!rb_budget_allows(budget, c, 1.0)) {
            refuse(c, fn, budget, t, H, tau, h_try, accepted, rejected, 1.0);
            return RB_ERROR;
        }
        rb_inputs_for(c, t, tau, h_try);
        err = rb_call_step(c, 1, x, c->k[cur], h_try, c->x_next, c->k[!cur], &est);
        rb_budget_charge(budget, c, 1);
        ok = err <= RB_NEWTON_ACCEPT && est >= 0 && rb_all_finite(c->x_next); /* false for NaN */
        target = tol * h_try > RB_ESTIMATE_FLOOR ? tol * h_try : RB_ESTIMATE_FLOOR;
        rho = est / target;
        if (ok && rho <= 1.0) {
            memcpy(x, c->x_next, sizeof c->x_next);
            rb_accept_compensation(c);
            cur = !cur;
            tau = tau_next;
            rb_inputs_accept(c);
            accepted++;
            report[RB_REPORT_H_LAST] = h_try;
            fac = rho > 0 ? SAFETY * pow(rho, -1.0 / (target > RB_ESTIMATE_FLOOR ? q : q + 1.0)) : FAC_MAX;
            fac = fac > FAC_MAX ? FAC_MAX : (fac < FAC_MIN ? FAC_MIN : fac);
            if (!grow && fac > 1.0) fac = 1.0;
            /* a step shortened to land on the communication point does not shrink the next one */
            h = (fac >= 1.0 && h_try < h) ? (h_try * fac > h ? h_try * fac : h) : h_try * fac;
            grow = 1;
        } else {
            rejected++;
            fac = ok ? SAFETY * pow(rho, -1.0 / (target > RB_ESTIMATE_FLOOR ? q : q + 1.0)) : FAC_FAIL;
            h = h_try * (fac < FAC_MIN ? FAC_MIN : (fac > SAFETY ? SAFETY : fac));
            grow = 0;
        }
    }
    if (cur) memcpy(c->k[0], c->k[1], sizeof c->k[0]);
    c->last_substeps = accepted;
    report[RB_REPORT_STEPS] = (double)accepted;
    report[RB_REPORT_REJECTED] = (double)rejected;
    report[RB_REPORT_H_NEXT] = h < cap ? h : cap;
    return RB_OK;
}
