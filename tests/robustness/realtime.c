/*
 * Real-time harness of the shipped Linux libraries (FMI 2.0 and FMI 3.0,
 * Co-Simulation and Model Exchange): heap allocations while stepping, and
 * the worst call. One harness for every mode on purpose (one binary, run
 * under valgrind too): hence its length.
 *
 *   realtime list
 *   realtime count FMI LIB TOKEN CASE
 *   realtime count-me FMI LIB TOKEN CASE
 *   realtime worst FMI LIB TOKEN CASE REPEATS SECONDS
 *   realtime worst-me FMI LIB TOKEN CASE REPEATS SECONDS
 *
 *   FMI     2 or 3
 *   LIB     binaries/linux64/tdvass.so (FMI 2.0) or
 *           binaries/x86_64-linux/tdvass.so (FMI 3.0) of the shipped FMU
 *   TOKEN   the GUID / instantiationToken of its modelDescription.xml:
 *           the quarter car's, the corner's or the chassis's
 *   CASE    a case name of `realtime list`: road, tire and step pattern
 *           (corner-*: the corner's, chassis-*: the chassis's; both
 *           Co-Simulation only)
 *
 * The harness defines malloc, calloc, realloc, free, posix_memalign,
 * aligned_alloc, memalign and valloc itself (linked with -rdynamic, so the
 * dlopen'ed library binds to them) and forwards them to glibc's
 * __libc_* functions. Counting starts when the Exit Initialization Mode
 * call has returned and stops before the instance is freed; the master's
 * own memory callbacks (FMI 2.0 allocateMemory) count too.
 *
 * A case's run, 30 s of simulated time (SECONDS in `worst`), does at
 * every communication point what a real-time master does:
 *   - in `count`, sets g to its value (a tunable parameter); on the input road
 *     x_g = 0.05 sin(5 t) with its first derivative (FMI 2.0);
 *   - one doStep;
 *   - reads every Float64/Real output, lift_off_count and (FMI 2.0) the
 *     first derivatives of the outputs;
 * `count` also saves the state in the middle of the run, serializes it,
 * deserializes it and restores it (not counted: FMU-state functions may
 * allocate), and goes on counting from the restored state; it changes g's
 * value at 10 s and back at 20 s; these two
 * calls rebuild the operators and check the stability of the new gain,
 * which allocates: their allocations are counted apart. In FMI 3.0 the
 * instance is created with earlyReturnAllowed and an intermediate-update
 * callback that reads every output at every internal node and asks for an
 * early return at every 7th one; the master then goes on from
 * lastSuccessfulTime.
 *
 * `count` prints "allocations N calls M (g value changes: 2 calls, G
 * allocations)" and exits 0 when N is 0, 1 otherwise. `count-me` drives a
 * Model Exchange instance instead, as a fixed-step real-time master does
 * (run_model_exchange: Heun's method at the case's steps, trial points,
 * events, CompletedIntegratorStep, the outputs read; the state restored
 * from its serialized bytes in the middle, apart), and prints
 * "allocations N steps M (restoring a serialized state: R allocations)". `worst` runs the case REPEATS times (the same calls, the same
 * results), takes each call's minimum time over the repetitions and prints
 * the median of these minima, the largest, the call it belongs to and their
 * ratio. `worst-me` does the same for `count-me`'s Model Exchange master, one
 * call being all the FMI calls of one of its steps (time, states and
 * derivatives at both ends, the indicators, an event if any, the completed
 * step, the outputs). Exit code 2: the library could not be loaded or a
 * call failed.
 *
 * The corner (`count` of a corner-* case, 10 s, the state restored after
 * 5 s, g changed at 1/3 and back at 2/3 of the run) is run as the quarter
 * car, under a point mass of 345 kg (static_load / g0) that the
 * body_force read after each step moves over it (a Jacobi loop): before
 * every step it sets body_displacement and body_velocity, and (FMI 2.0)
 * their first derivatives, which the corner ignores with a warning; it
 * reads the corner's outputs, lift_off_count and the output derivatives.
 * The chassis (chassis-*, 10 s, restored after 5 s) gets four changing
 * forces before every step and (FMI 2.0) force_fl's first derivative, and
 * has every output read (it has no output derivatives, no intermediate
 * updates, no g); its step patterns include libcosim's clock, whose steps
 * alternate between 1 ms and 1 ms + 1e-12, and the varying master's 8
 * lengths, each new to the chassis's 4 W_k maps. It prints "allocations N
 * calls M (restoring a serialized state: R allocations)".
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "../include/fmi3_types.h"

/* ---- the interposed allocator ---- */

extern void *__libc_malloc(size_t);
extern void *__libc_calloc(size_t, size_t);
extern void *__libc_realloc(void *, size_t);
extern void __libc_free(void *);
extern void *__libc_memalign(size_t, size_t);

static int counting;
static long allocations;
/* Allocations inside the calls that change g's value (not counted above). */
static int counting_gain_change;
static long gain_change_allocations;

/* Allocations while restoring a serialized FMU state (not counted above). */
static int counting_restore;
static long restore_allocations;

static void note_allocation(void) {
    if (counting) allocations++;
    if (counting_gain_change) gain_change_allocations++;
    if (counting_restore) restore_allocations++;
}

/* Counts the allocations of a call that changes g's value apart. */
static void begin_gain_change(void) {
    counting = 0;
    counting_gain_change = 1;
}

static void end_gain_change(void) {
    counting_gain_change = 0;
    counting = 1;
}

void *malloc(size_t size) {
    note_allocation();
    return __libc_malloc(size);
}

void *calloc(size_t count, size_t size) {
    note_allocation();
    return __libc_calloc(count, size);
}

void *realloc(void *pointer, size_t size) {
    note_allocation();
    return __libc_realloc(pointer, size);
}

void free(void *pointer) { __libc_free(pointer); }

void *memalign(size_t alignment, size_t size) {
    note_allocation();
    return __libc_memalign(alignment, size);
}

void *aligned_alloc(size_t alignment, size_t size) { return memalign(alignment, size); }

void *valloc(size_t size) { return memalign(4096, size); }

int posix_memalign(void **out, size_t alignment, size_t size) {
    void *pointer = memalign(alignment, size);
    if (!pointer) return ENOMEM;
    *out = pointer;
    return 0;
}

/* ---- the cases ---- */

enum { PATTERN_ALIGNED, PATTERN_IN_STEP, PATTERN_VARYING, PATTERN_LONG, PATTERN_LIBCOSIM };
enum { ROAD_INPUT = 0, ROAD_HARMONIC = 1, ROAD_ISO = 2, ROAD_PAPER = 3 };
/* The model the GUID / instantiation token picks. */
enum { MODEL_QUARTER_CAR, MODEL_CORNER, MODEL_CHASSIS };

typedef struct {
    const char *name;
    int model;
    int road;
    int road_class; /* ISO 8608: 1 = A ... 8 = H */
    double speed;   /* m/s */
    int tire;       /* 0 bilateral, 1 unilateral */
    int pattern;
} Case;

static const char *PATTERN_NAME[] = {"aligned", "0.7ms", "varying", "10ms", "libcosim"};
static const char *ROAD_NAME[] = {"input", "harmonic", "iso", "paper"};
/* The varying master's steps (s), taken in turn: 0.1 ... 1.9 ms. */
static const double VARYING[] = {0.13e-3, 1.9e-3, 0.71e-3, 0.29e-3, 1.37e-3, 0.53e-3, 1.03e-3, 0.1e-3};
#define N_VARYING (sizeof VARYING / sizeof VARYING[0])

#define MAX_CASES 128
static Case cases[MAX_CASES];
static int n_cases;
static char names[MAX_CASES][48];

