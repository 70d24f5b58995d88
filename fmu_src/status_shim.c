/* The status shim: the FMU's binary on Linux, in front of the one that runs the Python slave.
 *
 * Behind it (ORIGINAL_LIBRARY, "the original" below) is the Python bridge (python_bridge.c), or
 * pythonfmu 0.7.0's binary where the bridge could not be built. Both keep pythonfmu's contract:
 * fmi2OK from every call but doStep (fmi2Discard when the slave's do_step returns False), and
 * fmi2Fatal for a Python exception. This library exports the FMI 2.0 co-simulation API under the
 * FMU's model identifier and forwards every call to the original, shipped beside it. After the
 * calls that can fail on the importer's values (fmi2ExitInitializationMode,
 * fmi2SetReal/Integer/Boolean/String, fmi2SetFMUstate) have returned fmi2OK from the original, it
 * reads the slave's Integer variable STATUS_VR (fmi_status: the status of the slave's last such
 * call) through the original's fmi2GetInteger and returns that status when it is worse than
 * fmi2OK; after fmi2DoStep, when the original returned fmi2Discard, it returns fmi2Error where the
 * slave says so.
 *
 * A call the slave does not report in fmi_status (a getter, setupExperiment, enterInitializationMode,
 * terminate, the FMU-state calls) returns fmi2Error when the slave logged a message of status
 * fmi2Error or worse during it (filtered_log counts them): an unknown value reference read, a getter
 * before initialization mode, terminate outside a run.
 *
 * Calls the shim answers itself, its messages naming the scene file (SCENE_FILE) as the slave's do:
 *   - the functions this FMU does not support (fmi2GetDirectionalDerivative,
 *     fmi2SetRealInputDerivatives, fmi2GetRealOutputDerivatives, fmi2CancelStep: the capability
 *     flags of modelDescription.xml say so) return fmi2Error without entering Python, and change
 *     nothing (pythonfmu's binary logged a message that named no file);
 *   - the status functions (FMI 2.0 section 4.2.3): fmi2Error outside the states FMI 2.0 allows
 *     them in (stepComplete, stepFailed, terminated: section 4.2.4's table; the slave's phase is read
 *     through the private Integer NATIVE_SYNC_VR + 2), fmi2Discard for a status kind the function does
 *     not answer or that does not apply (fmi2DoStepStatus and fmi2PendingStatus: no doStep is ever
 *     pending, section 2.1.3: "fmi2Discard is returned also if the slave is not able to return the
 *     required status information"); fmi2LastSuccessfulTime is the slave's time (the private Real
 *     NATIVE_SYNC_VR + 1); fmi2Terminated is fmi2True after a doStep this FMU discarded (the run
 *     cannot go on from there: the message says why) until a doStep succeeds, a state is restored
 *     or the instance is reset (section 4.2.3: "Can be called after doStep returned fmi2Discard"; a
 *     master such as fmpy asks it to decide whether to end the run or retry the step);
 *   - fmi2DeSerializeFMUstate first hands the bytes (in hex) to the slave through the private String
 *     NATIVE_SYNC_VR + 3, which checks that they are a state of this FMU and logs why not; then it
 *     returns fmi2Error and makes no state (pythonfmu's binary took any bytes, and only
 *     fmi2SetFMUstate refused them).
 *
 * The component the importer holds is this library's (struct instance), wrapping the original's:
 * every call is forwarded with the original's component, and the slave's messages reach the
 * importer through the original's logger calls as before.
 *
 * Which messages reach the importer. The original passes the slave's messages on only while
 * the importer has logging on (fmi2Instantiate's loggingOn, fmi2SetDebugLogging), so with logging
 * off (fmpy's default) an fmi2Error said nothing of its cause. The shim keeps the original's
 * logging always on, with every category, through its own logger (filtered_log, with the instance
 * as the original's component environment), and passes on a message when the importer has logging
 * on and selected its category (fmi2SetDebugLogging's categories, all when it named none; an unknown
 * one is fmi2Error), or when its status is fmi2Discard, fmi2Error or fmi2Fatal: the reason for a status the
 * importer must act on is always logged, as FMI's reference implementations log errors.
 *
 * The native doStep (inerter/fmu/native.py says the protocol). After fmi2Instantiate and after
 * fmi2Reset (which replaces the slave object) the shim reads the slave's context address through the private Integer value references NATIVE_LINK_VR and
 * NATIVE_LINK_VR + 1. After a doStep the slave took and returned fmi2OK, and after an
 * fmi2ExitInitializationMode that returned fmi2OK, it arms itself where the context says so, and
 * then takes the next doStep by calling the context's C function on the
 * context's table without entering Python, and serves every getter from the context's map until a
 * call enters Python (outputs from the values the function wrote, every other variable from arrays
 * the slave filled when it armed the link). A step the function declines goes to the slave. Before
 * any other call enters Python after native steps, the shim sets the private Integer
 * NATIVE_SYNC_VR, and the slave takes them over. Every call but fmi2DoStep and the getters disarms
 * it until the next step the slave takes.
 *
 * The live logger. The original hands the slave's messages to the importer's logger when
 * the call that made them returns. A long call (exitInitializationMode while the kernels compile,
 * about a minute on a machine's first use) would say nothing until its end, so the shim writes the
 * address of live_log and of the instance into the context's CTX_LOG_FUNCTION and CTX_LOG_TARGET:
 * the slave calls it from within the call, on its thread, and the message reaches the importer's
 * logger at once, where it passes as the original's messages do (below).
 *
 * Build (inerter/fmu/build.py does it, with the value reference from modelDescription.xml):
 *   gcc -shared -fPIC -O2 -fvisibility=hidden -pthread -DSTATUS_VR=<n> \
 *       -DNATIVE_LINK_VR=<n> -DNATIVE_SYNC_VR=<n> -DNATIVE_MAGIC=<n> \
 *       -DORIGINAL_LIBRARY='"<modelIdentifier>.bridge.so"' -o <modelIdentifier>.so \
 *       status_shim.c -ldl
 *
 * The original is loaded at the first call (fmi2Instantiate, or fmi2GetVersion /
 * fmi2GetTypesPlatform before it) and unloaded when this library is.
 *
 * The exit of a process that loaded pythonfmu's binary as the original (the bridge has no such
 * state: it never finalises Python, and what follows does nothing for it). pythonfmu 0.7.0's
 * binary holds its Python state in a global std::shared_ptr (`pyState`), releases it in its
 * exported finalizePythonInterpreter(), and calls that from a destructor function (.fini_array).
 * When the binary is unloaded by dlclose, that runs before the shared_ptr's own C++ destructor,
 * and all is well. When the binary is still
 * loaded at exit(), the order is reversed: exit() runs the C++ destructor first (registered with
 * __cxa_atexit when the binary was loaded), which frees the state, and the destructor function
 * afterwards (_dl_fini), whose release finds the pointers the C++ destructor left behind and
 * decrements a word of the freed block. That write to freed heap memory is reported later, or not,
 * depending on what the block has become (glibc: "corrupted double-linked list" at exit). The first
 * pythonfmu binary a process loads is always still loaded at exit: it defines STB_GNU_UNIQUE
 * symbols of libstdc++, so glibc never unloads it. So the shim has the original release its state
 * before exit() reaches that C++ destructor:
 *   - while this library is loaded, with an exit handler registered after the original was loaded
 *     (exit handlers run last registered first): release_python_state;
 *   - when this library is unloaded (unload_original), right then where the state owns no
 *     interpreter (Python was running when the original was loaded afresh: a Python importer, or
 *     an earlier FMU's Python); where it may (the original started Python, which pythonfmu keeps
 *     running until exit, or was loaded before), the original is kept loaded and its
 *     finalizePythonInterpreter itself becomes an exit handler.
 * A second release finds the pointer null and does nothing.
 */
