/*
 * Platform-neutral harness of the tdvass FMI 2.0 library: the same source is
 * compiled natively for Linux x86-64, with MinGW-w64 for Windows x86-64 (run
 * under wine) and with the aarch64 GNU toolchain (run under qemu-user). It
 * loads one platform's library and writes what it computed as files, which
 * the tests (test_platforms.py) compare with the native Linux x86-64 run.
 * One source file on purpose (one compiler call per platform, no build
 * system): hence its length.
 *
 *   harness LIB GUID OUTPUT_VRS OUT_DIR STATE_IN [NAME TOKEN OUTPUTS INPUTS DERIVATIVES TABLE MODE]...
 *
 *   LIB         the library (binaries/<platform>/tdvass.so or .dll)
 *   GUID        the FMU's GUID (modelDescription.xml)
 *   OUTPUT_VRS  comma-separated value references of the outputs to record
 *   OUT_DIR     folder of the result files (must exist)
 *   STATE_IN    a serialized FMU state written by another run (state.bin of
 *               the linux64 run): restored and continued
 *
 * and, for each further group of seven arguments, a driven run (below).
 *
 * Result files (CSV: header line, then one line per communication point with
 * time in s and the outputs in SI units, each printed with 17 significant
 * digits, which round-trips an IEEE double exactly):
 *   default.csv       the default experiment (TDVASS, harmonic road,
 *                     0..15 s, 1 ms communication steps), from t = 0
 *   iso_c_cs.csv      CS on the ISO 8608 class C road, seed 7, same grid
 *   roundtrip.csv     default experiment to 5 s, serialize, free the
 *                     instance, deserialize into a new instance, continue
 *                     to 15 s (rows after 5 s)
 *   state.bin         the serialized state at 5 s of that run
 *   restored.csv      STATE_IN deserialized into a new instance, continued
 *                     from 5 s to 15 s
 *   model_exchange.csv  the default experiment as Model Exchange: explicit
 *                     Euler steps of ME_STEP from 0 to ME_END (the master's
 *                     own integrator), a row every ME_ROW_EVERY steps with
 *                     time, the 20 continuous states, their derivatives, the
 *                     event indicator and the outputs
 *   bad_input.csv     case,result,message: each refused call, its status
 *                     (0 OK .. 4 Fatal, or NULL/instance for fmi2Instantiate)
 *                     and the last message logged for it
 *   drive_NAME.csv    a driven run: the model of the library that TOKEN
 *                     (GUID) picks (the quarter car, the corner or the
 *                     chassis, whose FMUs carry this library) from t = 0
 *                     in 1 ms steps. Before step k it sets the inputs
 *                     INPUTS with fmi2SetReal and the order-1 derivatives
 *                     of the inputs DERIVATIVES ("-" for none) with
 *                     fmi2SetRealInputDerivatives, from TABLE: binary
 *                     doubles in the machine's byte order, per step the
 *                     inputs, then the derivatives; its length gives the
 *                     number of steps. The values come from a file, not
 *                     from a formula here, so that every platform's run
 *                     gets the same bits (the C libraries' sin differ).
 *                     MODE "cs": Co-Simulation, a row of time and the
 *                     outputs OUTPUTS (value references) at t = 0 and
 *                     after each step; "cs,VR" the same with the Integer
 *                     parameter VR (input_extrapolation) set to 1 before
 *                     initialization. MODE "me,NX,NZ": Model Exchange of
 *                     NX continuous states and NZ event indicators (the
 *                     FMU's modelDescription.xml), each step integrated
 *                     with DRIVE_SUBSTEPS explicit Euler steps of 0.1 ms,
 *                     events handled as in model_exchange.csv; the inputs
 *                     hold over the step (input derivatives are
 *                     Co-Simulation only: DERIVATIVES must be "-"). A row
 *                     at t = 0 and after each step of time, the states,
 *                     their derivatives there, the event indicators and
 *                     the outputs OUTPUTS.
 *
 * Exit code 0 when every file was written; 1 (message on stderr) when a call
 * of the good experiments did not return fmi2OK. Bad input is judged by the
 * tests, not here: the harness records what it observed.
 *
 * One source for every platform and every model on purpose (each platform
 * compiles this one file): hence its length.
 */
