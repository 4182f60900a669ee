/* Error-controlled internal steps of the FMU core: step sizes from the embedded estimates, rejections, the work budget.
 *
 * Hand-written and model-agnostic; the rules are docs/theory.md §5.5. Each internal step of
 * size h returns the square `est` of an estimate of its relative error (the generated steps,
 * modelsrc/integrators.py); the step is accepted when est <= max(tolerance h / 1 s,
 * RB_ESTIMATE_FLOOR)^2: an error per unit step (Shampine, Numerical Solution of ODEs §7.1),
 * so the error after T seconds is about tolerance T whatever the communication step, with a
 * floor where the estimate is round-off. The next step follows the elementary controller
 * h_new = h min(FAC_MAX, max(FAC_MIN, SAFETY rho^(-1/q))) with rho^2 = est / target^2 and q the
 * estimate's order (Hairer, Norsett, Wanner I §II.4), q + 1 where the floor is the target.
 * A rejected step is redone from its start state (its inputs, k1 and all) with the smaller
 * step, and no step grows right after a rejection. The last step lands exactly on the
 * communication point; the last few before it (at most four) are spread evenly. A tolerance
 * the estimate cannot resolve (tolerance h below the floor, or an estimate that proves to be
 * round-off) is raised to what it resolves and kept so (tolerance_floor), so that the steps
 * stop shrinking and the controller stops rejecting (docs/theory.md §5.5, "The estimate's
 * floor"). Every
 * attempt, a rejected one included, counts against the doStep's work budget (rbfmu_budget.c).
 * Nothing in the loop of an ordinary step divides or calls libm: on an RK4 step of ~60 ns,
 * pow and the divisions of an even spread over all remaining steps cost another 25 ns
 * (measured with perf on heavy_top), and error control was to cost at most 1.3 times the
 * fixed step at equal error. */
#include "rbfmu_core.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#define SAFETY 0.9   /* the usual margin below the step the estimate allows */
#define FAC_MIN 0.2  /* at most a factor 5 smaller per step ... */
#define FAC_MAX 5.0  /* ... or larger (DOP853 uses 1/3 and 6, HNW I §II.10) */
#define FAC_FAIL 0.25 /* after a non-finite state or a Newton failure */
#define SPREAD 4.0    /* the last steps, at most this many, share what remains evenly */
/* Round-off, not truncation, is what a rejected step's estimate is when a retry with the step
 * shrunk by r keeps est/(tolerance h)^2 above r^q times its first value (a truncation error
 * falls like r^(2q) there), once r^q <= ROUNDOFF_SHRINK separates the two, and only for an
 * estimate at the level of round-off (relative error per step below ROUNDOFF_LEVEL, a few
 * hundred eps: a jump or a stiff motion gives larger ones). The tolerance then rises to
 * ROUNDOFF_MARGIN times what the estimate resolves (docs/theory.md §5.5). */
/* An implicit step's estimate carries the error of its Newton solve, which stops at an absolute
 * residual (modelsrc/integrators.py, newton_tol) and varies erratically with h, so that a
 * smaller step does not reduce it: an estimate within NEWTON_NOISE times the step's scaled
 * residual err is that noise, not a truncation error, and does not reject the step
 * (measured on top_on_shaker under gauss6 with intermediate update: est/err up to 12). */
#define NEWTON_NOISE 16.0
#define ROUNDOFF_SHRINK 0.5
#define ROUNDOFF_LEVEL 1e-13
#define ROUNDOFF_MARGIN 2.0

/* rho2^e for the step factor, to 0.3 % relative (docs/theory.md §5.5): 2^(e log2 rho2) with
 * log2 of the mantissa 1 + u as u + c (u - u^2) (error 0.0076 in log2, times |e| <= 1/4) and
 * 2^f, |f| <= 1/2, from a quadratic (error 1.8e-3): a factor that the controller then
 * multiplies by its 0.9 safety margin needs no more, and every instruction here is paid
 * once per accepted step of an RK4 step of ~1000 instructions (callgrind: 55 instructions
 * with cubics to 2e-4, 44 with these). libm's pow costs ~15 ns per step and may round
 * differently on each platform, so the same FMU would take other steps on Windows; this is
 * the same arithmetic everywhere. rho2 is clamped to [1e-30, 1e30], beyond where FAC_MIN
 * and FAC_MAX clamp the factor. */
