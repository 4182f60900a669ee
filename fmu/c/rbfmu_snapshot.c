/* FMU state snapshots of the FMU core: get, set, free, serialize, deserialize (docs/fmi_layer.md).
 *
 * Snapshots live on the heap, allocated outside doStep. Each belongs to the instance that
 * made it, which keeps them in a list: a pointer the importer hands back is looked up
 * there by address before it is used, never dereferenced on trust, and FreeInstance frees
 * what is left. A state's values, whether set or deserialized, pass the checks of values
 * set through the API (state_passes_checks). A snapshot is the instance's persistent group
 * (RbPersistent, rbfmu_core.h), copied whole, with the interface it was taken from: what the
 * group holds is what a state keeps. The serialized form is written field by field,
 * little-endian, and ends with a CRC-32 of everything before it:
 *   instantiation token (with its NUL) | u32 format | u32 interface type | u32 instance
 *   state | i64 method (enumeration value) | u32 count n | n x f64 values (time, states,
 *   inputs, parameters, step report) | u32 CRC-32 (IEEE 802.3, the CRC of zlib and PNG) */
#include "rbfmu_core.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define RB_STATE_FORMAT 1u
#define RB_NSAVED RB_OFF_Y /* outputs and derivatives are not saved: they are computed when read. The step
                            * report is, since the error control's next step (h_next) decides the next doStep */
#define RB_TOKEN_BYTES sizeof(RB_INSTANTIATION_TOKEN)
#define RB_SERIALIZED_BYTES (RB_TOKEN_BYTES + 4 + 4 + 4 + 8 + 4 + 8 * (size_t)RB_NSAVED + 4)

struct RbState {
    struct RbState *next; /* the owning instance's list */
    InterfaceType type;   /* the interface the snapshot was taken from */
    RbPersistent kept;    /* the instance state, the method (index into this build's table), the values */
};

/* The instance states a snapshot can hold, per interface: those GetFMUState is allowed in
 * (rbfmu_fmi3.c, rbfmu_fmi2.c) that the interface reaches. */
static const unsigned rb_snapshot_states[] = {
    [RB_CO_SIMULATION] = M_INIT | M_STEP | M_TERM | M_ERR,
    [RB_MODEL_EXCHANGE] = M_INIT | M_EVENT | M_CONT | M_TERM | M_ERR,
};

static const char *type_name(long long type) { return type == RB_MODEL_EXCHANGE ? "Model Exchange" : "Co-Simulation"; }

/* `state` if it is a live state of this instance, else NULL: found by its address only. */
static struct RbState *owned(const Instance *c, const void *state) {
    struct RbState *s;
    for (s = c->snapshots; s; s = s->next)
        if ((const void *)s == state) return s;
    return NULL;
}

static RbStatus refuse_foreign(const Instance *c, const char *fn, const void *state) {
    RB_ERR(c, "%s: FMUState %p is not a live FMU state of this instance (one that its GetFMUState or "
              "DeserializeFMUState returned and FreeFMUState has not freed); a state moves between instances "
              "by SerializeFMUState and DeserializeFMUState", fn, state);
    return RB_ERROR;
}

/* rb_state_enters for state x with the saved values v (parameters, inputs) and method: the
 * instance takes them for the check and gets its own back. */
static bool enters_with(Instance *c, const char *fn, const double *x, const double *v, int method) {
    double own[RB_NV], xs[RB_NX];
    int own_method = c->persistent.method;
    bool ok;
    memcpy(xs, x, sizeof xs); /* x may be scratch that the check reuses */
    memcpy(own, c->persistent.buf, sizeof own);
    memcpy(c->persistent.buf, v, sizeof own);
    rb_select_method(c, method);
    rb_refresh_derived(c);
    ok = rb_state_enters(c, fn, xs);
    memcpy(c->persistent.buf, own, sizeof own);
    rb_select_method(c, own_method);
    rb_refresh_derived(c);
    return ok;
}

/* The checks a state's content must pass, as if it had been set through the API: a known
 * interface, the instance's own; an instance state this interface can be saved in; a
 * compiled method; finite values; and once initialised (not in InitializationMode or
 * Error), the generated validity checks of exitInitializationMode, with a Model Exchange
 * quaternion normalised first (the importer's solver may let |q| drift; the outputs use
 * q/|q|, docs/fmi_layer.md). Else logs why. */
