/*
 * C harness of the real tdvass shared library (dlopen), for valgrind and
 * for the threads test. No FMI headers needed: the few types are declared
 * here as in fmi2TypesPlatform.h / fmi2FunctionTypes.h.
 *
 *   harness LIB GUID cycles N     N instantiate / initialize / step /
 *                                 get-set-serialize-deserialize state /
 *                                 refused calls / terminate / free cycles,
 *                                 each followed by a Model Exchange cycle
 *                                 (Event and Continuous-Time Mode, Euler
 *                                 steps, refused calls, FMU states)
 *   harness LIB GUID threads T    T threads, each with its own instances,
 *                                 stepping concurrently; compares every
 *                                 output bit for bit with a single-threaded
 *                                 run of the same work
 *
 * Exit code 0 on success; the first mismatch or unexpected status is
 * printed and gives exit code 1.
 */
#include <dlfcn.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef void *fmi2Component;
typedef void *fmi2FMUstate;
typedef unsigned int fmi2ValueReference;
typedef double fmi2Real;
typedef int fmi2Integer;
typedef int fmi2Boolean;
typedef char fmi2Byte;
typedef const char *fmi2String;
typedef int fmi2Status;
enum { fmi2OK, fmi2Warning, fmi2Discard, fmi2Error, fmi2Fatal };
enum { fmi2ModelExchange, fmi2CoSimulation };

typedef struct {
    fmi2Boolean newDiscreteStatesNeeded;
    fmi2Boolean terminateSimulation;
    fmi2Boolean nominalsOfContinuousStatesChanged;
    fmi2Boolean valuesOfContinuousStatesChanged;
    fmi2Boolean nextEventTimeDefined;
    fmi2Real nextEventTime;
} fmi2EventInfo;

typedef struct {
    void (*logger)(void *, fmi2String, fmi2Status, fmi2String, fmi2String, ...);
    void *(*allocateMemory)(size_t, size_t);
    void (*freeMemory)(void *);
    void (*stepFinished)(void *, fmi2Status);
    void *componentEnvironment;
} fmi2CallbackFunctions;

static struct {
    fmi2Component (*Instantiate)(fmi2String, int, fmi2String, fmi2String,
                                 const fmi2CallbackFunctions *, fmi2Boolean, fmi2Boolean);
    void (*FreeInstance)(fmi2Component);
    fmi2Status (*SetupExperiment)(fmi2Component, fmi2Boolean, fmi2Real, fmi2Real, fmi2Boolean,
                                  fmi2Real);
    fmi2Status (*EnterInitializationMode)(fmi2Component);
    fmi2Status (*ExitInitializationMode)(fmi2Component);
    fmi2Status (*Terminate)(fmi2Component);
    fmi2Status (*GetReal)(fmi2Component, const fmi2ValueReference *, size_t, fmi2Real *);
    fmi2Status (*SetReal)(fmi2Component, const fmi2ValueReference *, size_t, const fmi2Real *);
    fmi2Status (*SetInteger)(fmi2Component, const fmi2ValueReference *, size_t,
                             const fmi2Integer *);
    fmi2Status (*GetFMUstate)(fmi2Component, fmi2FMUstate *);
    fmi2Status (*SetFMUstate)(fmi2Component, fmi2FMUstate);
    fmi2Status (*FreeFMUstate)(fmi2Component, fmi2FMUstate *);
    fmi2Status (*SerializedFMUstateSize)(fmi2Component, fmi2FMUstate, size_t *);
    fmi2Status (*SerializeFMUstate)(fmi2Component, fmi2FMUstate, fmi2Byte *, size_t);
    fmi2Status (*DeSerializeFMUstate)(fmi2Component, const fmi2Byte *, size_t, fmi2FMUstate *);
    fmi2Status (*DoStep)(fmi2Component, fmi2Real, fmi2Real, fmi2Boolean);
    fmi2Status (*EnterEventMode)(fmi2Component);
    fmi2Status (*NewDiscreteStates)(fmi2Component, fmi2EventInfo *);
    fmi2Status (*EnterContinuousTimeMode)(fmi2Component);
    fmi2Status (*CompletedIntegratorStep)(fmi2Component, fmi2Boolean, fmi2Boolean *, fmi2Boolean *);
    fmi2Status (*SetTime)(fmi2Component, fmi2Real);
    fmi2Status (*SetContinuousStates)(fmi2Component, const fmi2Real *, size_t);
    fmi2Status (*GetDerivatives)(fmi2Component, fmi2Real *, size_t);
    fmi2Status (*GetEventIndicators)(fmi2Component, fmi2Real *, size_t);
    fmi2Status (*GetContinuousStates)(fmi2Component, fmi2Real *, size_t);
    fmi2Status (*GetNominalsOfContinuousStates)(fmi2Component, fmi2Real *, size_t);
} fmi;

