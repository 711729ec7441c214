/*
 * Platform-neutral harness of the tdvass FMI 3.0 library (Co-Simulation
 * and Model Exchange), the counterpart of harness.c: compiled natively for
 * x86_64-linux, with MinGW-w64 for x86_64-windows (run under wine) and
 * with the aarch64 GNU toolchain for aarch64-linux (run under qemu-user),
 * each run loads that platform's binary of tdvass-fmi3.fmu. The FMI 3.0
 * types are declared in tests/include/fmi3_types.h. One source file on
 * purpose, as harness.c (one compiler call per platform): hence its length.
 *
 *   harness_fmi3 LIB TOKEN OUTPUT_VRS OUT_DIR STATE_IN [NAME TOKEN OUTPUTS INPUTS DERIVATIVES TABLE MODE]...
 *
 *   LIB         the library (binaries/<platform tuple>/tdvass.so or .dll)
 *   TOKEN       the instantiationToken of the FMU's modelDescription.xml
 *   OUTPUT_VRS  comma-separated value references of the Float64 outputs
 *   OUT_DIR     folder of the result files (must exist)
 *   STATE_IN    a serialized FMU state written by another run (state.bin of
 *               the x86_64-linux run): restored and continued
 *
 * and, for each further group of seven arguments, a driven run (below).
 *
 * Result files, as harness.c's (CSV, 17 significant digits):
 *   default.csv       the default experiment (TDVASS, harmonic road, 0..15 s,
 *                     1 ms communication steps), from t = 0
 *   iso_c_cs.csv      CS on the ISO 8608 class C road, seed 7 (Enumerations
 *                     set with fmi3SetInt64, the seed with fmi3SetInt32)
 *   roundtrip.csv     default experiment to 5 s, fmi3GetFMUState, serialize,
 *                     free the instance, deserialize into a new instance,
 *                     fmi3SetFMUState, continue to 15 s (rows after 5 s)
 *   state.bin         the serialized state at 5 s of that run
 *   restored.csv      STATE_IN deserialized into a new instance, continued
 *   intermediate.csv  the default experiment's first INTERMEDIATE_STEPS
 *                     steps with an intermediate-update callback that reads
 *                     every output at every internal node it is called at:
 *                     time,<outputs> per call
 *   model_exchange.csv  the default experiment as Model Exchange
 *                     (fmi3InstantiateModelExchange): explicit Euler steps
 *                     of ME_STEP to ME_END, rows as harness.c's file of
 *                     the same name (the same run through FMI 3.0)
 *   drive_NAME.csv    a driven run, as harness.c's: the model TOKEN picks
 *                     (the quarter car, the corner or the chassis) from
 *                     t = 0 in 1 ms steps, the Float64 inputs INPUTS set
 *                     with fmi3SetFloat64 before every step from TABLE
 *                     (binary doubles, one row of inputs per step). FMI
 *                     3.0 has no input derivatives: DERIVATIVES must be
 *                     "-". MODE "cs": Co-Simulation, the outputs OUTPUTS
 *                     at t = 0 and after each step; "cs,VR" the same with
 *                     the Int32 parameter VR (input_extrapolation) set to
 *                     1 before initialization. MODE "me,NX,NZ":
 *                     Model Exchange of NX continuous states and NZ event
 *                     indicators (modelDescription.xml; checked against
 *                     fmi3GetNumberOfContinuousStates and
 *                     fmi3GetNumberOfEventIndicators), each step
 *                     integrated with DRIVE_SUBSTEPS explicit Euler steps
 *                     of 0.1 ms under the inputs held, events handled as
 *                     in model_exchange.csv; a row at t = 0 and after
 *                     each step of time, the states, their derivatives
 *                     there, the event indicators and the outputs.
 *
 * Exit code 0 when every file was written; 1 (message on stderr) when a call
 * did not return fmi3OK, fmi3DoStep did not reach the end of its step or
 * a Model Exchange run's NX or NZ is not the FMU's.
 *
 * One source for every platform and every model on purpose (each platform
 * compiles this one file): hence its length.
 */
#define __USE_MINGW_ANSI_STDIO 1 /* C99 printf on Windows: exact %.17g */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _WIN32
#include <windows.h>
#else
#include <dlfcn.h>
#endif

#include "fmi3_types.h"

/* Model Exchange (not in fmi3_types.h). */
typedef fmi3Instance (*fmi3InstantiateModelExchangeTYPE)(fmi3String instanceName,
                                                         fmi3String instantiationToken,
                                                         fmi3String resourcePath,
                                                         fmi3Boolean visible, fmi3Boolean loggingOn,
                                                         fmi3InstanceEnvironment instanceEnvironment,
                                                         fmi3LogMessageCallback logMessage);