static bool state_passes_checks(Instance *c, const char *fn, long long type, long long state, int method,
                                const double *v) {
    int i;
    const double *x = v + RB_OFF_X;
    if (type != RB_CO_SIMULATION && type != RB_MODEL_EXCHANGE) {
        RB_ERR(c, "%s: the FMU state has interface type %lld, neither Co-Simulation (%d) nor Model Exchange (%d)",
               fn, type, RB_CO_SIMULATION, RB_MODEL_EXCHANGE);
        return false;
    }
    if (type != (long long)c->importer.type) {
        RB_ERR(c, "%s: the FMU state was taken from a %s instance; this one is %s", fn, type_name(type),
               type_name(c->importer.type));
        return false;
    }
    if (state < 0 || state > ST_ERROR || !(rb_snapshot_states[type] & (1u << state))) {
        RB_ERR(c, "%s: the FMU state holds instance state %lld (%s), which a %s instance is never saved in", fn,
               state, state >= 0 && state <= ST_ERROR ? rb_state_names[state] : "unknown", type_name(type));
        return false;
    }
    if (method < 0 || method >= RB_NMETHODS) {
        RB_ERR(c, "%s: the FMU state holds method index %d; this FMU has %d methods", fn, method, RB_NMETHODS);
        return false;
    }
    for (i = 0; i < RB_NSAVED; i++) {
        if (!isfinite(v[i])) {
            RB_ERR(c, "%s: the FMU state's '%s' (vr %d) must be finite, got %g", fn, rb_names[i], i, v[i]);
            return false;
        }
    }
    if (state == ST_INITIALIZATION || state == ST_ERROR) return true; /* not checked yet, or failed the checks */
    if (type == RB_MODEL_EXCHANGE) {
        rb_project(c, x, c->step.x_next);
        x = c->step.x_next;
    }
    if (!enters_with(c, fn, x, v, method)) {
        RB_ERR(c, "%s: the FMU state (in %s) fails the checks a running instance passes", fn, rb_state_names[state]);
        return false;
    }
    return true;
}

/* A kept group passes state_passes_checks. */
static bool kept_passes_checks(Instance *c, const char *fn, InterfaceType type, const RbPersistent *kept) {
    return state_passes_checks(c, fn, type, kept->state, kept->method, kept->buf);
}

/* A state to write into: *state if it is one of ours, a new one (in the list) if NULL. */
static struct RbState *target(Instance *c, const char *fn, void **state) {
    struct RbState *s;
    if (!state) {
        RB_ERR(c, "%s: FMUState pointer is NULL", fn);
        return NULL;
    }
    if (*state) {
        s = owned(c, *state);
        if (!s) refuse_foreign(c, fn, *state);
        return s;
    }
    s = (struct RbState *)calloc(1, sizeof *s);
    if (!s) {
        RB_ERR(c, "%s: out of memory", fn);
        return NULL;
    }
    s->next = c->snapshots;
    c->snapshots = s;
    *state = s;
    return s;
}

RbStatus rb_state_get(Instance *c, const char *fn, void **state) {
    struct RbState *s = target(c, fn, state);
    if (!s) return RB_ERROR;
    s->type = c->importer.type;
    s->kept = c->persistent;
    return RB_OK;
}

RbStatus rb_state_set(Instance *c, const char *fn, const void *state) {
    const struct RbState *s = owned(c, state);
    if (!s) return refuse_foreign(c, fn, state);
    if (!kept_passes_checks(c, fn, s->type, &s->kept)) return RB_ERROR;
    c->persistent = s->kept;
    rb_select_method(c, c->persistent.method);
    memset(c->inputs.du, 0, sizeof c->inputs.du); /* input derivatives belong to the doStep they were set for */
    c->inputs.du_set = false;
    rb_refresh_derived(c);
    return RB_OK;
}

RbStatus rb_state_free(Instance *c, const char *fn, void **state) {
    struct RbState **p;
    if (!state || !*state) return RB_OK; /* nothing to free */
    for (p = &c->snapshots; *p; p = &(*p)->next) {
        if ((void *)*p == *state) {
            struct RbState *s = *p;
            *p = s->next;
            free(s);
            *state = NULL;
            return RB_OK;
        }
    }
    return refuse_foreign(c, fn, *state);
}

void rb_state_free_all(Instance *c) {
    struct RbState *s = c->snapshots, *next;
    for (; s; s = next) {
        next = s->next;
        free(s);
    }
    c->snapshots = NULL;
}

RbStatus rb_state_size(Instance *c, const char *fn, const void *state, size_t *size) {
    if (!owned(c, state)) return refuse_foreign(c, fn, state);
    return rb_put_count(c, fn, size, RB_SERIALIZED_BYTES);
}

/* ---- the serialized form: little-endian fields, then the CRC ---- */

static unsigned char *put(unsigned char *p, unsigned long long v, int bytes) {
    int i;
    for (i = 0; i < bytes; i++) p[i] = (unsigned char)(v >> (8 * i));
    return p + bytes;
}