#define __USE_MINGW_ANSI_STDIO 1 /* C99 printf on Windows: exact %.17g */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _WIN32
#include <windows.h>
#else
#include <dlfcn.h>
#endif

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
    fmi2Status (*SetRealInputDerivatives)(fmi2Component, const fmi2ValueReference *, size_t,
                                          const fmi2Integer *, const fmi2Real *);
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
} fmi;

/* Value references of the inputs the harness sets (modelDescription.xml;
 * the tests check these names against the description). */
enum {
    VR_VARIANT = 1,
    VR_G = 10,
    VR_TAU = 11,
    VR_ROAD = 12,
    VR_ROAD_CLASS = 15,
    VR_ROAD_SEED = 18,
    VR_X_S = 31,
    VR_UNKNOWN = 9999
};
enum { VARIANT_CS = 1, ROAD_ISO8608 = 2, ROAD_CLASS_C = 3 };

#define STEP 1e-3          /* communication step, s */
#define STEPS 15000        /* 15 s, the DefaultExperiment */
#define SAVE_AT_STEP 5000  /* the state is saved at 5 s */
#define MAX_OUTPUTS 64
#define NX 20               /* Model Exchange: continuous states */
#define NZ 1                /* and event indicators */
#define ME_STEP 1e-4        /* the Euler step of the Model Exchange run, s */
#define ME_STEPS 10000      /* 1 s */
#define ME_ROW_EVERY 10     /* a row every 1 ms */
#define MAX_STATES 64       /* Model Exchange runs: continuous states */
#define MAX_INDICATORS 16   /* and event indicators */
_Static_assert(NX <= MAX_STATES && NZ <= MAX_INDICATORS, "the quarter car's states fit the arrays");

static const char *guid;
static fmi2ValueReference outputs[MAX_OUTPUTS];
static size_t n_outputs;
static char last_message[1024];

/* The FMU's messages are format strings (FMI 2.0); keep the last one. */
static void logger(void *env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env;
    (void)name;
    (void)status;
    (void)category;
    va_list args;
    va_start(args, message);
    vsnprintf(last_message, sizeof last_message, message, args);
    va_end(args);
}

static const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};

static void fail(const char *what, int line) {
    fprintf(stderr, "harness.c:%d: %s (last message: %s)\n", line, what, last_message);
    exit(1);
}

