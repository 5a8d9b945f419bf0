/*
 * A small FMI 2.0 co-simulation FMU written independently of fmi-abi, to test the fuzzer
 * itself: built as it is, it follows the standard's state table strictly and must pass the
 * fuzzer (no false alarms); built with one of the FAULT_* macros it has one deliberate bug
 * that the fuzzer must report with the seed that shows it.
 *
 *   FAULT_SEGV     fmi2GetReal writes through a NULL value array (segmentation fault)
 *   FAULT_HANG     fmi2DoStep with a step above 1e6 s never returns
 *   FAULT_LENIENT  fmi2DoStep is accepted in the instantiated state
 *   FAULT_SILENT   errors are returned without a logged message
 *   FAULT_LEAK     fmi2FreeFMUstate forgets to free the state (for the valgrind test)
 *
 * Model: dx/dt = -k x + g u (explicit Euler per communication step), y = x, n = steps taken.
 * Variables (vr): Real u=0 input, y=1 output, k=2 fixed parameter, g=3 tunable parameter;
 * Integer n=0 output, mode=1 tunable parameter; Boolean flag=0 tunable parameter;
 * String label=0 fixed parameter.
 */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef void *fmi2Component;
typedef void *fmi2ComponentEnvironment;
typedef void *fmi2FMUstate;
typedef unsigned int fmi2ValueReference;
typedef double fmi2Real;
typedef int fmi2Integer;
typedef int fmi2Boolean;
typedef char fmi2Char;
typedef const fmi2Char *fmi2String;
typedef char fmi2Byte;
typedef enum { fmi2OK, fmi2Warning, fmi2Discard, fmi2Error, fmi2Fatal, fmi2Pending } fmi2Status;
typedef enum { fmi2ModelExchange, fmi2CoSimulation } fmi2Type;
typedef enum {
    fmi2DoStepStatus,
    fmi2PendingStatus,
    fmi2LastSuccessfulTime,
    fmi2Terminated
} fmi2StatusKind;
typedef void (*fmi2CallbackLogger)(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String,
                                   fmi2String, ...);
typedef struct {
    fmi2CallbackLogger logger;
    void *(*allocateMemory)(size_t, size_t);
    void (*freeMemory)(void *);
    void (*stepFinished)(fmi2ComponentEnvironment, fmi2Status);
    fmi2ComponentEnvironment componentEnvironment;
} fmi2CallbackFunctions;

#define GUID "{fmi-fuzz-strict-0001}"
#define TAG 0x5354524943544655ULL   /* instance tag */
#define STAG 0x5354524943545354ULL  /* state tag */

enum {
    INSTANTIATED = 1,
    INIT = 2,
    STEP_COMPLETE = 4,
    STEP_FAILED = 8,
    TERMINATED = 16,
    ERROR = 32,
    FATAL = 64
};

typedef struct {
    int state;
    double time, x, u, k, g;
    int n, mode, flag;
    char *label;
} Data;

typedef struct {
    uint64_t tag;
    char *name;
    fmi2CallbackFunctions cb;
    int have_cb;
    int log_errors;
    Data d;
    char *strings_out;
} Inst;

typedef struct {
    uint64_t tag;
    Data d;
} State;

static Inst *inst(fmi2Component c) {
    Inst *i = (Inst *)c;
    return (i != NULL && i->tag == TAG) ? i : NULL;
}

static fmi2Status fail(Inst *i, const char *msg) {
#ifndef FAULT_SILENT
    if (i->have_cb && i->log_errors && i->cb.logger != NULL) {
        i->cb.logger(i->cb.componentEnvironment, i->name, fmi2Error, "logStatusError", "%s", msg);
    }
#else
    (void)msg;
#endif
    return fmi2Error;
}

static int allowed(Inst *i, int mask, const char *fn) {
    if (i->d.state & mask) {
        return 1;
    }
    fail(i, fn);
    return 0;
}

#define ALL_BUT_FATAL (INSTANTIATED | INIT | STEP_COMPLETE | STEP_FAILED | TERMINATED | ERROR)
#define GET_MASK (INIT | STEP_COMPLETE | STEP_FAILED | TERMINATED | ERROR)
#define SET_MASK (INSTANTIATED | INIT | STEP_COMPLETE)
#define STATUS_MASK (STEP_COMPLETE | STEP_FAILED | TERMINATED)

static char *dup(const char *s) {
    size_t n = strlen(s) + 1;
    char *p = malloc(n);
    memcpy(p, s, n);
    return p;
}