static void add_case_of(int model, int road, int road_class, double speed, int tire, int pattern) {
    Case *c = &cases[n_cases];
    const char *prefix = model == MODEL_CORNER ? "corner-" : "";
    c->model = model;
    c->road = road;
    c->road_class = road_class;
    c->speed = speed;
    c->tire = tire;
    c->pattern = pattern;
    if (road == ROAD_ISO)
        snprintf(names[n_cases], sizeof names[0], "%siso-%c-%g-%s-%s", prefix, 'A' + road_class - 1,
                 speed, tire ? "unilateral" : "bilateral", PATTERN_NAME[pattern]);
    else if (model == MODEL_CHASSIS)
        snprintf(names[n_cases], sizeof names[0], "chassis-%s", PATTERN_NAME[pattern]);
    else
        snprintf(names[n_cases], sizeof names[0], "%s%s-%s-%s", prefix, ROAD_NAME[road],
                 tire ? "unilateral" : "bilateral", PATTERN_NAME[pattern]);
    c->name = names[n_cases];
    n_cases++;
}

static void add_case(int road, int road_class, double speed, int tire, int pattern) {
    add_case_of(MODEL_QUARTER_CAR, road, road_class, speed, tire, pattern);
}

static void add_corner_case(int road, int road_class, double speed, int tire, int pattern) {
    add_case_of(MODEL_CORNER, road, road_class, speed, tire, pattern);
}

/* The quarter car: every road (the ISO road as class D at 20 m/s and class
 * E at 30 m/s, the most lift-offs) x both tires x every step pattern but
 * libcosim's. The corner: the same roads and tires x the aligned, varying
 * and 10 ms patterns. The chassis (no road, no tire): aligned, libcosim's
 * clock, varying and 10 ms. */
static void make_cases(void) {
    for (int pattern = 0; pattern < 4; pattern++)
        for (int tire = 0; tire < 2; tire++) {
            add_case(ROAD_INPUT, 3, 20.0, tire, pattern);
            add_case(ROAD_HARMONIC, 3, 20.0, tire, pattern);
            add_case(ROAD_ISO, 4, 20.0, tire, pattern);
            add_case(ROAD_ISO, 5, 30.0, tire, pattern);
            add_case(ROAD_PAPER, 3, 20.0, tire, pattern);
        }
    const int corner_patterns[] = {PATTERN_ALIGNED, PATTERN_VARYING, PATTERN_LONG};
    for (int p = 0; p < 3; p++)
        for (int tire = 0; tire < 2; tire++) {
            add_corner_case(ROAD_INPUT, 3, 20.0, tire, corner_patterns[p]);
            add_corner_case(ROAD_HARMONIC, 3, 20.0, tire, corner_patterns[p]);
            add_corner_case(ROAD_ISO, 4, 20.0, tire, corner_patterns[p]);
            add_corner_case(ROAD_ISO, 5, 30.0, tire, corner_patterns[p]);
            add_corner_case(ROAD_PAPER, 3, 20.0, tire, corner_patterns[p]);
        }
    const int chassis_patterns[] = {PATTERN_ALIGNED, PATTERN_LIBCOSIM, PATTERN_VARYING, PATTERN_LONG};
    for (int p = 0; p < 4; p++) add_case_of(MODEL_CHASSIS, ROAD_INPUT, 0, 0.0, 0, chassis_patterns[p]);
}

static const Case *find_case(const char *name) {
    for (int i = 0; i < n_cases; i++)
        if (!strcmp(cases[i].name, name)) return &cases[i];
    fprintf(stderr, "unknown case %s (see `realtime list`)\n", name);
    exit(2);
}

static double step_of(const Case *c, long k) {
    switch (c->pattern) {
    case PATTERN_ALIGNED: return 1e-3;
    case PATTERN_IN_STEP: return 0.7e-3;
    case PATTERN_VARYING: return VARYING[k % N_VARYING];
    /* libcosim's clock counts nanoseconds: its steps, as doubles, alternate
     * between lengths a rounding apart. */
    case PATTERN_LIBCOSIM: return k % 2 ? 1e-3 + 1e-12 : 1e-3;
    default: return 10e-3;
    }
}

/* The time after the step k of length `step` from t: the aligned and 10 ms
 * masters multiply, the others add. */
static double next_time(const Case *c, long k, double t, double step) {
    return c->pattern == PATTERN_ALIGNED || c->pattern == PATTERN_LONG ? (double)(k + 1) * step : t + step;
}

/* ---- the variables ---- */

enum {
    VR_G = 10,
    VR_ROAD = 12,
    VR_ROAD_CLASS = 15,
    VR_VEHICLE_SPEED = 16,
    VR_X_G = 30,
    VR_TIRE_CONTACT = 60,
    VR_LIFT_OFF_COUNT = 61,
};
static const unsigned OUTPUTS[] = {31, 32, 33, 34, 35, 36, 37, 38, 39, 40, 41, 42, 43,
                                   44, 45, 53, 54, 55, 56, 57, 58, 59};
#define N_OUTPUTS (sizeof OUTPUTS / sizeof OUTPUTS[0])
static const double G = 5386.0;

/* The corner: the quarter car's VR_* above that it has (g, road, road_class,
 * vehicle_speed, x_g, tire_contact, lift_off_count), and the body's. */
enum {
    /* input_extrapolation (Integer; FMI 3.0 Int32): 1 in the corner's and
     * the chassis's runs, as the full car's system files set it. */
    VR_INPUT_EXTRAPOLATION = 48,
    CORNER_VR_BODY_DISPLACEMENT = 143,
    CORNER_VR_BODY_VELOCITY = 144,
    CORNER_VR_BODY_FORCE = 145,
};
static const unsigned CORNER_OUTPUTS[] = {33, 34, 35, 36, 38, 39, 40, 41, 43, 44, 56, 57, 58, 59, 145};
#define N_CORNER_OUTPUTS (sizeof CORNER_OUTPUTS / sizeof CORNER_OUTPUTS[0])
/* The corner's body: a point mass of static_load / g0 (the default). */
static const double BODY_MASS = 345.0;

/* The chassis. */
enum {
    CHASSIS_VR_INPUT_EXTRAPOLATION = 209,
    CHASSIS_VR_FORCE_FL = 210,
    CHASSIS_VR_FORCE_FR = 211,
    CHASSIS_VR_FORCE_RL = 212,
    CHASSIS_VR_FORCE_RR = 213,
};
static const unsigned CHASSIS_OUTPUTS[] = {220, 221, 222, 223, 224, 225, 226, 227, 230, 231, 232, 233,
                                           234, 235, 236, 237, 238, 239, 240, 241, 242, 243, 244, 245};
#define N_CHASSIS_OUTPUTS (sizeof CHASSIS_OUTPUTS / sizeof CHASSIS_OUTPUTS[0])

/* The outputs of the model run (the quarter car's or the corner's). */
#define MAX_OUTPUTS 32
static const unsigned *outputs = OUTPUTS;
static size_t n_outputs = N_OUTPUTS;

/* The corner's body, moved by the body_force read after each step (a
 * Jacobi loop); its last acceleration. */
static double body_z, body_v, body_a;

static void move_body(double force, double h) {
    body_a = force / BODY_MASS;
    body_z += body_v * h + 0.5 * body_a * h * h;
    body_v += body_a * h;
}

/* A corner's force on the chassis (N): four different, changing signals,
 * and their rates. */
static double chassis_force(int i, double t) { return 800.0 * sin((3.0 + 2.0 * i) * t + i) + 50.0 * i; }
static double chassis_force_rate(int i, double t) {
    return 800.0 * (3.0 + 2.0 * i) * cos((3.0 + 2.0 * i) * t + i);
}

static double road_input(double t) { return 0.05 * sin(5.0 * t); }
static double road_input_rate(double t) { return 0.25 * cos(5.0 * t); }

