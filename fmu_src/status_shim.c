/* The status shim: the FMU's binary on Linux, in front of pythonfmu's own.
 *
 * pythonfmu 0.7.0's binary returns fmi2OK from every call but doStep (fmi2Discard when the
 * slave's do_step returns False), and turns a Python exception into fmi2Fatal. This library
 * exports the FMI 2.0 co-simulation API under the FMU's model identifier and forwards every call
 * to pythonfmu's binary, shipped beside it as ORIGINAL_LIBRARY. After the calls that can fail on
 * the importer's values (fmi2ExitInitializationMode, fmi2SetReal/Integer/Boolean/String,
 * fmi2SetFMUstate) have returned fmi2OK from the original, it reads the slave's Integer variable
 * STATUS_VR (fmi_status: the status of the slave's last such call) through the original's
 * fmi2GetInteger and returns that status when it is worse than fmi2OK; after fmi2DoStep, when the
 * original returned fmi2Discard, it returns fmi2Error where the slave says so.
 *
 * The component is the original's: every call is forwarded unchanged, and the slave's messages
 * reach the importer through the original's logger calls as before.
 *
 * Build (inerter/fmu_build.py does it, with the value reference from modelDescription.xml):
 *   gcc -shared -fPIC -O2 -fvisibility=hidden -pthread -DSTATUS_VR=<n> \
 *       -DORIGINAL_LIBRARY='"<modelIdentifier>.pythonfmu.so"' -o <modelIdentifier>.so \
 *       status_shim.c -ldl
 *
 * The original is loaded at the first call (fmi2Instantiate, or fmi2GetVersion /
 * fmi2GetTypesPlatform before it) and unloaded when this library is.
 */
#ifndef _GNU_SOURCE
#define _GNU_SOURCE /* dladdr */
#endif

#include <dlfcn.h>
#include <limits.h>
#include <pthread.h>
#include <stdio.h>
#include <string.h>

#include "fmi2_types.h"

#ifndef STATUS_VR
#error "compile with -DSTATUS_VR=<value reference of the slave's status variable>"
#endif
#ifndef ORIGINAL_LIBRARY
#error "compile with -DORIGINAL_LIBRARY='\"<file name of pythonfmu's binary>\"'"
#endif
#ifndef PATH_MAX
#define PATH_MAX 4096
#endif

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
static char load_error[PATH_MAX + 512];
static pthread_once_t load_once = PTHREAD_ONCE_INIT;

/* dlopen the original from this library's own directory, RTLD_LOCAL so that its symbols do not
 * meet this library's, and look up every function. */