static const char *guid;
static int quiet_logger_calls;

static void logger(void *env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env;
    (void)name;
    (void)status;
    (void)category;
    /* Read the message, as a real logger would (valgrind checks the bytes). */
    __atomic_add_fetch(&quiet_logger_calls, strlen(message) > 0, __ATOMIC_RELAXED);
}

static const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};

#define CHECK(expr, expected)                                                               \
    do {                                                                                    \
        fmi2Status s_ = (expr);                                                             \
        if (s_ != (expected)) {                                                             \
            fprintf(stderr, "%s:%d: %s returned %d, expected %d\n", __FILE__, __LINE__, #expr, \
                    s_, (expected));                                                        \
            exit(1);                                                                        \
        }                                                                                   \
    } while (0)

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
    SYM(Instantiate, "fmi2Instantiate");
    SYM(FreeInstance, "fmi2FreeInstance");
    SYM(SetupExperiment, "fmi2SetupExperiment");
    SYM(EnterInitializationMode, "fmi2EnterInitializationMode");
    SYM(ExitInitializationMode, "fmi2ExitInitializationMode");
    SYM(Terminate, "fmi2Terminate");
    SYM(GetReal, "fmi2GetReal");
    SYM(SetReal, "fmi2SetReal");
    SYM(SetInteger, "fmi2SetInteger");
    SYM(GetFMUstate, "fmi2GetFMUstate");
    SYM(SetFMUstate, "fmi2SetFMUstate");
    SYM(FreeFMUstate, "fmi2FreeFMUstate");
    SYM(SerializedFMUstateSize, "fmi2SerializedFMUstateSize");
    SYM(SerializeFMUstate, "fmi2SerializeFMUstate");
    SYM(DeSerializeFMUstate, "fmi2DeSerializeFMUstate");
    SYM(DoStep, "fmi2DoStep");
    SYM(EnterEventMode, "fmi2EnterEventMode");
    SYM(NewDiscreteStates, "fmi2NewDiscreteStates");
    SYM(EnterContinuousTimeMode, "fmi2EnterContinuousTimeMode");
    SYM(CompletedIntegratorStep, "fmi2CompletedIntegratorStep");
    SYM(SetTime, "fmi2SetTime");
    SYM(SetContinuousStates, "fmi2SetContinuousStates");
    SYM(GetDerivatives, "fmi2GetDerivatives");
    SYM(GetEventIndicators, "fmi2GetEventIndicators");
    SYM(GetContinuousStates, "fmi2GetContinuousStates");
    SYM(GetNominalsOfContinuousStates, "fmi2GetNominalsOfContinuousStates");
    /* The library stays loaded until exit (as in a simulation tool). */
}

/* Value references (modelDescription.xml). */
enum {
    VR_VARIANT = 1,
    VR_M_S = 2,
    VR_G = 10,
    VR_TAU = 11,
    VR_ROAD = 12,
    VR_ROAD_SEED = 18,
    VR_MAX_INTERNAL_STEP = 20,
    VR_FIRST_OUTPUT = 31,
    N_OUTPUTS = 15 /* x_s .. objective */
};
enum { NX = 20, NZ = 1 }; /* Model Exchange: continuous states, event indicators */

