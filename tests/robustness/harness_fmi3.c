/*
 * C harness of the real tdvass FMI 3.0 shared library (dlopen), for
 * valgrind. No FMI headers needed: the few types are declared here as in
 * fmi3PlatformTypes.h / fmi3FunctionTypes.h (fmi3Boolean is a C bool).
 *
 *   harness_fmi3 LIB TOKEN cycles N NAME=VR...
 *
 * N cycles of: instantiate with an intermediate-update callback (which
 * reads the outputs, sets x_g and asks for an early return) / refused calls /
 * Configuration Mode / initialize / step / read the rightmost_roots array /
 * get-set-serialize-deserialize state / terminate / free, and refused
 * instantiations; then a Model Exchange cycle (Event and Continuous-Time
 * Mode, Euler steps, refused calls, FMU states). The value references come
 * as NAME=VR arguments (from
 * modelDescription.xml): variant, road, root_count, rightmost_roots,
 * max_internal_step, intermediate_update_interval, x_g, m_s, x_s, objective.
 *
 * Exit code 0 on success; the first unexpected status is printed and gives
 * exit code 1.
 */
#include <dlfcn.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef void *fmi3Instance;
typedef void *fmi3FMUState;
typedef uint32_t fmi3ValueReference;
typedef double fmi3Float64;
typedef int64_t fmi3Int64;
typedef uint64_t fmi3UInt64;
typedef bool fmi3Boolean;
typedef uint8_t fmi3Byte;
typedef const char *fmi3String;
typedef int fmi3Status;
enum { fmi3OK, fmi3Warning, fmi3Discard, fmi3Error, fmi3Fatal };

typedef void (*fmi3LogMessageCallback)(void *, fmi3Status, fmi3String, fmi3String);
typedef void (*fmi3IntermediateUpdateCallback)(void *, fmi3Float64, fmi3Boolean, fmi3Boolean,
                                               fmi3Boolean, fmi3Boolean, fmi3Boolean *,
                                               fmi3Float64 *);

static struct {
    fmi3Instance (*InstantiateCoSimulation)(fmi3String, fmi3String, fmi3String, fmi3Boolean,
                                            fmi3Boolean, fmi3Boolean, fmi3Boolean,
                                            const fmi3ValueReference *, size_t, void *,
                                            fmi3LogMessageCallback,
                                            fmi3IntermediateUpdateCallback);
    fmi3Instance (*InstantiateModelExchange)(fmi3String, fmi3String, fmi3String, fmi3Boolean,
                                             fmi3Boolean, void *, fmi3LogMessageCallback);
    void (*FreeInstance)(fmi3Instance);
    fmi3Status (*EnterConfigurationMode)(fmi3Instance);
    fmi3Status (*ExitConfigurationMode)(fmi3Instance);
    fmi3Status (*EnterInitializationMode)(fmi3Instance, fmi3Boolean, fmi3Float64, fmi3Float64,
                                          fmi3Boolean, fmi3Float64);
    fmi3Status (*ExitInitializationMode)(fmi3Instance);
    fmi3Status (*Terminate)(fmi3Instance);
    fmi3Status (*GetFloat64)(fmi3Instance, const fmi3ValueReference *, size_t, fmi3Float64 *,
                             size_t);
    fmi3Status (*SetFloat64)(fmi3Instance, const fmi3ValueReference *, size_t,
                             const fmi3Float64 *, size_t);
    fmi3Status (*SetInt64)(fmi3Instance, const fmi3ValueReference *, size_t, const fmi3Int64 *,
                           size_t);
    fmi3Status (*SetUInt64)(fmi3Instance, const fmi3ValueReference *, size_t,
                            const fmi3UInt64 *, size_t);
    fmi3Status (*GetFMUState)(fmi3Instance, fmi3FMUState *);
    fmi3Status (*SetFMUState)(fmi3Instance, fmi3FMUState);
    fmi3Status (*FreeFMUState)(fmi3Instance, fmi3FMUState *);
    fmi3Status (*SerializedFMUStateSize)(fmi3Instance, fmi3FMUState, size_t *);
    fmi3Status (*SerializeFMUState)(fmi3Instance, fmi3FMUState, fmi3Byte *, size_t);
    fmi3Status (*DeserializeFMUState)(fmi3Instance, const fmi3Byte *, size_t, fmi3FMUState *);
    fmi3Status (*DoStep)(fmi3Instance, fmi3Float64, fmi3Float64, fmi3Boolean, fmi3Boolean *,
                         fmi3Boolean *, fmi3Boolean *, fmi3Float64 *);
    fmi3Status (*EnterEventMode)(fmi3Instance);
    fmi3Status (*UpdateDiscreteStates)(fmi3Instance, fmi3Boolean *, fmi3Boolean *, fmi3Boolean *,
                                       fmi3Boolean *, fmi3Boolean *, fmi3Float64 *);
    fmi3Status (*EnterContinuousTimeMode)(fmi3Instance);
    fmi3Status (*CompletedIntegratorStep)(fmi3Instance, fmi3Boolean, fmi3Boolean *, fmi3Boolean *);
    fmi3Status (*SetTime)(fmi3Instance, fmi3Float64);
    fmi3Status (*SetContinuousStates)(fmi3Instance, const fmi3Float64 *, size_t);
    fmi3Status (*GetContinuousStateDerivatives)(fmi3Instance, fmi3Float64 *, size_t);
    fmi3Status (*GetEventIndicators)(fmi3Instance, fmi3Float64 *, size_t);
    fmi3Status (*GetContinuousStates)(fmi3Instance, fmi3Float64 *, size_t);
    fmi3Status (*GetNominalsOfContinuousStates)(fmi3Instance, fmi3Float64 *, size_t);
    fmi3Status (*GetNumberOfContinuousStates)(fmi3Instance, size_t *);
    fmi3Status (*GetNumberOfEventIndicators)(fmi3Instance, size_t *);
} fmi;

