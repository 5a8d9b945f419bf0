/*
 * A tiny FMI 2.0 co-simulation FMU in C, compiled by the tests (cc -shared -fPIC) to exercise
 * the importer where our Rust FMUs cannot: real printf-style logging with arguments, NULL
 * instance/category, long messages, fmi2Discard/fmi2Error/fmi2Fatal/garbage statuses on
 * demand, and a record of the lifecycle calls it received (resources/calls.txt, located
 * through fmuResourceLocation) so the tests can check what Drop calls.
 *
 * Variables: Real x (vr 0, output: x += u*h per step), u (vr 1, input), time (vr 2);
 * Integer mode (vr 0, selects the DoStep behaviour below), steps (vr 1);
 * Boolean flag (vr 0); String label (vr 0).
 *
 * -DOMIT_SOME leaves out fmi2DoStep, fmi2CancelStep and fmi2GetRealStatus.
 * -DUNDEFINED_REF references a function that exists nowhere.
 * -DFMI_VERSION='"3.0"' makes fmi2GetVersion lie.
 */
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef void *fmi2Component;
typedef void *fmi2ComponentEnvironment;
typedef void *fmi2FMUstate;
typedef unsigned int fmi2ValueReference;
typedef double fmi2Real;
typedef int fmi2Integer;
typedef int fmi2Boolean;
typedef const char *fmi2String;
typedef char fmi2Byte;
typedef int fmi2Status; /* 0 OK, 1 Warning, 2 Discard, 3 Error, 4 Fatal, 5 Pending */

typedef struct {
    void (*logger)(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String, ...);
    void *(*allocateMemory)(size_t, size_t);
    void (*freeMemory)(void *);
    void (*stepFinished)(fmi2ComponentEnvironment, fmi2Status);
    fmi2ComponentEnvironment componentEnvironment;
} fmi2CallbackFunctions;

#define GUID "{5f1c0e2a-test-fmu-0001}"
#ifndef FMI_VERSION
#define FMI_VERSION "2.0"
#endif

typedef struct {
    double time, x, u;
    int mode, steps, flag;
    char label[64];
} State;

typedef struct {
    fmi2CallbackFunctions cb;
    char *name;
    char calls[4096];
    int logging_on;
    State s;
} Inst;

#define LOG(inst, status, cat, ...)                                                          \
    do {                                                                                     \
        if ((inst)->cb.logger)                                                               \
            (inst)->cb.logger((inst)->cb.componentEnvironment, (inst)->name, status, cat,    \
                              __VA_ARGS__);                                                  \
    } while (0)

static void record(Inst *inst, const char *what) {
    if (!inst->calls[0]) return;
    FILE *f = fopen(inst->calls, "a");
    if (!f) return;
    fprintf(f, "%s\n", what);
    fclose(f);
}