#ifndef _GNU_SOURCE
#define _GNU_SOURCE /* dladdr */
#endif

#include <dlfcn.h>
#include <limits.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2_types.h"
#include "log_format.h"

#ifndef STATUS_VR
#error "compile with -DSTATUS_VR=<value reference of the slave's status variable>"
#endif
#ifndef ORIGINAL_LIBRARY
#error "compile with -DORIGINAL_LIBRARY='\"<file name of the original>\"'"
#endif
#if !defined(NATIVE_LINK_VR) || !defined(NATIVE_SYNC_VR) || !defined(NATIVE_MAGIC)
#error "compile with -DNATIVE_LINK_VR, -DNATIVE_SYNC_VR and -DNATIVE_MAGIC (inerter/fmu/native.py)"
#endif
#ifndef SCENE_FILE
#error "compile with -DSCENE_FILE='\"<the scene file's name>\"' (the name the messages give)"
#endif
#ifndef PATH_MAX
#define PATH_MAX 4096
#endif

/* The slave's private value references beside NATIVE_SYNC_VR (inerter/fmu/native.py): its time
 * (Real), its phase (Integer), the check of serialized bytes (String), its stop time (Real, NaN:
 * none). */
#define TIME_VR (NATIVE_SYNC_VR + 1u)
#define PHASE_VR (NATIVE_SYNC_VR + 2u)
#define STATE_CHECK_VR (NATIVE_SYNC_VR + 3u)
#define STOP_VR (NATIVE_SYNC_VR + 4u)

#define EXPORT __attribute__((visibility("default")))

/* Every function of the co-simulation API, in the standard's order. */
#define FMI2_FUNCTIONS(X)                                                                       \
    X(GetTypesPlatform) X(GetVersion) X(SetDebugLogging) X(Instantiate) X(FreeInstance)         \
    X(SetupExperiment) X(EnterInitializationMode) X(ExitInitializationMode) X(Terminate)        \
    X(Reset) X(GetReal) X(GetInteger) X(GetBoolean) X(GetString) X(SetReal) X(SetInteger)        \
    X(SetBoolean) X(SetString) X(GetFMUstate) X(SetFMUstate) X(FreeFMUstate)                     \
    X(SerializedFMUstateSize) X(SerializeFMUstate) X(DeSerializeFMUstate)                        \
    X(GetDirectionalDerivative) X(SetRealInputDerivatives) X(GetRealOutputDerivatives)           \
    X(DoStep) X(CancelStep) X(GetStatus) X(GetRealStatus) X(GetIntegerStatus)                   \
    X(GetBooleanStatus) X(GetStringStatus)

/* The original's functions. */
#define FIELD(name) fmi2##name##TYPE *name;
static struct { FMI2_FUNCTIONS(FIELD) } original;
#undef FIELD

/* This library's exports, declared with the standard's types. */
#define DECLARE(name) EXPORT fmi2##name##TYPE fmi2##name;
FMI2_FUNCTIONS(DECLARE)
#undef DECLARE

static void *handle;                /* the original, once loaded */
static char original_path[PATH_MAX]; /* where it was loaded from */
static char load_error[PATH_MAX + 512];
static pthread_once_t load_once = PTHREAD_ONCE_INIT;

/* The original's finalizePythonInterpreter (pythonfmu's binary), or NULL; whether its state may
 * own the interpreter: no Python was running when the original was loaded, or it was loaded already
 * (by an earlier load of this library, which may have started Python through it). */
typedef void finalize_fn(void);
typedef int is_initialized_fn(void);
static finalize_fn *finalize_python;
static int may_own_python;
/* LOADED until the process exits (release_python_state ran) or this library is unloaded
 * (unload_original ran): whichever comes first. */
static enum { LOADED, EXITING, UNLOADED } phase = LOADED;