typedef fmi3Status (*fmi3EnterEventModeTYPE)(fmi3Instance);
typedef fmi3Status (*fmi3UpdateDiscreteStatesTYPE)(fmi3Instance, fmi3Boolean *discreteStatesNeedUpdate,
                                                   fmi3Boolean *terminateSimulation,
                                                   fmi3Boolean *nominalsOfContinuousStatesChanged,
                                                   fmi3Boolean *valuesOfContinuousStatesChanged,
                                                   fmi3Boolean *nextEventTimeDefined,
                                                   fmi3Float64 *nextEventTime);
typedef fmi3Status (*fmi3EnterContinuousTimeModeTYPE)(fmi3Instance);
typedef fmi3Status (*fmi3CompletedIntegratorStepTYPE)(fmi3Instance,
                                                      fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                                      fmi3Boolean *enterEventMode,
                                                      fmi3Boolean *terminateSimulation);
typedef fmi3Status (*fmi3SetTimeTYPE)(fmi3Instance, fmi3Float64);
typedef fmi3Status (*fmi3SetContinuousStatesTYPE)(fmi3Instance, const fmi3Float64[], size_t);
typedef fmi3Status (*fmi3GetFloat64VectorTYPE)(fmi3Instance, fmi3Float64[], size_t);
typedef fmi3Status (*fmi3GetNumberTYPE)(fmi3Instance, size_t *);

static struct {
    fmi3InstantiateCoSimulationTYPE InstantiateCoSimulation;
    fmi3FreeInstanceTYPE FreeInstance;
    fmi3EnterInitializationModeTYPE EnterInitializationMode;
    fmi3ExitInitializationModeTYPE ExitInitializationMode;
    fmi3TerminateTYPE Terminate;
    fmi3GetFloat64TYPE GetFloat64;
    fmi3SetFloat64TYPE SetFloat64;
    fmi3SetInt32TYPE SetInt32;
    fmi3SetInt64TYPE SetInt64;
    fmi3GetFMUStateTYPE GetFMUState;
    fmi3SetFMUStateTYPE SetFMUState;
    fmi3FreeFMUStateTYPE FreeFMUState;
    fmi3SerializedFMUStateSizeTYPE SerializedFMUStateSize;
    fmi3SerializeFMUStateTYPE SerializeFMUState;
    fmi3DeserializeFMUStateTYPE DeserializeFMUState;
    fmi3DoStepTYPE DoStep;
    fmi3InstantiateModelExchangeTYPE InstantiateModelExchange;
    fmi3EnterEventModeTYPE EnterEventMode;
    fmi3UpdateDiscreteStatesTYPE UpdateDiscreteStates;
    fmi3EnterContinuousTimeModeTYPE EnterContinuousTimeMode;
    fmi3CompletedIntegratorStepTYPE CompletedIntegratorStep;
    fmi3SetTimeTYPE SetTime;
    fmi3SetContinuousStatesTYPE SetContinuousStates;
    fmi3GetFloat64VectorTYPE GetContinuousStateDerivatives;
    fmi3GetFloat64VectorTYPE GetEventIndicators;
    fmi3GetFloat64VectorTYPE GetContinuousStates;
    fmi3GetNumberTYPE GetNumberOfContinuousStates;
    fmi3GetNumberTYPE GetNumberOfEventIndicators;
} fmi;

/* Value references of the parameters the harness sets (the tests check
 * these names against modelDescription.xml). */
enum { VR_VARIANT = 1, VR_ROAD = 12, VR_ROAD_CLASS = 15, VR_ROAD_SEED = 18, VR_MAX_INTERNAL_STEP = 20 };
enum { VARIANT_CS = 1, ROAD_ISO8608 = 2, ROAD_CLASS_C = 3 };

#define STEP 1e-3               /* communication step, s */
#define STEPS 15000             /* 15 s, the DefaultExperiment */
#define SAVE_AT_STEP 5000       /* the state is saved at 5 s */
#define INTERMEDIATE_STEPS 100  /* steps run with the intermediate-update callback */
#define MAX_OUTPUTS 64
#define NX 20               /* Model Exchange: continuous states */
#define NZ 1                /* and event indicators */
#define ME_STEP 1e-4        /* the Euler step of the Model Exchange run, s */
#define ME_STEPS 10000      /* 1 s */
#define ME_ROW_EVERY 10     /* a row every 1 ms */
#define MAX_STATES 64       /* Model Exchange runs: continuous states */
#define MAX_INDICATORS 16   /* and event indicators */
_Static_assert(NX <= MAX_STATES && NZ <= MAX_INDICATORS, "the quarter car's states fit the arrays");