enum { NX = 20, NZ = 1 }; /* Model Exchange: continuous states, event indicators */

static const char *token;
static int logger_calls;

static struct {
    fmi3ValueReference variant, road, root_count, rightmost_roots, max_internal_step,
        intermediate_update_interval, x_g, m_s, x_s, objective;
} vr;

static void logger(void *env, fmi3Status status, fmi3String category, fmi3String message) {
    (void)env;
    (void)status;
    /* Read the strings, as a real logger would (valgrind checks the bytes). */
    logger_calls += strlen(category) > 0 && strlen(message) > 0;
}

#define CHECK(expr, expected)                                                               \
    do {                                                                                    \
        fmi3Status s_ = (expr);                                                             \
        if (s_ != (expected)) {                                                             \
            fprintf(stderr, "%s:%d: %s returned %d, expected %d\n", __FILE__, __LINE__, #expr, \
                    s_, (expected));                                                        \
            exit(1);                                                                        \
        }                                                                                   \
    } while (0)

/* What the intermediate-update callback sees. */
typedef struct {
    fmi3Instance instance;
    int updates;
    double return_at;
} Master;

static void on_update(void *env, fmi3Float64 time, fmi3Boolean clock_active,
                      fmi3Boolean set_requested, fmi3Boolean get_allowed,
                      fmi3Boolean can_return_early, fmi3Boolean *early_return_requested,
                      fmi3Float64 *early_return_time) {
    (void)clock_active;
    Master *m = env;
    m->updates++;
    if (get_allowed) {
        fmi3ValueReference outs[] = {vr.x_s, vr.objective};
        fmi3Float64 values[2];
        CHECK(fmi.GetFloat64(m->instance, outs, 2, values, 2), fmi3OK);
    }
    if (set_requested) {
        fmi3Float64 x_g = 1e-3 * time;
        CHECK(fmi.SetFloat64(m->instance, &vr.x_g, 1, &x_g, 1), fmi3OK);
    }
    /* Refused inside the callback, logged. */
    CHECK(fmi.Terminate(m->instance), fmi3Error);
    if (can_return_early && m->return_at > 0 && time >= m->return_at) {
        *early_return_requested = true;
        *early_return_time = time;
        m->return_at = 0;
    }
}