/* ------------------------------------------------------------------ cycles */

/* One explicit Euler step of h in Continuous-Time Mode, completed. */
static void euler_step(fmi2Component c, fmi2Real *t, fmi2Real h) {
    fmi2Real x[NX], dx[NX], z[NZ];
    fmi2Boolean enter = -1, terminate = -1;
    CHECK(fmi.GetContinuousStates(c, x, NX), fmi2OK);
    CHECK(fmi.GetDerivatives(c, dx, NX), fmi2OK);
    for (int i = 0; i < NX; i++) x[i] += h * dx[i];
    *t += h;
    CHECK(fmi.SetTime(c, *t), fmi2OK);
    CHECK(fmi.SetContinuousStates(c, x, NX), fmi2OK);
    CHECK(fmi.GetEventIndicators(c, z, NZ), fmi2OK);
    CHECK(fmi.CompletedIntegratorStep(c, 1, &enter, &terminate), fmi2OK);
    if (enter != 0 || terminate != 0) {
        fprintf(stderr, "CompletedIntegratorStep: enterEventMode %d, terminateSimulation %d\n",
                enter, terminate);
        exit(1);
    }
}

/* A Model Exchange life cycle: Event Mode, Continuous-Time Mode with Euler
 * steps, refused calls, FMU states (own and deserialized), terminate, free. */
static void model_exchange_cycle(int k) {
    fmi2Component c = fmi.Instantiate("me", fmi2ModelExchange, guid, NULL, &callbacks, 0,
                                      k % 7 == 0);
    if (!c) {
        fprintf(stderr, "Model Exchange instantiate failed in cycle %d\n", k);
        exit(1);
    }
    fmi2Real x[NX], nominal[NX];
    CHECK(fmi.GetDerivatives(c, x, NX), fmi2Error); /* not initialized */
    /* TDVASS (the delay history) every other cycle, else PVASS. */
    fmi2ValueReference vrs[] = {VR_VARIANT, VR_ROAD};
    fmi2Integer ints[] = {k % 2 ? 2 : 3, (k % 3) + 1};
    CHECK(fmi.SetInteger(c, vrs, 2, ints), fmi2OK);
    CHECK(fmi.SetupExperiment(c, 0, 0.0, 0.0, 1, 1.0), fmi2OK);
    CHECK(fmi.EnterInitializationMode(c), fmi2OK);
    CHECK(fmi.ExitInitializationMode(c), fmi2OK);
    fmi2EventInfo info;
    CHECK(fmi.NewDiscreteStates(c, &info), fmi2OK);
    CHECK(fmi.NewDiscreteStates(c, NULL), fmi2Error);
    CHECK(fmi.GetNominalsOfContinuousStates(c, nominal, NX), fmi2OK);
    CHECK(fmi.SetContinuousStates(c, nominal, NX), fmi2Error); /* Event Mode */
    CHECK(fmi.DoStep(c, 0.0, 0.001, 1), fmi2Error);
    CHECK(fmi.EnterContinuousTimeMode(c), fmi2OK);
    fmi2Real t = 0.0;
    for (int i = 0; i < 5; i++) euler_step(c, &t, 1e-4);
    /* Refused: wrong counts, a NaN state, time before the completed step. */
    CHECK(fmi.GetContinuousStates(c, x, NX), fmi2OK);
    CHECK(fmi.SetContinuousStates(c, x, NX - 1), fmi2Error);
    CHECK(fmi.GetDerivatives(c, nominal, NX + 1), fmi2Error);
    fmi2Real saved = x[k % NX];
    x[k % NX] = strtod("nan", NULL);
    CHECK(fmi.SetContinuousStates(c, x, NX), fmi2Error);
    x[k % NX] = saved;
    CHECK(fmi.SetTime(c, t - 1e-4), fmi2Error);
    /* FMU states: own, and through bytes every 10th cycle. */
    fmi2FMUstate state = NULL;
    CHECK(fmi.GetFMUstate(c, &state), fmi2OK);
    euler_step(c, &t, 1e-4);
    size_t size = 0;
    CHECK(fmi.SerializedFMUstateSize(c, state, &size), fmi2OK);
    fmi2Byte *bytes = malloc(size);
    CHECK(fmi.SerializeFMUstate(c, state, bytes, size), fmi2OK);
    fmi2FMUstate copy = NULL;
    if (k % 10 == 0) CHECK(fmi.DeSerializeFMUstate(c, bytes, size, &copy), fmi2OK);
    bytes[size / 2] ^= 0x10;
    fmi2FMUstate refused = NULL;
    CHECK(fmi.DeSerializeFMUstate(c, bytes, size, &refused), fmi2Error);
    free(bytes);
    CHECK(fmi.SetFMUstate(c, copy ? copy : state), fmi2OK);
    t -= 1e-4;
    euler_step(c, &t, 1e-4);
    if (copy) CHECK(fmi.FreeFMUstate(c, &copy), fmi2OK);
    if (k % 2) CHECK(fmi.FreeFMUstate(c, &state), fmi2OK);
    CHECK(fmi.EnterEventMode(c), fmi2OK);
    CHECK(fmi.NewDiscreteStates(c, &info), fmi2OK);
    if (info.newDiscreteStatesNeeded || info.terminateSimulation) {
        fprintf(stderr, "NewDiscreteStates: %d %d\n", info.newDiscreteStatesNeeded,
                info.terminateSimulation);
        exit(1);
    }
    fmi2Real out[N_OUTPUTS];
    fmi2ValueReference out_vrs[N_OUTPUTS];
    for (int i = 0; i < N_OUTPUTS; i++) out_vrs[i] = VR_FIRST_OUTPUT + i;
    CHECK(fmi.GetReal(c, out_vrs, N_OUTPUTS, out), fmi2OK);
    CHECK(fmi.Terminate(c), fmi2OK);
    fmi.FreeInstance(c);
}