static const char *token;
static fmi3ValueReference outputs[MAX_OUTPUTS];
static size_t n_outputs;
static char last_message[1024];

static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
                   fmi3String message) {
    (void)env;
    (void)status;
    (void)category;
    snprintf(last_message, sizeof last_message, "%s", message);
}

static void fail(const char *what, int line) {
    fprintf(stderr, "harness_fmi3.c:%d: %s (last message: %s)\n", line, what, last_message);
    exit(1);
}

#define REQUIRE_OK(expr)                                                       \
    do {                                                                       \
        if ((expr) != fmi3OK) fail(#expr " did not return fmi3OK", __LINE__); \
    } while (0)

static void *symbol(void *library, const char *name) {
#ifdef _WIN32
    void *address = (void *)GetProcAddress((HMODULE)library, name);
#else
    void *address = dlsym(library, name);
#endif
    if (!address) {
        fprintf(stderr, "the library does not export %s\n", name);
        exit(2);
    }
    return address;
}

static void load(const char *path) {
#ifdef _WIN32
    void *library = (void *)LoadLibraryExA(path, NULL, LOAD_WITH_ALTERED_SEARCH_PATH);
    if (!library) {
        fprintf(stderr, "LoadLibraryEx %s failed: error %lu\n", path, GetLastError());
        exit(2);
    }
#else
    void *library = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!library) {
        fprintf(stderr, "dlopen: %s\n", dlerror());
        exit(2);
    }
#endif
#define SYM(field, name) memcpy(&fmi.field, &(void *){symbol(library, name)}, sizeof(void *))
    SYM(InstantiateCoSimulation, "fmi3InstantiateCoSimulation");
    SYM(FreeInstance, "fmi3FreeInstance");
    SYM(EnterInitializationMode, "fmi3EnterInitializationMode");
    SYM(ExitInitializationMode, "fmi3ExitInitializationMode");
    SYM(Terminate, "fmi3Terminate");
    SYM(GetFloat64, "fmi3GetFloat64");
    SYM(SetFloat64, "fmi3SetFloat64");
    SYM(SetInt32, "fmi3SetInt32");
    SYM(SetInt64, "fmi3SetInt64");
    SYM(GetFMUState, "fmi3GetFMUState");
    SYM(SetFMUState, "fmi3SetFMUState");
    SYM(FreeFMUState, "fmi3FreeFMUState");
    SYM(SerializedFMUStateSize, "fmi3SerializedFMUStateSize");
    SYM(SerializeFMUState, "fmi3SerializeFMUState");
    SYM(DeserializeFMUState, "fmi3DeserializeFMUState");
    SYM(DoStep, "fmi3DoStep");
    SYM(InstantiateModelExchange, "fmi3InstantiateModelExchange");
    SYM(EnterEventMode, "fmi3EnterEventMode");
    SYM(UpdateDiscreteStates, "fmi3UpdateDiscreteStates");
    SYM(EnterContinuousTimeMode, "fmi3EnterContinuousTimeMode");
    SYM(CompletedIntegratorStep, "fmi3CompletedIntegratorStep");
    SYM(SetTime, "fmi3SetTime");
    SYM(SetContinuousStates, "fmi3SetContinuousStates");
    SYM(GetContinuousStateDerivatives, "fmi3GetContinuousStateDerivatives");
    SYM(GetEventIndicators, "fmi3GetEventIndicators");
    SYM(GetContinuousStates, "fmi3GetContinuousStates");
    SYM(GetNumberOfContinuousStates, "fmi3GetNumberOfContinuousStates");
    SYM(GetNumberOfEventIndicators, "fmi3GetNumberOfEventIndicators");
#undef SYM
}

static FILE *open_file(const char *dir, const char *name, const char *mode) {
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *file = fopen(path, mode);
    if (!file) {
        fprintf(stderr, "cannot open %s\n", path);
        exit(2);
    }
    return file;
}

/* ------------------------------------------------------- good experiments */

/* The instance and, while the callback runs, where it writes. */
typedef struct {
    fmi3Instance instance;
    FILE *csv;
    long calls;
} Environment;