static void defaults(Data *d) {
    free(d->label);
    d->state = INSTANTIATED;
    d->time = 0;
    d->x = 1;
    d->u = 0;
    d->k = 1;
    d->g = 1;
    d->n = 0;
    d->mode = 0;
    d->flag = 0;
    d->label = dup("");
}

static void copy_data(Data *dst, const Data *src) {
    char *label = dup(src->label);
    free(dst->label);
    *dst = *src;
    dst->label = label;
}

const char *fmi2GetTypesPlatform(void) { return "default"; }
const char *fmi2GetVersion(void) { return "2.0"; }

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String res,
                              const fmi2CallbackFunctions *cb, fmi2Boolean visible,
                              fmi2Boolean loggingOn) {
    (void)res;
    (void)visible;
    (void)loggingOn;
    const char *why = NULL;
    if (type != fmi2CoSimulation) {
        why = "fmi2Instantiate: only co-simulation";
    } else if (guid == NULL || strcmp(guid, GUID) != 0) {
        why = "fmi2Instantiate: wrong GUID";
    }
    if (why != NULL) {
        if (cb != NULL && cb->logger != NULL) {
            cb->logger(cb->componentEnvironment, name ? name : "", fmi2Error, "logStatusError",
                       "%s", why);
        }
        return NULL;
    }
    Inst *i = calloc(1, sizeof *i);
    i->tag = TAG;
    i->name = dup(name ? name : "");
    if (cb != NULL) {
        i->cb = *cb;
        i->have_cb = 1;
    }
    i->log_errors = 1;
    defaults(&i->d);
    return i;
}

void fmi2FreeInstance(fmi2Component c) {
    Inst *i = inst(c);
    if (i == NULL) {
        return;
    }
    i->tag = 0;
    free(i->d.label);
    free(i->strings_out);
    free(i->name);
    free(i);
}

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cats[]) {
    Inst *i = inst(c);
    if (i == NULL) return fmi2Error;
    if (!allowed(i, ALL_BUT_FATAL, "fmi2SetDebugLogging: illegal state")) return fmi2Error;
    if (n > 0 && cats == NULL) return fail(i, "fmi2SetDebugLogging: categories NULL");
    if (n == 0) {
        i->log_errors = on != 0;
    }
    for (size_t k = 0; k < n; k++) {
        if (cats[k] != NULL && strcmp(cats[k], "logStatusError") == 0) {
            i->log_errors = on != 0;
        }
    }
    return fmi2OK;
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tolDefined, fmi2Real tol,
                               fmi2Real start, fmi2Boolean stopDefined, fmi2Real stop) {
    (void)tolDefined;
    (void)tol;
    Inst *i = inst(c);
    if (i == NULL) return fmi2Error;
    if (!allowed(i, INSTANTIATED, "fmi2SetupExperiment: illegal state")) return fmi2Error;
    if (!(start - start == 0)) return fail(i, "fmi2SetupExperiment: start not finite");
    if (stopDefined && !(stop >= start)) return fail(i, "fmi2SetupExperiment: stop < start");
    i->d.time = start;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    Inst *i = inst(c);
    if (i == NULL) return fmi2Error;
    if (!allowed(i, INSTANTIATED, "fmi2EnterInitializationMode: illegal state")) return fmi2Error;
    i->d.state = INIT;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    Inst *i = inst(c);
    if (i == NULL) return fmi2Error;
    if (!allowed(i, INIT, "fmi2ExitInitializationMode: illegal state")) return fmi2Error;
    i->d.state = STEP_COMPLETE;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c) {
    Inst *i = inst(c);
    if (i == NULL) return fmi2Error;
    if (!allowed(i, STEP_COMPLETE | STEP_FAILED, "fmi2Terminate: illegal state")) return fmi2Error;
    i->d.state = TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
    Inst *i = inst(c);
    if (i == NULL) return fmi2Error;
    if (!allowed(i, ALL_BUT_FATAL, "fmi2Reset: illegal state")) return fmi2Error;
    defaults(&i->d);
    return fmi2OK;
}

/* Real: 0 u (input), 1 y (output), 2 k (fixed), 3 g (tunable). */
static double *real_ref(Inst *i, fmi2ValueReference vr) {
    switch (vr) {
    case 0: return &i->d.u;
    case 1: return &i->d.x;
    case 2: return &i->d.k;
    case 3: return &i->d.g;
    default: return NULL;
    }
}

static int *int_ref(Inst *i, fmi2ValueReference vr) {
    switch (vr) {
    case 0: return &i->d.n;
    case 1: return &i->d.mode;
    default: return NULL;
    }
}