extern int __cxa_atexit(void (*function)(void *), void *argument, void *dso_handle);

/* At exit(), before the original's C++ destructors: it releases its Python state (see the top).
 * Registered with atexit(), so it also runs when this library is unloaded, after unload_original:
 * then it does nothing. */
static void release_python_state(void)
{
    if (phase != LOADED)
        return;
    phase = EXITING;
    if (finalize_python != NULL)
        finalize_python();
}

/* dlopen the original from this library's own directory, RTLD_LOCAL so that its symbols do not
 * meet this library's, and look up every function. */
static void load_original(void)
{
    Dl_info self;
    char path[PATH_MAX];
    const char *slash;
    int written;
    void *lib;
    is_initialized_fn *is_initialized;

    if (!dladdr((void *)&handle, &self) || self.dli_fname == NULL) {
        snprintf(load_error, sizeof load_error, "cannot locate the FMU's binary (dladdr failed)");
        return;
    }
    slash = strrchr(self.dli_fname, '/');
    if (slash == NULL) /* loaded without a directory: look in the current one */
        written = snprintf(path, sizeof path, "./%s", ORIGINAL_LIBRARY);
    else
        written = snprintf(path, sizeof path, "%.*s/%s", (int)(slash - self.dli_fname),
                           self.dli_fname, ORIGINAL_LIBRARY);
    if (written < 0 || (size_t)written >= sizeof path) {
        snprintf(load_error, sizeof load_error, "path too long: %s", self.dli_fname);
        return;
    }

    memcpy(original_path, path, (size_t)written + 1);
    /* Whether its state may own the interpreter (see the top): loaded already, or no Python. */
    *(void **)&is_initialized = dlsym(RTLD_DEFAULT, "Py_IsInitialized");
    lib = dlopen(path, RTLD_LOCAL | RTLD_NOW | RTLD_NOLOAD);
    may_own_python = lib != NULL || is_initialized == NULL || !is_initialized();
    if (lib != NULL)
        dlclose(lib);
    lib = dlopen(path, RTLD_LOCAL | RTLD_NOW);
    if (lib == NULL) {
        snprintf(load_error, sizeof load_error,
                 "cannot load the binary behind the status shim %s: %s", path,
                 dlerror());
        return;
    }
#define LOOKUP(name)                                                                             \
    *(void **)&original.name = dlsym(lib, "fmi2" #name);                                          \
    if (original.name == NULL) {                                                                  \
        snprintf(load_error, sizeof load_error, "%s does not export fmi2" #name, path);           \
        memset(&original, 0, sizeof original);                                                    \
        dlclose(lib);                                                                             \
        return;                                                                                   \
    }
    FMI2_FUNCTIONS(LOOKUP)
#undef LOOKUP
    handle = lib;
    *(void **)&finalize_python = dlsym(lib, "finalizePythonInterpreter");
    if (finalize_python != NULL)
        atexit(release_python_state); /* after the original's C++ destructors: runs before them */
}

static int loaded(void)
{
    pthread_once(&load_once, load_original);
    return handle != NULL;
}

/* When this library is unloaded: the original releases its state (or is kept loaded to release it
 * at exit, see the top), and is unloaded too. At exit, after release_python_state, there is
 * nothing to do. */
__attribute__((destructor)) static void unload_original(void)
{
    void *pin;

    if (phase != LOADED)
        return;
    phase = UNLOADED;
    if (handle == NULL)
        return;
    if (finalize_python != NULL && !may_own_python) {
        finalize_python();
    } else if (finalize_python != NULL) {
        pin = dlopen(original_path, RTLD_LOCAL | RTLD_NOW | RTLD_NOLOAD | RTLD_NODELETE);
        if (pin != NULL) {
            /* The cast glibc's atexit() makes: a function of no argument, called with one. */
            __cxa_atexit((void (*)(void *))finalize_python, NULL, NULL);
            dlclose(pin);
        }
    }
    dlclose(handle);
    handle = NULL;
}

/* The context's slots and the kinds of variables in its map (inerter/fmu/native.py). */
enum {
    CTX_MAGIC, CTX_ARMED, CTX_FUNCTION, CTX_TABLE, CTX_MAP_SIZE, CTX_MAP, CTX_VALUES, CTX_REALS,
    CTX_INTEGERS, CTX_BOOLEANS, CTX_STRINGS, CTX_LOG_FUNCTION, CTX_LOG_TARGET
};
enum { KIND_OUTPUT, KIND_REAL, KIND_INTEGER, KIND_BOOLEAN, KIND_STRING };

/* inerter.engine.kernels.native_step: 1 when it took the step (t, t + h], else 0. */
typedef int32_t native_step_fn(const int64_t *table, double t, double h);

/* An instance: the original's component and the native link's state. */
struct instance {
    fmi2Component inner;      /* the original's */
    const int64_t *ctx;       /* the slave's context, or NULL: no native steps */
    int armed;                /* the next doStep may be taken natively */
    int discarded;            /* the last doStep returned fmi2Discard: fmi2Terminated */
    int dirty;                /* native steps (or a declined one) the slave has not taken over */
    fmi2CallbackLogger logger;            /* the importer's, for live_log and filtered_log */
    fmi2ComponentEnvironment environment;
    char *name;                           /* the instance name, copied */
    int logging_on;                       /* as the importer last set it */
    unsigned categories;                  /* the LOG_CATEGORIES it selected (bits), 0: all */
    unsigned long errors;                 /* messages of status fmi2Error or worse the slave logged */
    int stop_defined;                     /* fmi2SetupExperiment's stopTimeDefined and stopTime */
    double stop_time;
    fmi2CallbackFunctions functions;      /* the original's: the importer's, logger filtered_log */
};

/* The FMU's log categories, as pythonfmu 0.7.0 writes them into modelDescription.xml's
 * <LogCategories> (tests/test_fmu_call_sequences.py checks that they are the same): the slave's
 * messages of status fmi2OK have the category logAll. */
static const char *const LOG_CATEGORIES[] = {"logStatusWarning", "logStatusDiscard",
                                             "logStatusError", "logStatusFatal", "logAll"};
#define N_LOG_CATEGORIES (sizeof LOG_CATEGORIES / sizeof LOG_CATEGORIES[0])
#define LOG_ALL_BIT (1u << (N_LOG_CATEGORIES - 1))

/* The index of `name` in LOG_CATEGORIES, or -1. */
static int category_index(const char *name)
{
    size_t i;
    for (i = 0; name != NULL && i < N_LOG_CATEGORIES; i++)
        if (strcmp(name, LOG_CATEGORIES[i]) == 0)
            return (int)i;
    return -1;
}

/* Whether a message of `status` and `category` reaches the importer (see the top): with logging
 * on, those of the categories it selected with fmi2SetDebugLogging (all when it named none, or
 * logAll); those of a status the importer must act on always, whatever it selected. */
static int passes(const struct instance *w, int status, const char *category)
{
    int k;
    if (status >= (int)fmi2Discard)
        return 1;
    if (!w->logging_on)
        return 0;
    if (w->categories == 0 || (w->categories & LOG_ALL_BIT))
        return 1;
    k = category_index(category);
    return k >= 0 && ((w->categories >> k) & 1u);
}

/* The original's logger: the message passed on to the importer's where `passes` lets it. The
 * original passes each message as the format, with no argument, and so does this. */
static void filtered_log(fmi2ComponentEnvironment environment, fmi2String instanceName,
                         fmi2Status status, fmi2String category, fmi2String message, ...)
{
    struct instance *w = (struct instance *)environment;

    if (w == NULL)
        return;
    if (status >= fmi2Error)
        w->errors++;
    if (w->logger == NULL || !passes(w, (int)status, category))
        return;
    w->logger(w->environment, instanceName, status, category, message);
}

/* A message from the slave to the importer's logger, now (see the top). The message is passed as
 * the format, with no argument, '%' doubled, as fmi2Instantiate's own. */
static void live_log(int64_t target, int32_t status, const char *category, const char *message)
{
    const struct instance *w = (const struct instance *)(uintptr_t)target;
    char *text;

    if (w == NULL || w->logger == NULL || !passes(w, (int)status, category) || message == NULL)
        return;
    text = as_format(message);
    if (text == NULL)
        return;
    w->logger(w->environment, w->name, (fmi2Status)status, category != NULL ? category : "logAll",
              text);
    free(text);
}

#define INNER(c) (((struct instance *)(c))->inner)

/* The slave's context address, read through the private value references; NULL when the slave
 * has none (the link is off, or the slave does not know the value references). */
static const int64_t *native_context(fmi2Component inner)
{
    const fmi2ValueReference vr[2] = {NATIVE_LINK_VR, NATIVE_LINK_VR + 1u};
    fmi2Integer words[2] = {0, 0};
    const int64_t *ctx;

    if (original.GetInteger(inner, vr, 2, words) != fmi2OK || words[0] < 0 || words[1] < 0)
        return NULL;
    ctx = (const int64_t *)(uintptr_t)((uint64_t)words[0] | ((uint64_t)words[1] << 31));
    if (ctx == NULL || ctx[CTX_MAGIC] != (int64_t)NATIVE_MAGIC)
        return NULL;
    return ctx;
}

/* The slave's context, disarmed, with the live logger written into it: after fmi2Instantiate, and
 * after fmi2Reset, where the original replaces the slave object, and its context with it (the old one
 * may be freed: it must not be read again). */
static void link_context(struct instance *w)
{
    w->ctx = native_context(w->inner);
    w->armed = 0;
    w->dirty = 0;
    if (w->ctx != NULL && w->name != NULL) {
        int64_t *ctx = (int64_t *)(uintptr_t)w->ctx;
        ctx[CTX_LOG_TARGET] = (int64_t)(uintptr_t)w;
        ctx[CTX_LOG_FUNCTION] = (int64_t)(uintptr_t)&live_log;
    }
}

/* The slave takes over the native steps (before any call that enters Python after them). */
static fmi2Status sync(struct instance *w)
{
    const fmi2ValueReference vr = NATIVE_SYNC_VR;
    const fmi2Integer one = 1;

    if (!w->dirty)
        return fmi2OK;
    w->dirty = 0;
    return original.SetInteger(w->inner, &vr, 1, &one);
}

/* A call that may change what the slave does: take over the native steps, and disarm. */
static fmi2Status enter(fmi2Component c)
{
    struct instance *w = c;
    w->armed = 0;
    return sync(w);
}

/* Where the value of each of vr[0..nvr) is, as (kind << 32) + index (inerter/fmu/native.py), when
 * native steps were taken since the slave last ran and every one of them is of kind `kind` (or
 * KIND_OUTPUT, where `kind` is KIND_REAL); else 0, and the getter goes to the slave. */
static int served(const struct instance *w, const fmi2ValueReference vr[], size_t nvr, int kind,
                  int64_t where[])
{
    const int64_t *map;
    uint64_t size;
    size_t i;

    if (!w->dirty || w->ctx == NULL || (vr == NULL && nvr > 0))
        return 0;
    map = (const int64_t *)(uintptr_t)w->ctx[CTX_MAP];
    size = (uint64_t)w->ctx[CTX_MAP_SIZE];
    for (i = 0; i < nvr; i++) {
        int64_t entry;
        int entry_kind;
        if (vr[i] >= size || (entry = map[vr[i]]) < 0)
            return 0;
        entry_kind = (int)(entry >> 32);
        if (entry_kind != kind && !(kind == KIND_REAL && entry_kind == KIND_OUTPUT))
            return 0;
        where[i] = entry;
    }
    return 1;
}

/* An array of the context. */
#define CONTEXT_ARRAY(w, type, slot) ((const type *)(uintptr_t)(w)->ctx[slot])
#define INDEX(entry) ((size_t)((entry) & 0xFFFFFFFF))

/* A getter served from the context: `where` on the stack for small requests. */
#define SERVE(kind, ...)                                                                         \
    {                                                                                            \
        int64_t stack[64];                                                                       \
        int64_t *where = nvr <= 64 ? stack : malloc(nvr * sizeof *where);                        \
        size_t i;                                                                                \
        if (where != NULL && served(w, vr, nvr, kind, where)) {                                  \
            for (i = 0; i < nvr; i++) {                                                          \
                __VA_ARGS__;                                                                     \
            }                                                                                    \
            if (where != stack)                                                                  \
                free(where);                                                                     \
            return fmi2OK;                                                                       \
        }                                                                                        \
        if (where != stack)                                                                      \
            free(where);                                                                         \
    }

/* The status of a call that the original returned as `status`: the slave's own when the original
 * said fmi2OK and the slave's is worse (fmi2Warning, fmi2Discard or fmi2Error). */
static fmi2Status checked(fmi2Component c, fmi2Status status)
{
    const fmi2ValueReference vr = STATUS_VR;
    fmi2Integer value = fmi2OK;
    fmi2Status read;

    if (status != fmi2OK || c == NULL)
        return status;
    read = original.GetInteger(c, &vr, 1, &value);
    if (read != fmi2OK)
        return read;
    if (value <= fmi2OK)
        return fmi2OK;
    return value >= fmi2Error ? fmi2Error : (fmi2Status)value;
}

/* The status of a call the slave does not report in fmi_status (a getter, setupExperiment,
 * terminate, ...) that the original returned as `status`: fmi2Error where the slave logged an error
 * during it (`before`: the instance's error count when the call began). pythonfmu's binary returns
 * fmi2OK from such a call whatever the slave said: an unknown value reference, a call FMI 2.0 does
 * not allow in the instance's state. */
static fmi2Status logged(const struct instance *w, unsigned long before, fmi2Status status)
{
    return status <= fmi2Warning && w->errors != before ? fmi2Error : status;
}

/* Whether a step (t, t + h] ends past fmi2SetupExperiment's stopTime (1e-9 relative to
 * max(1 s, stopTime), the slave's TIME_TOLERANCE): such a step is the slave's to refuse. */
static int past_stop(const struct instance *w, double t, double h)
{
    double scale = w->stop_time < 0 ? -w->stop_time : w->stop_time;
    return w->stop_defined && t + h > w->stop_time + 1e-9 * (scale > 1.0 ? scale : 1.0);
}

/* A call that enters Python and reports the slave's errors by what it logged (see logged). */
#define FORWARD_LOGGED(call)                                                                     \
    {                                                                                            \
        struct instance *w_ = c;                                                                 \
        unsigned long before_ = w_->errors;                                                      \
        return logged(w_, before_, call);                                                        \
    }

/* A message of the shim's own, "SCENE_FILE: " and the text, to the importer's logger as the
 * slave's reach it (live_log: passed on where `passes` lets it; fmi2Discard and worse always). */
static void say(const struct instance *w, fmi2Status status, const char *format, ...)
    __attribute__((format(printf, 3, 4)));
static void say(const struct instance *w, fmi2Status status, const char *format, ...)
{
    char message[1024];
    int n = snprintf(message, sizeof message, "%s: ", SCENE_FILE);
    va_list arguments;

    if (n < 0 || (size_t)n >= sizeof message)
        n = 0;
    va_start(arguments, format);
    vsnprintf(message + n, sizeof message - (size_t)n, format, arguments);
    va_end(arguments);
    live_log((int64_t)(uintptr_t)w, (int32_t)status,
             status >= fmi2Error   ? "logStatusError"
             : status == fmi2Discard ? "logStatusDiscard"
             : status == fmi2Warning ? "logStatusWarning" : "logAll",
             message);
}

/* A function this FMU does not support: fmi2Error, its reason logged, nothing changed. */
static fmi2Status unsupported(fmi2Component c, const char *function, const char *why)
{
    if (handle == NULL || c == NULL)
        return fmi2Error;
    say(c, fmi2Error, "%s: not supported by this FMU (%s); nothing changes", function, why);
    return fmi2Error;
}

/* Whether `size` bytes are a serialized state of this FMU: the slave says so through the private
 * String STATE_CHECK_VR, the bytes in hex (they may hold any byte; a String is UTF-8 text ending
 * at NUL), and logs why not (then fmi2Error). Nothing changes. */
static fmi2Status check_serialized(struct instance *w, const fmi2Byte bytes[], size_t size)
{
    static const char digits[] = "0123456789abcdef";
    const fmi2ValueReference vr = STATE_CHECK_VR;
    unsigned long before = w->errors;
    fmi2String text;
    char *hex;
    size_t i;
    fmi2Status status;

    if (bytes == NULL && size > 0) {
        say(w, fmi2Error, "fmi2DeSerializeFMUstate: serializedState is NULL (size %zu); no FMU "
            "state is made", size);
        return fmi2Error;
    }
    hex = size < ((size_t)-1) / 2 ? malloc(2 * size + 1) : NULL;
    if (hex == NULL) {
        say(w, fmi2Error, "fmi2DeSerializeFMUstate: out of memory for %zu bytes; no FMU state is "
            "made", size);
        return fmi2Error;
    }
    for (i = 0; i < size; i++) {
        hex[2 * i] = digits[((unsigned char)bytes[i]) >> 4];
        hex[2 * i + 1] = digits[((unsigned char)bytes[i]) & 15];
    }
    hex[2 * size] = '\0';
    text = hex;
    status = logged(w, before, original.SetString(w->inner, &vr, 1, &text));
    free(hex);
    return status;
}

/* The fmi2StatusKind names, and the function that answers each (FMI 2.0 section 4.2.3). */
static const char *const STATUS_KINDS[] = {"fmi2DoStepStatus", "fmi2PendingStatus",
                                           "fmi2LastSuccessfulTime", "fmi2Terminated"};
static const char *const STATUS_FUNCTIONS[] = {"fmi2GetStatus", "fmi2GetStringStatus",
                                               "fmi2GetRealStatus", "fmi2GetBooleanStatus"};
#define N_STATUS_KINDS (sizeof STATUS_KINDS / sizeof STATUS_KINDS[0])

/* The slave's phases, in the order of inerter_slave.PHASES (read through PHASE_VR), and whether
 * the status functions may be called in each: in FMI 2.0's stepComplete, stepFailed and terminated
 * states (section 4.2.4), which are the slave's stepping and terminated phases. */
static const char *const PHASES[] = {"instantiated", "initialization", "stepping", "failed",
                                     "terminated"};
static const int STATUS_ALLOWED[] = {0, 0, 1, 0, 1};
#define N_PHASES (sizeof PHASES / sizeof PHASES[0])

/* fmi2OK when `function` may answer status kind `s` now (`answers`: the kind it gives a value for,
 * -1 none); else fmi2Error (not allowed in the instance's state, a kind that is none of FMI 2.0's,
 * no value pointer) or fmi2Discard (a kind it does not answer, or one that does not apply), with
 * the reason logged. */
static fmi2Status status_inquiry(struct instance *w, const char *function, fmi2StatusKind s,
                                 const void *value, int answers)
{
    const fmi2ValueReference vr = PHASE_VR;
    fmi2Integer phase = -1;

    if (original.GetInteger(w->inner, &vr, 1, &phase) != fmi2OK || phase < 0 ||
        (size_t)phase >= N_PHASES) {
        say(w, fmi2Error, "%s: the FMU's phase cannot be read (got %d)", function, (int)phase);
        return fmi2Error;
    }
    if (!STATUS_ALLOWED[phase]) {
        say(w, fmi2Error, "%s: refused in the %s state (expected it after a successful "
            "fmi2ExitInitializationMode: FMI 2.0 allows the status functions in the "
            "stepComplete, stepFailed and terminated states only); nothing changes", function,
            PHASES[phase]);
        return fmi2Error;
    }
    if ((int)s < 0 || (size_t)s >= N_STATUS_KINDS) {
        say(w, fmi2Error, "%s: %d is not an fmi2StatusKind (expected 0 fmi2DoStepStatus, "
            "1 fmi2PendingStatus, 2 fmi2LastSuccessfulTime or 3 fmi2Terminated)", function, (int)s);
        return fmi2Error;
    }
    if (value == NULL) {
        say(w, fmi2Error, "%s(%s): value is NULL", function, STATUS_KINDS[s]);
        return fmi2Error;
    }
    if ((int)s == answers)
        return fmi2OK;
    if (strcmp(function, STATUS_FUNCTIONS[s]) != 0)
        say(w, fmi2Discard, "%s: %s is not a status this function gives (FMI 2.0 section 4.2.3: "
            "it is asked of %s)%s", function, STATUS_KINDS[s], STATUS_FUNCTIONS[s],
            answers < 0 && strcmp(function, "fmi2GetIntegerStatus") == 0
                ? "; FMI 2.0 defines no Integer status" : "");
    else /* fmi2DoStepStatus, fmi2PendingStatus: only after a doStep returned fmi2Pending */
        say(w, fmi2Discard, "%s(%s): not applicable: no asynchronous doStep is pending (this FMU "
            "never returns fmi2Pending: canRunAsynchronuously is false)", function,
            STATUS_KINDS[s]);
    return fmi2Discard;
}

/* ---------------------------------------------------------------------------------------------
 * Common functions
 * ------------------------------------------------------------------------------------------- */
const char *fmi2GetTypesPlatform(void)
{
    return loaded() ? original.GetTypesPlatform() : fmi2TypesPlatform;
}

const char *fmi2GetVersion(void)
{
    return loaded() ? original.GetVersion() : fmi2Version;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn)
{
    struct instance *w;
    fmi2Component inner;

    if (!loaded()) {
        /* The message is passed as the format, with no argument: some importers (fmpy) show
         * the format as it is. A '%' is doubled for those that format it. */
        char message[sizeof load_error + 32];
        char *text;
        snprintf(message, sizeof message, "fmi2Instantiate: %s", load_error);
        text = as_format(message);
        if (text != NULL && functions != NULL && functions->logger != NULL)
            functions->logger(functions->componentEnvironment, instanceName, fmi2Error,
                              "logStatusError", text);
        free(text);
        return NULL;
    }
    w = calloc(1, sizeof *w);
    if (w == NULL) {
        if (functions != NULL && functions->logger != NULL)
            functions->logger(functions->componentEnvironment, instanceName, fmi2Error,
                              "logStatusError", "fmi2Instantiate: out of memory");
        return NULL;
    }
    if (functions != NULL) {
        w->logger = functions->logger;
        w->environment = functions->componentEnvironment;
        const fmi2CallbackFunctions filtered = {filtered_log, functions->allocateMemory,
                                                functions->freeMemory, functions->stepFinished, w};
        memcpy(&w->functions, &filtered, sizeof filtered);    /* its members are const */
    }
    w->logging_on = loggingOn == fmi2True;
    inner = original.Instantiate(instanceName, fmuType, fmuGUID, fmuResourceLocation,
                                 functions != NULL ? &w->functions : NULL, visible, fmi2True);
    if (inner == NULL) {
        free(w);
        return NULL;
    }
    w->inner = inner;
    w->name = strdup(instanceName != NULL ? instanceName : "");
    link_context(w);
    return w;
}

/* Every other function is called with a component from fmi2Instantiate: the original is loaded. */
#define GUARD                                                                                    \
    if (handle == NULL || c == NULL)                                                             \
        return fmi2Error;

/* A call that enters Python and may change what the slave does. */
#define ENTER                                                                                    \
    GUARD                                                                                        \
    if (enter(c) != fmi2OK)                                                                      \
        return fmi2Error;

/* A call that enters Python to read: the slave takes over the native steps first. */
#define READ                                                                                     \
    GUARD                                                                                        \
    if (sync(c) != fmi2OK)                                                                       \
        return fmi2Error;

void fmi2FreeInstance(fmi2Component c)
{
    if (handle != NULL && c != NULL) {
        original.FreeInstance(INNER(c));
        free(((struct instance *)c)->name);
        free(c);
    }
}

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[])
{
    struct instance *w = c;
    unsigned selected = 0;
    size_t i;

    ENTER
    for (i = 0; loggingOn == fmi2True && i < nCategories; i++) {
        const char *name = categories != NULL ? categories[i] : NULL;
        const int k = category_index(name);
        if (k < 0) {
            char message[512];
            snprintf(message, sizeof message, "%s: fmi2SetDebugLogging: unknown log category "
                     "'%.200s' (expected one of the LogCategories of modelDescription.xml: "
                     "logStatusWarning, logStatusDiscard, logStatusError, logStatusFatal, logAll); "
                     "logging unchanged", SCENE_FILE, name != NULL ? name : "(null)");
            live_log((int64_t)(uintptr_t)w, (int32_t)fmi2Error, "logStatusError", message);
            return fmi2Error;
        }
        selected |= 1u << k;
    }
    w->logging_on = loggingOn == fmi2True;
    w->categories = selected;
    /* the original keeps logging every category; filtered_log does what the importer asked */
    FORWARD_LOGGED(original.SetDebugLogging(INNER(c), fmi2True, 0, NULL))
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    struct instance *w = c;
    unsigned long before;
    fmi2Status status;

    ENTER
    before = w->errors;
    status = logged(w, before, original.SetupExperiment(w->inner, toleranceDefined, tolerance,
                                                        startTime, stopTimeDefined, stopTime));
    if (status <= fmi2Warning) { /* the slave took it: native steps stop there too */
        w->stop_defined = stopTimeDefined == fmi2True;
        w->stop_time = stopTime;
    }
    return status;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    ENTER
    FORWARD_LOGGED(original.EnterInitializationMode(INNER(c)))
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    struct instance *w = c;
    fmi2Status status;

    ENTER
    status = checked(w->inner, original.ExitInitializationMode(w->inner));
    /* The slave arms the link at the end of initialisation too: the first step may be native. */
    w->armed = status == fmi2OK && w->ctx != NULL && w->ctx[CTX_ARMED];
    return status;
}

fmi2Status fmi2Terminate(fmi2Component c)
{
    ENTER
    FORWARD_LOGGED(original.Terminate(INNER(c)))
}

fmi2Status fmi2Reset(fmi2Component c)
{
    struct instance *w = c;
    fmi2Status status;

    ENTER
    w->ctx = NULL; /* the slave object and its context are replaced */
    w->stop_defined = 0;
    w->discarded = 0;
    status = original.Reset(w->inner);
    link_context(w);
    return status;
}

/* After native steps, the getters are served from the context (see served); else by the slave. */
fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[])
{
    struct instance *w = c;
    GUARD
    SERVE(KIND_REAL, value[i] = (where[i] >> 32) == KIND_OUTPUT
                                    ? CONTEXT_ARRAY(w, double, CTX_VALUES)[INDEX(where[i])]
                                    : CONTEXT_ARRAY(w, double, CTX_REALS)[INDEX(where[i])])
    if (sync(w) != fmi2OK)
        return fmi2Error;
    FORWARD_LOGGED(original.GetReal(w->inner, vr, nvr, value))
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[])
{
    struct instance *w = c;
    GUARD
    SERVE(KIND_INTEGER,
          value[i] = (fmi2Integer)CONTEXT_ARRAY(w, int64_t, CTX_INTEGERS)[INDEX(where[i])])
    if (sync(w) != fmi2OK)
        return fmi2Error;
    FORWARD_LOGGED(original.GetInteger(w->inner, vr, nvr, value))
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[])
{
    struct instance *w = c;
    GUARD
    SERVE(KIND_BOOLEAN,
          value[i] = CONTEXT_ARRAY(w, int64_t, CTX_BOOLEANS)[INDEX(where[i])] ? fmi2True : fmi2False)
    if (sync(w) != fmi2OK)
        return fmi2Error;
    FORWARD_LOGGED(original.GetBoolean(w->inner, vr, nvr, value))
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[])
{
    struct instance *w = c;
    GUARD
    SERVE(KIND_STRING, value[i] = (fmi2String)(uintptr_t)CONTEXT_ARRAY(w, int64_t,
                                                                       CTX_STRINGS)[INDEX(where[i])])
    if (sync(w) != fmi2OK)
        return fmi2Error;
    FORWARD_LOGGED(original.GetString(w->inner, vr, nvr, value))
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[])
{
    ENTER
    return checked(INNER(c), original.SetReal(INNER(c), vr, nvr, value));
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[])
{
    ENTER
    return checked(INNER(c), original.SetInteger(INNER(c), vr, nvr, value));
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[])
{
    ENTER
    return checked(INNER(c), original.SetBoolean(INNER(c), vr, nvr, value));
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[])
{
    ENTER
    return checked(INNER(c), original.SetString(INNER(c), vr, nvr, value));
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    READ
    FORWARD_LOGGED(original.GetFMUstate(INNER(c), FMUstate))
}