static void write_values(FILE *csv, fmi3Instance c, double time) {
    fmi3Float64 values[MAX_OUTPUTS];
    REQUIRE_OK(fmi.GetFloat64(c, outputs, n_outputs, values, n_outputs));
    fprintf(csv, "%.17g", time);
    for (size_t i = 0; i < n_outputs; i++) fprintf(csv, ",%.17g", values[i]);
    fprintf(csv, "\n");
}

/* Reads every output at every internal node (Intermediate Update Mode). */
static void intermediate_update(fmi3InstanceEnvironment env, fmi3Float64 time, fmi3Boolean set_requested,
                                fmi3Boolean get_allowed, fmi3Boolean step_finished,
                                fmi3Boolean can_return_early, fmi3Boolean *early_return_requested,
                                fmi3Float64 *early_return_time) {
    (void)set_requested;
    (void)step_finished;
    (void)can_return_early;
    (void)early_return_time;
    Environment *e = env;
    *early_return_requested = false;
    e->calls++;
    if (get_allowed && e->csv) write_values(e->csv, e->instance, time);
}

/* Int64 (Enumerations), Int32 and Float64 parameters set before
 * initialization. */
typedef struct {
    size_t count;
    fmi3ValueReference vrs[3];
    fmi3Int64 values[3];
    fmi3Int32 seed; /* road_seed, when > 0 */
    fmi3Float64 max_internal_step; /* when > 0 */
    fmi3ValueReference extrapolation; /* input_extrapolation's, set to 1, when > 0 */
} Parameters;

static const Parameters defaults = {0, {0}, {0}, 0, 0.0, 0};

static fmi3Instance initialized(const char *name, const Parameters *parameters, Environment *env) {
    fmi3Instance c = fmi.InstantiateCoSimulation(
        name, token, NULL, false, false, false, false, env ? outputs : NULL, env ? n_outputs : 0,
        env, logger, env ? intermediate_update : NULL);
    if (!c) fail("fmi3InstantiateCoSimulation returned NULL", __LINE__);
    if (env) env->instance = c;
    if (parameters->count)
        REQUIRE_OK(fmi.SetInt64(c, parameters->vrs, parameters->count, parameters->values,
                                parameters->count));
    if (parameters->seed > 0) {
        const fmi3ValueReference vr = VR_ROAD_SEED;
        REQUIRE_OK(fmi.SetInt32(c, &vr, 1, &parameters->seed, 1));
    }
    if (parameters->max_internal_step > 0.0) {
        const fmi3ValueReference vr = VR_MAX_INTERNAL_STEP;
        REQUIRE_OK(fmi.SetFloat64(c, &vr, 1, &parameters->max_internal_step, 1));
    }
    if (parameters->extrapolation > 0) {
        const fmi3Int32 one = 1;
        REQUIRE_OK(fmi.SetInt32(c, &parameters->extrapolation, 1, &one, 1));
    }
    REQUIRE_OK(fmi.EnterInitializationMode(c, false, 0.0, 0.0, true, STEPS * STEP));
    REQUIRE_OK(fmi.ExitInitializationMode(c));
    return c;
}

static void write_header(FILE *csv) {
    fprintf(csv, "time");
    for (size_t i = 0; i < n_outputs; i++) fprintf(csv, ",%u", (unsigned)outputs[i]);
    fprintf(csv, "\n");
}

/* Communication steps `from` .. `to - 1`, a row after each (when csv). */
static void run_steps(fmi3Instance c, FILE *csv, int from, int to) {
    for (int k = from; k < to; k++) {
        fmi3Boolean event = true, terminate = true, early = true;
        fmi3Float64 last = -1.0;
        REQUIRE_OK(fmi.DoStep(c, k * STEP, STEP, true, &event, &terminate, &early, &last));
        if (event || terminate || early || last != k * STEP + STEP)
            fail("fmi3DoStep did not complete its step", __LINE__);
        if (csv) write_values(csv, c, (k + 1) * STEP);
    }
}

static void finish(fmi3Instance c) {
    REQUIRE_OK(fmi.Terminate(c));
    fmi.FreeInstance(c);
}

static void experiment(const char *dir, const char *file, const Parameters *parameters) {
    FILE *csv = open_file(dir, file, "wb");
    write_header(csv);
    fmi3Instance c = initialized(file, parameters, NULL);
    write_values(csv, c, 0.0);
    run_steps(c, csv, 0, STEPS);
    finish(c);
    fclose(csv);
}

/* Deserializes `bytes` into a new, initialized instance and continues it
 * from SAVE_AT_STEP to the end. */