static double step_power(double rho2, double e) {
    const double round = 6755399441055744.0; /* 1.5 * 2^52: y + round holds round(y) in its low bits */
    uint64_t bits;
    double u, y, r, f, scale;
    int64_t n;
    if (!(rho2 > 1e-30)) rho2 = 1e-30; /* also NaN: the factor is clamped afterwards */
    if (rho2 > 1e30) rho2 = 1e30;
    memcpy(&bits, &rho2, sizeof bits);
    n = (int64_t)((bits >> 52) & 0x7ff) - 1023;
    bits = (bits & 0x000fffffffffffffULL) | 0x3ff0000000000000ULL; /* the mantissa in [1, 2) */
    memcpy(&u, &bits, sizeof u);
    u -= 1.0;
    y = e * ((double)n + (u + 0.346555 * (u - u * u)));
    r = y + round;
    memcpy(&bits, &r, sizeof bits);
    n = (int64_t)(bits - 0x4338000000000000ULL); /* round(y); |y| <= 100 |e| */
    f = y - (r - round);                          /* exact: -1/2 <= f <= 1/2 */
    bits = (uint64_t)(n + 1023) << 52;            /* 2^n */
    memcpy(&scale, &bits, sizeof scale);
    return scale * (1.000443 + f * (0.703448 + 0.238429 * f));
}

/* The scaled max norm of v: |v_i| / (tol max(|x_i|, nominal_i)), the estimate's relative
 * scale (modelsrc/nominals.py) in units of the tolerance. */
static double scaled_norm(const double *v, const double *x, double tol) {
    double d = 0.0;
    int i;
    for (i = 0; i < RB_NX; i++) {
        double s = fabs(x[i]) > rb_nominal[i] ? fabs(x[i]) : rb_nominal[i], r = fabs(v[i]) / (tol * s);
        if (!(r <= d)) d = r; /* NaN wins: it makes the step the fallback below */
    }
    return d;
}

/* The first step of a run: as large as the communication step, the cap and the method's
 * stability and rotation limits allow, and no larger than the state's rates allow: the
 * starting step of Hairer, Norsett & Wanner I §II.4 (p. 169) with the scale
 * sc_i = tol max(|x_i|, nominal_i) and the estimate's order q: h0 = 0.01 |x|/|f| (an Euler
 * step changes x by 1 %), d2 = |f(x + h0 f) - f| / h0, h1 = (0.01 / max(|f|, d2))^(1/(q+1)),
 * h = min(100 h0, h1). Where x does not change (|f| = 0) there is no rate to bound the
 * step. Without it a burst of torque from rest (8e9 N on spacecraft_thruster) took a first
 * step whose stages overflowed (issue 23.12). Costs one right-hand side, at a doStep that
 * has no step of the previous one to start from. */
static double first_step(Instance *c, double H, double cap, const double rate[2], double q) {
    int method = c->persistent.method;
    double h = H < cap ? H : cap, limit = rb_method_rate_limit[method], rot = rb_method_rotation_limit[method];
    double tol = c->persistent.buf[RB_VR_TOLERANCE], *x = c->persistent.buf + RB_OFF_X, *f = c->step.k[0];
    double *x1 = c->step.x_next, *f1 = c->step.k[1];
    double d0, d1, d2, h0, h1;
    int i;
    if (isfinite(limit) && rate[0] * h > limit) h = limit / rate[0];
    if (isfinite(rot) && rate[1] * h > rot) h = rot / rate[1];
    if (tol < RB_ESTIMATE_FLOOR) tol = RB_ESTIMATE_FLOOR;
    d0 = scaled_norm(x, x, tol);
    d1 = scaled_norm(f, x, tol);
    if (!(d1 > 0)) return h; /* no rate (or a NaN one, which the step itself reports) */
    h0 = 0.01 * d0 / d1 < h ? 0.01 * d0 / d1 : h;
    for (i = 0; i < RB_NX; i++) x1[i] = x[i] + h0 * f[i];
    RB_BIND_MODEL(c, model_rhs, x1);
    RB_RES(c, model_rhs, xdot) = f1;
    RB_CALL(c, model_rhs);
    for (i = 0; i < RB_NX; i++) f1[i] -= f[i];
    d2 = scaled_norm(f1, x, tol) / h0;
    h1 = pow(0.01 / (d1 > d2 ? d1 : d2), 1.0 / (q + 1.0)); /* NaN d2: h1 NaN, ignored below */
    if (100.0 * h0 < h) h = 100.0 * h0;
    if (h1 < h) h = h1;
    return h;
}