#define REQUIRE_OK(expr)                                              \
    do {                                                              \
        if ((expr) != fmi2OK) fail(#expr " did not return fmi2OK", __LINE__); \
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
    /* Dependencies are looked up in the DLL's own folder, then as usual. */
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
    /* Function pointers from data pointers: the loaders return them so. */
#define SYM(field, name) memcpy(&fmi.field, &(void *){symbol(library, name)}, sizeof(void *))
    SYM(Instantiate, "fmi2Instantiate");
    SYM(FreeInstance, "fmi2FreeInstance");
    SYM(SetupExperiment, "fmi2SetupExperiment");
    SYM(EnterInitializationMode, "fmi2EnterInitializationMode");
    SYM(ExitInitializationMode, "fmi2ExitInitializationMode");
    SYM(Terminate, "fmi2Terminate");
    SYM(GetReal, "fmi2GetReal");
    SYM(SetReal, "fmi2SetReal");
    SYM(SetInteger, "fmi2SetInteger");
    SYM(SetRealInputDerivatives, "fmi2SetRealInputDerivatives");
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

/* Integer parameters set before initialization. */
typedef struct {
    size_t count;
    fmi2ValueReference vrs[4];
    fmi2Integer values[4];
} Integers;

static fmi2Component initialized(const char *name, const Integers *integers) {
    fmi2Component c = fmi.Instantiate(name, fmi2CoSimulation, guid, NULL, &callbacks, 0, 0);
    if (!c) fail("fmi2Instantiate returned NULL", __LINE__);
    if (integers->count) REQUIRE_OK(fmi.SetInteger(c, integers->vrs, integers->count, integers->values));
    REQUIRE_OK(fmi.SetupExperiment(c, 0, 0.0, 0.0, 1, STEPS * STEP));
    REQUIRE_OK(fmi.EnterInitializationMode(c));
    REQUIRE_OK(fmi.ExitInitializationMode(c));
    return c;
}

static void write_header(FILE *csv) {
    fprintf(csv, "time");
    for (size_t i = 0; i < n_outputs; i++) fprintf(csv, ",%u", outputs[i]);
    fprintf(csv, "\n");
}

static void write_row(FILE *csv, fmi2Component c, double time) {
    fmi2Real values[MAX_OUTPUTS];
    REQUIRE_OK(fmi.GetReal(c, outputs, n_outputs, values));
    fprintf(csv, "%.17g", time);
    for (size_t i = 0; i < n_outputs; i++) fprintf(csv, ",%.17g", values[i]);
    fprintf(csv, "\n");
}

/* Communication steps `from` .. `to - 1`, a row after each (when csv). */
static void run_steps(fmi2Component c, FILE *csv, int from, int to) {
    for (int k = from; k < to; k++) {
        REQUIRE_OK(fmi.DoStep(c, k * STEP, STEP, 1));
        if (csv) write_row(csv, c, (k + 1) * STEP);
    }
}

static void finish(fmi2Component c) {
    REQUIRE_OK(fmi.Terminate(c));
    fmi.FreeInstance(c);
}

static void experiment(const char *dir, const char *file, const Integers *integers) {
    FILE *csv = open_file(dir, file, "wb");
    write_header(csv);
    fmi2Component c = initialized(file, integers);
    write_row(csv, c, 0.0);
    run_steps(c, csv, 0, STEPS);
    finish(c);
    fclose(csv);
}

/* Deserializes `bytes` into a new, initialized instance and continues it
 * from SAVE_AT_STEP to the end. */
static void continue_from(const char *dir, const char *file, const fmi2Byte *bytes, size_t size) {
    static const Integers defaults = {0, {0}, {0}};
    fmi2Component c = initialized(file, &defaults);
    fmi2FMUstate state = NULL;
    REQUIRE_OK(fmi.DeSerializeFMUstate(c, bytes, size, &state));
    REQUIRE_OK(fmi.SetFMUstate(c, state));
    REQUIRE_OK(fmi.FreeFMUstate(c, &state));
    FILE *csv = open_file(dir, file, "wb");
    write_header(csv);
    run_steps(c, csv, SAVE_AT_STEP, STEPS);
    fclose(csv);
    finish(c);
}

/* The serialized state of the default experiment at SAVE_AT_STEP; the
 * instance that wrote it is freed before returning. */
static fmi2Byte *saved_state(size_t *size) {
    static const Integers defaults = {0, {0}, {0}};
    fmi2Component c = initialized("save", &defaults);
    run_steps(c, NULL, 0, SAVE_AT_STEP);
    fmi2FMUstate state = NULL;
    REQUIRE_OK(fmi.GetFMUstate(c, &state));
    REQUIRE_OK(fmi.SerializedFMUstateSize(c, state, size));
    fmi2Byte *bytes = malloc(*size);
    if (!bytes) fail("out of memory", __LINE__);
    REQUIRE_OK(fmi.SerializeFMUstate(c, state, bytes, *size));
    REQUIRE_OK(fmi.FreeFMUstate(c, &state));
    finish(c);
    return bytes;
}

/* ------------------------------------------------------- Model Exchange */

/* A Model Exchange instance of the default experiment, in Event Mode. */
static fmi2Component model_exchange_instance(const char *name) {
    fmi2Component c = fmi.Instantiate(name, fmi2ModelExchange, guid, NULL, &callbacks, 0, 0);
    if (!c) fail("fmi2Instantiate(fmi2ModelExchange) returned NULL", __LINE__);
    REQUIRE_OK(fmi.SetupExperiment(c, 0, 0.0, 0.0, 1, STEPS * STEP));
    REQUIRE_OK(fmi.EnterInitializationMode(c));
    REQUIRE_OK(fmi.ExitInitializationMode(c));
    return c;
}

/* Event iteration: new discrete states until none are needed. */
static void event_iteration(fmi2Component c) {
    fmi2EventInfo info;
    int k = 0;
    do {
        REQUIRE_OK(fmi.NewDiscreteStates(c, &info));
        if (info.terminateSimulation) fail("fmi2NewDiscreteStates: terminateSimulation", __LINE__);
        if (++k > 10) fail("the event iteration does not end", __LINE__);
    } while (info.newDiscreteStatesNeeded);
}

/* One explicit Euler step of `h` to the time `t` (Continuous-Time Mode)
 * of `nx` states and `nz` event indicators: the derivatives at the start
 * of the step in `dx`, the indicators there in `z`, replaced by those at
 * its end. An event (the FMU asks for one, or an indicator changes sign)
 * is handled in Event Mode. Returns whether there was one. */
static int euler_step(fmi2Component c, double h, double t, size_t nx, size_t nz, fmi2Real *dx, fmi2Real *z) {
    fmi2Real x[MAX_STATES], z_end[MAX_INDICATORS];
    REQUIRE_OK(fmi.GetContinuousStates(c, x, nx));
    REQUIRE_OK(fmi.GetDerivatives(c, dx, nx));
    for (size_t i = 0; i < nx; i++) x[i] += h * dx[i];
    REQUIRE_OK(fmi.SetTime(c, t));
    REQUIRE_OK(fmi.SetContinuousStates(c, x, nx));
    REQUIRE_OK(fmi.GetEventIndicators(c, z_end, nz));
    fmi2Boolean enter = 1, terminate = 1;
    REQUIRE_OK(fmi.CompletedIntegratorStep(c, 1, &enter, &terminate));
    if (terminate) fail("fmi2CompletedIntegratorStep: terminateSimulation", __LINE__);
    for (size_t i = 0; i < nz; i++) enter |= (z_end[i] > 0) != (z[i] > 0);
    if (enter) {
        REQUIRE_OK(fmi.EnterEventMode(c));
        event_iteration(c);
        REQUIRE_OK(fmi.EnterContinuousTimeMode(c));
        REQUIRE_OK(fmi.GetEventIndicators(c, z_end, nz));
    }
    memcpy(z, z_end, nz * sizeof *z);
    return enter != 0;
}

/* The header of a Model Exchange file: x0.., der_x0.., z0.., the outputs. */
static void model_exchange_header(FILE *csv, size_t nx, size_t nz) {
    fprintf(csv, "time");
    for (size_t i = 0; i < nx; i++) fprintf(csv, ",x%zu", i);
    for (size_t i = 0; i < nx; i++) fprintf(csv, ",der_x%zu", i);
    for (size_t i = 0; i < nz; i++) fprintf(csv, ",z%zu", i);
    for (size_t i = 0; i < n_outputs; i++) fprintf(csv, ",%u", outputs[i]);
    fprintf(csv, "\n");
}

static void model_exchange_row(FILE *csv, fmi2Component c, double t, size_t nx, size_t nz, const fmi2Real *dx) {
    fmi2Real x[MAX_STATES], z[MAX_INDICATORS], values[MAX_OUTPUTS];
    REQUIRE_OK(fmi.GetContinuousStates(c, x, nx));
    REQUIRE_OK(fmi.GetEventIndicators(c, z, nz));
    REQUIRE_OK(fmi.GetReal(c, outputs, n_outputs, values));
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
    fmi2Component c = model_exchange_instance("model_exchange");
    event_iteration(c);
    REQUIRE_OK(fmi.EnterContinuousTimeMode(c));
    fmi2Real dx[NX], z[NZ];
    REQUIRE_OK(fmi.GetDerivatives(c, dx, NX));
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

static fmi2Byte *read_file(const char *path, size_t *size) {
    FILE *file = fopen(path, "rb");
    if (!file) {
        fprintf(stderr, "cannot open %s\n", path);
        exit(2);
    }
    size_t capacity = 1 << 16;
    fmi2Byte *bytes = malloc(capacity);
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

/* -------------------------------------------------------------- bad input */

static FILE *bad_csv;

/* One refused call: its name, the status and the message logged for it. */
static void record(const char *name, const char *result) {
    fprintf(bad_csv, "%s,%s,\"", name, result);
    for (const char *p = last_message; *p; p++) {
        if (*p == '"') fputc('"', bad_csv);
        if (*p != '\n' && *p != '\r') fputc(*p, bad_csv);
    }
    fprintf(bad_csv, "\"\n");
    last_message[0] = '\0';
}

static void record_status(const char *name, fmi2Status status) {
    char text[16];
    snprintf(text, sizeof text, "%d", status);
    record(name, text);
}

static void record_instance(const char *name, fmi2Component c) {
    record(name, c ? "instance" : "NULL");
    if (c) fmi.FreeInstance(c);
}

static void bad_input(const char *dir, const fmi2Byte *state, size_t state_size) {
    bad_csv = open_file(dir, "bad_input.csv", "wb");
    fprintf(bad_csv, "case,result,message\n");
    fmi2Real value = 0.0;
    fmi2ValueReference vr_unknown = VR_UNKNOWN, vr_tau = VR_TAU, vr_g = VR_G, vr_x_s = VR_X_S;

    last_message[0] = '\0';
    record_status("null_instance_do_step", fmi.DoStep(NULL, 0.0, STEP, 1));
    record_status("null_instance_get_real", fmi.GetReal(NULL, &vr_x_s, 1, &value));
    record_instance("wrong_guid",
                    fmi.Instantiate("bad", fmi2CoSimulation,
                                    "{00000000-0000-0000-0000-000000000000}", NULL, &callbacks,
                                    0, 0));
    record_instance("model_exchange",
                    fmi.Instantiate("bad", fmi2ModelExchange, guid, NULL, &callbacks, 0, 0));
    record_instance("unknown_fmu_type", fmi.Instantiate("bad", 7, guid, NULL, &callbacks, 0, 0));

    fmi2Component c = fmi.Instantiate("bad", fmi2CoSimulation, guid, NULL, &callbacks, 0, 0);
    if (!c) fail("fmi2Instantiate returned NULL", __LINE__);
    record_status("do_step_before_initialization", fmi.DoStep(c, 0.0, STEP, 1));
    REQUIRE_OK(fmi.SetupExperiment(c, 0, 0.0, 0.0, 1, STEPS * STEP));
    REQUIRE_OK(fmi.EnterInitializationMode(c));
    record_status("unknown_value_reference_get", fmi.GetReal(c, &vr_unknown, 1, &value));
    value = 1.0;
    record_status("unknown_value_reference_set", fmi.SetReal(c, &vr_unknown, 1, &value));
    value = strtod("nan", NULL);
    record_status("nan_parameter", fmi.SetReal(c, &vr_g, 1, &value));
    value = -2e-4;
    record_status("negative_tau", fmi.SetReal(c, &vr_tau, 1, &value));
    value = 1.0;
    record_status("set_output", fmi.SetReal(c, &vr_x_s, 1, &value));
    value = 1e4;
    REQUIRE_OK(fmi.SetReal(c, &vr_tau, 1, &value));
    record_status("delay_too_long_at_initialization", fmi.ExitInitializationMode(c));
    value = 2e-4;
    REQUIRE_OK(fmi.SetReal(c, &vr_tau, 1, &value));
    REQUIRE_OK(fmi.ExitInitializationMode(c));

    record_status("negative_step_size", fmi.DoStep(c, 0.0, -STEP, 1));
    record_status("null_state_pointer", fmi.GetFMUstate(c, NULL));
    fmi2FMUstate restored = NULL;
    record_status("truncated_state", fmi.DeSerializeFMUstate(c, state, state_size / 2, &restored));
    fmi2Byte *flipped = malloc(state_size);
    if (!flipped) fail("out of memory", __LINE__);
    memcpy(flipped, state, state_size);
    flipped[state_size / 2] ^= 0x04;
    record_status("bit_flipped_state", fmi.DeSerializeFMUstate(c, flipped, state_size, &restored));
    free(flipped);
    fmi2FMUstate own = NULL;
    REQUIRE_OK(fmi.GetFMUstate(c, &own));
    fmi2Byte small[8] = {0};
    record_status("serialize_buffer_too_small", fmi.SerializeFMUstate(c, own, small, sizeof small));
    REQUIRE_OK(fmi.FreeFMUstate(c, &own));
    if (restored) fail("a refused state was returned", __LINE__);

    /* After every refusal the instance still simulates. */
    fmi2Status status = fmi.DoStep(c, 0.0, 10 * STEP, 1);
    if (status == fmi2OK) status = fmi.GetReal(c, &vr_x_s, 1, &value);
    if (status == fmi2OK && !(value == value)) status = fmi2Error; /* a NaN output */
    record_status("simulates_after_refusals", status);

    /* Model Exchange: refusals by the state table and of bad arguments. */
    fmi2Component me = fmi.Instantiate("bad", fmi2ModelExchange, guid, NULL, &callbacks, 0, 0);
    if (!me) fail("fmi2Instantiate(fmi2ModelExchange) returned NULL", __LINE__);
    fmi2Real x[NX + 1], dx[NX];
    record_status("me_get_derivatives_before_initialization", fmi.GetDerivatives(me, dx, NX));
    fmi.FreeInstance(me);
    me = model_exchange_instance("bad");
    REQUIRE_OK(fmi.GetContinuousStates(me, x, NX));
    record_status("me_set_continuous_states_in_event_mode", fmi.SetContinuousStates(me, x, NX));
    record_status("me_null_event_info", fmi.NewDiscreteStates(me, NULL));
    event_iteration(me);
    REQUIRE_OK(fmi.EnterContinuousTimeMode(me));
    record_status("me_do_step", fmi.DoStep(me, 0.0, STEP, 1));
    record_status("me_too_few_states", fmi.SetContinuousStates(me, x, NX - 1));
    x[NX] = 0.0;
    record_status("me_too_many_derivatives", fmi.GetDerivatives(me, x, NX + 1));
    REQUIRE_OK(fmi.GetContinuousStates(me, x, NX));
    fmi2Real saved = x[3];
    x[3] = strtod("nan", NULL);
    record_status("me_nan_state", fmi.SetContinuousStates(me, x, NX));
    x[3] = saved;
    REQUIRE_OK(fmi.SetTime(me, 1e-3));
    fmi2Boolean enter = 1, terminate = 1;
    REQUIRE_OK(fmi.CompletedIntegratorStep(me, 1, &enter, &terminate));
    record_status("me_time_before_completed_step", fmi.SetTime(me, 5e-4));
    record_status("me_null_flags", fmi.CompletedIntegratorStep(me, 1, NULL, &terminate));
    fmi2FMUstate me_state = NULL;
    REQUIRE_OK(fmi.GetFMUstate(me, &me_state));
    size_t me_size = 0;
    REQUIRE_OK(fmi.SerializedFMUstateSize(me, me_state, &me_size));
    fmi2Byte *me_bytes = malloc(me_size);
    if (!me_bytes) fail("out of memory", __LINE__);
    REQUIRE_OK(fmi.SerializeFMUstate(me, me_state, me_bytes, me_size));
    REQUIRE_OK(fmi.FreeFMUstate(me, &me_state));
    fmi2FMUstate into_cs = NULL;
    record_status("me_state_into_cs_instance", fmi.DeSerializeFMUstate(c, me_bytes, me_size, &into_cs));
    free(me_bytes);
    if (into_cs) fail("a refused state was returned", __LINE__);
    /* After the refusals the Model Exchange instance still integrates. */
    status = fmi.SetTime(me, 2e-3);
    if (status == fmi2OK) status = fmi.SetContinuousStates(me, x, NX);
    if (status == fmi2OK) status = fmi.GetDerivatives(me, dx, NX);
    if (status == fmi2OK) status = fmi.CompletedIntegratorStep(me, 1, &enter, &terminate);
    if (status == fmi2OK && (enter || terminate)) status = fmi2Error;
    for (int i = 0; status == fmi2OK && i < NX; i++)
        if (!(dx[i] == dx[i])) status = fmi2Error; /* a NaN derivative */
    record_status("me_integrates_after_refusals", status);
    finish(me);
    finish(c);
    fclose(bad_csv);
}

/* ------------------------------------------------------------------- main */

/* Comma-separated value references into `vrs` (at most `max`); "-" is
 * none. Returns how many. */
static size_t parse_vrs(const char *what, const char *list, fmi2ValueReference *vrs, size_t max) {
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
        vrs[n++] = (fmi2ValueReference)vr;
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

/* MODE of a driven run: "cs" (Co-Simulation), "cs,VR" (Co-Simulation with
 * the Integer parameter VR, input_extrapolation, set to 1) or "me,NX,NZ"
 * (Model Exchange of NX continuous states and NZ event indicators). */
typedef struct {
    int model_exchange;
    size_t nx, nz;
    unsigned long extrapolation_vr; /* "cs,VR": VR; else 0 */
} Mode;

static Mode parse_mode(const char *text) {
    Mode mode = {0, 0, 0, 0};
    if (strcmp(text, "cs") == 0) return mode;
    unsigned long nx = 0, nz = 0;
    char end = 0;
    if (sscanf(text, "cs,%lu%c", &mode.extrapolation_vr, &end) == 1 && mode.extrapolation_vr > 0) return mode;
    if (sscanf(text, "me,%lu,%lu%c", &nx, &nz, &end) != 2) {
        fprintf(stderr, "bad MODE `%s`: cs, cs,VR or me,NX,NZ\n", text);
        exit(2);
    }
    if (nx > MAX_STATES || nz > MAX_INDICATORS) {
        fprintf(stderr, "MODE `%s`: at most %d continuous states and %d event indicators (harness.c)\n", text,
                MAX_STATES, MAX_INDICATORS);
        exit(2);
    }
    mode.model_exchange = 1;
    mode.nx = nx;
    mode.nz = nz;
    return mode;
}

/* One driven run (drive_NAME.csv in `dir`); sets `guid` and the outputs. */
static void drive(const char *dir, char **args) {
    const char *name = args[0];
    guid = args[1];
    parse_outputs(args[2]);
    fmi2ValueReference inputs[MAX_INPUTS], derivatives[MAX_INPUTS];
    const size_t n_inputs = parse_vrs("INPUTS", args[3], inputs, MAX_INPUTS);
    const size_t n_derivatives = parse_vrs("DERIVATIVES", args[4], derivatives, MAX_INPUTS);
    const Mode mode = parse_mode(args[6]);
    if (mode.model_exchange && n_derivatives) {
        fprintf(stderr, "MODE %s: input derivatives are Co-Simulation only: DERIVATIVES must be -\n", args[6]);
        exit(2);
    }
    fmi2Integer orders[MAX_INPUTS];
    for (size_t i = 0; i < MAX_INPUTS; i++) orders[i] = 1;
    const size_t row = n_inputs + n_derivatives;
    size_t size = 0;
    fmi2Byte *table = read_file(args[5], &size);
    if (row == 0 || size == 0 || size % (row * sizeof(double)) != 0) {
        fprintf(stderr, "TABLE %s: %zu bytes is not a whole number of rows of %zu doubles\n", args[5], size, row);
        exit(2);
    }
    const size_t steps = size / (row * sizeof(double));

    char file[256];
    snprintf(file, sizeof file, "drive_%s.csv", name);
    FILE *csv = open_file(dir, file, "wb");
    fmi2Component c;
    fmi2Real dx[MAX_STATES], z[MAX_INDICATORS]; /* Model Exchange */
    if (mode.model_exchange) {
        model_exchange_header(csv, mode.nx, mode.nz);
        c = model_exchange_instance(file);
        event_iteration(c);
        REQUIRE_OK(fmi.EnterContinuousTimeMode(c));
        REQUIRE_OK(fmi.GetDerivatives(c, dx, mode.nx));
        REQUIRE_OK(fmi.GetEventIndicators(c, z, mode.nz));
        model_exchange_row(csv, c, 0.0, mode.nx, mode.nz, dx);
    } else {
        write_header(csv);
        const Integers extrapolating = {mode.extrapolation_vr ? 1 : 0, {(fmi2ValueReference)mode.extrapolation_vr}, {1}};
        c = initialized(file, &extrapolating);
        write_row(csv, c, 0.0);
    }
    size_t events = 0;
    for (size_t k = 0; k < steps; k++) {
        fmi2Real values[2 * MAX_INPUTS];
        memcpy(values, table + k * row * sizeof(double), row * sizeof(double));
        if (n_inputs) REQUIRE_OK(fmi.SetReal(c, inputs, n_inputs, values));
        if (n_derivatives)
            REQUIRE_OK(fmi.SetRealInputDerivatives(c, derivatives, n_derivatives, orders, values + n_inputs));
        const double t = (double)(k + 1) * STEP;
        if (mode.model_exchange) {
            /* Euler steps to t_k + j STEP / DRIVE_SUBSTEPS: the last ends at t exactly. */
            double now = (double)k * STEP;
            for (int j = 1; j <= DRIVE_SUBSTEPS; j++) {
                const double next = ((double)k + (double)j / DRIVE_SUBSTEPS) * STEP;
                events += euler_step(c, next - now, next, mode.nx, mode.nz, dx, z);
                now = next;
            }
            REQUIRE_OK(fmi.GetDerivatives(c, dx, mode.nx)); /* the row's: at t */
            model_exchange_row(csv, c, t, mode.nx, mode.nz, dx);
        } else {
            REQUIRE_OK(fmi.DoStep(c, (double)k * STEP, STEP, 1));
            write_row(csv, c, t);
        }
    }
    finish(c);
    fclose(csv);
    free(table);
    printf("harness: drive %s: %zu outputs x %zu steps, %zu inputs, %zu input derivatives", name, n_outputs, steps,
           n_inputs, n_derivatives);
    if (mode.model_exchange)
        printf(", Model Exchange: %zu states, %zu event indicators, %zu events", mode.nx, mode.nz, events);
    printf("\n");
}

int main(int argc, char **argv) {
    if (argc < 6 || (argc - 6) % DRIVE_ARGS != 0) {
        fprintf(stderr,
                "usage: %s LIB GUID OUTPUT_VRS OUT_DIR STATE_IN"
                " [NAME TOKEN OUTPUTS INPUTS DERIVATIVES TABLE MODE]...\n",
                argv[0]);
        return 2;
    }
    load(argv[1]);
    guid = argv[2];
    parse_outputs(argv[3]);
    const char *dir = argv[4];

    static const Integers defaults = {0, {0}, {0}};
    experiment(dir, "default.csv", &defaults);
    static const Integers iso_c_cs = {
        4, {VR_VARIANT, VR_ROAD, VR_ROAD_CLASS, VR_ROAD_SEED}, {VARIANT_CS, ROAD_ISO8608, ROAD_CLASS_C, 7}};
    experiment(dir, "iso_c_cs.csv", &iso_c_cs);

    size_t size = 0;
    fmi2Byte *state = saved_state(&size);
    FILE *file = open_file(dir, "state.bin", "wb");
    if (fwrite(state, 1, size, file) != size) fail("cannot write state.bin", __LINE__);
    fclose(file);
    continue_from(dir, "roundtrip.csv", state, size);

    size_t foreign_size = 0;
    fmi2Byte *foreign = read_file(argv[5], &foreign_size);
    continue_from(dir, "restored.csv", foreign, foreign_size);
    free(foreign);

    model_exchange(dir);
    bad_input(dir, state, size);
    free(state);
    printf("harness: %zu outputs x %d steps, state of %zu bytes, results in %s\n", n_outputs,
           STEPS, size, dir);
    for (int i = 6; i < argc; i += DRIVE_ARGS) drive(dir, argv + i); /* last: they set guid, outputs */
    return 0;
}