/* 0 input, 1 output, 2 fixed parameter, 3 tunable parameter */
static int settable(int kind, int state) {
    switch (state) {
    case INSTANTIATED: return kind != 1;
    case INIT: return kind != 1;
    case STEP_COMPLETE: return kind == 0 || kind == 3;
    default: return 0;
    }
}

static const int REAL_KIND[4] = {0, 1, 2, 3};
static const int INT_KIND[2] = {1, 3};

#define GET_PRELUDE(fn)                                                                    \
    Inst *i = inst(c);                                                                     \
    if (i == NULL) return fmi2Error;                                                       \
    if (!allowed(i, GET_MASK, fn ": illegal state")) return fmi2Error;                     \
    if (nvr > 0 && vr == NULL) return fail(i, fn ": vr NULL");

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real v[]) {
    GET_PRELUDE("fmi2GetReal")
#ifndef FAULT_SEGV
    if (nvr > 0 && v == NULL) return fail(i, "fmi2GetReal: value NULL");
#endif
    for (size_t k = 0; k < nvr; k++) {
        double *p = real_ref(i, vr[k]);
        if (p == NULL) return fail(i, "fmi2GetReal: unknown vr");
        v[k] = *p;
    }
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer v[]) {
    GET_PRELUDE("fmi2GetInteger")
    if (nvr > 0 && v == NULL) return fail(i, "fmi2GetInteger: value NULL");
    for (size_t k = 0; k < nvr; k++) {
        int *p = int_ref(i, vr[k]);
        if (p == NULL) return fail(i, "fmi2GetInteger: unknown vr");
        v[k] = *p;
    }
    return fmi2OK;
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean v[]) {
    GET_PRELUDE("fmi2GetBoolean")
    if (nvr > 0 && v == NULL) return fail(i, "fmi2GetBoolean: value NULL");
    for (size_t k = 0; k < nvr; k++) {
        if (vr[k] != 0) return fail(i, "fmi2GetBoolean: unknown vr");
        v[k] = i->d.flag;
    }
    return fmi2OK;
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String v[]) {
    GET_PRELUDE("fmi2GetString")
    if (nvr > 0 && v == NULL) return fail(i, "fmi2GetString: value NULL");
    for (size_t k = 0; k < nvr; k++) {
        if (vr[k] != 0) return fail(i, "fmi2GetString: unknown vr");
    }
    free(i->strings_out);
    i->strings_out = dup(i->d.label);
    for (size_t k = 0; k < nvr; k++) {
        v[k] = i->strings_out;
    }
    return fmi2OK;
}

#define SET_PRELUDE(fn)                                                                    \
    Inst *i = inst(c);                                                                     \
    if (i == NULL) return fmi2Error;                                                       \
    if (!allowed(i, SET_MASK, fn ": illegal state")) return fmi2Error;                     \
    if (nvr > 0 && (vr == NULL || v == NULL)) return fail(i, fn ": NULL array");

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real v[]) {
    SET_PRELUDE("fmi2SetReal")
    for (size_t k = 0; k < nvr; k++) {
        if (vr[k] > 3) return fail(i, "fmi2SetReal: unknown vr");
        if (!settable(REAL_KIND[vr[k]], i->d.state)) return fail(i, "fmi2SetReal: not settable");
    }
    for (size_t k = 0; k < nvr; k++) {
        *real_ref(i, vr[k]) = v[k];
    }
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer v[]) {
    SET_PRELUDE("fmi2SetInteger")
    for (size_t k = 0; k < nvr; k++) {
        if (vr[k] > 1) return fail(i, "fmi2SetInteger: unknown vr");
        if (!settable(INT_KIND[vr[k]], i->d.state)) return fail(i, "fmi2SetInteger: not settable");
    }
    for (size_t k = 0; k < nvr; k++) {
        *int_ref(i, vr[k]) = v[k];
    }
    return fmi2OK;
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean v[]) {
    SET_PRELUDE("fmi2SetBoolean")
    for (size_t k = 0; k < nvr; k++) {
        if (vr[k] != 0) return fail(i, "fmi2SetBoolean: unknown vr");
        if (!settable(3, i->d.state)) return fail(i, "fmi2SetBoolean: not settable");
    }
    for (size_t k = 0; k < nvr; k++) {
        i->d.flag = v[k] != 0;
    }
    return fmi2OK;
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String v[]) {
    SET_PRELUDE("fmi2SetString")
    for (size_t k = 0; k < nvr; k++) {
        if (vr[k] != 0) return fail(i, "fmi2SetString: unknown vr");
        if (!settable(2, i->d.state)) return fail(i, "fmi2SetString: not settable");
        if (v[k] == NULL) return fail(i, "fmi2SetString: NULL string");
    }
    for (size_t k = 0; k < nvr; k++) {
        free(i->d.label);
        i->d.label = dup(v[k]);
    }
    return fmi2OK;
}

