/* A Co-Simulation doStep of the FMU core: its checks, start and end, and the choice of fixed or controlled steps.
 * Hand-written and model-agnostic. The steps themselves are fixed ones (rbfmu_step.c,
 * docs/theory.md §5.4) or, with tolerance > 0 and a method that has an error estimate, the
 * error control's (rbfmu_control.c, docs/theory.md §5.5). A doStep that fails leaves the
 * state, time and inputs at its start. */
#include "rbfmu_core.h"

#include <math.h>
#include <string.h>

RbStatus rb_do_step(Instance *c, const char *fn, double t, double H) {
    RbStepScratch *s = &c->step;
    double *buf = c->persistent.buf, *x = buf + RB_OFF_X, tol, tolerance = buf[RB_VR_TOLERANCE];
    RbStatus status;
    bool controlled;
    RbBudget budget;
    if (!(H > 0) || !isfinite(H)) {
        RB_ERR(c, "%s: communicationStepSize must be finite and > 0, got %g", fn, H);
        return RB_ERROR;
    }
    tol = 1e-10 * (fabs(buf[0]) > 1.0 ? fabs(buf[0]) : 1.0);
    if (!(fabs(t - buf[0]) <= tol)) {
        RB_ERR(c, "%s: currentCommunicationPoint %.17g is not the FMU's current time %.17g", fn, t, buf[0]);
        return RB_ERROR;
    }
    if (!isfinite(t + H) || !(t + H > t)) { /* time must stay finite and advance */
        RB_ERR(c, "%s: currentCommunicationPoint %.17g + communicationStepSize %.17g = %.17g: %s", fn, t, H, t + H,
               isfinite(t + H) ? "the step is below the resolution of the time, it would not advance"
                               : "the time overflows");
        return RB_ERROR;
    }
    memcpy(s->x_start, x, sizeof s->x_start);
    rb_budget_start(&budget, c);
    controlled = tolerance > 0 && rb_method_estimate_order[c->persistent.method] > 0;
    rb_inputs_begin(c, controlled);
    rb_bind_step(c);
    memset(s->comp, 0, sizeof s->comp); /* a doStep starts from its state as stored: reproducible */
    buf[RB_OFF_L + RB_REPORT_STEPS] = 0.0;
    buf[RB_OFF_L + RB_REPORT_REJECTED] = 0.0;
    buf[RB_OFF_L + RB_REPORT_TOL_EFFECTIVE] = 0.0; /* fixed stepping holds no tolerance */
    if (controlled) {
        rb_compute_derivatives(c, s->k[0]); /* f at the start: the first step's k1 */
        status = rb_step_controlled(c, fn, t, H, &budget);
    } else /* k1 with the start rate (rbfmu_step.c, start_rate) */
        status = rb_step_fixed(c, fn, t, H, &budget);
    if (status != RB_OK) {
        memcpy(x, s->x_start, sizeof s->x_start);
        rb_inputs_end(c, H, false);
        return status;
    }
    /* the outputs are not computed here: every Get of an output computes them at the state
     * it reads and refuses a non-finite one (rb_get_reals; docs/fmi_layer.md, Outputs) */
    rb_inputs_end(c, H, true);
    buf[0] = t + H;
    return RB_OK;
}