static void continue_from(const char *dir, const char *file, const fmi3Byte *bytes, size_t size) {
    fmi3Instance c = initialized(file, &defaults, NULL);
    fmi3FMUState state = NULL;
    REQUIRE_OK(fmi.DeserializeFMUState(c, bytes, size, &state));
    REQUIRE_OK(fmi.SetFMUState(c, state));
    REQUIRE_OK(fmi.FreeFMUState(c, &state));
    if (state) fail("fmi3FreeFMUState left the state pointer set", __LINE__);
    FILE *csv = open_file(dir, file, "wb");
    write_header(csv);
    run_steps(c, csv, SAVE_AT_STEP, STEPS);
    fclose(csv);
    finish(c);
}

/* The serialized state of the default experiment at SAVE_AT_STEP; the
 * instance that wrote it is freed before returning. */
static fmi3Byte *saved_state(size_t *size) {
    fmi3Instance c = initialized("save", &defaults, NULL);
    run_steps(c, NULL, 0, SAVE_AT_STEP);
    fmi3FMUState state = NULL;
    REQUIRE_OK(fmi.GetFMUState(c, &state));
    REQUIRE_OK(fmi.SerializedFMUStateSize(c, state, size));
    fmi3Byte *bytes = malloc(*size);
    if (!bytes) fail("out of memory", __LINE__);
    REQUIRE_OK(fmi.SerializeFMUState(c, state, bytes, *size));
    REQUIRE_OK(fmi.FreeFMUState(c, &state));
    finish(c);
    return bytes;
}

static fmi3Byte *read_file(const char *path, size_t *size) {
    FILE *file = fopen(path, "rb");
    if (!file) {
        fprintf(stderr, "cannot open %s\n", path);
        exit(2);
    }
    size_t capacity = 1 << 16;
    fmi3Byte *bytes = malloc(capacity);
    *size = 0;
    size_t n;
    while (bytes && (n = fread(bytes + *size, 1, capacity - *size, file)) > 0) {
        *size += n;
        if (*size == capacity) bytes = realloc(bytes, capacity *= 2);
    }
    if (!bytes) fail("out of memory", __LINE__);
    fclose(file);
    return bytes;
}

/* The default experiment's first steps with the callback reading outputs,
 * on internal nodes every 0.1 ms (max_internal_step): nine inside each
 * 1 ms step. */
static long intermediate(const char *dir) {
    Environment env = {NULL, NULL, 0};
    env.csv = open_file(dir, "intermediate.csv", "wb");
    write_header(env.csv);
    const Parameters fine = {0, {0}, {0}, 0, 1e-4, 0};
    fmi3Instance c = initialized("intermediate", &fine, &env);
    run_steps(c, NULL, 0, INTERMEDIATE_STEPS);
    finish(c);
    fclose(env.csv);
    return env.calls;
}

/* ------------------------------------------------------- Model Exchange */

/* Event iteration: discrete-state updates until none is needed. */
static void event_iteration(fmi3Instance c) {
    int k = 0;
    fmi3Boolean again;
    do {
        fmi3Boolean terminate = true, nominals = true, values = true, defined = true;
        fmi3Float64 next = -1.0;
        again = true;
        REQUIRE_OK(fmi.UpdateDiscreteStates(c, &again, &terminate, &nominals, &values, &defined, &next));
        if (terminate) fail("fmi3UpdateDiscreteStates: terminateSimulation", __LINE__);
        if (++k > 10) fail("the event iteration does not end", __LINE__);
    } while (again);
}

/* A Model Exchange instance of the model `token` picks, initialized: in
 * Event Mode. */
static fmi3Instance model_exchange_instance(const char *name) {
    fmi3Instance c = fmi.InstantiateModelExchange(name, token, NULL, false, false, NULL, logger);
    if (!c) fail("fmi3InstantiateModelExchange returned NULL", __LINE__);
    REQUIRE_OK(fmi.EnterInitializationMode(c, false, 0.0, 0.0, true, STEPS * STEP));
    REQUIRE_OK(fmi.ExitInitializationMode(c));
    return c;
}

/* One explicit Euler step of `h` to the time `t` (Continuous-Time Mode)
 * of `nx` states and `nz` event indicators: the derivatives at the start
 * of the step in `dx`, the indicators there in `z`, replaced by those at
 * its end. An event (the FMU asks for one, or an indicator changes sign)
 * is handled in Event Mode. Returns whether there was one. */
