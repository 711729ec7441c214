/*
 * Cost of one fmi2DoStep through the real tdvass shared library (dlopen).
 *
 *   dostep_cost LIB GUID [REPEATS]
 *   dostep_cost --interleaved GUID CALLS ROUNDS LIB [LIB ...]
 *   dostep_cost --case N GUID CALLS LIB
 *
 * The first form:
 * 1. The fixed call cost, with the internal step pinned at 1e-4 s
 *    (max_internal_step): 15 s of the default experiment at 1 ms and 10 ms
 *    (10 and 100 internal steps, exact times t = k h and accumulated
 *    t += h), the fastest of REPEATS runs (default 7). A line through the
 *    exact-time costs gives the fixed call cost and the cost per internal
 *    step.
 * 2. The default tolerance (the FMU's internal step divides the
 *    DefaultExperiment stepSize: 1 ms): a doStep of one internal step
 *    (aligned, exact times), of 1 ms, and of steps that are not multiples
 *    of it (0.7 ms, 9.9e-5 s, 1e-7 s, and a master that varies its step
 *    among 0.13 ... 1.9 ms), each against the aligned one. Each runs at
 *    most 200 000 calls (or 15 s); times accumulated (t += step) unless
 *    EXACT is set in the environment.
 *
 * The second form compares builds of the library in one process (each
 * loaded with RTLD_LOCAL): ROUNDS rounds, each running CALLS calls of every
 * case above at the default tolerance with every library in turn, and the
 * fastest run of each (library, case). Interleaving puts the libraries
 * under the same load, which separate runs on a shared machine do not.
 *
 * The third form runs CALLS calls of case N alone (0 aligned, 1 1 ms with
 * t += h, 2 0.7 ms, 3 9.9e-5 s, 4 1e-7 s, 5 varying; 6, for the corner's
 * GUID only: 1 ms with t += h, the body's attachment point set before
 * every step, moving as 1 mm sin(2 pi 1.5 Hz t), as a chassis moves it;
 * 7, for the quarter car's GUID: the same with the road input, road = 0
 * and x_g set so before every step; 8, for the corner's GUID: case 6 with
 * input_extrapolation = 1, the attachment on the extrapolated velocity),
 * for an instruction count: under callgrind, the difference of two CALLS
 * over their difference is the cost of one call.
 *
 * Figures in BENCHMARKS.md.
 */
#define _POSIX_C_SOURCE 199309L
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

typedef void *fmi2Component;
typedef int fmi2Status;
typedef struct {
    void (*logger)(void *, const char *, fmi2Status, const char *, const char *, ...);
    void *(*allocateMemory)(size_t, size_t);
    void (*freeMemory)(void *);
    void (*stepFinished)(void *, fmi2Status);
    void *componentEnvironment;
} fmi2CallbackFunctions;

static void logger(void *env, const char *name, fmi2Status status, const char *category,
                   const char *message, ...) {
    (void)env, (void)name, (void)status, (void)category, (void)message;
}

static const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};

/* The functions of one loaded library. */
typedef struct {
    fmi2Component (*instantiate)(const char *, int, const char *, const char *,
                                 const fmi2CallbackFunctions *, int, int);
    void (*free_instance)(fmi2Component);
    fmi2Status (*setup)(fmi2Component, int, double, double, int, double);
    fmi2Status (*enter_init)(fmi2Component);
    fmi2Status (*exit_init)(fmi2Component);
    fmi2Status (*do_step)(fmi2Component, double, double, int);
    fmi2Status (*set_real)(fmi2Component, const unsigned *, size_t, const double *);
    fmi2Status (*set_integer)(fmi2Component, const unsigned *, size_t, const int *);
} Library;

/* Value reference of max_internal_step. */
static const unsigned MAX_INTERNAL_STEP = 20;
/* Value references of the corner's body_displacement and body_velocity. */
static const unsigned BODY_INPUTS[2] = {143, 144};
/* Value references of the quarter car's road (Integer) and x_g. */
static const unsigned ROAD = 12, ROAD_INPUT = 30;
/* Value reference of input_extrapolation (Integer). */
static const unsigned EXTRAPOLATION = 48;
/* The default experiment's internal step at the default tolerance. */
static const double DEFAULT_INTERNAL_STEP = 1e-3;
/* The step sizes of the varying master (s), taken in turn. */
static const double VARYING[] = {0.13e-3, 1.9e-3, 0.71e-3, 0.29e-3, 1.37e-3, 0.53e-3, 1.03e-3};

static void *symbol(void *lib, const char *name) {
    void *f = dlsym(lib, name);
    if (!f) {
        fprintf(stderr, "missing %s\n", name);
        exit(1);
    }
    return f;
}