/* What the next step size is computed from, once an accepted step's estimate is known:
 * rho2 = est / target^2, the exponent, the step taken and the step proposed before it
 * (larger when the step was shortened to land on the communication point), whether it may
 * grow (not right after a rejection) and whether it was shortened. */
typedef struct {
    double rho2, e, h_try, h_proposed;
    int grow, shortened;
} Proposal;

static inline double propose(const Proposal *p) {
    double fac = p->rho2 > 0 ? SAFETY * step_power(p->rho2, p->e) : FAC_MAX;
    fac = fac > FAC_MAX ? FAC_MAX : (fac < FAC_MIN ? FAC_MIN : fac);
    if (!p->grow && fac > 1.0) fac = 1.0;
    /* a step shortened to land on the communication point does not shrink the next one
     * (fac >= 1 as a select: near 1 in steady state, a branch on it is a coin flip) */
    if (p->shortened && p->h_try < p->h_proposed) {
        double keep = fac >= 1.0 ? p->h_proposed : 0.0;
        return p->h_try * fac > keep ? p->h_try * fac : keep;
    }
    return p->h_try * fac;
}

/* r^q for the estimate's order q (an integer): the same arithmetic on every platform. */
static double power_q(double r, int q) {
    double p = 1.0;
    while (q-- > 0) p *= r;
    return p;
}

/* The tolerance per second that the retry of a rejected step shows to be below the estimate's
 * round-off, else 0 (see ROUNDOFF_SHRINK). first2 and first_h: est/(tol h)^2 and h of the
 * step's first rejected attempt. */
static double roundoff_tolerance(double est, double tol, double h, double first2, double first_h, int q) {
    double ratio2 = est / (tol * h * (tol * h)), shrink = power_q(h / first_h, q);
    if (!(first_h > h) || !(est <= ROUNDOFF_LEVEL * ROUNDOFF_LEVEL) || shrink > ROUNDOFF_SHRINK) return 0.0;
    if (!(ratio2 > first2 * shrink)) return 0.0; /* it fell like a truncation error */
    return ROUNDOFF_MARGIN * sqrt(est) / h;
}

/* Why the tolerance the error control held in a doStep is above the one set: the estimate
 * cannot resolve the one set (report_floor). */
typedef enum {
    HELD_AS_SET,          /* not raised in this doStep */
    HELD_AT_STEP_FLOOR,   /* tolerance h is below the floor of a step's estimate at the steps taken */
    HELD_AT_ROUNDOFF,     /* the retry of a rejected step showed the estimate's round-off */
    HELD_AT_NEWTON_NOISE, /* steps were accepted at the noise of their Newton solve */
} HeldBecause;

/* Once per rise (by 2x): the tolerance the error control held is above the one set, because
 * the estimate cannot resolve that (h_floor: the step at which it met the floor); said
 * through the logger with the value that applied. */