static void load(const char *path) {
    void *lib = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fprintf(stderr, "dlopen: %s\n", dlerror());
        exit(2);
    }
#define SYM(field, name)                                                    \
    do {                                                                    \
        *(void **)&fmi.field = dlsym(lib, name);                            \
        if (!fmi.field) {                                                   \
            fprintf(stderr, "missing %s\n", name);                          \
            exit(2);                                                        \
        }                                                                   \
    } while (0)
    SYM(InstantiateCoSimulation, "fmi3InstantiateCoSimulation");
    SYM(InstantiateModelExchange, "fmi3InstantiateModelExchange");
    SYM(FreeInstance, "fmi3FreeInstance");
    SYM(EnterConfigurationMode, "fmi3EnterConfigurationMode");
    SYM(ExitConfigurationMode, "fmi3ExitConfigurationMode");
    SYM(EnterInitializationMode, "fmi3EnterInitializationMode");
    SYM(ExitInitializationMode, "fmi3ExitInitializationMode");
    SYM(Terminate, "fmi3Terminate");
    SYM(GetFloat64, "fmi3GetFloat64");
    SYM(SetFloat64, "fmi3SetFloat64");
    SYM(SetInt64, "fmi3SetInt64");
    SYM(SetUInt64, "fmi3SetUInt64");
    SYM(GetFMUState, "fmi3GetFMUState");
    SYM(SetFMUState, "fmi3SetFMUState");
    SYM(FreeFMUState, "fmi3FreeFMUState");
    SYM(SerializedFMUStateSize, "fmi3SerializedFMUStateSize");
    SYM(SerializeFMUState, "fmi3SerializeFMUState");
    SYM(DeserializeFMUState, "fmi3DeserializeFMUState");
    SYM(DoStep, "fmi3DoStep");
    SYM(EnterEventMode, "fmi3EnterEventMode");
    SYM(UpdateDiscreteStates, "fmi3UpdateDiscreteStates");
    SYM(EnterContinuousTimeMode, "fmi3EnterContinuousTimeMode");
    SYM(CompletedIntegratorStep, "fmi3CompletedIntegratorStep");
    SYM(SetTime, "fmi3SetTime");
    SYM(SetContinuousStates, "fmi3SetContinuousStates");
    SYM(GetContinuousStateDerivatives, "fmi3GetContinuousStateDerivatives");
    SYM(GetEventIndicators, "fmi3GetEventIndicators");
    SYM(GetContinuousStates, "fmi3GetContinuousStates");
    SYM(GetNominalsOfContinuousStates, "fmi3GetNominalsOfContinuousStates");
    SYM(GetNumberOfContinuousStates, "fmi3GetNumberOfContinuousStates");
    SYM(GetNumberOfEventIndicators, "fmi3GetNumberOfEventIndicators");
    /* The library stays loaded until exit (as in a simulation tool). */
}

static fmi3Status step(fmi3Instance c, double t, double h, fmi3Boolean *early, double *last) {
    fmi3Boolean event, terminate;
    return fmi.DoStep(c, t, h, false, &event, &terminate, early, last);
}

/* One explicit Euler step of h in Continuous-Time Mode, completed. */
static void euler_step(fmi3Instance c, fmi3Float64 *t, fmi3Float64 h) {
    fmi3Float64 x[NX], dx[NX], z[NZ];
    fmi3Boolean enter = true, terminate = true;
    CHECK(fmi.GetContinuousStates(c, x, NX), fmi3OK);
    CHECK(fmi.GetContinuousStateDerivatives(c, dx, NX), fmi3OK);
    for (int i = 0; i < NX; i++) x[i] += h * dx[i];
    *t += h;
    CHECK(fmi.SetTime(c, *t), fmi3OK);
    CHECK(fmi.SetContinuousStates(c, x, NX), fmi3OK);
    CHECK(fmi.GetEventIndicators(c, z, NZ), fmi3OK);
    CHECK(fmi.CompletedIntegratorStep(c, true, &enter, &terminate), fmi3OK);
    if (enter || terminate) {
        fprintf(stderr, "CompletedIntegratorStep: enterEventMode %d, terminateSimulation %d\n",
                enter, terminate);
        exit(1);
    }
}