static const unsigned char *get(const unsigned char *p, unsigned long long *v, int bytes) {
    int i;
    *v = 0;
    for (i = 0; i < bytes; i++) *v |= (unsigned long long)p[i] << (8 * i);
    return p + bytes;
}

/* CRC-32 of IEEE 802.3 (reflected polynomial 0xEDB88320; zlib's crc32): every error of
 * up to three bits in a serialized state is detected. */
static unsigned long crc32_ieee(const unsigned char *p, size_t n) {
    unsigned long crc = 0xFFFFFFFFul;
    size_t i;
    int k;
    for (i = 0; i < n; i++) {
        crc ^= p[i];
        for (k = 0; k < 8; k++) crc = (crc >> 1) ^ (0xEDB88320ul & (0ul - (crc & 1ul)));
    }
    return (crc ^ 0xFFFFFFFFul) & 0xFFFFFFFFul;
}

RbStatus rb_state_serialize(Instance *c, const char *fn, const void *state, unsigned char *out, size_t size) {
    const struct RbState *s = owned(c, state);
    unsigned char *p = out;
    unsigned long long bits;
    int i;
    if (!s) return refuse_foreign(c, fn, state);
    if (size != RB_SERIALIZED_BYTES || !out) {
        RB_ERR(c, "%s: buffer of %zu bytes%s, the serialized state has %zu", fn, size, out ? "" : " (NULL)",
               (size_t)RB_SERIALIZED_BYTES);
        return RB_ERROR;
    }
    memcpy(p, RB_INSTANTIATION_TOKEN, RB_TOKEN_BYTES); /* the token first: only the same build reads it */
    p += RB_TOKEN_BYTES;
    p = put(p, RB_STATE_FORMAT, 4);
    p = put(p, (unsigned long long)s->type, 4);
    p = put(p, (unsigned long long)s->kept.state, 4);
    p = put(p, (unsigned long long)rb_method_values[s->kept.method], 8);
    p = put(p, RB_NSAVED, 4);
    for (i = 0; i < RB_NSAVED; i++) {
        memcpy(&bits, &s->kept.buf[i], sizeof bits);
        p = put(p, bits, 8);
    }
    put(p, crc32_ieee(out, (size_t)(p - out)), 4);
    return RB_OK;
}

RbStatus rb_state_deserialize(Instance *c, const char *fn, const unsigned char *in, size_t size, void **state) {
    const unsigned char *p;
    unsigned long long format, type, st, method, n, crc, bits;
    RbPersistent kept;
    int i, index = -1;
    struct RbState *s;
    if (!in || size != RB_SERIALIZED_BYTES || memcmp(in, RB_INSTANTIATION_TOKEN, RB_TOKEN_BYTES) != 0) {
        RB_ERR(c, "%s: %zu bytes%s are not a serialized state of this FMU build (expected %zu bytes starting "
                  "with its instantiation token)", fn, size, in ? "" : " (NULL)", (size_t)RB_SERIALIZED_BYTES);
        return RB_ERROR;
    }
    get(in + RB_SERIALIZED_BYTES - 4, &crc, 4);
    if (crc != crc32_ieee(in, RB_SERIALIZED_BYTES - 4)) {
        RB_ERR(c, "%s: the serialized state is corrupted: its CRC-32 is %08llx, its content's %08lx", fn, crc,
               crc32_ieee(in, RB_SERIALIZED_BYTES - 4));
        return RB_ERROR;
    }
    p = get(in + RB_TOKEN_BYTES, &format, 4);
    p = get(p, &type, 4);
    p = get(p, &st, 4);
    p = get(p, &method, 8);
    p = get(p, &n, 4);
    if (format != RB_STATE_FORMAT || n != RB_NSAVED) {
        RB_ERR(c, "%s: serialized state format %llu with %llu values; this FMU reads format %u with %d", fn, format,
               n, RB_STATE_FORMAT, RB_NSAVED);
        return RB_ERROR;
    }
    memset(&kept, 0, sizeof kept); /* the outputs and derivatives: computed when read */
    for (i = 0; i < RB_NSAVED; i++) {
        p = get(p, &bits, 8);
        memcpy(&kept.buf[i], &bits, sizeof bits);
    }
    for (i = 0; i < RB_NMETHODS; i++)
        if ((unsigned long long)rb_method_values[i] == method) index = i;
    if (index < 0) {
        RB_ERR(c, "%s: the serialized state's method %lld is not compiled into this FMU", fn, (long long)method);
        return RB_ERROR;
    }
    if (!state_passes_checks(c, fn, (long long)type, (long long)st, index, kept.buf)) return RB_ERROR;
    s = target(c, fn, state);
    if (!s) return RB_ERROR;
    kept.state = (InstanceState)st;
    kept.method = index;
    s->type = (InterfaceType)type;
    s->kept = kept;
    return RB_OK;
}