static void report_floor(Instance *c, const char *fn, double t, double tol, double held, HeldBecause because,
                         double h_floor) {
    char reason[160];
    if (because == HELD_AS_SET || !(held > 2.0 * c->importer.tolerance_logged)) return;
    c->importer.tolerance_logged = held;
    if (because == HELD_AT_NEWTON_NOISE)
        snprintf(reason, sizeof reason, "steps whose estimate is within %g times the residual left by Newton's "
                 "method, which a smaller step does not reduce", NEWTON_NOISE);
    else if (because == HELD_AT_STEP_FLOOR)
        snprintf(reason, sizeof reason, "at steps of %g s tolerance h is below the floor %g of a step's estimate",
                 h_floor, RB_ESTIMATE_FLOOR);
    else
        snprintf(reason, sizeof reason, "its round-off: the estimate did not fall when the step shrank");
    rb_logf(c, RB_WARNING, "%s: in the step from t=%.17g the error control holds %g per second, not tolerance = %g: "
            "the error estimate of method %s cannot resolve less (%s); results are as accurate as that (output "
            "tolerance_effective; docs/user_guide.md section 2.2)", fn, t, held, tol,
            rb_method_names[c->persistent.method], reason);
}

static void refuse(Instance *c, const char *fn, RbBudget *budget, double t, double H, double tau, double h,
                   long accepted, long rejected, double steps) {
    char context[240];
    snprintf(context, sizeof context, "the error-controlled step %g from t=%.17g (tolerance %g, h_max %g; at t=%.17g "
             "after %ld accepted and %ld rejected steps, step %g)", H, t, c->persistent.buf[RB_VR_TOLERANCE],
             c->persistent.buf[RB_VR_HMAX], t + tau, accepted, rejected, h);
    rb_budget_refuse(c, fn, budget, steps, context);
}

/* An accepted state that is not finite although its estimate was: an overflow that the
 * estimate's scale overflowed with (|x| near 1e308), which no smaller step cures. */
static RbStatus overflow(Instance *c, const char *fn, double t, double tau) {
    RB_ERR(c, "%s: the state became non-finite (an overflow) at t=%.17g under error control (method %s, "
              "tolerance %g); the state stays at the doStep's start t=%.17g", fn, t + tau,
           rb_method_names[c->persistent.method], c->persistent.buf[RB_VR_TOLERANCE], t);
    return RB_ERROR;
}

static RbStatus too_small(Instance *c, const char *fn, double t, double tau, double h_min, double tol) {
    RB_ERR(c, "%s: the error control needs a step below %g s at t=%.17g (method %s, tolerance %g): the "
              "tolerance cannot be met there; loosen it or choose another method", fn, h_min, t + tau,
           rb_method_names[c->persistent.method], tol);
    return RB_ERROR;
}

/* ---- the controller and its named steps ---- */

/* What the estimate of an attempt says (classify). */
typedef enum {
    ESTIMATE_WITHIN,       /* within the target: accept */
    ESTIMATE_NEWTON_NOISE, /* above it, but the noise of the Newton solve: accept */
    ESTIMATE_ROUNDOFF,     /* above it, but round-off, which the retry showed: accept, the tolerance raised */
    ESTIMATE_ABOVE,        /* a finite estimate above the target: reject, shrink by it */
    ESTIMATE_FAILED,       /* Newton did not converge, or the estimate is not a number: reject, shrink by FAC_FAIL */
} Estimate;

/* The error control's state over one doStep. */
typedef struct {
    double t, H, tau;  /* the span [t, t + H] and how much of it is done */
    double cap, h_min; /* the largest step (h_max, stability), the smallest the times resolve */
    double h;          /* the step proposed next */
    double h_try;      /* this attempt's step: tau_next - tau, shortened when it lands or spreads */
    double tau_next;
    bool shortened;
    int q;                           /* the estimate's order */
    double e_target, e_floor;        /* the controller's exponents on rho2 for the target and the floor */
    double inv_target2, e_step;      /* this attempt's 1/target^2 and exponent */
    double est, err, rho2;           /* this attempt's estimate, Newton residual, est/target^2 */
    double tol_set, tol;             /* the tolerance set and the one held */
    double noise_held;               /* the largest error per second of a step accepted at its Newton noise */
    HeldBecause because;             /* why tol was raised in this doStep */
    double h_floor;                  /* a step at which the target met the estimate's floor */
    double first2, first_h;          /* est/(tol h)^2 and h of the step's first rejected attempt (0: none) */
    Proposal last;                   /* the previous accepted step's proposal */
    bool lagged, grow;               /* it is there to use; the next step may grow */
    long accepted, rejected, tried, left; /* attempts tried but not yet charged; steps the budget admits */
    double *xa, *xb, *ca, *cb;       /* the state and its compensation, and the other of each (ping-pong) */
    int cur;                         /* k[cur] is f at xa */
} Control;