static void fail(const char *what, double t) {
    counting = 0;
    fprintf(stderr, "%s failed at t = %.17g\n", what, t);
    exit(2);
}

static void *symbol(void *library, const char *name) {
    void *address = dlsym(library, name);
    if (!address) {
        fprintf(stderr, "the library does not export %s\n", name);
        exit(2);
    }
    return address;
}

static void *open_library(const char *path) {
    void *library = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!library) {
        fprintf(stderr, "dlopen: %s\n", dlerror());
        exit(2);
    }
    return library;
}

#define SYM(variable, library, name) memcpy(&(variable), &(void *){symbol(library, name)}, sizeof(void *))

/* `count` also sets g at every call (as masters that set every tunable
 * parameter do); `worst` times doStep and the getters alone. */
static int set_gain_every_call;

/* `count` restores a serialized copy of the state before this call (the
 * middle of the run); -1: never. */
static long restore_at = -1;

/* One call's time, or nothing (NULL). */
static double *call_times;
static long max_calls;

static double seconds_now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* ---- FMI 2.0 ---- */

typedef void *fmi2Component;
typedef int fmi2Status;
typedef struct {
    void (*logger)(void *, const char *, fmi2Status, const char *, const char *, ...);
    void *(*allocateMemory)(size_t, size_t);
    void (*freeMemory)(void *);
    void (*stepFinished)(void *, fmi2Status);
    void *componentEnvironment;
} fmi2CallbackFunctions;

static void logger2(void *env, const char *name, fmi2Status status, const char *category,
                    const char *message, ...) {
    (void)env, (void)name, (void)status, (void)category;
    if (status > 1) fprintf(stderr, "log: %s\n", message);
}

static void *master_allocate(size_t count, size_t size) { return calloc(count, size); }

/* The FMU-state functions of FMI 2.0 (both interfaces). */
static struct {
    fmi2Status (*get)(fmi2Component, void **);
    fmi2Status (*set)(fmi2Component, void *);
    fmi2Status (*free)(fmi2Component, void **);
    fmi2Status (*size)(fmi2Component, void *, size_t *);
    fmi2Status (*serialize)(fmi2Component, void *, char *, size_t);
    fmi2Status (*deserialize)(fmi2Component, const char *, size_t, void **);
} states2;

static void bind_states2(void *library) {
    SYM(states2.get, library, "fmi2GetFMUstate");
    SYM(states2.set, library, "fmi2SetFMUstate");
    SYM(states2.free, library, "fmi2FreeFMUstate");
    SYM(states2.size, library, "fmi2SerializedFMUstateSize");
    SYM(states2.serialize, library, "fmi2SerializeFMUstate");
    SYM(states2.deserialize, library, "fmi2DeSerializeFMUstate");
}

/* Saves the state, serializes it, deserializes it and restores it (these
 * may allocate; stepping on from the restored state must not); nonzero on
 * failure. */
static int restore_serialized2(void *instance) {
    void *state = NULL, *restored = NULL;
    size_t size = 0;
    char *bytes = NULL;
    int failed = states2.get(instance, &state) || states2.size(instance, state, &size) ||
                 !(bytes = malloc(size)) || states2.serialize(instance, state, bytes, size) ||
                 states2.deserialize(instance, bytes, size, &restored) || states2.set(instance, restored) ||
                 states2.free(instance, &state) || states2.free(instance, &restored);
    free(bytes);
    return failed;
}

static long run_fmi2(void *library, const char *token, const Case *c, double seconds, int change_g) {
    fmi2Component (*instantiate)(const char *, int, const char *, const char *,
                                 const fmi2CallbackFunctions *, int, int);
    void (*free_instance)(fmi2Component);
    fmi2Status (*setup)(fmi2Component, int, double, double, int, double);
    fmi2Status (*enter_init)(fmi2Component);
    fmi2Status (*exit_init)(fmi2Component);
    fmi2Status (*do_step)(fmi2Component, double, double, int);
    fmi2Status (*set_real)(fmi2Component, const unsigned *, size_t, const double *);
    fmi2Status (*set_integer)(fmi2Component, const unsigned *, size_t, const int *);
    fmi2Status (*get_real)(fmi2Component, const unsigned *, size_t, double *);
    fmi2Status (*get_integer)(fmi2Component, const unsigned *, size_t, int *);
    fmi2Status (*set_input_derivatives)(fmi2Component, const unsigned *, size_t, const int *,
                                        const double *);
    fmi2Status (*get_output_derivatives)(fmi2Component, const unsigned *, size_t, const int *,
                                         double *);
    SYM(instantiate, library, "fmi2Instantiate");
    SYM(free_instance, library, "fmi2FreeInstance");
    SYM(setup, library, "fmi2SetupExperiment");
    SYM(enter_init, library, "fmi2EnterInitializationMode");
    SYM(exit_init, library, "fmi2ExitInitializationMode");
    SYM(do_step, library, "fmi2DoStep");
    SYM(set_real, library, "fmi2SetReal");
    SYM(set_integer, library, "fmi2SetInteger");
    SYM(get_real, library, "fmi2GetReal");
    SYM(get_integer, library, "fmi2GetInteger");
    SYM(set_input_derivatives, library, "fmi2SetRealInputDerivatives");
    SYM(get_output_derivatives, library, "fmi2GetRealOutputDerivatives");
    bind_states2(library);

    static const fmi2CallbackFunctions callbacks = {logger2, master_allocate, free, NULL, NULL};
    fmi2Component instance = instantiate("realtime", 1, token, NULL, &callbacks, 0, 0);
    if (!instance) fail("fmi2Instantiate", 0.0);
    const unsigned integer_vrs[] = {VR_ROAD, VR_ROAD_CLASS, VR_TIRE_CONTACT};
    const int integers[] = {c->road, c->road_class, c->tire};
    const unsigned speed_vr = VR_VEHICLE_SPEED, g_vr = VR_G, x_g_vr = VR_X_G;
    if (set_integer(instance, integer_vrs, 3, integers) || set_real(instance, &speed_vr, 1, &c->speed))
        fail("setting the parameters", 0.0);
    const unsigned extrapolation_vr = VR_INPUT_EXTRAPOLATION;
    const int extrapolate = 1;
    if (c->model == MODEL_CORNER && set_integer(instance, &extrapolation_vr, 1, &extrapolate))
        fail("setting input_extrapolation", 0.0);
    if (setup(instance, 0, 0.0, 0.0, 0, 0.0) || enter_init(instance)) fail("initialization", 0.0);
    if (c->road == ROAD_INPUT) {
        double x_g = road_input(0.0);
        if (set_real(instance, &x_g_vr, 1, &x_g)) fail("fmi2SetReal x_g", 0.0);
    }
    if (exit_init(instance)) fail("fmi2ExitInitializationMode", 0.0);

    int orders[MAX_OUTPUTS];
    for (size_t i = 0; i < MAX_OUTPUTS; i++) orders[i] = 1;
    double values[MAX_OUTPUTS], rates[MAX_OUTPUTS];
    int lift_offs = 0;
    const unsigned lift_off_vr = VR_LIFT_OFF_COUNT;
    const unsigned body_vrs[] = {CORNER_VR_BODY_DISPLACEMENT, CORNER_VR_BODY_VELOCITY};
    const int body_orders[] = {1, 1};
    double t = 0.0, last_g = G;
    long k = 0;
    counting = 1;
    while (t < seconds - 1e-9) {
        double step = step_of(c, k);
        double g = G;
        if (change_g && t >= seconds / 3.0 && t < 2.0 * seconds / 3.0) g = 0.8 * G;
        double start = call_times ? seconds_now() : 0.0;
        int change = set_gain_every_call && g != last_g;
        if (change) begin_gain_change();
        if (set_gain_every_call && set_real(instance, &g_vr, 1, &g) > 1) fail("fmi2SetReal g", t);
        if (change) end_gain_change();
        last_g = g;
        if (c->road == ROAD_INPUT) {
            double x_g = road_input(t), rate = road_input_rate(t);
            const int order = 1;
            if (set_real(instance, &x_g_vr, 1, &x_g) ||
                set_input_derivatives(instance, &x_g_vr, 1, &order, &rate))
                fail("setting x_g", t);
        }
        if (c->model == MODEL_CORNER) {
            /* The body inputs and their derivatives (which the corner
             * ignores with a warning). */
            const double body[] = {body_z, body_v}, body_rates[] = {body_v, body_a};
            if (set_real(instance, body_vrs, 2, body) ||
                set_input_derivatives(instance, body_vrs, 2, body_orders, body_rates) > 1)
                fail("setting the body inputs", t);
        }
        if (restore_at == k) {
            counting = 0;
            if (restore_serialized2(instance)) fail("restoring a serialized FMU state", t);
            counting = 1;
        }
        if (do_step(instance, t, step, 1)) fail("fmi2DoStep", t);
        if (get_real(instance, outputs, n_outputs, values) ||
            get_integer(instance, &lift_off_vr, 1, &lift_offs) ||
            get_output_derivatives(instance, outputs, n_outputs, orders, rates))
            fail("reading the outputs", t);
        if (c->model == MODEL_CORNER) move_body(values[n_outputs - 1], step);
        if (call_times && k < max_calls) call_times[k] = seconds_now() - start;
        t = next_time(c, k, t, step);
        k++;
    }
    counting = 0;
    free_instance(instance);
    return k;
}