static void one_cycle(int k) {
    fmi2Component c = fmi.Instantiate("cycle", 1, guid, "file:///tmp/resources", &callbacks, 0,
                                      k % 7 == 0);
    if (!c) {
        fprintf(stderr, "instantiate failed in cycle %d\n", k);
        exit(1);
    }
    /* Refused calls (logged) in the cycle too: their messages must not leak. */
    fmi2ValueReference bad = 9999;
    fmi2Real value = -1.0;
    fmi2ValueReference m_s = VR_M_S;
    CHECK(fmi.SetReal(c, &m_s, 1, &value), fmi2Error);
    CHECK(fmi.SetReal(c, &bad, 1, &value), fmi2Error);
    CHECK(fmi.DoStep(c, 0.0, 0.001, 1), fmi2Error);
    /* A cheap configuration: PVASS (no delay), a coarse internal step. */
    fmi2ValueReference vrs[] = {VR_VARIANT, VR_ROAD};
    fmi2Integer ints[] = {2, (k % 3) + 1};
    CHECK(fmi.SetInteger(c, vrs, 2, ints), fmi2OK);
    fmi2ValueReference h_vr = VR_MAX_INTERNAL_STEP;
    fmi2Real h_max = 1e-3;
    CHECK(fmi.SetReal(c, &h_vr, 1, &h_max), fmi2OK);
    CHECK(fmi.SetupExperiment(c, 0, 0.0, 0.0, 1, 1.0), fmi2OK);
    CHECK(fmi.EnterInitializationMode(c), fmi2OK);
    CHECK(fmi.ExitInitializationMode(c), fmi2OK);
    CHECK(fmi.DoStep(c, 0.0, 0.01, 1), fmi2OK);
    fmi2FMUstate state = NULL;
    CHECK(fmi.GetFMUstate(c, &state), fmi2OK);
    CHECK(fmi.DoStep(c, 0.01, 0.01, 1), fmi2OK);
    size_t size = 0;
    CHECK(fmi.SerializedFMUstateSize(c, state, &size), fmi2OK);
    fmi2Byte *bytes = malloc(size);
    CHECK(fmi.SerializeFMUstate(c, state, bytes, size), fmi2OK);
    CHECK(fmi.SerializeFMUstate(c, state, bytes, size - 1), fmi2Error);
    /* Restoring rebuilds the solver's operators, the dearest part of a
     * cycle under valgrind: every 10th cycle; otherwise roll back with the
     * state itself. A corrupted copy is refused in every cycle. */
    fmi2FMUstate copy = NULL;
    if (k % 10 == 0) {
        CHECK(fmi.DeSerializeFMUstate(c, bytes, size, &copy), fmi2OK);
    } else {
        CHECK(fmi.GetFMUstate(c, &copy), fmi2OK);
        CHECK(fmi.SetFMUstate(c, state), fmi2OK);
    }
    bytes[size / 2] ^= 0x10;
    fmi2FMUstate refused = NULL;
    CHECK(fmi.DeSerializeFMUstate(c, bytes, size, &refused), fmi2Error);
    free(bytes);
    CHECK(fmi.SetFMUstate(c, copy), fmi2OK);
    /* Back at 0.01 s (the deserialized state) or at 0.02 s (the copy). */
    fmi2Real now = k % 10 == 0 ? 0.01 : 0.02;
    CHECK(fmi.DoStep(c, now, 0.01, 1), fmi2OK);
    fmi2Real out[N_OUTPUTS];
    fmi2ValueReference out_vrs[N_OUTPUTS];
    for (int i = 0; i < N_OUTPUTS; i++) out_vrs[i] = VR_FIRST_OUTPUT + i;
    CHECK(fmi.GetReal(c, out_vrs, N_OUTPUTS, out), fmi2OK);
    CHECK(fmi.FreeFMUstate(c, &copy), fmi2OK);
    /* Every other cycle frees the remaining state with the instance. */
    if (k % 2) CHECK(fmi.FreeFMUstate(c, &state), fmi2OK);
    CHECK(fmi.Terminate(c), fmi2OK);
    fmi.FreeInstance(c);
    /* Refused instantiations log and allocate nothing that survives. */
    if (k % 10 == 0) {
        if (fmi.Instantiate("x", 1, "{wrong}", NULL, &callbacks, 0, 0) ||
            fmi.Instantiate("x", 7, guid, NULL, &callbacks, 0, 0) ||
            fmi.Instantiate("x", 1, guid, "http://host/r", &callbacks, 0, 0)) {
            fprintf(stderr, "a refused instantiation succeeded\n");
            exit(1);
        }
    }
    fmi.FreeInstance(NULL);
    model_exchange_cycle(k);
}