/* Land or spread: the attempt's end. The last step lands exactly on the communication point
 * when h reaches it within the rounding of the times (as rb_steps_in); the last few before it
 * (at most SPREAD) share what remains evenly. */
static inline void land_or_spread(Control *k) {
    double remaining = k->H - k->tau, n;
    if (k->h > k->cap) k->h = k->cap;
    k->shortened = true; /* a step other than h: known here, not from h_try < h, which rounding decides */
    if (k->h >= remaining - rb_time_slack(remaining, k->t + k->tau)) {
        k->tau_next = k->H;
    } else if (SPREAD * k->h >= remaining) {
        n = rb_steps_in(remaining, k->h, k->t + k->tau);
        k->tau_next = k->tau + remaining / n;
    } else {
        k->tau_next = k->tau + k->h;
        k->shortened = false;
    }
    /* the step is the exact difference of the two times (Sterbenz), so the steps add up to
     * H exactly: a rounding of tau per step would otherwise shift the time the body
     * turns for by N ulps, an attitude error of W times that at a fast spin W */
    k->h_try = k->tau_next - k->tau;
}

/* The attempt's target, tolerance h_try, or the estimate's floor where that is below it:
 * 1/target^2 before the step, so that the division overlaps with it. */
static inline void aim(Control *k) {
    if (k->tol * k->h_try > RB_ESTIMATE_FLOOR) {
        k->inv_target2 = 1.0 / (k->tol * k->h_try * (k->tol * k->h_try));
        k->e_step = k->e_target;
    } else {
        k->inv_target2 = 1.0 / (RB_ESTIMATE_FLOOR * RB_ESTIMATE_FLOOR);
        k->e_step = k->e_floor;
    }
}

/* An estimate above the target that a smaller step would not reduce: the Newton solve's noise,
 * or round-off that the retry of a rejected step shows. A cold path: an ordinary step is
 * within the target at the first test. */
static Estimate classify_above(Instance *c, Control *k) {
    double est = k->est, err = k->err, h = k->h_try, raised;
    if (err > 0 && est <= NEWTON_NOISE * NEWTON_NOISE * err * err) {
        k->rho2 = est / (NEWTON_NOISE * NEWTON_NOISE * err * err); /* proposals grow from it as from the floor */
        k->e_step = k->e_floor;
        if (sqrt(est) / h > k->noise_held) k->noise_held = sqrt(est) / h;
        return ESTIMATE_NEWTON_NOISE;
    }
    if (k->first_h > 0 && (raised = roundoff_tolerance(est, k->tol, h, k->first2, k->first_h, k->q)) > 0) {
        k->tol = raised;
        c->persistent.buf[RB_OFF_L + RB_REPORT_TOL_FLOOR] = raised;
        k->rho2 = est / (k->tol * h * (k->tol * h)); /* ROUNDOFF_MARGIN^-2 */
        k->e_step = k->e_target;
        k->because = HELD_AT_ROUNDOFF;
        return ESTIMATE_ROUNDOFF;
    }
    return k->rho2 == k->rho2 ? ESTIMATE_ABOVE : ESTIMATE_FAILED;
}

/* Classify the estimate: rho2 = est / target^2 <= 1 accepts. rho2 <= 1 is false for NaN: a
 * non-finite stage makes est NaN or infinite (est is a sum of squares over positive scales; a
 * non-finite k_next, which not every estimate reads, is the next step's k1 and makes that
 * step's estimate non-finite), so the state itself is checked only every 64 accepted steps
 * and at the end, as in fixed stepping (a check of every state is a tenth of the overhead of
 * error control on an RK4 step, docs/theory.md §5.5). */
