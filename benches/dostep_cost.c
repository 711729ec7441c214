/*
 * Cost of one fmi2DoStep through the real tdvass shared library (dlopen),
 * with exact (t = k h) and accumulated (t += h) communication times.
 *
 *   dostep_cost LIB GUID [REPEATS]
 *
 * For each time style and communication step h (1 ms and 10 ms, that is 10
 * and 100 internal steps of 1e-4 s) it runs 15 s of the default experiment
 * and keeps the fastest of REPEATS runs (default 7). A line through the
 * exact-time costs at 10 and 100 internal steps gives the fixed call cost
 * and the cost per internal step; the ratios printed compare each 1 ms cost
 * with "10 internal steps plus the fixed call cost" and the two time styles
 * with each other. Figures in BENCHMARKS.md.
 */
#define _POSIX_C_SOURCE 199309L
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
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

static fmi2Component (*instantiate)(const char *, int, const char *, const char *,
                                    const fmi2CallbackFunctions *, int, int);
static void (*free_instance)(fmi2Component);
static fmi2Status (*setup)(fmi2Component, int, double, double, int, double);
static fmi2Status (*enter_init)(fmi2Component);
static fmi2Status (*exit_init)(fmi2Component);
static fmi2Status (*do_step)(fmi2Component, double, double, int);

static void *symbol(void *lib, const char *name) {
    void *f = dlsym(lib, name);
    if (!f) {
        fprintf(stderr, "missing %s\n", name);
        exit(1);
    }
    return f;
}

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* Seconds per fmi2DoStep over 15 s with step h; `accumulate`: t += h. */
static double run(const char *guid, double h, int accumulate) {
    fmi2Component c = instantiate("bench", 1, guid, NULL, &callbacks, 0, 0);
    if (!c || setup(c, 0, 0.0, 0.0, 0, 0.0) || enter_init(c) || exit_init(c)) {
        fprintf(stderr, "cannot start an instance\n");
        exit(1);
    }
    long n = (long)(15.0 / h + 0.5);
    double t = 0.0;
    double start = now();
    for (long k = 0; k < n; k++) {
        if (do_step(c, t, h, 1) != 0) {
            fprintf(stderr, "fmi2DoStep failed at t = %g\n", t);
            exit(1);
        }
        t = accumulate ? t + h : (double)(k + 1) * h;
    }
    double seconds = (now() - start) / n;
    free_instance(c);
    return seconds;
}

static double fastest(const char *guid, double h, int accumulate, int repeats) {
    double best = 1e30;
    for (int i = 0; i < repeats; i++) {
        double s = run(guid, h, accumulate);
        best = s < best ? s : best;
    }
    return best;
}

int main(int argc, char **argv) {
    if (argc < 3) {
        fprintf(stderr, "usage: %s LIB GUID [REPEATS]\n", argv[0]);
        return 2;
    }
    void *lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fprintf(stderr, "%s\n", dlerror());
        return 1;
    }
    int repeats = argc > 3 ? atoi(argv[3]) : 7;
    *(void **)&instantiate = symbol(lib, "fmi2Instantiate");
    *(void **)&free_instance = symbol(lib, "fmi2FreeInstance");
    *(void **)&setup = symbol(lib, "fmi2SetupExperiment");
    *(void **)&enter_init = symbol(lib, "fmi2EnterInitializationMode");
    *(void **)&exit_init = symbol(lib, "fmi2ExitInitializationMode");
    *(void **)&do_step = symbol(lib, "fmi2DoStep");
    double exact_10 = fastest(argv[2], 1e-3, 0, repeats);
    double exact_100 = fastest(argv[2], 1e-2, 0, repeats);
    double drift_10 = fastest(argv[2], 1e-3, 1, repeats);
    double drift_100 = fastest(argv[2], 1e-2, 1, repeats);
    double per_step = (exact_100 - exact_10) / 90.0;
    double fixed = exact_10 - 10.0 * per_step;
    printf("fmi2DoStep, default experiment, fastest of %d runs of 15 s:\n", repeats);
    printf("  1 ms (10 internal steps):   exact t = k h %7.3f us, accumulated t += h %7.3f us\n",
           exact_10 * 1e6, drift_10 * 1e6);
    printf("  10 ms (100 internal steps): exact t = k h %7.3f us, accumulated t += h %7.3f us\n",
           exact_100 * 1e6, drift_100 * 1e6);
    printf("  fit on exact times: %.2f ns per internal step, fixed call cost %.3f us\n",
           per_step * 1e9, fixed * 1e6);
    printf("  1 ms against 10 internal steps + fixed cost: exact %.3f, accumulated %.3f\n",
           exact_10 / (fixed + 10.0 * per_step), drift_10 / (fixed + 10.0 * per_step));
    printf("  accumulated / exact: 1 ms %.3f, 10 ms %.3f\n", drift_10 / exact_10,
           drift_100 / exact_100);
    return 0;
}