/* ----------------------------------------------------------------- threads */

#define INSTANCES_PER_THREAD 2
#define STEPS 4000
#define STEP 0.005

typedef struct {
    int index;
    fmi2Real outputs[INSTANCES_PER_THREAD][STEPS][N_OUTPUTS];
    int failed;
} Work;

/* Instance j of worker i: its own parameters (gain, delay, road, seed). */
static void run_work(Work *w) {
    fmi2ValueReference out_vrs[N_OUTPUTS];
    for (int i = 0; i < N_OUTPUTS; i++) out_vrs[i] = VR_FIRST_OUTPUT + i;
    fmi2Component c[INSTANCES_PER_THREAD];
    for (int j = 0; j < INSTANCES_PER_THREAD; j++) {
        int id = w->index * INSTANCES_PER_THREAD + j;
        char name[32];
        snprintf(name, sizeof name, "worker%d", id);
        c[j] = fmi.Instantiate(name, 1, guid, NULL, &callbacks, 0, 0);
        if (!c[j]) {
            w->failed = 1;
            return;
        }
        fmi2ValueReference ivr[] = {VR_ROAD, VR_ROAD_SEED};
        fmi2Integer ival[] = {1 + id % 3, 1 + id};
        fmi2ValueReference rvr[] = {VR_G, VR_TAU};
        fmi2Real rval[] = {1000.0 + 700.0 * id, 1e-4 * (1 + id % 5)};
        if (fmi.SetInteger(c[j], ivr, 2, ival) != fmi2OK ||
            fmi.SetReal(c[j], rvr, 2, rval) != fmi2OK ||
            fmi.SetupExperiment(c[j], 0, 0.0, 0.0, 0, 0.0) != fmi2OK ||
            fmi.EnterInitializationMode(c[j]) != fmi2OK ||
            fmi.ExitInitializationMode(c[j]) > fmi2Warning) {
            w->failed = 1;
            return;
        }
    }
    /* Interleave the instances of this thread step by step. */
    for (int k = 0; k < STEPS; k++) {
        for (int j = 0; j < INSTANCES_PER_THREAD; j++) {
            if (fmi.DoStep(c[j], k * STEP, STEP, 1) != fmi2OK ||
                fmi.GetReal(c[j], out_vrs, N_OUTPUTS, w->outputs[j][k]) != fmi2OK) {
                w->failed = 1;
                return;
            }
        }
    }
    for (int j = 0; j < INSTANCES_PER_THREAD; j++) {
        fmi.Terminate(c[j]);
        fmi.FreeInstance(c[j]);
    }
}