static inline Estimate classify(Instance *c, Control *k) {
    k->rho2 = k->est * k->inv_target2;
    if (k->rho2 <= 1.0 && k->err <= RB_NEWTON_ACCEPT) return ESTIMATE_WITHIN;
    if (!(k->err <= RB_NEWTON_ACCEPT)) return ESTIMATE_FAILED;
    return classify_above(c, k);
}

/* Accept the attempt: its state and compensation become the current ones (ping-pong: not
 * copied), the time advances, and the next step is proposed. False when the state, checked
 * every 64 accepted steps, overflowed. */
static inline bool accept(Instance *c, Control *k) {
    double *swap, *report = c->persistent.buf + RB_OFF_L;
    Proposal now;
    swap = k->xa, k->xa = k->xb, k->xb = swap;
    swap = k->ca, k->ca = k->cb, k->cb = swap; /* the compensation goes with the state */
    k->cur = !k->cur;
    k->tau = k->tau_next;
    rb_inputs_accept(c);
    k->accepted++;
    /* a step at the floor (tolerance h below it for the step proposed, not only for one
     * shortened to land): the tolerance held rises to floor / h and stays (docs/theory.md
     * §5.5), so that later steps target tolerance h again instead of the floor, which
     * round-off ~h fits under at ever smaller steps */
    if (k->e_step == k->e_floor && k->tol * k->h <= RB_ESTIMATE_FLOOR) {
        k->tol = RB_ESTIMATE_FLOOR / k->h;
        report[RB_REPORT_TOL_FLOOR] = k->tol;
        k->because = HELD_AT_STEP_FLOOR;
        k->h_floor = k->h;
    }
    if ((k->accepted & 63) == 0 && !rb_all_finite(k->xa)) return false;
    report[RB_REPORT_H_LAST] = k->h_try;
    /* the proposal from this step's estimate sizes the step after next; the next takes the
     * previous step's (its own after a rejection or at a doStep's first step). The previous
     * proposal is computed here, from inputs long known: were this step's power computed
     * here, its chain of ~50 cycles after the estimate would hold up the retirement of the
     * next step (14 % of an RK4 step on sleeping_top; docs/theory.md §5.5) */
    now = (Proposal){k->rho2, k->e_step, k->h_try, k->h, k->grow, k->shortened};
    if (k->lagged) /* a branch, not a select: a select would make the power wait for this estimate */
        k->h = propose(&k->last);
    else
        k->h = propose(&now);
    k->last = now;
    k->lagged = true;
    k->grow = true;
    k->first_h = 0.0;
    return true;
}

/* Reject the attempt: it is redone from its start state with a smaller step (by the estimate,
 * or FAC_FAIL after a failure), which does not grow right after. */
static inline void reject(Control *k, Estimate estimate) {
    double fac;
    bool finite = estimate == ESTIMATE_ABOVE; /* a finite estimate above the target */
    k->rejected++;
    if (finite && !(k->first_h > 0)) { /* the step's first rejection: what a retry is compared with */
        k->first2 = k->est / (k->tol * k->h_try * (k->tol * k->h_try));
        k->first_h = k->h_try;
    }
    fac = finite ? SAFETY * step_power(k->rho2, k->e_step) : FAC_FAIL;
    k->h = k->h_try * (fac < FAC_MIN ? FAC_MIN : (fac > SAFETY ? SAFETY : fac));
    k->grow = false;
    k->lagged = false;
}

/* The controller: attempts until the span is done, or a step below h_min or beyond the
 * budget is needed (out_of_budget), or the state overflowed. */
static RbStatus control(Instance *c, const char *fn, Control *k, bool *out_of_budget) {
    RbStepScratch *s = &c->step;
    Estimate estimate;
    double est; /* a local, not k->est: k's address stays in this file, and k in registers */
    while (k->tau < k->H) {
        land_or_spread(k);
        if (k->h_try < k->h_min) return too_small(c, fn, k->t, k->tau, k->h_min, k->tol_set);
        if (k->tried == k->left) {
            *out_of_budget = true;
            return RB_ERROR;
        }
        rb_inputs_for(c, k->t, k->tau, k->h_try);
        aim(k);
        k->err = rb_call_step(c, true, k->xa, s->k[k->cur], k->h_try, k->xb, s->k[!k->cur], k->ca, k->cb, &est);
        k->est = est;
        k->tried++;
        estimate = classify(c, k);
        if (estimate <= ESTIMATE_ROUNDOFF) {
            if (!accept(c, k)) return overflow(c, fn, k->t, k->tau);
        } else {
            reject(k, estimate);
        }
    }
    return RB_OK;
}