static int euler_step(fmi3Instance c, double h, double t, size_t nx, size_t nz, fmi3Float64 *dx, fmi3Float64 *z) {
    fmi3Float64 x[MAX_STATES], z_end[MAX_INDICATORS];
    REQUIRE_OK(fmi.GetContinuousStates(c, x, nx));
    REQUIRE_OK(fmi.GetContinuousStateDerivatives(c, dx, nx));
    for (size_t i = 0; i < nx; i++) x[i] += h * dx[i];
    REQUIRE_OK(fmi.SetTime(c, t));
    REQUIRE_OK(fmi.SetContinuousStates(c, x, nx));
    REQUIRE_OK(fmi.GetEventIndicators(c, z_end, nz));
    fmi3Boolean enter = true, terminate = true;
    REQUIRE_OK(fmi.CompletedIntegratorStep(c, true, &enter, &terminate));
    if (terminate) fail("fmi3CompletedIntegratorStep: terminateSimulation", __LINE__);
    for (size_t i = 0; i < nz; i++) enter = enter || (z_end[i] > 0) != (z[i] > 0);
    if (enter) {
        REQUIRE_OK(fmi.EnterEventMode(c));
        event_iteration(c);
        REQUIRE_OK(fmi.EnterContinuousTimeMode(c));
        REQUIRE_OK(fmi.GetEventIndicators(c, z_end, nz));
    }
    memcpy(z, z_end, nz * sizeof *z);
    return enter;
}

/* The header of a Model Exchange file: x0.., der_x0.., z0.., the outputs. */
static void model_exchange_header(FILE *csv, size_t nx, size_t nz) {
    fprintf(csv, "time");
    for (size_t i = 0; i < nx; i++) fprintf(csv, ",x%zu", i);
    for (size_t i = 0; i < nx; i++) fprintf(csv, ",der_x%zu", i);
    for (size_t i = 0; i < nz; i++) fprintf(csv, ",z%zu", i);
    for (size_t i = 0; i < n_outputs; i++) fprintf(csv, ",%u", (unsigned)outputs[i]);
    fprintf(csv, "\n");
}

static void model_exchange_row(FILE *csv, fmi3Instance c, double t, size_t nx, size_t nz, const fmi3Float64 *dx) {
    fmi3Float64 x[MAX_STATES], z[MAX_INDICATORS], values[MAX_OUTPUTS];
    REQUIRE_OK(fmi.GetContinuousStates(c, x, nx));
    REQUIRE_OK(fmi.GetEventIndicators(c, z, nz));
    REQUIRE_OK(fmi.GetFloat64(c, outputs, n_outputs, values, n_outputs));
    fprintf(csv, "%.17g", t);
    for (size_t i = 0; i < nx; i++) fprintf(csv, ",%.17g", x[i]);
    for (size_t i = 0; i < nx; i++) fprintf(csv, ",%.17g", dx[i]);
    for (size_t i = 0; i < nz; i++) fprintf(csv, ",%.17g", z[i]);
    for (size_t i = 0; i < n_outputs; i++) fprintf(csv, ",%.17g", values[i]);
    fprintf(csv, "\n");
}

static void model_exchange(const char *dir) {
    FILE *csv = open_file(dir, "model_exchange.csv", "wb");
    model_exchange_header(csv, NX, NZ);
    fmi3Instance c = model_exchange_instance("model_exchange");
    event_iteration(c);
    REQUIRE_OK(fmi.EnterContinuousTimeMode(c));
    fmi3Float64 dx[NX], z[NZ];
    REQUIRE_OK(fmi.GetContinuousStateDerivatives(c, dx, NX));
    REQUIRE_OK(fmi.GetEventIndicators(c, z, NZ));
    double t = 0.0;
    model_exchange_row(csv, c, t, NX, NZ, dx);
    for (int k = 1; k <= ME_STEPS; k++) {
        t += ME_STEP;
        euler_step(c, ME_STEP, t, NX, NZ, dx, z);
        if (k % ME_ROW_EVERY == 0) model_exchange_row(csv, c, t, NX, NZ, dx);
    }
    REQUIRE_OK(fmi.EnterEventMode(c));
    event_iteration(c);
    finish(c);
    fclose(csv);
}

/* ------------------------------------------------------------------- main */

/* Comma-separated value references into `vrs` (at most `max`); "-" is
 * none. Returns how many. */