/* ---- FMI 3.0 ---- */

static fmi3GetFloat64TYPE get_float64;
static fmi3Instance instance3;
static long intermediate_calls;

static void logger3(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
                    fmi3String message) {
    (void)env, (void)category;
    if (status > fmi3Warning) fprintf(stderr, "log: %s\n", message);
}

static void intermediate_update(fmi3InstanceEnvironment env, fmi3Float64 time,
                                fmi3Boolean set_requested, fmi3Boolean get_allowed,
                                fmi3Boolean step_finished, fmi3Boolean can_return_early,
                                fmi3Boolean *early_return_requested,
                                fmi3Float64 *early_return_time) {
    (void)env, (void)set_requested, (void)step_finished;
    double values[MAX_OUTPUTS];
    if (get_allowed && get_float64(instance3, outputs, n_outputs, values, n_outputs) != fmi3OK)
        fail("fmi3GetFloat64 in an intermediate update", time);
    intermediate_calls++;
    *early_return_requested = can_return_early && intermediate_calls % 7 == 0;
    *early_return_time = time;
}

/* The FMU-state functions of FMI 3.0 (both interfaces). */
static struct {
    fmi3GetFMUStateTYPE get;
    fmi3SetFMUStateTYPE set;
    fmi3FreeFMUStateTYPE free;
    fmi3SerializedFMUStateSizeTYPE size;
    fmi3SerializeFMUStateTYPE serialize;
    fmi3DeserializeFMUStateTYPE deserialize;
} states3;

static void bind_states3(void *library) {
    SYM(states3.get, library, "fmi3GetFMUState");
    SYM(states3.set, library, "fmi3SetFMUState");
    SYM(states3.free, library, "fmi3FreeFMUState");
    SYM(states3.size, library, "fmi3SerializedFMUStateSize");
    SYM(states3.serialize, library, "fmi3SerializeFMUState");
    SYM(states3.deserialize, library, "fmi3DeserializeFMUState");
}

/* restore_serialized2 for FMI 3.0. */
static int restore_serialized3(void *instance) {
    fmi3FMUState state = NULL, restored = NULL;
    size_t size = 0;
    fmi3Byte *bytes = NULL;
    int failed = states3.get(instance, &state) || states3.size(instance, state, &size) ||
                 !(bytes = malloc(size)) || states3.serialize(instance, state, bytes, size) ||
                 states3.deserialize(instance, bytes, size, &restored) || states3.set(instance, restored) ||
                 states3.free(instance, &state) || states3.free(instance, &restored);
    free(bytes);
    return failed;
}

static long run_fmi3(void *library, const char *token, const Case *c, double seconds, int change_g) {
    fmi3InstantiateCoSimulationTYPE instantiate;
    fmi3FreeInstanceTYPE free_instance;
    fmi3EnterInitializationModeTYPE enter_init;
    fmi3ExitInitializationModeTYPE exit_init;
    fmi3DoStepTYPE do_step;
    fmi3SetFloat64TYPE set_float64;
    fmi3SetInt64TYPE set_int64;
    fmi3SetInt32TYPE set_int32;
    fmi3Status (*get_int32)(fmi3Instance, const fmi3ValueReference[], size_t, fmi3Int32[], size_t);
    fmi3Status (*get_output_derivatives)(fmi3Instance, const fmi3ValueReference[], size_t,
                                         const fmi3Int32[], fmi3Float64[], size_t);
    SYM(instantiate, library, "fmi3InstantiateCoSimulation");
    SYM(free_instance, library, "fmi3FreeInstance");
    SYM(enter_init, library, "fmi3EnterInitializationMode");
    SYM(exit_init, library, "fmi3ExitInitializationMode");
    SYM(do_step, library, "fmi3DoStep");
    SYM(set_float64, library, "fmi3SetFloat64");
    SYM(set_int64, library, "fmi3SetInt64");
    SYM(set_int32, library, "fmi3SetInt32");
    SYM(get_float64, library, "fmi3GetFloat64");
    SYM(get_int32, library, "fmi3GetInt32");
    SYM(get_output_derivatives, library, "fmi3GetOutputDerivatives");
    bind_states3(library);

    instance3 = instantiate("realtime", token, NULL, 0, 0, 0, 1, NULL, 0, NULL, logger3,
                            intermediate_update);
    if (!instance3) fail("fmi3InstantiateCoSimulation", 0.0);
    const fmi3ValueReference enum_vrs[] = {VR_ROAD, VR_ROAD_CLASS, VR_TIRE_CONTACT};
    const fmi3Int64 enums[] = {c->road, c->road_class, c->tire};
    const fmi3ValueReference speed_vr = VR_VEHICLE_SPEED, g_vr = VR_G, x_g_vr = VR_X_G;
    if (set_int64(instance3, enum_vrs, 3, enums, 3) ||
        set_float64(instance3, &speed_vr, 1, &c->speed, 1))
        fail("setting the parameters", 0.0);
    const fmi3ValueReference extrapolation_vr = VR_INPUT_EXTRAPOLATION;
    const fmi3Int32 extrapolate = 1;
    if (c->model == MODEL_CORNER && set_int32(instance3, &extrapolation_vr, 1, &extrapolate, 1))
        fail("setting input_extrapolation", 0.0);
    if (enter_init(instance3, 0, 0.0, 0.0, 0, 0.0)) fail("initialization", 0.0);
    if (c->road == ROAD_INPUT) {
        double x_g = road_input(0.0);
        if (set_float64(instance3, &x_g_vr, 1, &x_g, 1)) fail("fmi3SetFloat64 x_g", 0.0);
    }
    if (exit_init(instance3)) fail("fmi3ExitInitializationMode", 0.0);

    fmi3Int32 orders[MAX_OUTPUTS];
    for (size_t i = 0; i < MAX_OUTPUTS; i++) orders[i] = 1;
    double values[MAX_OUTPUTS], rates[MAX_OUTPUTS];
    fmi3Int32 lift_offs = 0;
    const fmi3ValueReference lift_off_vr = VR_LIFT_OFF_COUNT;
    const fmi3ValueReference body_vrs[] = {CORNER_VR_BODY_DISPLACEMENT, CORNER_VR_BODY_VELOCITY};
    double t = 0.0, last_g = G;
    long k = 0;
    intermediate_calls = 0;
    counting = 1;
    while (t < seconds - 1e-9) {
        double step = step_of(c, k);
        double g = G;
        if (change_g && t >= seconds / 3.0 && t < 2.0 * seconds / 3.0) g = 0.8 * G;
        double start = call_times ? seconds_now() : 0.0;
        int change = set_gain_every_call && g != last_g;
        if (change) begin_gain_change();
        if (set_gain_every_call && set_float64(instance3, &g_vr, 1, &g, 1) > fmi3Warning)
            fail("fmi3SetFloat64 g", t);
        if (change) end_gain_change();
        last_g = g;
        if (c->road == ROAD_INPUT) {
            double x_g = road_input(t);
            if (set_float64(instance3, &x_g_vr, 1, &x_g, 1)) fail("fmi3SetFloat64 x_g", t);
        }
        if (c->model == MODEL_CORNER) {
            const double body[] = {body_z, body_v};
            if (set_float64(instance3, body_vrs, 2, body, 2)) fail("setting the body inputs", t);
        }
        if (restore_at == k) {
            counting = 0;
            if (restore_serialized3(instance3)) fail("restoring a serialized FMU state", t);
            counting = 1;
        }
        fmi3Boolean event_needed, terminate, early_return;
        double last_time = t;
        if (do_step(instance3, t, step, 1, &event_needed, &terminate, &early_return, &last_time))
            fail("fmi3DoStep", t);
        if (get_float64(instance3, outputs, n_outputs, values, n_outputs) ||
            get_int32(instance3, &lift_off_vr, 1, &lift_offs, 1) ||
            get_output_derivatives(instance3, outputs, n_outputs, orders, rates, n_outputs))
            fail("reading the outputs", t);
        if (call_times && k < max_calls) call_times[k] = seconds_now() - start;
        double next = early_return ? last_time : next_time(c, k, t, step);
        if (c->model == MODEL_CORNER) move_body(values[n_outputs - 1], next - t);
        t = next;
        k++;
    }
    counting = 0;
    free_instance(instance3);
    return k;
}