RbStatus rb_step_controlled(Instance *c, const char *fn, double t, double H, RbBudget *budget) {
    RbStepScratch *s = &c->step;
    double *buf = c->persistent.buf, *x = buf + RB_OFF_X, *report = buf + RB_OFF_L;
    double h_max = buf[RB_VR_HMAX], rate[2] = {0, 0}, n, stab = INFINITY, held, q;
    int method = c->persistent.method;
    bool out_of_budget = false;
    RbStatus status;
    /* a designated initializer (the rest 0), not a memset: k's address is never taken, so
     * that the compiler keeps its fields in registers over the loop */
    Control k = {.t = t, .H = H, .cap = h_max > 0 ? h_max : INFINITY, .h_min = 16.0 * DBL_EPSILON * (fabs(t) + H),
                 .q = rb_method_estimate_order[method], .tol_set = buf[RB_VR_TOLERANCE], .because = HELD_AS_SET,
                 .grow = true, .xa = x, .xb = s->x_next, .ca = s->comp, .cb = s->comp_next};
    /* the tolerance held: the one set, or the round-off the estimate showed earlier in the run */
    k.tol = k.tol_set > report[RB_REPORT_TOL_FLOOR] ? k.tol_set : report[RB_REPORT_TOL_FLOOR];
    q = (double)k.q;
    /* the controller's exponents on rho^2 = est / target^2, once */
    k.e_target = -0.5 / q;
    k.e_floor = -0.5 / (q + 1.0);
    rb_eval_rate(c, x, rate);
    if (isfinite(rb_method_rate_limit[method]) && rate[0] > 0) stab = rb_method_rate_limit[method] / rate[0];
    if (stab < k.cap) k.cap = stab; /* explicit methods: inside the stability interval, like fixed steps */
    n = rb_steps_in(H, k.cap, t); /* the cap alone needs this many steps: refuse at once if too many */
    if (!rb_budget_allows(budget, c, n)) {
        refuse(c, fn, budget, t, H, 0.0, H / n, 0, 0, n);
        return RB_ERROR;
    }
    k.h = report[RB_REPORT_H_NEXT];
    if (!(k.h > 0) || !isfinite(k.h)) k.h = first_step(c, H, k.cap, rate, q);
    k.left = rb_budget_steps_left(budget, c);
    status = control(c, fn, &k, &out_of_budget);
    if (status == RB_OK && !rb_all_finite(k.xa)) status = overflow(c, fn, t, k.tau);
    rb_budget_charge(budget, c, k.tried);
    if (k.xa != x) memcpy(x, k.xa, sizeof s->x_next);
    if (k.ca != s->comp) memcpy(s->comp, k.ca, sizeof s->comp);
    if (status != RB_OK) {
        if (out_of_budget) refuse(c, fn, budget, t, H, k.tau, k.h_try, k.accepted, k.rejected, 1.0);
        return status;
    }
    if (k.lagged) k.h = propose(&k.last); /* the newest proposal starts the next doStep */
    if (k.cur) memcpy(s->k[0], s->k[1], sizeof s->k[0]);
    s->last_substeps = k.accepted;
    report[RB_REPORT_STEPS] = (double)k.accepted;
    report[RB_REPORT_REJECTED] = (double)k.rejected;
    report[RB_REPORT_H_NEXT] = k.h < k.cap ? k.h : k.cap;
    held = k.noise_held > k.tol ? k.noise_held : k.tol;
    report[RB_REPORT_TOL_EFFECTIVE] = held;
    report_floor(c, fn, t, k.tol_set, held, k.noise_held > k.tol ? HELD_AT_NEWTON_NOISE : k.because, k.h_floor);
    return RB_OK;
}