static size_t parse_vrs(const char *what, const char *list, fmi3ValueReference *vrs, size_t max) {
    size_t n = 0;
    if (strcmp(list, "-") == 0) return 0;
    const char *p = list;
    while (*p) {
        char *end;
        unsigned long vr = strtoul(p, &end, 10);
        if (end == p || n == max) {
            fprintf(stderr, "bad %s `%s`\n", what, list);
            exit(2);
        }
        vrs[n++] = (fmi3ValueReference)vr;
        p = *end == ',' ? end + 1 : end;
    }
    return n;
}

static void parse_outputs(const char *list) {
    n_outputs = parse_vrs("OUTPUT_VRS", list, outputs, MAX_OUTPUTS);
    if (n_outputs == 0) {
        fprintf(stderr, "OUTPUT_VRS is empty\n");
        exit(2);
    }
}

/* ------------------------------------------------------------ driven runs */

#define MAX_INPUTS 16
#define DRIVE_ARGS 7 /* NAME TOKEN OUTPUTS INPUTS DERIVATIVES TABLE MODE */
#define DRIVE_SUBSTEPS 10 /* Model Exchange: Euler steps per 1 ms step, of 0.1 ms */

/* MODE of a driven run: "cs" (Co-Simulation), "cs,VR" (input_extrapolation
 * VR set to 1) or "me,NX,NZ" (Model
 * Exchange of NX continuous states and NZ event indicators). */
typedef struct {
    bool model_exchange;
    size_t nx, nz;
    unsigned long extrapolation_vr; /* "cs,VR": input_extrapolation's VR, set to 1; else 0 */
} Mode;

static Mode parse_mode(const char *text) {
    Mode mode = {false, 0, 0, 0};
    if (strcmp(text, "cs") == 0) return mode;
    unsigned long nx = 0, nz = 0;
    char end = 0;
    if (sscanf(text, "cs,%lu%c", &mode.extrapolation_vr, &end) == 1 && mode.extrapolation_vr > 0) return mode;
    if (sscanf(text, "me,%lu,%lu%c", &nx, &nz, &end) != 2) {
        fprintf(stderr, "bad MODE `%s`: cs, cs,VR or me,NX,NZ\n", text);
        exit(2);
    }
    if (nx > MAX_STATES || nz > MAX_INDICATORS) {
        fprintf(stderr, "MODE `%s`: at most %d continuous states and %d event indicators (harness_fmi3.c)\n", text,
                MAX_STATES, MAX_INDICATORS);
        exit(2);
    }
    mode.model_exchange = true;
    mode.nx = nx;
    mode.nz = nz;
    return mode;
}

/* A Model Exchange instance of a driven run in Continuous-Time Mode, its
 * numbers of states and event indicators checked against `mode`. */
static fmi3Instance driven_model_exchange(const char *name, Mode mode) {
    fmi3Instance c = model_exchange_instance(name);
    event_iteration(c);
    REQUIRE_OK(fmi.EnterContinuousTimeMode(c));
    size_t nx = 0, nz = 0;
    REQUIRE_OK(fmi.GetNumberOfContinuousStates(c, &nx));
    REQUIRE_OK(fmi.GetNumberOfEventIndicators(c, &nz));
    if (nx != mode.nx || nz != mode.nz) {
        fprintf(stderr, "harness_fmi3.c: %s: %zu continuous states and %zu event indicators, MODE says %zu and %zu\n",
                name, nx, nz, mode.nx, mode.nz);
        exit(1);
    }
    return c;
}