static int hex(char c) {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

/* file:///a%20b/resources -> /a b/resources/calls.txt */
static void calls_path(const char *uri, char *out, size_t n) {
    out[0] = 0;
    if (!uri || strncmp(uri, "file://", 7) != 0) return;
    const char *p = uri + 7;
    size_t k = 0;
    while (*p && k + 1 < n) {
        if (*p == '%' && hex(p[1]) >= 0 && hex(p[2]) >= 0) {
            out[k++] = (char)(hex(p[1]) * 16 + hex(p[2]));
            p += 3;
        } else {
            out[k++] = *p++;
        }
    }
    out[k] = 0;
    if (k + 11 < n) strcat(out, "/calls.txt");
}

const char *fmi2GetTypesPlatform(void) { return "default"; }
const char *fmi2GetVersion(void) { return FMI_VERSION; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cats[]) {
    Inst *inst = c;
    fmi2Status st = 0;
    inst->logging_on = on;
    for (size_t i = 0; i < n; i++) {
        if (strcmp(cats[i], "logInfo") != 0 && strcmp(cats[i], "logStep") != 0) {
            LOG(inst, 1, "logStatusWarning", "fmi2SetDebugLogging: unknown category '%s'", cats[i]);
            st = 1;
        }
    }
    return st;
}

fmi2Component fmi2Instantiate(fmi2String name, int type, fmi2String guid, fmi2String res,
                              const fmi2CallbackFunctions *f, fmi2Boolean visible,
                              fmi2Boolean loggingOn) {
    (void)visible;
    if (!f || !f->allocateMemory || !f->freeMemory) return NULL;
    if (type != 1) {
        if (f->logger) f->logger(f->componentEnvironment, name, 3, "logStatusError", "fmuType %d is not co-simulation", type);
        return NULL;
    }
    if (!guid || strcmp(guid, GUID) != 0) {
        if (f->logger)
            f->logger(f->componentEnvironment, name, 3, "logStatusError",
                      "fmi2Instantiate: GUID '%s' does not match the binary's GUID '%s'", guid ? guid : "(null)", GUID);
        return NULL;
    }
    Inst *inst = f->allocateMemory(1, sizeof(Inst));
    if (!inst) return NULL;
    inst->cb = *f;
    inst->name = f->allocateMemory(strlen(name) + 1, 1);
    strcpy(inst->name, name);
    inst->logging_on = loggingOn;
    calls_path(res, inst->calls, sizeof inst->calls);
    record(inst, "fmi2Instantiate");
    if (inst->logging_on) LOG(inst, 0, "logInfo", "resource location: %s", res);
    return inst;
}

void fmi2FreeInstance(fmi2Component c) {
    Inst *inst = c;
    if (!inst) return;
    record(inst, "fmi2FreeInstance");
    void (*fr)(void *) = inst->cb.freeMemory;
    fr(inst->name);
    fr(inst);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tolDefined, fmi2Real tol, fmi2Real start, fmi2Boolean stopDefined, fmi2Real stop) {
    Inst *inst = c;
    (void)tolDefined; (void)tol; (void)stopDefined; (void)stop;
    inst->s.time = start;
    record(inst, "fmi2SetupExperiment");
    return 0;
}
fmi2Status fmi2EnterInitializationMode(fmi2Component c) { record(c, "fmi2EnterInitializationMode"); return 0; }
fmi2Status fmi2ExitInitializationMode(fmi2Component c) { record(c, "fmi2ExitInitializationMode"); return 0; }
fmi2Status fmi2Terminate(fmi2Component c) { record(c, "fmi2Terminate"); return 0; }
fmi2Status fmi2Reset(fmi2Component c) {
    Inst *inst = c;
    memset(&inst->s, 0, sizeof inst->s);
    record(inst, "fmi2Reset");
    return 0;
}

#define UNKNOWN(fn, r) do { LOG(inst, 3, "logStatusError", fn ": unknown value reference %u", r); return 3; } while (0)

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real v[]) {
    Inst *inst = c;
    for (size_t i = 0; i < n; i++) {
        switch (vr[i]) {
        case 0: v[i] = inst->s.x; break;
        case 1: v[i] = inst->s.u; break;
        case 2: v[i] = inst->s.time; break;
        default: UNKNOWN("fmi2GetReal", vr[i]);
        }
    }
    return 0;
}
fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer v[]) {
    Inst *inst = c;
    for (size_t i = 0; i < n; i++) {
        switch (vr[i]) {
        case 0: v[i] = inst->s.mode; break;
        case 1: v[i] = inst->s.steps; break;
        default: UNKNOWN("fmi2GetInteger", vr[i]);
        }
    }
    return 0;
}
fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Boolean v[]) {
    Inst *inst = c;
    for (size_t i = 0; i < n; i++) {
        if (vr[i] != 0) UNKNOWN("fmi2GetBoolean", vr[i]);
        v[i] = inst->s.flag;
    }
    return 0;
}
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2String v[]) {
    Inst *inst = c;
    for (size_t i = 0; i < n; i++) {
        if (vr[i] != 0) UNKNOWN("fmi2GetString", vr[i]);
        v[i] = inst->s.label;
    }
    return 0;
}
fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real v[]) {
    Inst *inst = c;
    for (size_t i = 0; i < n; i++) {
        switch (vr[i]) {
        case 0: inst->s.x = v[i]; break;
        case 1: inst->s.u = v[i]; break;
        default: UNKNOWN("fmi2SetReal", vr[i]);
        }
    }
    return 0;
}
fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer v[]) {
    Inst *inst = c;
    for (size_t i = 0; i < n; i++) {
        if (vr[i] != 0) UNKNOWN("fmi2SetInteger", vr[i]);
        inst->s.mode = v[i];
    }
    return 0;
}
fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Boolean v[]) {
    Inst *inst = c;
    for (size_t i = 0; i < n; i++) {
        if (vr[i] != 0) UNKNOWN("fmi2SetBoolean", vr[i]);
        inst->s.flag = v[i] != 0;
    }
    return 0;
}
fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2String v[]) {
    Inst *inst = c;
    for (size_t i = 0; i < n; i++) {
        if (vr[i] != 0) UNKNOWN("fmi2SetString", vr[i]);
        snprintf(inst->s.label, sizeof inst->s.label, "%s", v[i]);
    }
    return 0;
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *state) {
    Inst *inst = c;
    if (*state == NULL) {
        *state = inst->cb.allocateMemory(1, sizeof(State));
        if (!*state) return 3;
    }
    memcpy(*state, &inst->s, sizeof(State));
    return 0;
}
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
    Inst *inst = c;
    if (!state) return 3;
    memcpy(&inst->s, state, sizeof(State));
    return 0;
}
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state) {
    Inst *inst = c;
    if (!state || !*state) return 0;
    inst->cb.freeMemory(*state);
    *state = NULL;
    record(inst, "fmi2FreeFMUstate");
    return 0;
}
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t *size) {
    (void)c; (void)state;
    *size = sizeof(State);
    return 0;
}
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[], size_t size) {
    Inst *inst = c;
    if (size < sizeof(State)) {
        LOG(inst, 3, "logStatusError", "buffer too small");
        return 3;
    }
    memcpy(bytes, state, sizeof(State));
    return 0;
}
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size, fmi2FMUstate *state) {
    Inst *inst = c;
    if (size != sizeof(State)) {
        LOG(inst, 3, "logStatusError", "fmi2DeSerializeFMUstate: %zu bytes, expected %zu", size, sizeof(State));
        return 3;
    }
    if (*state == NULL) *state = inst->cb.allocateMemory(1, sizeof(State));
    memcpy(*state, bytes, sizeof(State));
    return 0;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu, const fmi2ValueReference z[], size_t nz, const fmi2Real dz[], fmi2Real du[]) {
    (void)c; (void)u; (void)nu; (void)z; (void)nz; (void)dz; (void)du;
    return 3;
}
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer order[], const fmi2Real v[]) {
    (void)c; (void)vr; (void)n; (void)order; (void)v;
    return 3;
}
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer order[], fmi2Real v[]) {
    (void)c; (void)vr; (void)n; (void)order; (void)v;
    return 3;
}