static State *state_of(fmi2FMUstate s) {
    State *p = (State *)s;
    return (p != NULL && p->tag == STAG) ? p : NULL;
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s) {
    Inst *i = inst(c);
    if (i == NULL) return fmi2Error;
    if (!allowed(i, ALL_BUT_FATAL, "fmi2GetFMUstate: illegal state")) return fmi2Error;
    if (s == NULL) return fail(i, "fmi2GetFMUstate: NULL");
    State *p;
    if (*s == NULL) {
        p = calloc(1, sizeof *p);
        p->tag = STAG;
    } else if ((p = state_of(*s)) == NULL) {
        return fail(i, "fmi2GetFMUstate: not a state");
    }
    copy_data(&p->d, &i->d);
    *s = p;
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s) {
    Inst *i = inst(c);
    if (i == NULL) return fmi2Error;
    if (!allowed(i, ALL_BUT_FATAL, "fmi2SetFMUstate: illegal state")) return fmi2Error;
    State *p = state_of(s);
    if (p == NULL) return fail(i, "fmi2SetFMUstate: not a state");
    copy_data(&i->d, &p->d);
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *s) {
    Inst *i = inst(c);
    if (i == NULL) return fmi2Error;
    if (!allowed(i, ALL_BUT_FATAL, "fmi2FreeFMUstate: illegal state")) return fmi2Error;
    if (s == NULL || *s == NULL) return fmi2OK;
    State *p = state_of(*s);
    if (p == NULL) return fail(i, "fmi2FreeFMUstate: not a state");
    p->tag = 0;
#ifndef FAULT_LEAK
    free(p->d.label);
    free(p);
#endif
    *s = NULL;
    return fmi2OK;
}

/* Serialized: "FZS1", u64 total length, the Data fields, the label, u64 FNV-1a of all before. */
static uint64_t fnv(const unsigned char *b, size_t n) {
    uint64_t h = 0xcbf29ce484222325ULL;
    for (size_t k = 0; k < n; k++) {
        h ^= b[k];
        h *= 0x100000001b3ULL;
    }
    return h;
}

#define FIXED (4 + 8 + sizeof(int) + 5 * sizeof(double) + 3 * sizeof(int))

static size_t ser_size(const Data *d) { return FIXED + strlen(d->label) + 8; }