static void load_original(void)
{
    Dl_info self;
    char path[PATH_MAX];
    const char *slash;
    int written;
    void *lib;

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

    lib = dlopen(path, RTLD_LOCAL | RTLD_NOW);
    if (lib == NULL) {
        snprintf(load_error, sizeof load_error, "cannot load pythonfmu's binary %s: %s", path,
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
}

static int loaded(void)
{
    pthread_once(&load_once, load_original);
    return handle != NULL;
}

__attribute__((destructor)) static void unload_original(void)
{
    if (handle != NULL) {
        dlclose(handle);
        handle = NULL;
    }
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
    if (!loaded()) {
        /* The message is passed as the format, with no argument: some importers (fmpy) show
         * the format as it is. A '%' is doubled for those that format it. */
        char message[2 * sizeof load_error + 32];
        const char *from;
        char *to = message + sprintf(message, "fmi2Instantiate: ");
        for (from = load_error; *from != '\0'; from++) {
            if (*from == '%')
                *to++ = '%';
            *to++ = *from;
        }
        *to = '\0';
        if (functions != NULL && functions->logger != NULL)
            functions->logger(functions->componentEnvironment, instanceName, fmi2Error,
                              "logStatusError", message);
        return NULL;
    }
    return original.Instantiate(instanceName, fmuType, fmuGUID, fmuResourceLocation, functions,
                                visible, loggingOn);
}

/* Every other function is called with a component from fmi2Instantiate: the original is loaded. */
#define GUARD                                                                                    \
    if (handle == NULL)                                                                          \
        return fmi2Error;

void fmi2FreeInstance(fmi2Component c)
{
    if (handle != NULL)
        original.FreeInstance(c);
}

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[])
{
    GUARD
    return original.SetDebugLogging(c, loggingOn, nCategories, categories);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    GUARD
    return original.SetupExperiment(c, toleranceDefined, tolerance, startTime, stopTimeDefined,
                                    stopTime);
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    GUARD
    return original.EnterInitializationMode(c);
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    GUARD
    return checked(c, original.ExitInitializationMode(c));
}

fmi2Status fmi2Terminate(fmi2Component c)
{
    GUARD
    return original.Terminate(c);
}

fmi2Status fmi2Reset(fmi2Component c)
{
    GUARD
    return original.Reset(c);
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[])
{
    GUARD
    return original.GetReal(c, vr, nvr, value);
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[])
{
    GUARD
    return original.GetInteger(c, vr, nvr, value);
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[])
{
    GUARD
    return original.GetBoolean(c, vr, nvr, value);
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[])
{
    GUARD
    return original.GetString(c, vr, nvr, value);
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[])
{
    GUARD
    return checked(c, original.SetReal(c, vr, nvr, value));
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[])
{
    GUARD
    return checked(c, original.SetInteger(c, vr, nvr, value));
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[])
{
    GUARD
    return checked(c, original.SetBoolean(c, vr, nvr, value));
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[])
{
    GUARD
    return checked(c, original.SetString(c, vr, nvr, value));
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    GUARD
    return original.GetFMUstate(c, FMUstate);
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate)
{
    GUARD
    return checked(c, original.SetFMUstate(c, FMUstate));
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    GUARD
    return original.FreeFMUstate(c, FMUstate);
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size)
{
    GUARD
    return original.SerializedFMUstateSize(c, FMUstate, size);
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate,
                                 fmi2Byte serializedState[], size_t size)
{
    GUARD
    return original.SerializeFMUstate(c, FMUstate, serializedState, size);
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[],
                                   size_t size, fmi2FMUstate *FMUstate)
{
    GUARD
    return original.DeSerializeFMUstate(c, serializedState, size, FMUstate);
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                        size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[])
{
    GUARD
    return original.GetDirectionalDerivative(c, vUnknown_ref, nUnknown, vKnown_ref, nKnown,
                                             dvKnown, dvUnknown);
}

/* ---------------------------------------------------------------------------------------------
 * Co-simulation functions
 * ------------------------------------------------------------------------------------------- */
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                       size_t nvr, const fmi2Integer order[],
                                       const fmi2Real value[])
{
    GUARD
    return original.SetRealInputDerivatives(c, vr, nvr, order, value);
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t nvr, const fmi2Integer order[], fmi2Real value[])
{
    GUARD
    return original.GetRealOutputDerivatives(c, vr, nvr, order, value);
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    fmi2Status status;

    GUARD
    status = original.DoStep(c, currentCommunicationPoint, communicationStepSize,
                             noSetFMUStatePriorToCurrentPoint);
    /* The slave's do_step returns True (fmi2OK) only with fmi_status fmi2OK, so a step that went
     * well costs no second call into the slave; a refused or failed one (fmi2Discard) says which
     * it was through fmi_status (fmi2Discard or fmi2Error). */
    if (status != fmi2Discard || c == NULL)
        return status;
    status = checked(c, fmi2OK);
    return status == fmi2OK || status == fmi2Warning ? fmi2Discard : status;
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
    GUARD
    return original.CancelStep(c);
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{
    GUARD
    return original.GetStatus(c, s, value);
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    GUARD
    return original.GetRealStatus(c, s, value);
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value)
{
    GUARD
    return original.GetIntegerStatus(c, s, value);
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value)
{
    GUARD
    return original.GetBooleanStatus(c, s, value);
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value)
{
    GUARD
    return original.GetStringStatus(c, s, value);
}