/* ---- the chassis (both versions) ---- */

/* The chassis driven by four forces set at every communication point (FMI
 * 2.0: force_fl with its order-1 derivative too), every output read, a
 * serialized state restored in the middle. Its steps vary at least by
 * roundings (the chassis keeps the W_k filter's maps of its last 4 step
 * lengths and makes those of a new one). */
static long run_chassis(int fmi, void *library, const char *token, const Case *c, double seconds) {
    fmi2Component (*instantiate2)(const char *, int, const char *, const char *,
                                  const fmi2CallbackFunctions *, int, int) = NULL;
    fmi2Status (*setup2)(fmi2Component, int, double, double, int, double) = NULL;
    fmi2Status (*enter_init2)(fmi2Component) = NULL;
    fmi2Status (*exit_init2)(fmi2Component) = NULL;
    fmi2Status (*do_step2)(fmi2Component, double, double, int) = NULL;
    fmi2Status (*set_real2)(fmi2Component, const unsigned *, size_t, const double *) = NULL;
    fmi2Status (*set_integer2)(fmi2Component, const unsigned *, size_t, const int *) = NULL;
    fmi2Status (*get_real2)(fmi2Component, const unsigned *, size_t, double *) = NULL;
    fmi2Status (*set_input_derivatives2)(fmi2Component, const unsigned *, size_t, const int *,
                                         const double *) = NULL;
    void (*free_instance2)(fmi2Component) = NULL;
    fmi3InstantiateCoSimulationTYPE instantiate3 = NULL;
    fmi3EnterInitializationModeTYPE enter_init3 = NULL;
    fmi3ExitInitializationModeTYPE exit_init3 = NULL;
    fmi3DoStepTYPE do_step3 = NULL;
    fmi3SetFloat64TYPE set_float64 = NULL;
    fmi3SetInt32TYPE set_int32 = NULL;
    fmi3FreeInstanceTYPE free_instance3 = NULL;
    void *instance;
    const unsigned extrapolation_vr = CHASSIS_VR_INPUT_EXTRAPOLATION;
    const int extrapolate = 1;
    if (fmi == 2) {
        SYM(instantiate2, library, "fmi2Instantiate");
        SYM(setup2, library, "fmi2SetupExperiment");
        SYM(enter_init2, library, "fmi2EnterInitializationMode");
        SYM(exit_init2, library, "fmi2ExitInitializationMode");
        SYM(do_step2, library, "fmi2DoStep");
        SYM(set_real2, library, "fmi2SetReal");
        SYM(set_integer2, library, "fmi2SetInteger");
        SYM(get_real2, library, "fmi2GetReal");
        SYM(set_input_derivatives2, library, "fmi2SetRealInputDerivatives");
        SYM(free_instance2, library, "fmi2FreeInstance");
        bind_states2(library);
        static const fmi2CallbackFunctions callbacks = {logger2, master_allocate, free, NULL, NULL};
        instance = instantiate2("realtime", 1, token, NULL, &callbacks, 0, 0);
        if (!instance) fail("fmi2Instantiate", 0.0);
        if (set_integer2(instance, &extrapolation_vr, 1, &extrapolate) ||
            setup2(instance, 0, 0.0, 0.0, 0, 0.0) || enter_init2(instance) || exit_init2(instance))
            fail("initialization", 0.0);
    } else {
        SYM(instantiate3, library, "fmi3InstantiateCoSimulation");
        SYM(enter_init3, library, "fmi3EnterInitializationMode");
        SYM(exit_init3, library, "fmi3ExitInitializationMode");
        SYM(do_step3, library, "fmi3DoStep");
        SYM(set_float64, library, "fmi3SetFloat64");
        SYM(set_int32, library, "fmi3SetInt32");
        SYM(get_float64, library, "fmi3GetFloat64");
        SYM(free_instance3, library, "fmi3FreeInstance");
        bind_states3(library);
        instance = instantiate3("realtime", token, NULL, 0, 0, 0, 0, NULL, 0, NULL, logger3, NULL);
        if (!instance) fail("fmi3InstantiateCoSimulation", 0.0);
        if (set_int32(instance, &extrapolation_vr, 1, &extrapolate, 1) ||
            enter_init3(instance, 0, 0.0, 0.0, 0, 0.0) || exit_init3(instance))
            fail("initialization", 0.0);
    }
    const unsigned force_vrs[] = {CHASSIS_VR_FORCE_FL, CHASSIS_VR_FORCE_FR, CHASSIS_VR_FORCE_RL,
                                  CHASSIS_VR_FORCE_RR};
    double values[N_CHASSIS_OUTPUTS];
    double t = 0.0;
    long k = 0;
    counting = 1;
    while (t < seconds - 1e-9) {
        double step = step_of(c, k);
        double start = call_times ? seconds_now() : 0.0;
        double forces[4];
        for (int i = 0; i < 4; i++) forces[i] = chassis_force(i, t);
        if (fmi == 2) {
            const int order = 1;
            const double rate = chassis_force_rate(0, t);
            if (set_real2(instance, force_vrs, 4, forces) ||
                set_input_derivatives2(instance, force_vrs, 1, &order, &rate))
                fail("setting the forces", t);
        } else if (set_float64(instance, force_vrs, 4, forces, 4))
            fail("setting the forces", t);
        if (restore_at == k) {
            counting = 0;
            counting_restore = 1;
            if (fmi == 2 ? restore_serialized2(instance) : restore_serialized3(instance))
                fail("restoring a serialized FMU state", t);
            counting_restore = 0;
            counting = 1;
        }
        if (fmi == 2) {
            if (do_step2(instance, t, step, 1) ||
                get_real2(instance, CHASSIS_OUTPUTS, N_CHASSIS_OUTPUTS, values))
                fail("fmi2DoStep and reading the outputs", t);
        } else {
            fmi3Boolean event_needed, terminate, early_return;
            double last_time = t;
            if (do_step3(instance, t, step, 1, &event_needed, &terminate, &early_return, &last_time) ||
                get_float64(instance, CHASSIS_OUTPUTS, N_CHASSIS_OUTPUTS, values, N_CHASSIS_OUTPUTS))
                fail("fmi3DoStep and reading the outputs", t);
        }
        if (call_times && k < max_calls) call_times[k] = seconds_now() - start;
        t = next_time(c, k, t, step);
        k++;
    }
    counting = 0;
    if (fmi == 2)
        free_instance2(instance);
    else
        free_instance3(instance);
    return k;
}

