/* The work budget of one doStep: internal steps weighted by each method's cost, against the tunable work_limit.
 *
 * Work is counted in right-hand-side evaluations: an internal step of the current method
 * costs rb_method_cost[method] of them (modelsrc/methods.py, the one table of the costs).
 * A count, not a clock: whether a doStep is refused must not depend on the machine or its
 * load. Every attempt counts, a rejected one included, so retries cannot multiply the
 * bound. A step controller (rbfmu_step.c, rbfmu_control.c) starts a budget per doStep, asks before every
 * batch of internal steps and refuses before doing any of it when the batch would exceed
 * the limit, then charges the steps it actually took (docs/fmi_layer.md, Work limit). */
#include "rbfmu_core.h"

#include <limits.h>
#include <math.h>

void rb_budget_start(RbBudget *b, Instance *c) {
    b->limit = c->persistent.buf[RB_VR_WORK_LIMIT];
    b->used = 0.0;
    c->step.last_work = 0.0;
}

/* Also false for a NaN count, and for more steps than a long counts (the loop counter). */
bool rb_budget_allows(const RbBudget *b, const Instance *c, double steps) {
    return steps <= (double)(LONG_MAX / 2) && b->used + steps * rb_method_cost[c->persistent.method] <= b->limit;
}

void rb_budget_refuse(const Instance *c, const char *fn, const RbBudget *b, double steps, const char *context) {
    int method = c->persistent.method;
    double cost = rb_method_cost[method];
    if (b->used + steps * cost <= b->limit) { /* within work_limit, but beyond the loop's counter */
        RB_ERR(c, "%s: %s needs %.4g internal steps of method %s, more than one doStep can count (%ld); shorten "
                  "the communication step or raise h_max", fn, context, steps, rb_method_names[method],
               LONG_MAX / 2);
        return;
    }
    RB_ERR(c, "%s: %s needs %.4g internal steps of method %s at %g right-hand-side evaluations each: %.4g "
              "evaluations%s, more than work_limit = %.6g; raise the tunable parameter work_limit, shorten the "
              "communication step or raise h_max",
           fn, context, steps, rb_method_names[method], cost, b->used + steps * cost,
           b->used > 0 ? " with those this doStep already spent" : "", b->limit);
}

/* How many more internal steps the budget admits: the error control counts them down
 * locally instead of asking before each one (rbfmu_control.c). */
long rb_budget_steps_left(const RbBudget *b, const Instance *c) {
    int i;
    double k = floor((b->limit - b->used) / rb_method_cost[c->persistent.method]);
    if (!(k > 0)) return 0;
    if (k > (double)(LONG_MAX / 2)) k = (double)(LONG_MAX / 2);
    /* The division may round k up by one unit of its last place, so k may need lowering
     * once or twice; a bounded loop: work_limit <= WORK_LIMIT_MAX (modelsrc/methods.py, a generated check)
     * keeps k below 2^53, where k - 1 is exact, and an unchecked huge limit still
     * terminates (docs/fmi_layer.md, Work limit). */
    for (i = 0; i < 4 && k > 0 && !rb_budget_allows(b, c, k); i++) k -= 1.0;
    return k > 0 && rb_budget_allows(b, c, k) ? (long)k : 0;
}

void rb_budget_charge(RbBudget *b, Instance *c, long steps) {
    b->used += (double)steps * rb_method_cost[c->persistent.method];
    c->step.last_work = b->used;
}
