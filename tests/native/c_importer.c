/* A minimal FMI 2.0 co-simulation importer in C, for tests: the kind of host in which pythonfmu's
 * binary starts Python itself (the host has libpython loaded, but no interpreter running).
 *
 *   c_importer <unpacked FMU folder> <modelIdentifier> <guid> <loads> <steps> <step size> <vr>
 *
 * Loads the binary <loads> times one after the other; each time it instantiates, initialises, takes
 * <steps> steps, prints the Real <vr> ("load <k>: <value>"), terminates and frees the instance, and
 * unloads the binary, except after the last load: that one stays loaded until the process exits.
 * Exits with 0 when every call returned fmi2OK, else with 1 and a message. */
#include <dlfcn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>

#include "fmi2_types.h"

static void logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    (void)env;
    if (status != fmi2OK)
        fprintf(stderr, "[%s %d %s] %s\n", instance, (int)status, category, message);
}

#define CHECK(call)                                                                              \
    if ((call) != fmi2OK) {                                                                      \
        fprintf(stderr, "c_importer: %s failed\n", #call);                                       \
        return 1;                                                                                \
    }

#define LOOKUP(name)                                                                             \
    fmi2##name##TYPE *name;                                                                      \
    *(void **)&name = dlsym(lib, "fmi2" #name);                                                  \
    if (name == NULL) {                                                                          \
        fprintf(stderr, "c_importer: fmi2" #name " missing\n");                                  \
        return 1;                                                                                \
    }

static int run(const char *folder, const char *id, const char *guid, int steps, double h,
               fmi2ValueReference vr, int load, int unload)
{
    char path[4096], resources[4096];
    const fmi2CallbackFunctions functions = {logger, calloc, free, NULL, NULL};
    fmi2Component c;
    fmi2Real value;
    void *lib;
    int k;

    snprintf(path, sizeof path, "%s/binaries/linux64/%s.so", folder, id);
    snprintf(resources, sizeof resources, "file://%s/resources", folder);
    lib = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (lib == NULL) {
        fprintf(stderr, "c_importer: %s\n", dlerror());
        return 1;
    }
    {
        LOOKUP(Instantiate) LOOKUP(SetupExperiment) LOOKUP(EnterInitializationMode)
        LOOKUP(ExitInitializationMode) LOOKUP(DoStep) LOOKUP(GetReal) LOOKUP(Terminate)
        LOOKUP(FreeInstance)
        c = Instantiate("c_importer", fmi2CoSimulation, guid, resources, &functions, fmi2False,
                        fmi2False);
        if (c == NULL) {
            fprintf(stderr, "c_importer: fmi2Instantiate failed\n");
            return 1;
        }
        CHECK(SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0))
        CHECK(EnterInitializationMode(c))
        CHECK(ExitInitializationMode(c))
        for (k = 0; k < steps; k++)
            CHECK(DoStep(c, k * h, h, fmi2True))
        CHECK(GetReal(c, &vr, 1, &value))
        printf("load %d: %.17g\n", load, value);
        fflush(stdout);
        CHECK(Terminate(c))
        FreeInstance(c);
    }
    if (unload)
        dlclose(lib);
    return 0;
}

int main(int argc, char **argv)
{
    int load, loads;
    if (argc != 8) {
        fprintf(stderr, "usage: c_importer FOLDER ID GUID LOADS STEPS H VR\n");
        return 2;
    }
    loads = atoi(argv[4]);
    for (load = 1; load <= loads; load++)
        if (run(argv[1], argv[2], argv[3], atoi(argv[5]), atof(argv[6]),
                (fmi2ValueReference)strtoul(argv[7], NULL, 10), load, load < loads))
            return 1;
    return 0;
}
