/* The importer's floor: an FMI 2.0 co-simulation binary in C that does nothing.
 *
 * benchmarks/fmu_overhead.py puts it in place of the binary of a pythonfmu FMU with as many outputs
 * (same modelDescription.xml), so that fmpy.simulate_fmu drives it exactly as it drives the
 * project's FMUs: what remains is fmpy's own cost per step (its Python loop, recording every
 * output), which no FMU can go below. Every output reads 0; FMU state is not supported.
 *
 *   gcc -shared -fPIC -O2 -I fmu_src -o <modelIdentifier>.so benchmarks/c_floor_fmu.c
 */
#include <stdlib.h>
#include <string.h>

#include "fmi2_types.h"

#define EXPORT __attribute__((visibility("default")))
#define UNUSED(x) (void)(x)

EXPORT const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
EXPORT const char *fmi2GetVersion(void) { return fmi2Version; }

EXPORT fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid,
                                     fmi2String resources, const fmi2CallbackFunctions *functions,
                                     fmi2Boolean visible, fmi2Boolean loggingOn)
{
    UNUSED(name); UNUSED(type); UNUSED(guid); UNUSED(resources); UNUSED(functions);
    UNUSED(visible); UNUSED(loggingOn);
    return calloc(1, 16);
}

EXPORT void fmi2FreeInstance(fmi2Component c) { free(c); }

#define OK_WITH(...)                                                                             \
    {                                                                                            \
        UNUSED(c);                                                                               \
        __VA_ARGS__;                                                                             \
        return fmi2OK;                                                                           \
    }
#define REFUSED(...)                                                                             \
    {                                                                                            \
        UNUSED(c);                                                                               \
        __VA_ARGS__;                                                                             \
        return fmi2Error;                                                                        \
    }

EXPORT fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n,
                                      const fmi2String categories[])
OK_WITH(UNUSED(on); UNUSED(n); UNUSED(categories))
EXPORT fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined,
                                      fmi2Real tolerance, fmi2Real start,
                                      fmi2Boolean stopDefined, fmi2Real stop)
OK_WITH(UNUSED(toleranceDefined); UNUSED(tolerance); UNUSED(start); UNUSED(stopDefined);
        UNUSED(stop))
EXPORT fmi2Status fmi2EnterInitializationMode(fmi2Component c) OK_WITH()
EXPORT fmi2Status fmi2ExitInitializationMode(fmi2Component c) OK_WITH()
EXPORT fmi2Status fmi2Terminate(fmi2Component c) OK_WITH()
EXPORT fmi2Status fmi2Reset(fmi2Component c) OK_WITH()

EXPORT fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                              fmi2Real value[])
OK_WITH(UNUSED(vr); memset(value, 0, n * sizeof *value))
EXPORT fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                 fmi2Integer value[])
OK_WITH(UNUSED(vr); memset(value, 0, n * sizeof *value))
EXPORT fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                 fmi2Boolean value[])
OK_WITH(UNUSED(vr); memset(value, 0, n * sizeof *value))
EXPORT fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                fmi2String value[])
OK_WITH(UNUSED(vr); for (size_t i = 0; i < n; i++) value[i] = "")
EXPORT fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                              const fmi2Real value[])
OK_WITH(UNUSED(vr); UNUSED(n); UNUSED(value))
EXPORT fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                 const fmi2Integer value[])
OK_WITH(UNUSED(vr); UNUSED(n); UNUSED(value))
EXPORT fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                 const fmi2Boolean value[])
OK_WITH(UNUSED(vr); UNUSED(n); UNUSED(value))
EXPORT fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                const fmi2String value[])
OK_WITH(UNUSED(vr); UNUSED(n); UNUSED(value))

EXPORT fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noPrior)
OK_WITH(UNUSED(t); UNUSED(h); UNUSED(noPrior))
EXPORT fmi2Status fmi2CancelStep(fmi2Component c) OK_WITH()
EXPORT fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
OK_WITH(UNUSED(s); *value = fmi2OK)
EXPORT fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
OK_WITH(UNUSED(s); *value = 0.0)
EXPORT fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s,
                                       fmi2Integer *value)
OK_WITH(UNUSED(s); *value = 0)
EXPORT fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s,
                                       fmi2Boolean *value)
OK_WITH(UNUSED(s); *value = fmi2False)
EXPORT fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value)
OK_WITH(UNUSED(s); *value = "")
EXPORT fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                              size_t n, const fmi2Integer order[],
                                              const fmi2Real value[])
OK_WITH(UNUSED(vr); UNUSED(n); UNUSED(order); UNUSED(value))
EXPORT fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                               size_t n, const fmi2Integer order[],
                                               fmi2Real value[])
OK_WITH(UNUSED(vr); UNUSED(order); memset(value, 0, n * sizeof *value))

EXPORT fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *state) REFUSED(UNUSED(state))
EXPORT fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) REFUSED(UNUSED(state))
EXPORT fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state) REFUSED(UNUSED(state))
EXPORT fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t *size)
REFUSED(UNUSED(state); UNUSED(size))
EXPORT fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[],
                                        size_t size)
REFUSED(UNUSED(state); UNUSED(bytes); UNUSED(size))
EXPORT fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size,
                                          fmi2FMUstate *state)
REFUSED(UNUSED(bytes); UNUSED(size); UNUSED(state))
EXPORT fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[],
                                               size_t nu, const fmi2ValueReference k[], size_t nk,
                                               const fmi2Real dk[], fmi2Real du[])
REFUSED(UNUSED(u); UNUSED(nu); UNUSED(k); UNUSED(nk); UNUSED(dk); UNUSED(du))