/* A restored state brings its stop time (the slave keeps fmi2SetupExperiment's in the state):
 * native steps stop there too. */
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate)
{
    struct instance *w = c;
    const fmi2ValueReference vr = STOP_VR;
    fmi2Real stop = 0.0;
    fmi2Status status;

    ENTER
    status = checked(w->inner, original.SetFMUstate(w->inner, FMUstate));
    if (status == fmi2OK)
        w->discarded = 0;
    if (status == fmi2OK && original.GetReal(w->inner, &vr, 1, &stop) == fmi2OK) {
        w->stop_defined = stop == stop; /* not NaN */
        w->stop_time = stop;
    }
    return status;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    READ
    FORWARD_LOGGED(original.FreeFMUstate(INNER(c), FMUstate))
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size)
{
    READ
    FORWARD_LOGGED(original.SerializedFMUstateSize(INNER(c), FMUstate, size))
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate,
                                 fmi2Byte serializedState[], size_t size)
{
    READ
    FORWARD_LOGGED(original.SerializeFMUstate(INNER(c), FMUstate, serializedState, size))
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[],
                                   size_t size, fmi2FMUstate *FMUstate)
{
    READ
    if (FMUstate == NULL) {
        say(c, fmi2Error, "fmi2DeSerializeFMUstate: FMUstate is NULL; no FMU state is made");
        return fmi2Error;
    }
    if (check_serialized(c, serializedState, size) != fmi2OK)
        return fmi2Error;
    FORWARD_LOGGED(original.DeSerializeFMUstate(INNER(c), serializedState, size, FMUstate))
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                        size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[])
{
    (void)vUnknown_ref, (void)nUnknown, (void)vKnown_ref, (void)nKnown, (void)dvKnown,
        (void)dvUnknown;
    return unsupported(c, "fmi2GetDirectionalDerivative", "modelDescription.xml: "
                       "providesDirectionalDerivative is false");
}