static Library load(const char *path) {
    void *lib = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fprintf(stderr, "%s\n", dlerror());
        exit(1);
    }
    Library l;
    *(void **)&l.instantiate = symbol(lib, "fmi2Instantiate");
    *(void **)&l.free_instance = symbol(lib, "fmi2FreeInstance");
    *(void **)&l.setup = symbol(lib, "fmi2SetupExperiment");
    *(void **)&l.enter_init = symbol(lib, "fmi2EnterInitializationMode");
    *(void **)&l.exit_init = symbol(lib, "fmi2ExitInitializationMode");
    *(void **)&l.do_step = symbol(lib, "fmi2DoStep");
    *(void **)&l.set_real = symbol(lib, "fmi2SetReal");
    *(void **)&l.set_integer = symbol(lib, "fmi2SetInteger");
    return l;
}

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* Seconds per fmi2DoStep with step h (h < 0: the varying master) over
 * `calls` calls (0: 15 s, at most 200 000 calls); `accumulate`: t += h;
 * `bound`: the max_internal_step set before initialization (0: none);
 * `body`: 1, the corner's body inputs set before every step; 2, the
 * quarter car's road input; 3, as 1 with input_extrapolation = 1. */
static double run_body(const Library *l, const char *guid, double h, int accumulate, double bound,
                       long calls, int body) {
    fmi2Component c = l->instantiate("bench", 1, guid, NULL, &callbacks, 0, 0);
    const int road_input = 0, extrapolate = 1;
    if (!c || l->set_real(c, &MAX_INTERNAL_STEP, 1, &bound) ||
        (body == 2 && l->set_integer(c, &ROAD, 1, &road_input)) ||
        (body == 3 && l->set_integer(c, &EXTRAPOLATION, 1, &extrapolate)) ||
        l->setup(c, 0, 0.0, 0.0, 0, 0.0) ||
        l->enter_init(c) || l->exit_init(c)) {
        fprintf(stderr, "cannot start an instance\n");
        exit(1);
    }
    double mean = h > 0 ? h : 0.8e-3;
    long n = calls > 0 ? calls : (long)(15.0 / mean + 0.5);
    if (calls <= 0 && n > 200000) n = 200000;
    double t = 0.0;
    double start = now();
    for (long k = 0; k < n; k++) {
        double step = h > 0 ? h : VARYING[k % 7];
        if (body) {
            const double w = 2.0 * 3.141592653589793 * 1.5;
            const double motion[2] = {1e-3 * __builtin_sin(w * t), 1e-3 * w * __builtin_cos(w * t)};
            int refused = body == 2 ? l->set_real(c, &ROAD_INPUT, 1, motion)
                                    : l->set_real(c, BODY_INPUTS, 2, motion);
            if (refused) {
                fprintf(stderr, "fmi2SetReal of the inputs failed (the GUID of another model?)\n");
                exit(1);
            }
        }
        if (l->do_step(c, t, step, 1) != 0) {
            fprintf(stderr, "fmi2DoStep failed at t = %g\n", t);
            exit(1);
        }
        t = accumulate || h < 0 ? t + step : (double)(k + 1) * h;
    }
    double seconds = (now() - start) / n;
    l->free_instance(c);
    return seconds;
}

static double run(const Library *l, const char *guid, double h, int accumulate, double bound,
                  long calls) {
    return run_body(l, guid, h, accumulate, bound, calls, 0);
}

static double fastest(const Library *l, const char *guid, double h, int accumulate, double bound,
                      int repeats) {
    double best = 1e30;
    for (int i = 0; i < repeats; i++) {
        double s = run(l, guid, h, accumulate, bound, 0);
        best = s < best ? s : best;
    }
    return best;
}

/* The cases at the default tolerance: step (< 0: varying) and whether the
 * master accumulates its time. */
#define CASES 6
static const double CASE_STEP[CASES] = {1e-3, 1e-3, 0.7e-3, 9.9e-5, 1e-7, -1.0};
static const int CASE_ACCUMULATED[CASES] = {0, 1, 1, 1, 1, 1};
static const char *CASE_NAME[CASES] = {"aligned, t = k h", "1 ms, t += h", "0.7 ms",
                                       "9.9e-5 s",         "1e-7 s",       "varying"};

#define MAX_LIBRARIES 8