/* One driven run (drive_NAME.csv in `dir`); sets `token` and the outputs. */
static void drive(const char *dir, char **args) {
    const char *name = args[0];
    token = args[1];
    parse_outputs(args[2]);
    fmi3ValueReference inputs[MAX_INPUTS], derivatives[MAX_INPUTS];
    const size_t n_inputs = parse_vrs("INPUTS", args[3], inputs, MAX_INPUTS);
    if (parse_vrs("DERIVATIVES", args[4], derivatives, MAX_INPUTS) != 0) {
        fprintf(stderr, "FMI 3.0 has no input derivatives: DERIVATIVES must be -\n");
        exit(2);
    }
    const Mode mode = parse_mode(args[6]);
    size_t size = 0;
    fmi3Byte *table = read_file(args[5], &size);
    if (n_inputs == 0 || size == 0 || size % (n_inputs * sizeof(double)) != 0) {
        fprintf(stderr, "TABLE %s: %zu bytes is not a whole number of rows of %zu doubles\n", args[5], size,
                n_inputs);
        exit(2);
    }
    const size_t steps = size / (n_inputs * sizeof(double));

    char file[256];
    snprintf(file, sizeof file, "drive_%s.csv", name);
    FILE *csv = open_file(dir, file, "wb");
    fmi3Instance c;
    fmi3Float64 dx[MAX_STATES], z[MAX_INDICATORS]; /* Model Exchange */
    if (mode.model_exchange) {
        model_exchange_header(csv, mode.nx, mode.nz);
        c = driven_model_exchange(file, mode);
        REQUIRE_OK(fmi.GetContinuousStateDerivatives(c, dx, mode.nx));
        REQUIRE_OK(fmi.GetEventIndicators(c, z, mode.nz));
        model_exchange_row(csv, c, 0.0, mode.nx, mode.nz, dx);
    } else {
        write_header(csv);
        const Parameters extrapolating = {0, {0}, {0}, 0, 0.0, (fmi3ValueReference)mode.extrapolation_vr};
        c = initialized(file, &extrapolating, NULL);
        write_values(csv, c, 0.0);
    }
    size_t events = 0;
    for (size_t k = 0; k < steps; k++) {
        fmi3Float64 values[MAX_INPUTS];
        memcpy(values, table + k * n_inputs * sizeof(double), n_inputs * sizeof(double));
        REQUIRE_OK(fmi.SetFloat64(c, inputs, n_inputs, values, n_inputs));
        const double t = (double)(k + 1) * STEP;
        if (mode.model_exchange) {
            /* Euler steps to t_k + j STEP / DRIVE_SUBSTEPS: the last ends at t exactly. */
            double now = (double)k * STEP;
            for (int j = 1; j <= DRIVE_SUBSTEPS; j++) {
                const double next = ((double)k + (double)j / DRIVE_SUBSTEPS) * STEP;
                events += euler_step(c, next - now, next, mode.nx, mode.nz, dx, z);
                now = next;
            }
            REQUIRE_OK(fmi.GetContinuousStateDerivatives(c, dx, mode.nx)); /* the row's: at t */
            model_exchange_row(csv, c, t, mode.nx, mode.nz, dx);
        } else {
            fmi3Boolean event = true, terminate = true, early = true;
            fmi3Float64 last = -1.0;
            REQUIRE_OK(fmi.DoStep(c, (double)k * STEP, STEP, true, &event, &terminate, &early, &last));
            if (event || terminate || early || last != (double)k * STEP + STEP)
                fail("fmi3DoStep did not complete its step", __LINE__);
            write_values(csv, c, t);
        }
    }
    finish(c);
    fclose(csv);
    free(table);
    printf("harness_fmi3: drive %s: %zu outputs x %zu steps, %zu inputs", name, n_outputs, steps, n_inputs);
    if (mode.model_exchange)
        printf(", Model Exchange: %zu states, %zu event indicators, %zu events", mode.nx, mode.nz, events);
    printf("\n");
}

int main(int argc, char **argv) {
    if (argc < 6 || (argc - 6) % DRIVE_ARGS != 0) {
        fprintf(stderr,
                "usage: %s LIB TOKEN OUTPUT_VRS OUT_DIR STATE_IN"
                " [NAME TOKEN OUTPUTS INPUTS DERIVATIVES TABLE MODE]...\n",
                argv[0]);
        return 2;
    }
    load(argv[1]);
    token = argv[2];
    parse_outputs(argv[3]);
    const char *dir = argv[4];

    experiment(dir, "default.csv", &defaults);
    static const Parameters iso_c_cs = {
        3, {VR_VARIANT, VR_ROAD, VR_ROAD_CLASS}, {VARIANT_CS, ROAD_ISO8608, ROAD_CLASS_C}, 7, 0.0, 0};
    experiment(dir, "iso_c_cs.csv", &iso_c_cs);

    size_t size = 0;
    fmi3Byte *state = saved_state(&size);
    FILE *file = open_file(dir, "state.bin", "wb");
    if (fwrite(state, 1, size, file) != size) fail("cannot write state.bin", __LINE__);
    fclose(file);
    continue_from(dir, "roundtrip.csv", state, size);
    free(state);

    size_t foreign_size = 0;
    fmi3Byte *foreign = read_file(argv[5], &foreign_size);
    continue_from(dir, "restored.csv", foreign, foreign_size);
    free(foreign);

    long calls = intermediate(dir);
    model_exchange(dir);
    printf("harness_fmi3: %zu outputs x %d steps, state of %zu bytes, %ld intermediate updates, results in %s\n",
           n_outputs, STEPS, size, calls, dir);
    for (int i = 6; i < argc; i += DRIVE_ARGS) drive(dir, argv + i); /* last: they set token, outputs */
    return 0;
}