/* ---- Model Exchange (both versions) ---- */

/* The continuous states and event indicators of Model Exchange. */
#define N_STATES 20
#define N_INDICATORS 1

/* The calls a Model Exchange master makes, for either FMI version; each
 * returns nonzero on failure (a status above Warning). */
typedef struct {
    void *instance;
    int (*set_time)(void *, double);
    int (*set_states)(void *, const double *);
    int (*get_derivatives)(void *, double *);
    int (*get_indicators)(void *, double *);
    int (*get_states)(void *, double *);
    int (*enter_event_mode)(void *);
    /* One event iteration: *again when another is needed. */
    int (*update_discrete_states)(void *, int *again, int *terminate);
    int (*enter_continuous_time_mode)(void *);
    int (*completed_integrator_step)(void *, int *terminate);
    int (*set_x_g)(void *, double);
    int (*read_outputs)(void *, double *values, int *lift_offs);
    /* Save, serialize, deserialize and restore the state (not counted). */
    int (*restore_serialized_state)(void *);
    void (*free_instance)(void *);
} ModelExchangeMaster;

/* Event Mode to Continuous-Time Mode: the event iteration, then the
 * states and indicators as the event left them. */
static void handle_event(const ModelExchangeMaster *m, double t, double *x, double *z) {
    int again = 1, terminate = 0;
    while (again)
        if (m->update_discrete_states(m->instance, &again, &terminate) || terminate)
            fail("the event update", t);
    if (m->enter_continuous_time_mode(m->instance) || m->get_states(m->instance, x) ||
        m->get_indicators(m->instance, z))
        fail("entering Continuous-Time Mode", t);
}

/* A master integrating with Heun's method at the case's steps (each
 * step a trial point at its end, then the accepted one), an event when
 * the indicator changed sign over a step (at its end, not located),
 * CompletedIntegratorStep after every step, and the outputs read: what a
 * fixed-step real-time master does. The 10 ms pattern steps by 1 ms (the
 * W_k filter's 100 Hz poles bound an explicit method's step). */
static long run_model_exchange(const ModelExchangeMaster *m, const Case *c, double seconds) {
    double x[N_STATES], start_rates[N_STATES], end_rates[N_STATES], trial[N_STATES];
    double z[N_INDICATORS], z_end[N_INDICATORS], values[N_OUTPUTS];
    int lift_offs = 0, terminate = 0;
    void *fmu = m->instance;
    if (c->road == ROAD_INPUT && m->set_x_g(fmu, road_input(0.0))) fail("setting x_g", 0.0);
    handle_event(m, 0.0, x, z);
    double t = 0.0;
    long k = 0;
    counting = 1;
    while (t < seconds - 1e-9) {
        double h = c->pattern == PATTERN_LONG ? 1e-3 : step_of(c, k);
        double next = c->pattern == PATTERN_IN_STEP || c->pattern == PATTERN_VARYING
                          ? t + h
                          : (double)(k + 1) * h;
        h = next - t;
        double start = call_times ? seconds_now() : 0.0;
        if (restore_at == k) {
            counting = 0;
            counting_restore = 1;
            if (m->restore_serialized_state(fmu)) fail("restoring a serialized FMU state", t);
            counting_restore = 0;
            counting = 1;
        }
        if (m->set_time(fmu, t) || (c->road == ROAD_INPUT && m->set_x_g(fmu, road_input(t))) ||
            m->set_states(fmu, x) || m->get_derivatives(fmu, start_rates))
            fail("the derivatives at the step's start", t);
        for (int i = 0; i < N_STATES; i++) trial[i] = x[i] + h * start_rates[i];
        if (m->set_time(fmu, next) ||
            (c->road == ROAD_INPUT && m->set_x_g(fmu, road_input(next))) ||
            m->set_states(fmu, trial) || m->get_derivatives(fmu, end_rates))
            fail("the derivatives at the step's end", next);
        for (int i = 0; i < N_STATES; i++) x[i] += 0.5 * h * (start_rates[i] + end_rates[i]);
        if (m->set_states(fmu, x) || m->get_indicators(fmu, z_end)) fail("the event indicators", next);
        if ((z[0] > 0.0) != (z_end[0] > 0.0)) {
            if (m->enter_event_mode(fmu)) fail("entering Event Mode", next);
            handle_event(m, next, x, z_end);
        }
        z[0] = z_end[0];
        if (m->completed_integrator_step(fmu, &terminate) || terminate)
            fail("the completed integrator step", next);
        if (m->read_outputs(fmu, values, &lift_offs)) fail("reading the outputs", next);
        if (call_times && k < max_calls) call_times[k] = seconds_now() - start;
        t = next;
        k++;
    }
    counting = 0;
    m->free_instance(fmu);
    return k;
}

/* FMI 2.0 Model Exchange. */
typedef struct {
    int newDiscreteStatesNeeded, terminateSimulation, nominalsOfContinuousStatesChanged,
        valuesOfContinuousStatesChanged, nextEventTimeDefined;
    double nextEventTime;
} fmi2EventInfo;

static struct {
    fmi2Status (*set_time)(fmi2Component, double);
    fmi2Status (*set_states)(fmi2Component, const double *, size_t);
    fmi2Status (*get_derivatives)(fmi2Component, double *, size_t);
    fmi2Status (*get_indicators)(fmi2Component, double *, size_t);
    fmi2Status (*get_states)(fmi2Component, double *, size_t);
    fmi2Status (*enter_event_mode)(fmi2Component);
    fmi2Status (*new_discrete_states)(fmi2Component, fmi2EventInfo *);
    fmi2Status (*enter_continuous_time_mode)(fmi2Component);
    fmi2Status (*completed_integrator_step)(fmi2Component, int, int *, int *);
    fmi2Status (*set_real)(fmi2Component, const unsigned *, size_t, const double *);
    fmi2Status (*get_real)(fmi2Component, const unsigned *, size_t, double *);
    fmi2Status (*get_integer)(fmi2Component, const unsigned *, size_t, int *);
    void (*free_instance)(fmi2Component);
} me2;

static int me2_set_time(void *i, double t) { return me2.set_time(i, t) > 1; }
static int me2_set_states(void *i, const double *x) { return me2.set_states(i, x, N_STATES) > 1; }
static int me2_get_derivatives(void *i, double *dx) { return me2.get_derivatives(i, dx, N_STATES) > 1; }
static int me2_get_indicators(void *i, double *z) { return me2.get_indicators(i, z, N_INDICATORS) > 1; }
static int me2_get_states(void *i, double *x) { return me2.get_states(i, x, N_STATES) > 1; }
static int me2_enter_event_mode(void *i) { return me2.enter_event_mode(i) > 1; }
static int me2_update(void *i, int *again, int *terminate) {
    fmi2EventInfo info;
    memset(&info, 0, sizeof info);
    int failed = me2.new_discrete_states(i, &info) > 1;
    *again = info.newDiscreteStatesNeeded;
    *terminate = info.terminateSimulation;
    return failed;
}
static int me2_enter_continuous(void *i) { return me2.enter_continuous_time_mode(i) > 1; }
static int me2_completed(void *i, int *terminate) {
    int enter = 0;
    return me2.completed_integrator_step(i, 1, &enter, terminate) > 1 || enter;
}
static int me2_set_x_g(void *i, double x_g) {
    const unsigned vr = VR_X_G;
    return me2.set_real(i, &vr, 1, &x_g) > 1;
}
static int me2_read_outputs(void *i, double *values, int *lift_offs) {
    const unsigned vr = VR_LIFT_OFF_COUNT;
    return me2.get_real(i, OUTPUTS, N_OUTPUTS, values) > 1 || me2.get_integer(i, &vr, 1, lift_offs) > 1;
}
static void me2_free(void *i) { me2.free_instance(i); }