/* ---------------------------------------------------------------------------------------------
 * Co-simulation functions
 * ------------------------------------------------------------------------------------------- */
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                       size_t nvr, const fmi2Integer order[],
                                       const fmi2Real value[])
{
    (void)vr, (void)nvr, (void)order, (void)value;
    return unsupported(c, "fmi2SetRealInputDerivatives", "modelDescription.xml: "
                       "canInterpolateInputs is false: an input is held over a communication step");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t nvr, const fmi2Integer order[], fmi2Real value[])
{
    (void)vr, (void)nvr, (void)order, (void)value;
    return unsupported(c, "fmi2GetRealOutputDerivatives", "modelDescription.xml: "
                       "maxOutputDerivativeOrder is 0");
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    struct instance *w = c;
    fmi2Status status;

    GUARD
    if (w->armed && w->ctx[CTX_ARMED] && !past_stop(w, currentCommunicationPoint, communicationStepSize)) {
        native_step_fn *step = (native_step_fn *)(uintptr_t)w->ctx[CTX_FUNCTION];
        const int32_t took = step((const int64_t *)(uintptr_t)w->ctx[CTX_TABLE],
                                  currentCommunicationPoint, communicationStepSize);
        w->dirty = 1;
        if (took == 1) {
            w->discarded = 0;
            return fmi2OK;
        }
        w->armed = 0; /* declined: the slave restores the integration and takes the step */
    }
    if (sync(w) != fmi2OK)
        return fmi2Error;
    status = original.DoStep(w->inner, currentCommunicationPoint, communicationStepSize,
                             noSetFMUStatePriorToCurrentPoint);
    w->armed = status == fmi2OK && w->ctx != NULL && w->ctx[CTX_ARMED];
    /* The slave's do_step returns True (fmi2OK) only with fmi_status fmi2OK, so a step that went
     * well costs no second call into the slave; a refused or failed one (fmi2Discard) says which
     * it was through fmi_status (fmi2Discard or fmi2Error). */
    if (status == fmi2OK)
        w->discarded = 0;
    if (status != fmi2Discard)
        return status;
    status = checked(w->inner, fmi2OK);
    if (status == fmi2OK || status == fmi2Warning)
        status = fmi2Discard;
    w->discarded = status == fmi2Discard;
    return status;
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
    return unsupported(c, "fmi2CancelStep", "modelDescription.xml: canRunAsynchronuously is "
                       "false: no doStep is ever pending, there is none to cancel");
}