/* An update of the discrete states in Event Mode: nothing more to do. */
static void update_discrete_states(fmi3Instance c) {
    fmi3Boolean again = true, terminate = true, nominals = true, values = true, defined = true;
    fmi3Float64 next = -1.0;
    CHECK(fmi.UpdateDiscreteStates(c, &again, &terminate, &nominals, &values, &defined, &next),
          fmi3OK);
    if (again || terminate || nominals || values || defined) {
        fprintf(stderr, "UpdateDiscreteStates: %d %d %d %d %d\n", again, terminate, nominals,
                values, defined);
        exit(1);
    }
}

/* A Model Exchange life cycle: Event Mode, Continuous-Time Mode with Euler
 * steps, refused calls, FMU states (own and deserialized), terminate, free. */
static void model_exchange_cycle(int k) {
    fmi3Instance c = fmi.InstantiateModelExchange("me", token, NULL, false, k % 7 == 0, NULL,
                                                  logger);
    if (!c) {
        fprintf(stderr, "Model Exchange instantiate failed in cycle %d\n", k);
        exit(1);
    }
    fmi3Float64 x[NX], nominal[NX];
    size_t n = 0;
    CHECK(fmi.GetContinuousStateDerivatives(c, x, NX), fmi3Error); /* not initialized */
    CHECK(fmi.GetNumberOfContinuousStates(c, &n), fmi3Error);
    /* TDVASS (the delay history) every other cycle, else PVASS. */
    fmi3ValueReference enums[] = {vr.variant, vr.road};
    fmi3Int64 codes[] = {k % 2 ? 2 : 3, (k % 3) + 1};
    CHECK(fmi.SetInt64(c, enums, 2, codes, 2), fmi3OK);
    CHECK(fmi.EnterInitializationMode(c, false, 0.0, 0.0, true, 1.0), fmi3OK);
    CHECK(fmi.GetNumberOfContinuousStates(c, &n), fmi3OK);
    CHECK(fmi.GetNumberOfEventIndicators(c, &n), fmi3OK);
    CHECK(fmi.ExitInitializationMode(c), fmi3OK);
    update_discrete_states(c);
    CHECK(fmi.UpdateDiscreteStates(c, NULL, NULL, NULL, NULL, NULL, NULL), fmi3Error);
    CHECK(fmi.GetNominalsOfContinuousStates(c, nominal, NX), fmi3OK);
    CHECK(fmi.SetContinuousStates(c, nominal, NX), fmi3Error); /* Event Mode */
    CHECK(step(c, 0.0, 0.001, &(fmi3Boolean){0}, &x[0]), fmi3Error);
    CHECK(fmi.EnterContinuousTimeMode(c), fmi3OK);
    fmi3Float64 t = 0.0;
    for (int i = 0; i < 5; i++) euler_step(c, &t, 1e-4);
    /* Refused: wrong counts, a NaN state, time before the completed step. */
    CHECK(fmi.GetContinuousStates(c, x, NX), fmi3OK);
    CHECK(fmi.SetContinuousStates(c, x, NX - 1), fmi3Error);
    CHECK(fmi.GetContinuousStateDerivatives(c, nominal, NX + 1), fmi3Error);
    fmi3Float64 saved = x[k % NX];
    x[k % NX] = strtod("nan", NULL);
    CHECK(fmi.SetContinuousStates(c, x, NX), fmi3Error);
    x[k % NX] = saved;
    CHECK(fmi.SetTime(c, t - 1e-4), fmi3Error);
    /* FMU states: own, and through bytes every 10th cycle. */
    fmi3FMUState state = NULL;
    CHECK(fmi.GetFMUState(c, &state), fmi3OK);
    euler_step(c, &t, 1e-4);
    size_t size = 0;
    CHECK(fmi.SerializedFMUStateSize(c, state, &size), fmi3OK);
    fmi3Byte *bytes = malloc(size);
    CHECK(fmi.SerializeFMUState(c, state, bytes, size), fmi3OK);
    fmi3FMUState copy = NULL;
    if (k % 10 == 0) CHECK(fmi.DeserializeFMUState(c, bytes, size, &copy), fmi3OK);
    bytes[size / 2] ^= 0x10;
    fmi3FMUState refused = NULL;
    CHECK(fmi.DeserializeFMUState(c, bytes, size, &refused), fmi3Error);
    free(bytes);
    CHECK(fmi.SetFMUState(c, copy ? copy : state), fmi3OK);
    t -= 1e-4;
    euler_step(c, &t, 1e-4);
    if (copy) CHECK(fmi.FreeFMUState(c, &copy), fmi3OK);
    if (k % 2) CHECK(fmi.FreeFMUState(c, &state), fmi3OK);
    CHECK(fmi.EnterEventMode(c), fmi3OK);
    update_discrete_states(c);
    fmi3ValueReference outs[] = {vr.x_s, vr.objective};
    fmi3Float64 out[2];
    CHECK(fmi.GetFloat64(c, outs, 2, out, 2), fmi3OK);
    CHECK(fmi.Terminate(c), fmi3OK);
    fmi.FreeInstance(c);
}