static void *thread_main(void *arg) {
    run_work(arg);
    return NULL;
}

static int threads(int n) {
    Work *serial = calloc(n, sizeof(Work));
    Work *parallel = calloc(n, sizeof(Work));
    for (int i = 0; i < n; i++) {
        serial[i].index = parallel[i].index = i;
        run_work(&serial[i]);
    }
    pthread_t *t = calloc(n, sizeof(pthread_t));
    for (int i = 0; i < n; i++) pthread_create(&t[i], NULL, thread_main, &parallel[i]);
    for (int i = 0; i < n; i++) pthread_join(t[i], NULL);
    int status = 0;
    for (int i = 0; i < n; i++) {
        if (serial[i].failed || parallel[i].failed) {
            fprintf(stderr, "worker %d failed (serial %d, parallel %d)\n", i, serial[i].failed,
                    parallel[i].failed);
            status = 1;
        } else if (memcmp(serial[i].outputs, parallel[i].outputs, sizeof serial[i].outputs)) {
            fprintf(stderr, "worker %d: outputs differ between serial and threaded runs\n", i);
            status = 1;
        }
    }
    /* The workers differ from each other (each has its own parameters). */
    if (n > 1 && !memcmp(serial[0].outputs, serial[1].outputs, sizeof serial[0].outputs)) {
        fprintf(stderr, "workers 0 and 1 computed the same outputs\n");
        status = 1;
    }
    if (status == 0)
        printf("threads: %d threads x %d instances x %d steps, bit-identical to the serial run\n",
               n, INSTANCES_PER_THREAD, STEPS);
    free(t);
    free(serial);
    free(parallel);
    return status;
}

int main(int argc, char **argv) {
    if (argc != 5) {
        fprintf(stderr, "usage: %s LIB GUID cycles N | threads T\n", argv[0]);
        return 2;
    }
    load(argv[1]);
    guid = argv[2];
    int n = atoi(argv[4]);
    if (!strcmp(argv[3], "cycles")) {
        for (int k = 0; k < n; k++) one_cycle(k);
        printf("cycles: %d completed, %d log messages\n", n, quiet_logger_calls);
        return 0;
    }
    if (!strcmp(argv[3], "threads")) return threads(n);
    fprintf(stderr, "unknown mode %s\n", argv[3]);
    return 2;
}