static long run_model_exchange_fmi2(void *library, const char *token, const Case *c, double seconds) {
    fmi2Component (*instantiate)(const char *, int, const char *, const char *,
                                 const fmi2CallbackFunctions *, int, int);
    fmi2Status (*setup)(fmi2Component, int, double, double, int, double);
    fmi2Status (*enter_init)(fmi2Component);
    fmi2Status (*exit_init)(fmi2Component);
    fmi2Status (*set_integer)(fmi2Component, const unsigned *, size_t, const int *);
    SYM(instantiate, library, "fmi2Instantiate");
    SYM(setup, library, "fmi2SetupExperiment");
    SYM(enter_init, library, "fmi2EnterInitializationMode");
    SYM(exit_init, library, "fmi2ExitInitializationMode");
    SYM(set_integer, library, "fmi2SetInteger");
    SYM(me2.set_time, library, "fmi2SetTime");
    SYM(me2.set_states, library, "fmi2SetContinuousStates");
    SYM(me2.get_derivatives, library, "fmi2GetDerivatives");
    SYM(me2.get_indicators, library, "fmi2GetEventIndicators");
    SYM(me2.get_states, library, "fmi2GetContinuousStates");
    SYM(me2.enter_event_mode, library, "fmi2EnterEventMode");
    SYM(me2.new_discrete_states, library, "fmi2NewDiscreteStates");
    SYM(me2.enter_continuous_time_mode, library, "fmi2EnterContinuousTimeMode");
    SYM(me2.completed_integrator_step, library, "fmi2CompletedIntegratorStep");
    SYM(me2.set_real, library, "fmi2SetReal");
    SYM(me2.get_real, library, "fmi2GetReal");
    SYM(me2.get_integer, library, "fmi2GetInteger");
    bind_states2(library);
    SYM(me2.free_instance, library, "fmi2FreeInstance");

    static const fmi2CallbackFunctions callbacks = {logger2, master_allocate, free, NULL, NULL};
    fmi2Component instance = instantiate("realtime", 0, token, NULL, &callbacks, 0, 0);
    if (!instance) fail("fmi2Instantiate (Model Exchange)", 0.0);
    const unsigned integer_vrs[] = {VR_ROAD, VR_ROAD_CLASS, VR_TIRE_CONTACT};
    const int integers[] = {c->road, c->road_class, c->tire};
    const unsigned speed_vr = VR_VEHICLE_SPEED;
    if (set_integer(instance, integer_vrs, 3, integers) || me2.set_real(instance, &speed_vr, 1, &c->speed))
        fail("setting the parameters", 0.0);
    if (setup(instance, 0, 0.0, 0.0, 0, 0.0) || enter_init(instance) || exit_init(instance))
        fail("initialization", 0.0);
    const ModelExchangeMaster master = {
        instance, me2_set_time, me2_set_states, me2_get_derivatives, me2_get_indicators,
        me2_get_states, me2_enter_event_mode, me2_update, me2_enter_continuous, me2_completed,
        me2_set_x_g, me2_read_outputs, restore_serialized2, me2_free,
    };
    return run_model_exchange(&master, c, seconds);
}

/* FMI 3.0 Model Exchange. */
static struct {
    fmi3Status (*set_time)(fmi3Instance, fmi3Float64);
    fmi3Status (*set_states)(fmi3Instance, const fmi3Float64 *, size_t);
    fmi3Status (*get_derivatives)(fmi3Instance, fmi3Float64 *, size_t);
    fmi3Status (*get_indicators)(fmi3Instance, fmi3Float64 *, size_t);
    fmi3Status (*get_states)(fmi3Instance, fmi3Float64 *, size_t);
    fmi3Status (*enter_event_mode)(fmi3Instance);
    fmi3Status (*update_discrete_states)(fmi3Instance, fmi3Boolean *, fmi3Boolean *, fmi3Boolean *,
                                         fmi3Boolean *, fmi3Boolean *, fmi3Float64 *);
    fmi3Status (*enter_continuous_time_mode)(fmi3Instance);
    fmi3Status (*completed_integrator_step)(fmi3Instance, fmi3Boolean, fmi3Boolean *, fmi3Boolean *);
    fmi3SetFloat64TYPE set_float64;
    fmi3Status (*get_int32)(fmi3Instance, const fmi3ValueReference[], size_t, fmi3Int32[], size_t);
    fmi3FreeInstanceTYPE free_instance;
} me3;

static int me3_set_time(void *i, double t) { return me3.set_time(i, t) > fmi3Warning; }
static int me3_set_states(void *i, const double *x) { return me3.set_states(i, x, N_STATES) > fmi3Warning; }
static int me3_get_derivatives(void *i, double *dx) {
    return me3.get_derivatives(i, dx, N_STATES) > fmi3Warning;
}
static int me3_get_indicators(void *i, double *z) {
    return me3.get_indicators(i, z, N_INDICATORS) > fmi3Warning;
}
static int me3_get_states(void *i, double *x) { return me3.get_states(i, x, N_STATES) > fmi3Warning; }
static int me3_enter_event_mode(void *i) { return me3.enter_event_mode(i) > fmi3Warning; }
static int me3_update(void *i, int *again, int *terminate) {
    fmi3Boolean needed = 0, stop = 0, nominals = 0, values = 0, defined = 0;
    double next = 0.0;
    int failed = me3.update_discrete_states(i, &needed, &stop, &nominals, &values, &defined, &next) >
                 fmi3Warning;
    *again = needed;
    *terminate = stop;
    return failed;
}
static int me3_enter_continuous(void *i) { return me3.enter_continuous_time_mode(i) > fmi3Warning; }
static int me3_completed(void *i, int *terminate) {
    fmi3Boolean enter = 0, stop = 0;
    int failed = me3.completed_integrator_step(i, 1, &enter, &stop) > fmi3Warning || enter;
    *terminate = stop;
    return failed;
}
static int me3_set_x_g(void *i, double x_g) {
    const fmi3ValueReference vr = VR_X_G;
    return me3.set_float64(i, &vr, 1, &x_g, 1) > fmi3Warning;
}
static int me3_read_outputs(void *i, double *values, int *lift_offs) {
    const fmi3ValueReference vr = VR_LIFT_OFF_COUNT;
    fmi3Int32 count = 0;
    int failed = get_float64(i, OUTPUTS, N_OUTPUTS, values, N_OUTPUTS) > fmi3Warning ||
                 me3.get_int32(i, &vr, 1, &count, 1) > fmi3Warning;
    *lift_offs = count;
    return failed;
}
static void me3_free(void *i) { me3.free_instance(i); }