static void one_cycle(int k) {
    Master m = {NULL, 0, k % 3 == 0 ? 0.0125 : 0.0};
    fmi3Instance c = fmi.InstantiateCoSimulation("cycle", token, NULL, false, k % 7 == 0, false,
                                                 true, NULL, 0, &m, logger, on_update);
    if (!c) {
        fprintf(stderr, "instantiate failed in cycle %d\n", k);
        exit(1);
    }
    m.instance = c;
    /* Refused calls (logged) in the cycle too: their messages must not leak. */
    fmi3ValueReference bad = 9999;
    fmi3Float64 value = -1.0;
    CHECK(fmi.SetFloat64(c, &vr.m_s, 1, &value, 1), fmi3Error);
    CHECK(fmi.SetFloat64(c, &bad, 1, &value, 1), fmi3Error);
    CHECK(step(c, 0.0, 0.001, &(fmi3Boolean){0}, &value), fmi3Error);
    CHECK(fmi.EnterEventMode(c), fmi3Error);
    /* Configuration Mode: the structural parameter, and a refused one. */
    CHECK(fmi.EnterConfigurationMode(c), fmi3OK);
    fmi3UInt64 roots = 1 + k % 3;
    CHECK(fmi.SetUInt64(c, &vr.root_count, 1, &roots, 1), fmi3OK);
    CHECK(fmi.SetFloat64(c, &vr.m_s, 1, &value, 1), fmi3Error);
    CHECK(fmi.ExitConfigurationMode(c), fmi3OK);
    /* A cheap configuration: PVASS (no delay), a coarse internal step. */
    fmi3ValueReference enums[] = {vr.variant, vr.road};
    fmi3Int64 codes[] = {2, (k % 3) + 1};
    CHECK(fmi.SetInt64(c, enums, 2, codes, 2), fmi3OK);
    fmi3ValueReference reals[] = {vr.max_internal_step, vr.intermediate_update_interval};
    fmi3Float64 real_values[] = {1e-3, k % 2 ? 0.0 : 4e-3};
    CHECK(fmi.SetFloat64(c, reals, 2, real_values, 2), fmi3OK);
    CHECK(fmi.EnterInitializationMode(c, false, 0.0, 0.0, true, 1.0), fmi3OK);
    CHECK(fmi.ExitInitializationMode(c), fmi3OK);
    fmi3Boolean early = false;
    fmi3Float64 last = 0.0;
    CHECK(step(c, 0.0, 0.01, &early, &last), fmi3OK);
    fmi3Float64 now = early ? last : 0.01;
    fmi3Float64 pairs[2 * 3];
    CHECK(fmi.GetFloat64(c, &vr.rightmost_roots, 1, pairs, 2 * roots), fmi3OK);
    CHECK(fmi.GetFloat64(c, &vr.rightmost_roots, 1, pairs, 2 * roots + 1), fmi3Error);
    fmi3FMUState state = NULL;
    CHECK(fmi.GetFMUState(c, &state), fmi3OK);
    CHECK(step(c, now, 0.01, &early, &last), fmi3OK);
    size_t size = 0;
    CHECK(fmi.SerializedFMUStateSize(c, state, &size), fmi3OK);
    fmi3Byte *bytes = malloc(size);
    CHECK(fmi.SerializeFMUState(c, state, bytes, size), fmi3OK);
    CHECK(fmi.SerializeFMUState(c, state, bytes, size - 1), fmi3Error);
    /* Restoring from bytes rebuilds the solver (the dearest part under
     * valgrind): every 10th cycle; otherwise roll back with the state
     * itself. A corrupted copy is refused in every cycle. */
    fmi3FMUState copy = NULL;
    if (k % 10 == 0) {
        CHECK(fmi.DeserializeFMUState(c, bytes, size, &copy), fmi3OK);
    } else {
        CHECK(fmi.GetFMUState(c, &copy), fmi3OK);
    }
    bytes[size / 2] ^= 0x10;
    fmi3FMUState refused = NULL;
    CHECK(fmi.DeserializeFMUState(c, bytes, size, &refused), fmi3Error);
    CHECK(fmi.DeserializeFMUState(c, bytes, size / 3, &refused), fmi3Error);
    free(bytes);
    CHECK(fmi.SetFMUState(c, state), fmi3OK);
    CHECK(step(c, now, 0.005, &early, &last), fmi3OK);
    fmi3ValueReference outs[] = {vr.x_s, vr.objective};
    fmi3Float64 out[2];
    CHECK(fmi.GetFloat64(c, outs, 2, out, 2), fmi3OK);
    CHECK(fmi.FreeFMUState(c, &copy), fmi3OK);
    /* Every other cycle frees the remaining state with the instance. */
    if (k % 2) CHECK(fmi.FreeFMUState(c, &state), fmi3OK);
    CHECK(fmi.Terminate(c), fmi3OK);
    fmi.FreeInstance(c);
    if (m.updates == 0) {
        fprintf(stderr, "no intermediate update in cycle %d\n", k);
        exit(1);
    }
    /* Refused instantiations log and allocate nothing that survives. */
    if (k % 10 == 0) {
        fmi3ValueReference not_intermediate = vr.m_s;
        if (fmi.InstantiateCoSimulation("x", "{wrong}", NULL, false, false, false, false, NULL, 0,
                                        NULL, logger, NULL) ||
            fmi.InstantiateCoSimulation("x", token, NULL, false, false, false, false,
                                        &not_intermediate, 1, NULL, logger, NULL) ||
            fmi.InstantiateModelExchange("x", "{wrong}", NULL, false, false, NULL, logger)) {
            fprintf(stderr, "a refused instantiation succeeded\n");
            exit(1);
        }
    }
    fmi.FreeInstance(NULL);
    model_exchange_cycle(k);
}

static fmi3ValueReference value_reference(int argc, char **argv, const char *name) {
    size_t n = strlen(name);
    for (int i = 5; i < argc; i++)
        if (!strncmp(argv[i], name, n) && argv[i][n] == '=') return (fmi3ValueReference)atol(argv[i] + n + 1);
    fprintf(stderr, "no value reference given for %s\n", name);
    exit(2);
}

int main(int argc, char **argv) {
    if (argc < 5 || strcmp(argv[3], "cycles")) {
        fprintf(stderr, "usage: %s LIB TOKEN cycles N NAME=VR...\n", argv[0]);
        return 2;
    }
    load(argv[1]);
    token = argv[2];
#define VR(field) vr.field = value_reference(argc, argv, #field)
    VR(variant);
    VR(road);
    VR(root_count);
    VR(rightmost_roots);
    VR(max_internal_step);
    VR(intermediate_update_interval);
    VR(x_g);
    VR(m_s);
    VR(x_s);
    VR(objective);
    int n = atoi(argv[4]);
    for (int k = 0; k < n; k++) one_cycle(k);
    printf("cycles: %d completed, %d log messages\n", n, logger_calls);
    return 0;
}
