/* FMU state snapshots of the FMU core: get, set, free, serialize, deserialize (docs/fmi_layer.md).
 * Snapshots live on the heap, allocated outside doStep. */
#include "rbfmu_core.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>


#define RB_STATE_MAGIC 0x52424653u /* "RBFS" */

struct RbState {
    unsigned magic;
    unsigned nv;
    int type; /* the interface the snapshot was taken from */
    int state;
    int method;
    double buf[RB_NV];
};

size_t rb_state_size(void) { return sizeof(struct RbState) + sizeof(RB_INSTANTIATION_TOKEN); }

int rb_state_get(Instance *c, const char *fn, void **state) {
    struct RbState *s;
    if (!state) {
        RB_ERR(c, "%s: FMUState pointer is NULL", fn);
        return RB_ERROR;
    }
    s = (struct RbState *)(*state ? *state : malloc(sizeof(struct RbState)));
    if (!s) {
        RB_ERR(c, "%s: out of memory", fn);
        return RB_ERROR;
    }
    s->magic = RB_STATE_MAGIC;
    s->nv = RB_NV;
    s->type = (int)c->type;
    s->state = (int)c->state;
    s->method = c->method;
    memcpy(s->buf, c->buf, sizeof s->buf);
    *state = s;
    return RB_OK;
}

static int valid_state(const Instance *c, const char *fn, const struct RbState *s) {
    if (!s || s->magic != RB_STATE_MAGIC || s->nv != RB_NV || s->method < 0 || s->method >= RB_NMETHODS ||
        s->state < ST_INSTANTIATED || s->state > ST_ERROR) {
        RB_ERR(c, "%s: not an FMU state of this FMU", fn);
        return 0;
    }
    return 1;
}

int rb_state_set(Instance *c, const char *fn, const void *state) {
    const struct RbState *s = (const struct RbState *)state;
    if (!valid_state(c, fn, s)) return RB_ERROR;
    if (s->type != (int)c->type) {
        RB_ERR(c, "%s: the FMU state was taken from a %s instance; this one is %s", fn,
               s->type == RB_MODEL_EXCHANGE ? "Model Exchange" : "Co-Simulation",
               c->type == RB_MODEL_EXCHANGE ? "Model Exchange" : "Co-Simulation");
        return RB_ERROR;
    }
    c->state = (InstanceState)s->state;
    rb_select_method(c, s->method);
    memcpy(c->buf, s->buf, sizeof c->buf);
    return RB_OK;
}

int rb_state_free(Instance *c, const char *fn, void **state) {
    UNUSED(c);
    UNUSED(fn);
    if (state && *state) {
        free(*state);
        *state = NULL;
    }
    return RB_OK;
}

int rb_state_serialize(Instance *c, const char *fn, const void *state, unsigned char *out, size_t size) {
    if (!valid_state(c, fn, (const struct RbState *)state)) return RB_ERROR;
    if (size != rb_state_size() || !out) {
        RB_ERR(c, "%s: buffer of %zu bytes, the serialized state has %zu", fn, size, rb_state_size());
        return RB_ERROR;
    }
    /* the token first: a state only deserializes into the same build */
    memcpy(out, RB_INSTANTIATION_TOKEN, sizeof(RB_INSTANTIATION_TOKEN));
    memcpy(out + sizeof(RB_INSTANTIATION_TOKEN), state, sizeof(struct RbState));
    return RB_OK;
}

int rb_state_deserialize(Instance *c, const char *fn, const unsigned char *in, size_t size, void **state) {
    struct RbState tmp;
    if (!in || !state || size != rb_state_size() ||
        memcmp(in, RB_INSTANTIATION_TOKEN, sizeof(RB_INSTANTIATION_TOKEN)) != 0) {
        RB_ERR(c, "%s: %zu bytes are not a serialized state of this FMU build (expected %zu bytes starting "
                  "with its instantiation token)", fn, size, rb_state_size());
        return RB_ERROR;
    }
    memcpy(&tmp, in + sizeof(RB_INSTANTIATION_TOKEN), sizeof tmp);
    if (!valid_state(c, fn, &tmp)) return RB_ERROR;
    if (!*state) *state = malloc(sizeof(struct RbState));
    if (!*state) {
        RB_ERR(c, "%s: out of memory", fn);
        return RB_ERROR;
    }
    memcpy(*state, &tmp, sizeof tmp);
    return RB_OK;
}