static int interleaved(int argc, char **argv) {
    if (argc < 6) {
        fprintf(stderr, "usage: %s --interleaved GUID CALLS ROUNDS LIB [LIB ...]\n", argv[0]);
        return 2;
    }
    const char *guid = argv[2];
    long calls = atol(argv[3]);
    int rounds = atoi(argv[4]);
    int count = argc - 5;
    if (count > MAX_LIBRARIES || calls <= 0 || rounds <= 0) {
        fprintf(stderr, "CALLS and ROUNDS must be positive, at most %d libraries\n",
                MAX_LIBRARIES);
        return 2;
    }
    Library libraries[MAX_LIBRARIES];
    double best[MAX_LIBRARIES][CASES];
    for (int i = 0; i < count; i++) {
        libraries[i] = load(argv[5 + i]);
        for (int j = 0; j < CASES; j++) best[i][j] = 1e30;
    }
    for (int r = 0; r < rounds; r++) {
        for (int j = 0; j < CASES; j++) {
            for (int i = 0; i < count; i++) {
                double s = run(&libraries[i], guid, CASE_STEP[j], CASE_ACCUMULATED[j], 0.0, calls);
                best[i][j] = s < best[i][j] ? s : best[i][j];
            }
        }
    }
    printf("fmi2DoStep at the default tolerance, fastest of %d interleaved runs of %ld calls\n",
           rounds, calls);
    printf("(us per call; in brackets: against the aligned call, against 1 ms with t += h)\n");
    for (int i = 0; i < count; i++) {
        printf("%s\n", argv[5 + i]);
        for (int j = 0; j < CASES; j++) {
            printf("  %-18s %7.3f", CASE_NAME[j], best[i][j] * 1e6);
            if (j > 0) printf("  (%.2f, %.2f)", best[i][j] / best[i][0], best[i][j] / best[i][1]);
            printf("\n");
        }
    }
    return 0;
}

static int one_case(int argc, char **argv) {
    int which = argc == 6 ? atoi(argv[2]) : -1;
    long calls = argc == 6 ? atol(argv[4]) : 0;
    if (which < 0 || which > CASES + 2 || calls <= 0) {
        fprintf(stderr, "usage: %s --case N GUID CALLS LIB (N in 0..%d, CALLS > 0)\n", argv[0],
                CASES + 2);
        return 2;
    }
    Library l = load(argv[5]);
    if (which >= CASES) {
        int body = which - CASES + 1;
        double s = run_body(&l, argv[3], 1e-3, 1, 0.0, calls, body);
        const char *what[3] = {"body moving (corner)", "road input moving (quarter car)",
                               "body moving, extrapolated (corner)"};
        printf("1 ms, t += h, %s: %.3f us per call\n", what[body - 1], s * 1e6);
        return 0;
    }
    double s = run(&l, argv[3], CASE_STEP[which], CASE_ACCUMULATED[which], 0.0, calls);
    printf("%s: %.3f us per call\n", CASE_NAME[which], s * 1e6);
    return 0;
}

int main(int argc, char **argv) {
    if (argc > 1 && strcmp(argv[1], "--interleaved") == 0) return interleaved(argc, argv);
    if (argc > 1 && strcmp(argv[1], "--case") == 0) return one_case(argc, argv);
    if (argc < 3) {
        fprintf(stderr, "usage: %s LIB GUID [REPEATS]\n", argv[0]);
        return 2;
    }
    Library l = load(argv[1]);
    const char *guid = argv[2];
    int repeats = argc > 3 ? atoi(argv[3]) : 7;
    double exact_10 = fastest(&l, guid, 1e-3, 0, 1e-4, repeats);
    double exact_100 = fastest(&l, guid, 1e-2, 0, 1e-4, repeats);
    double drift_10 = fastest(&l, guid, 1e-3, 1, 1e-4, repeats);
    double drift_100 = fastest(&l, guid, 1e-2, 1, 1e-4, repeats);
    double per_step = (exact_100 - exact_10) / 90.0;
    double fixed = exact_10 - 10.0 * per_step;
    printf("fmi2DoStep, default experiment, fastest of %d runs:\n", repeats);
    printf("internal step pinned at 1e-4 s (max_internal_step):\n");
    printf("  1 ms (10 internal steps):   exact t = k h %7.3f us, accumulated t += h %7.3f us\n",
           exact_10 * 1e6, drift_10 * 1e6);
    printf("  10 ms (100 internal steps): exact t = k h %7.3f us, accumulated t += h %7.3f us\n",
           exact_100 * 1e6, drift_100 * 1e6);
    printf("  fit on exact times: %.2f ns per internal step, fixed call cost %.3f us\n",
           per_step * 1e9, fixed * 1e6);
    double aligned = fastest(&l, guid, DEFAULT_INTERNAL_STEP, 0, 0.0, repeats);
    printf("default tolerance (internal step %.6g s):\n", DEFAULT_INTERNAL_STEP);
    printf("  %-28s %8.3f us\n", "aligned (one internal step)", aligned * 1e6);
    const double steps[] = {1e-3, 0.7e-3, 9.9e-5, 1e-7, -1.0};
    const char *names[] = {"1 ms", "0.7 ms", "9.9e-5 s", "1e-7 s", "varying 0.13 to 1.9 ms"};
    for (int i = 0; i < 5; i++) {
        double cost = fastest(&l, guid, steps[i], getenv("EXACT") ? 0 : 1, 0.0, repeats);
        printf("  %-28s %8.3f us  (%.2f x aligned)\n", names[i], cost * 1e6, cost / aligned);
    }
    return 0;
}