static long run_model_exchange_fmi3(void *library, const char *token, const Case *c, double seconds) {
    fmi3Instance (*instantiate)(fmi3String, fmi3String, fmi3String, fmi3Boolean, fmi3Boolean,
                                fmi3InstanceEnvironment, fmi3LogMessageCallback);
    fmi3EnterInitializationModeTYPE enter_init;
    fmi3ExitInitializationModeTYPE exit_init;
    fmi3SetInt64TYPE set_int64;
    SYM(instantiate, library, "fmi3InstantiateModelExchange");
    SYM(enter_init, library, "fmi3EnterInitializationMode");
    SYM(exit_init, library, "fmi3ExitInitializationMode");
    SYM(set_int64, library, "fmi3SetInt64");
    SYM(get_float64, library, "fmi3GetFloat64");
    SYM(me3.set_time, library, "fmi3SetTime");
    SYM(me3.set_states, library, "fmi3SetContinuousStates");
    SYM(me3.get_derivatives, library, "fmi3GetContinuousStateDerivatives");
    SYM(me3.get_indicators, library, "fmi3GetEventIndicators");
    SYM(me3.get_states, library, "fmi3GetContinuousStates");
    SYM(me3.enter_event_mode, library, "fmi3EnterEventMode");
    SYM(me3.update_discrete_states, library, "fmi3UpdateDiscreteStates");
    SYM(me3.enter_continuous_time_mode, library, "fmi3EnterContinuousTimeMode");
    SYM(me3.completed_integrator_step, library, "fmi3CompletedIntegratorStep");
    SYM(me3.set_float64, library, "fmi3SetFloat64");
    SYM(me3.get_int32, library, "fmi3GetInt32");
    bind_states3(library);
    SYM(me3.free_instance, library, "fmi3FreeInstance");

    fmi3Instance instance = instantiate("realtime", token, NULL, 0, 0, NULL, logger3);
    if (!instance) fail("fmi3InstantiateModelExchange", 0.0);
    const fmi3ValueReference enum_vrs[] = {VR_ROAD, VR_ROAD_CLASS, VR_TIRE_CONTACT};
    const fmi3Int64 enums[] = {c->road, c->road_class, c->tire};
    const fmi3ValueReference speed_vr = VR_VEHICLE_SPEED;
    if (set_int64(instance, enum_vrs, 3, enums, 3) ||
        me3.set_float64(instance, &speed_vr, 1, &c->speed, 1))
        fail("setting the parameters", 0.0);
    if (enter_init(instance, 0, 0.0, 0.0, 0, 0.0) || exit_init(instance)) fail("initialization", 0.0);
    const ModelExchangeMaster master = {
        instance, me3_set_time, me3_set_states, me3_get_derivatives, me3_get_indicators,
        me3_get_states, me3_enter_event_mode, me3_update, me3_enter_continuous, me3_completed,
        me3_set_x_g, me3_read_outputs, restore_serialized3, me3_free,
    };
    return run_model_exchange(&master, c, seconds);
}

static long run(int fmi, void *library, const char *token, const Case *c, double seconds,
                int change_g) {
    if (c->model == MODEL_CHASSIS) return run_chassis(fmi, library, token, c, seconds);
    outputs = c->model == MODEL_CORNER ? CORNER_OUTPUTS : OUTPUTS;
    n_outputs = c->model == MODEL_CORNER ? N_CORNER_OUTPUTS : N_OUTPUTS;
    body_z = body_v = body_a = 0.0;
    return fmi == 2 ? run_fmi2(library, token, c, seconds, change_g)
                    : run_fmi3(library, token, c, seconds, change_g);
}

static int compare(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(int argc, char **argv) {
    make_cases();
    if (argc == 2 && !strcmp(argv[1], "list")) {
        for (int i = 0; i < n_cases; i++) printf("%s\n", cases[i].name);
        return 0;
    }
    int count_mode = argc == 6 && !strcmp(argv[1], "count");
    int model_exchange_mode = argc == 6 && !strcmp(argv[1], "count-me");
    int worst_me_mode = argc == 8 && !strcmp(argv[1], "worst-me");
    int worst_mode = (argc == 8 && !strcmp(argv[1], "worst")) || worst_me_mode;
    if (!count_mode && !model_exchange_mode && !worst_mode) {
        fprintf(stderr,
                "usage: %s list | count FMI LIB TOKEN CASE | count-me FMI LIB TOKEN CASE | worst FMI LIB "
                "TOKEN CASE REPEATS SECONDS | worst-me FMI LIB TOKEN CASE REPEATS SECONDS\n",
                argv[0]);
        return 2;
    }
    int fmi = atoi(argv[2]);
    if (fmi != 2 && fmi != 3) {
        fprintf(stderr, "FMI must be 2 or 3\n");
        return 2;
    }
    void *library = open_library(argv[3]);
    const char *token = argv[4];
    const Case *c = find_case(argv[5]);
    if (model_exchange_mode && c->model != MODEL_QUARTER_CAR) {
        fprintf(stderr, "%s: the corner and the chassis are Co-Simulation only\n", c->name);
        return 2;
    }
    if (model_exchange_mode) {
        restore_at = 15000;
        long steps = fmi == 2 ? run_model_exchange_fmi2(library, token, c, 30.0)
                              : run_model_exchange_fmi3(library, token, c, 30.0);
        printf("allocations %ld steps %ld (restoring a serialized state: %ld allocations)\n", allocations,
               steps, restore_allocations);
        return allocations == 0 ? 0 : 1;
    }
    if (count_mode && c->model != MODEL_QUARTER_CAR) {
        /* 10 s, a serialized state restored after 5 s (the 10 ms steps: 500). */
        set_gain_every_call = 1;
        restore_at = c->pattern == PATTERN_LONG ? 500 : 5000;
        long calls = run(fmi, library, token, c, 10.0, 1);
        if (c->model == MODEL_CHASSIS)
            printf("allocations %ld calls %ld (restoring a serialized state: %ld allocations)\n",
                   allocations, calls, restore_allocations);
        else
            printf("allocations %ld calls %ld (g value changes: 2 calls, %ld allocations)\n", allocations,
                   calls, gain_change_allocations);
        return allocations == 0 ? 0 : 1;
    }
    if (count_mode) {
        set_gain_every_call = 1;
        restore_at = c->pattern == PATTERN_LONG ? 1500 : 15000;
        long calls = run(fmi, library, token, c, 30.0, 1);
        printf("allocations %ld calls %ld (g value changes: 2 calls, %ld allocations)\n",
               allocations, calls, gain_change_allocations);
        return allocations == 0 ? 0 : 1;
    }
    int repeats = atoi(argv[6]);
    double seconds = atof(argv[7]);
    if (repeats < 1 || !(seconds > 0.0)) {
        fprintf(stderr, "REPEATS and SECONDS must be positive\n");
        return 2;
    }
    max_calls = (long)(seconds / 0.1e-3) + 16;
    call_times = __libc_malloc(sizeof(double) * (size_t)max_calls);
    double *minima = __libc_malloc(sizeof(double) * (size_t)max_calls);
    long calls = 0;
    for (int r = 0; r < repeats; r++) {
        long n = !worst_me_mode ? run(fmi, library, token, c, seconds, 0)
                 : fmi == 2     ? run_model_exchange_fmi2(library, token, c, seconds)
                                : run_model_exchange_fmi3(library, token, c, seconds);
        if (r > 0 && n != calls) {
            fprintf(stderr, "repetition %d made %ld calls, the first %ld\n", r, n, calls);
            return 2;
        }
        calls = n < max_calls ? n : max_calls;
        for (long k = 0; k < calls; k++)
            minima[k] = r == 0 || call_times[k] < minima[k] ? call_times[k] : minima[k];
    }
    long worst = 0;
    for (long k = 1; k < calls; k++)
        if (minima[k] > minima[worst]) worst = k;
    double largest = minima[worst];
    qsort(minima, (size_t)calls, sizeof(double), compare);
    double median = minima[calls / 2];
    printf("%s FMI %d%s: %ld calls, %d repetitions; per-call minimum: median %.3f us, largest %.3f us "
           "(call %ld), largest/median %.1f\n",
           c->name, fmi, worst_me_mode ? " Model Exchange" : "", calls, repeats, median * 1e6,
           largest * 1e6, worst, largest / median);
    return 0;
}