/* The status functions: see status_inquiry. None changes anything. */
fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{
    READ
    return status_inquiry(c, "fmi2GetStatus", s, value, -1);
}

/* fmi2LastSuccessfulTime is the slave's time, read through the private Real TIME_VR:
 * pythonfmu's binary answers the end of the last doStep it was called for (NaN before the first,
 * the end of a refused step, not the native steps', not a rollback's). */
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    fmi2Status status;

    READ
    status = status_inquiry(c, "fmi2GetRealStatus", s, value, fmi2LastSuccessfulTime);
    if (status == fmi2OK) {
        const fmi2ValueReference vr = TIME_VR;
        return original.GetReal(INNER(c), &vr, 1, value);
    }
    return status;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value)
{
    READ
    return status_inquiry(c, "fmi2GetIntegerStatus", s, value, -1);
}

/* fmi2Terminated: fmi2False. The slave never asks to end a run: a step it cannot complete is
 * fmi2Discard with the FMU at its last communication point, from where the importer may go on. */
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value)
{
    fmi2Status status;

    READ
    status = status_inquiry(c, "fmi2GetBooleanStatus", s, value, fmi2Terminated);
    if (status == fmi2OK)
        *value = ((struct instance *)c)->discarded ? fmi2True : fmi2False;
    return status;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value)
{
    READ
    return status_inquiry(c, "fmi2GetStringStatus", s, value, -1);
}