#ifndef OMIT_SOME
fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noSetPrior) {
    Inst *inst = c;
    (void)noSetPrior;
    switch (inst->s.mode) {
    case 0:
        break;
    case 1:
        LOG(inst, 1, "logStatusWarning", "cannot step past t=%g: discarding", inst->s.time);
        return 2;
    case 2:
        LOG(inst, 3, "logStatusError", "step %d failed at t=%g: %s", inst->s.steps, t, "100% sure (%s%d)");
        return 3;
    case 3:
        LOG(inst, 4, "logStatusFatal", "fatal at t=%g", t);
        return 4;
    case 4: {
        static char big[5001];
        memset(big, 'x', 5000);
        big[5000] = 0;
        LOG(inst, 1, "logStatusWarning", "long:%s|%d", big, 42);
        break;
    }
    case 5:
        if (inst->cb.logger) inst->cb.logger(inst->cb.componentEnvironment, NULL, 1, NULL, "null instance and category %d", 7);
        break;
    case 6:
        return 42;
    case 7:
        LOG(inst, 1, "logStatusWarning", "just a warning at step %d", inst->s.steps);
        break;
    }
    inst->s.x += inst->s.u * h;
    inst->s.time = t + h;
    inst->s.steps++;
    if (inst->logging_on) LOG(inst, 0, "logStep", "step %d to t=%g", inst->s.steps, inst->s.time);
    return 0;
}
fmi2Status fmi2CancelStep(fmi2Component c) { (void)c; return 3; }
fmi2Status fmi2GetRealStatus(fmi2Component c, int kind, fmi2Real *v) {
    Inst *inst = c;
    if (kind != 2) return 2;
    *v = inst->s.time;
    return 0;
}
#endif

fmi2Status fmi2GetStatus(fmi2Component c, int kind, fmi2Status *v) { (void)c; (void)kind; (void)v; return 2; }
fmi2Status fmi2GetIntegerStatus(fmi2Component c, int kind, fmi2Integer *v) { (void)c; (void)kind; (void)v; return 2; }
fmi2Status fmi2GetBooleanStatus(fmi2Component c, int kind, fmi2Boolean *v) { (void)c; (void)kind; (void)v; return 2; }
fmi2Status fmi2GetStringStatus(fmi2Component c, int kind, fmi2String *v) { (void)c; (void)kind; (void)v; return 2; }

#ifdef UNDEFINED_REF
extern void testfmu_undefined_function(void);
void testfmu_uses_undefined(void) { testfmu_undefined_function(); }
#endif