static void ser(const Data *d, unsigned char *b) {
    size_t n = ser_size(d), o = 0;
    uint64_t len = n;
    memcpy(b + o, "FZS1", 4); o += 4;
    memcpy(b + o, &len, 8); o += 8;
    memcpy(b + o, &d->state, sizeof(int)); o += sizeof(int);
    double r[5] = {d->time, d->x, d->u, d->k, d->g};
    memcpy(b + o, r, sizeof r); o += sizeof r;
    int z[3] = {d->n, d->mode, d->flag};
    memcpy(b + o, z, sizeof z); o += sizeof z;
    memcpy(b + o, d->label, strlen(d->label)); o += strlen(d->label);
    uint64_t h = fnv(b, o);
    memcpy(b + o, &h, 8);
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *size) {
    Inst *i = inst(c);
    if (i == NULL) return fmi2Error;
    if (!allowed(i, ALL_BUT_FATAL, "fmi2SerializedFMUstateSize: illegal state")) return fmi2Error;
    State *p = state_of(s);
    if (p == NULL || size == NULL) return fail(i, "fmi2SerializedFMUstateSize: bad argument");
    *size = ser_size(&p->d);
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t size) {
    Inst *i = inst(c);
    if (i == NULL) return fmi2Error;
    if (!allowed(i, ALL_BUT_FATAL, "fmi2SerializeFMUstate: illegal state")) return fmi2Error;
    State *p = state_of(s);
    if (p == NULL || b == NULL) return fail(i, "fmi2SerializeFMUstate: bad argument");
    if (size < ser_size(&p->d)) return fail(i, "fmi2SerializeFMUstate: buffer too small");
    ser(&p->d, (unsigned char *)b);
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte b[], size_t size,
                                   fmi2FMUstate *s) {
    Inst *i = inst(c);
    if (i == NULL) return fmi2Error;
    if (!allowed(i, ALL_BUT_FATAL, "fmi2DeSerializeFMUstate: illegal state")) return fmi2Error;
    if (s == NULL || (size > 0 && b == NULL)) return fail(i, "fmi2DeSerializeFMUstate: NULL");
    const unsigned char *u = (const unsigned char *)b;
    uint64_t len, h;
    if (size < FIXED + 8 || memcmp(u, "FZS1", 4) != 0) return fail(i, "deserialize: corrupt");
    memcpy(&len, u + 4, 8);
    if (len != size) return fail(i, "deserialize: wrong length");
    memcpy(&h, u + size - 8, 8);
    if (h != fnv(u, size - 8)) return fail(i, "deserialize: checksum");
    Data d;
    size_t o = 12;
    memcpy(&d.state, u + o, sizeof(int)); o += sizeof(int);
    double r[5];
    memcpy(r, u + o, sizeof r); o += sizeof r;
    int z[3];
    memcpy(z, u + o, sizeof z); o += sizeof z;
    size_t llen = size - 8 - o;
    d.label = malloc(llen + 1);
    memcpy(d.label, u + o, llen);
    d.label[llen] = 0;
    d.time = r[0]; d.x = r[1]; d.u = r[2]; d.k = r[3]; d.g = r[4];
    d.n = z[0]; d.mode = z[1]; d.flag = z[2];
    State *p;
    if (*s == NULL) {
        p = calloc(1, sizeof *p);
        p->tag = STAG;
    } else if ((p = state_of(*s)) == NULL) {
        free(d.label);
        return fail(i, "deserialize: not a state");
    } else {
        free(p->d.label);
    }
    p->d = d;
    *s = p;
    return fmi2OK;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu,
                                        const fmi2ValueReference k[], size_t nk,
                                        const fmi2Real dk[], fmi2Real du[]) {
    (void)u; (void)nu; (void)k; (void)nk; (void)dk; (void)du;
    Inst *i = inst(c);
    if (i == NULL) return fmi2Error;
    return fail(i, "fmi2GetDirectionalDerivative: not supported");
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                       const fmi2Integer o[], const fmi2Real v[]) {
    (void)vr; (void)n; (void)o; (void)v;
    Inst *i = inst(c);
    if (i == NULL) return fmi2Error;
    return fail(i, "fmi2SetRealInputDerivatives: not supported");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                        const fmi2Integer o[], fmi2Real v[]) {
    (void)vr; (void)n; (void)o; (void)v;
    Inst *i = inst(c);
    if (i == NULL) return fmi2Error;
    return fail(i, "fmi2GetRealOutputDerivatives: not supported");
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noPrior) {
    (void)noPrior;
    Inst *i = inst(c);
    if (i == NULL) return fmi2Error;
#ifdef FAULT_HANG
    if (h > 1e6) {
        volatile int forever = 1;
        while (forever) {
        }
    }
#endif
#ifdef FAULT_LENIENT
    int mask = STEP_COMPLETE | INSTANTIATED;
#else
    int mask = STEP_COMPLETE;
#endif
    if (!allowed(i, mask, "fmi2DoStep: illegal state")) return fmi2Error;
    if (!(h > 0) || !(h - h == 0)) return fail(i, "fmi2DoStep: bad step size");
    if (!(t - t == 0)) return fail(i, "fmi2DoStep: bad time");
    double tol = 1e-9 * (i->d.time > 1 || i->d.time < -1 ? (i->d.time < 0 ? -i->d.time : i->d.time) : 1);
    if (t - i->d.time > tol || i->d.time - t > tol) return fail(i, "fmi2DoStep: wrong time");
    i->d.x += h * (-i->d.k * i->d.x + i->d.g * i->d.u);
    i->d.n += 1;
    i->d.time = t + h;
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    Inst *i = inst(c);
    if (i == NULL) return fmi2Error;
    return fail(i, "fmi2CancelStep: no step in progress");
}

#define STATUS_PRELUDE(fn)                                                                 \
    Inst *i = inst(c);                                                                     \
    if (i == NULL) return fmi2Error;                                                       \
    if (!allowed(i, STATUS_MASK, fn ": illegal state")) return fmi2Error;                  \
    if (v == NULL) return fail(i, fn ": NULL");

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *v) {
    (void)s;
    STATUS_PRELUDE("fmi2GetStatus")
    return fmi2Discard;
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *v) {
    STATUS_PRELUDE("fmi2GetRealStatus")
    if (s != fmi2LastSuccessfulTime) return fmi2Discard;
    *v = i->d.time;
    return fmi2OK;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *v) {
    (void)s;
    STATUS_PRELUDE("fmi2GetIntegerStatus")
    return fmi2Discard;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *v) {
    STATUS_PRELUDE("fmi2GetBooleanStatus")
    if (s != fmi2Terminated) return fmi2Discard;
    *v = 0;
    return fmi2OK;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *v) {
    (void)s;
    STATUS_PRELUDE("fmi2GetStringStatus")
    return fmi2Discard;
}
