/* FMI 3.0 Model Exchange and Co-Simulation interface on top of the FMI 2.0 functions of the same library.
 *
 * Written by pyfit's build (pyfit/build/fmi3_adapter.c) and linked with fmi2_wrapper.c and the generated
 * model functions: the equations, the integrators, the FMI state machine, the error latch and the FMU state
 * are those of the FMI 2.0 implementation; this file only translates the calls. Differences a user sees:
 *   - Variables are scalars of type Float64 or Int32; the independent variable `time` has the value
 *     reference VR_TIME (one past the FMI 2.0 layout) and is read with fmi3GetFloat64.
 *   - Co-simulation holds each input constant over a communication step (FMI 3.0 has no input-derivative
 *     call); the element FMUs' held-input reference results (docs/fmus/<name>_ref_held.csv) apply.
 *   - No event mode, clocks, configuration mode, adjoint derivatives or variable-dependency queries: those
 *     calls return fmi3Error with a logged reason, as the capability flags in modelDescription.xml declare.
 *   - Log messages come from the FMI 2.0 layer and name its calls (e.g. fmi2DoStep for fmi3DoStep).
 */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "fmi3Functions.h"
#include "model_data.h"

#define VR_TIME (N_PARAMS + N_CALC + N_INPUTS + 2 * N_STATES + N_VARS)

typedef struct {
  fmi2Component c2;
  fmi2CallbackFunctions cb; /* the FMI 2.0 layer keeps a pointer to this: the struct must not move */
  fmi3InstanceEnvironment env;
  fmi3LogMessageCallback log;
  char *name;
} Instance3;

#define I3(inst) ((Instance3 *)(inst))
#define C2(inst) (I3(inst)->c2)

static fmi3Status st3(fmi2Status s) { return s > fmi2Fatal ? fmi3Error : (fmi3Status)s; }

/* the FMI 2.0 layer's logger (printf-style) forwarded to the FMI 3.0 callback (plain message) */
static void log2to3(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                    fmi2String fmt, ...) {
  Instance3 *i = (Instance3 *)env;
  char buf[2048];
  va_list ap;
  (void)name;
  if (!i || !i->log) return;
  va_start(ap, fmt);
  vsnprintf(buf, sizeof buf, fmt, ap);
  va_end(ap);
  i->log(i->env, st3(status), category, buf);
}

static void log3(fmi3Instance inst, const char *fmt, ...) {
  Instance3 *i = I3(inst);
  char buf[1024];
  va_list ap;
  if (!i || !i->log) return;
  va_start(ap, fmt);
  vsnprintf(buf, sizeof buf, fmt, ap);
  va_end(ap);
  i->log(i->env, fmi3Error, "logStatusError", buf);
}

static fmi3Instance instantiate(fmi3String name, fmi3String token, fmi2Type type, fmi3Boolean visible,
                                fmi3Boolean logging, fmi3InstanceEnvironment env, fmi3LogMessageCallback log) {
  Instance3 *i = (Instance3 *)calloc(1, sizeof(Instance3));
  if (!i) {
    if (log) log(env, fmi3Error, "logStatusError", "fmi3Instantiate: out of memory");
    return NULL;
  }
  i->env = env;
  i->log = log;
  i->cb.logger = log2to3;
  i->cb.allocateMemory = calloc;
  i->cb.freeMemory = free;
  i->cb.componentEnvironment = i;
  i->c2 = fmi2Instantiate(name, type, token, "", &i->cb, visible, logging);
  if (!i->c2) { free(i); return NULL; }
  return i;
}

/* ---- common functions ----------------------------------------------------------------------- */
const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance inst, fmi3Boolean on, size_t n, const fmi3String cats[]) {
  return st3(fmi2SetDebugLogging(C2(inst), on, n, cats));
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String name, fmi3String token, fmi3String resources,
                                          fmi3Boolean visible, fmi3Boolean logging, fmi3InstanceEnvironment env,
                                          fmi3LogMessageCallback log) {
  (void)resources;
  return instantiate(name, token, fmi2ModelExchange, visible, logging, env, log);
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String name, fmi3String token, fmi3String resources,
                                         fmi3Boolean visible, fmi3Boolean logging, fmi3Boolean eventModeUsed,
                                         fmi3Boolean earlyReturnAllowed, const fmi3ValueReference required[],
                                         size_t nRequired, fmi3InstanceEnvironment env,
                                         fmi3LogMessageCallback log, fmi3IntermediateUpdateCallback update) {
  (void)resources; (void)earlyReturnAllowed; (void)required; (void)nRequired; (void)update;
  if (eventModeUsed) {
    if (log) log(env, fmi3Error, "logStatusError", "fmi3InstantiateCoSimulation: the FMU has no event mode "
                 "(hasEventMode=\"false\"); instantiate with eventModeUsed = false");
    return NULL;
  }
  return instantiate(name, token, fmi2CoSimulation, visible, logging, env, log);
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String name, fmi3String token, fmi3String resources,
                                               fmi3Boolean visible, fmi3Boolean logging,
                                               fmi3InstanceEnvironment env, fmi3LogMessageCallback log,
                                               fmi3ClockUpdateCallback clockUpdate,
                                               fmi3LockPreemptionCallback lock, fmi3UnlockPreemptionCallback unlock) {
  (void)name; (void)token; (void)resources; (void)visible; (void)logging; (void)clockUpdate; (void)lock;
  (void)unlock;
  if (log) log(env, fmi3Error, "logStatusError", "Scheduled Execution is not supported (Model Exchange and "
               "Co-Simulation are)");
  return NULL;
}

void fmi3FreeInstance(fmi3Instance inst) {
  if (!inst) return;
  fmi2FreeInstance(C2(inst));
  free(inst);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance inst, fmi3Boolean tolDefined, fmi3Float64 tol,
                                       fmi3Float64 start, fmi3Boolean stopDefined, fmi3Float64 stop) {
  fmi2Status s = fmi2SetupExperiment(C2(inst), tolDefined, tol, start, stopDefined, stop);
  return s != fmi2OK ? st3(s) : st3(fmi2EnterInitializationMode(C2(inst)));
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance inst) { return st3(fmi2ExitInitializationMode(C2(inst))); }
fmi3Status fmi3EnterEventMode(fmi3Instance inst) { return st3(fmi2EnterEventMode(C2(inst))); }
fmi3Status fmi3Terminate(fmi3Instance inst) { return st3(fmi2Terminate(C2(inst))); }
fmi3Status fmi3Reset(fmi3Instance inst) { return st3(fmi2Reset(C2(inst))); }

/* ---- variable access: Float64 and Int32 scalars ----------------------------------------------- */
static fmi3Status scalars_only(fmi3Instance inst, size_t nvr, size_t nValues, const char *fn) {
  if (nvr == nValues) return fmi3OK;
  log3(inst, "%s: %zu values for %zu value references; every variable is a scalar", fn, nValues, nvr);
  return fmi3Error;
}

fmi3Status fmi3GetFloat64(fmi3Instance inst, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 values[],
                          size_t nValues) {
  size_t k;
  fmi3Status s = scalars_only(inst, nvr, nValues, "fmi3GetFloat64");
  if (s != fmi3OK) return s;
  for (k = 0; k < nvr; k++) if (vr[k] == VR_TIME) break;
  if (k == nvr) return st3(fmi2GetReal(C2(inst), vr, nvr, values));
  for (k = 0; k < nvr && s == fmi3OK; k++)  /* the independent variable is among them: one at a time */
    s = st3(vr[k] == VR_TIME ? fmi2GetRealStatus(C2(inst), fmi2LastSuccessfulTime, &values[k])
                             : fmi2GetReal(C2(inst), &vr[k], 1, &values[k]));
  return s;
}

fmi3Status fmi3SetFloat64(fmi3Instance inst, const fmi3ValueReference vr[], size_t nvr, const fmi3Float64 values[],
                          size_t nValues) {
  fmi3Status s = scalars_only(inst, nvr, nValues, "fmi3SetFloat64");
  return s != fmi3OK ? s : st3(fmi2SetReal(C2(inst), vr, nvr, values));
}

fmi3Status fmi3GetInt32(fmi3Instance inst, const fmi3ValueReference vr[], size_t nvr, fmi3Int32 values[],
                        size_t nValues) {
  fmi3Status s = scalars_only(inst, nvr, nValues, "fmi3GetInt32");
  return s != fmi3OK ? s : st3(fmi2GetInteger(C2(inst), vr, nvr, (fmi2Integer *)values));
}

fmi3Status fmi3SetInt32(fmi3Instance inst, const fmi3ValueReference vr[], size_t nvr, const fmi3Int32 values[],
                        size_t nValues) {
  fmi3Status s = scalars_only(inst, nvr, nValues, "fmi3SetInt32");
  return s != fmi3OK ? s : st3(fmi2SetInteger(C2(inst), vr, nvr, (const fmi2Integer *)values));
}

/* types the models do not have: an empty call succeeds, any variable is an error */
#define NO_SUCH_TYPE(T, CT)                                                                                  \
  fmi3Status fmi3Get##T(fmi3Instance inst, const fmi3ValueReference vr[], size_t nvr, CT values[], size_t nv) { \
    (void)vr; (void)values; (void)nv;                                                                        \
    if (nvr == 0) return fmi3OK;                                                                             \
    log3(inst, "fmi3Get" #T ": the model has no " #T " variables");                                        \
    return fmi3Error;                                                                                        \
  }                                                                                                          \
  fmi3Status fmi3Set##T(fmi3Instance inst, const fmi3ValueReference vr[], size_t nvr, const CT values[],      \
                        size_t nv) {                                                                         \
    (void)vr; (void)values; (void)nv;                                                                        \
    if (nvr == 0) return fmi3OK;                                                                             \
    log3(inst, "fmi3Set" #T ": the model has no " #T " variables");                                        \
    return fmi3Error;                                                                                        \
  }
NO_SUCH_TYPE(Float32, fmi3Float32)
NO_SUCH_TYPE(Int8, fmi3Int8)
NO_SUCH_TYPE(UInt8, fmi3UInt8)
NO_SUCH_TYPE(Int16, fmi3Int16)
NO_SUCH_TYPE(UInt16, fmi3UInt16)
NO_SUCH_TYPE(UInt32, fmi3UInt32)
NO_SUCH_TYPE(Int64, fmi3Int64)
NO_SUCH_TYPE(UInt64, fmi3UInt64)
NO_SUCH_TYPE(Boolean, fmi3Boolean)
NO_SUCH_TYPE(String, fmi3String)

fmi3Status fmi3GetBinary(fmi3Instance inst, const fmi3ValueReference vr[], size_t nvr, size_t sizes[],
                         fmi3Binary values[], size_t nv) {
  (void)vr; (void)sizes; (void)values; (void)nv;
  if (nvr == 0) return fmi3OK;
  log3(inst, "fmi3GetBinary: the model has no Binary variables");
  return fmi3Error;
}

fmi3Status fmi3SetBinary(fmi3Instance inst, const fmi3ValueReference vr[], size_t nvr, const size_t sizes[],
                         const fmi3Binary values[], size_t nv) {
  (void)vr; (void)sizes; (void)values; (void)nv;
  if (nvr == 0) return fmi3OK;
  log3(inst, "fmi3SetBinary: the model has no Binary variables");
  return fmi3Error;
}

/* ---- capabilities the FMU does not declare ----------------------------------------------------- */
#define NOT_PROVIDED(fn, what) do { (void)inst; log3(inst, fn ": " what " (not declared in modelDescription.xml)"); \
                                    return fmi3Error; } while (0)

fmi3Status fmi3GetClock(fmi3Instance inst, const fmi3ValueReference vr[], size_t n, fmi3Clock values[]) {
  (void)vr; (void)n; (void)values; NOT_PROVIDED("fmi3GetClock", "the model has no clocks");
}
fmi3Status fmi3SetClock(fmi3Instance inst, const fmi3ValueReference vr[], size_t n, const fmi3Clock values[]) {
  (void)vr; (void)n; (void)values; NOT_PROVIDED("fmi3SetClock", "the model has no clocks");
}
fmi3Status fmi3GetIntervalDecimal(fmi3Instance inst, const fmi3ValueReference vr[], size_t n, fmi3Float64 iv[],
                                  fmi3IntervalQualifier q[]) {
  (void)vr; (void)n; (void)iv; (void)q; NOT_PROVIDED("fmi3GetIntervalDecimal", "the model has no clocks");
}
fmi3Status fmi3GetIntervalFraction(fmi3Instance inst, const fmi3ValueReference vr[], size_t n, fmi3UInt64 c[],
                                   fmi3UInt64 r[], fmi3IntervalQualifier q[]) {
  (void)vr; (void)n; (void)c; (void)r; (void)q; NOT_PROVIDED("fmi3GetIntervalFraction", "the model has no clocks");
}
fmi3Status fmi3GetShiftDecimal(fmi3Instance inst, const fmi3ValueReference vr[], size_t n, fmi3Float64 s[]) {
  (void)vr; (void)n; (void)s; NOT_PROVIDED("fmi3GetShiftDecimal", "the model has no clocks");
}
fmi3Status fmi3GetShiftFraction(fmi3Instance inst, const fmi3ValueReference vr[], size_t n, fmi3UInt64 c[],
                                fmi3UInt64 r[]) {
  (void)vr; (void)n; (void)c; (void)r; NOT_PROVIDED("fmi3GetShiftFraction", "the model has no clocks");
}
fmi3Status fmi3SetIntervalDecimal(fmi3Instance inst, const fmi3ValueReference vr[], size_t n, const fmi3Float64 iv[]) {
  (void)vr; (void)n; (void)iv; NOT_PROVIDED("fmi3SetIntervalDecimal", "the model has no clocks");
}
fmi3Status fmi3SetIntervalFraction(fmi3Instance inst, const fmi3ValueReference vr[], size_t n, const fmi3UInt64 c[],
                                   const fmi3UInt64 r[]) {
  (void)vr; (void)n; (void)c; (void)r; NOT_PROVIDED("fmi3SetIntervalFraction", "the model has no clocks");
}
fmi3Status fmi3SetShiftDecimal(fmi3Instance inst, const fmi3ValueReference vr[], size_t n, const fmi3Float64 s[]) {
  (void)vr; (void)n; (void)s; NOT_PROVIDED("fmi3SetShiftDecimal", "the model has no clocks");
}
fmi3Status fmi3SetShiftFraction(fmi3Instance inst, const fmi3ValueReference vr[], size_t n, const fmi3UInt64 c[],
                                const fmi3UInt64 r[]) {
  (void)vr; (void)n; (void)c; (void)r; NOT_PROVIDED("fmi3SetShiftFraction", "the model has no clocks");
}
fmi3Status fmi3ActivateModelPartition(fmi3Instance inst, fmi3ValueReference clock, fmi3Float64 t) {
  (void)clock; (void)t; NOT_PROVIDED("fmi3ActivateModelPartition", "Scheduled Execution is not supported");
}
fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance inst, fmi3ValueReference vr, size_t *n) {
  (void)vr; (void)n; NOT_PROVIDED("fmi3GetNumberOfVariableDependencies", "per-element dependencies are not provided");
}
fmi3Status fmi3GetVariableDependencies(fmi3Instance inst, fmi3ValueReference dep, size_t ed[],
                                       fmi3ValueReference ind[], size_t ei[], fmi3DependencyKind kinds[], size_t n) {
  (void)dep; (void)ed; (void)ind; (void)ei; (void)kinds; (void)n;
  NOT_PROVIDED("fmi3GetVariableDependencies", "per-element dependencies are not provided");
}
fmi3Status fmi3GetAdjointDerivative(fmi3Instance inst, const fmi3ValueReference u[], size_t nu,
                                    const fmi3ValueReference k[], size_t nk, const fmi3Float64 seed[], size_t ns,
                                    fmi3Float64 sens[], size_t nsens) {
  (void)u; (void)nu; (void)k; (void)nk; (void)seed; (void)ns; (void)sens; (void)nsens;
  NOT_PROVIDED("fmi3GetAdjointDerivative", "adjoint derivatives are not provided (directional derivatives are)");
}
fmi3Status fmi3EnterConfigurationMode(fmi3Instance inst) {
  NOT_PROVIDED("fmi3EnterConfigurationMode", "the model has no structural parameters");
}
fmi3Status fmi3ExitConfigurationMode(fmi3Instance inst) {
  NOT_PROVIDED("fmi3ExitConfigurationMode", "the model has no structural parameters");
}
fmi3Status fmi3EnterStepMode(fmi3Instance inst) {
  NOT_PROVIDED("fmi3EnterStepMode", "the FMU has no event mode; it is in step mode after initialization");
}

/* ---- FMU state and derivatives ---------------------------------------------------------------- */
fmi3Status fmi3GetFMUState(fmi3Instance inst, fmi3FMUState *s) { return st3(fmi2GetFMUstate(C2(inst), s)); }
fmi3Status fmi3SetFMUState(fmi3Instance inst, fmi3FMUState s) { return st3(fmi2SetFMUstate(C2(inst), s)); }
fmi3Status fmi3FreeFMUState(fmi3Instance inst, fmi3FMUState *s) { return st3(fmi2FreeFMUstate(C2(inst), s)); }

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance inst, fmi3FMUState s, size_t *size) {
  return st3(fmi2SerializedFMUstateSize(C2(inst), s, size));
}
fmi3Status fmi3SerializeFMUState(fmi3Instance inst, fmi3FMUState s, fmi3Byte out[], size_t size) {
  return st3(fmi2SerializeFMUstate(C2(inst), s, (fmi2Byte *)out, size));
}
fmi3Status fmi3DeserializeFMUState(fmi3Instance inst, const fmi3Byte in[], size_t size, fmi3FMUState *s) {
  return st3(fmi2DeSerializeFMUstate(C2(inst), (const fmi2Byte *)in, size, s));
}

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance inst, const fmi3ValueReference unknowns[], size_t nu,
                                        const fmi3ValueReference knowns[], size_t nk, const fmi3Float64 seed[],
                                        size_t nseed, fmi3Float64 sensitivity[], size_t nsens) {
  if (nseed != nk || nsens != nu) {
    log3(inst, "fmi3GetDirectionalDerivative: seed and sensitivity must have one value per known and unknown");
    return fmi3Error;
  }
  return st3(fmi2GetDirectionalDerivative(C2(inst), unknowns, nu, knowns, nk, seed, sensitivity));
}

/* ---- Model Exchange --------------------------------------------------------------------------- */
fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance inst) { (void)inst; return fmi3OK; }

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance inst, fmi3Boolean *needUpdate, fmi3Boolean *terminate,
                                    fmi3Boolean *nominalsChanged, fmi3Boolean *valuesChanged,
                                    fmi3Boolean *nextEventTimeDefined, fmi3Float64 *nextEventTime) {
  fmi2EventInfo info;
  fmi2Status s = fmi2NewDiscreteStates(C2(inst), &info);
  *needUpdate = info.newDiscreteStatesNeeded != 0;
  *terminate = info.terminateSimulation != 0;
  *nominalsChanged = info.nominalsOfContinuousStatesChanged != 0;
  *valuesChanged = info.valuesOfContinuousStatesChanged != 0;
  *nextEventTimeDefined = info.nextEventTimeDefined != 0;
  *nextEventTime = info.nextEventTime;
  return st3(s);
}

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance inst) { return st3(fmi2EnterContinuousTimeMode(C2(inst))); }

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance inst, fmi3Boolean noSetPrior, fmi3Boolean *enterEventMode,
                                       fmi3Boolean *terminate) {
  fmi2Boolean e = fmi2False, t = fmi2False;
  fmi2Status s = fmi2CompletedIntegratorStep(C2(inst), noSetPrior, &e, &t);
  *enterEventMode = e != 0;
  *terminate = t != 0;
  return st3(s);
}

fmi3Status fmi3SetTime(fmi3Instance inst, fmi3Float64 t) { return st3(fmi2SetTime(C2(inst), t)); }

fmi3Status fmi3SetContinuousStates(fmi3Instance inst, const fmi3Float64 x[], size_t nx) {
  return st3(fmi2SetContinuousStates(C2(inst), x, nx));
}
fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance inst, fmi3Float64 dx[], size_t nx) {
  return st3(fmi2GetDerivatives(C2(inst), dx, nx));
}
fmi3Status fmi3GetEventIndicators(fmi3Instance inst, fmi3Float64 ind[], size_t ni) {
  return st3(fmi2GetEventIndicators(C2(inst), ind, ni));
}
fmi3Status fmi3GetContinuousStates(fmi3Instance inst, fmi3Float64 x[], size_t nx) {
  return st3(fmi2GetContinuousStates(C2(inst), x, nx));
}
fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance inst, fmi3Float64 nom[], size_t nx) {
  return st3(fmi2GetNominalsOfContinuousStates(C2(inst), nom, nx));
}
fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance inst, size_t *n) { (void)inst; *n = 0; return fmi3OK; }
fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance inst, size_t *n) { (void)inst; *n = N_STATES; return fmi3OK; }

/* ---- Co-Simulation ---------------------------------------------------------------------------- */
fmi3Status fmi3GetOutputDerivatives(fmi3Instance inst, const fmi3ValueReference vr[], size_t nvr,
                                    const fmi3Int32 orders[], fmi3Float64 values[], size_t nValues) {
  (void)nValues;
  return st3(fmi2GetRealOutputDerivatives(C2(inst), vr, nvr, (const fmi2Integer *)orders, values));
}

fmi3Status fmi3DoStep(fmi3Instance inst, fmi3Float64 t, fmi3Float64 h, fmi3Boolean noSetPrior,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminate, fmi3Boolean *earlyReturn,
                      fmi3Float64 *lastSuccessfulTime) {
  fmi2Status s = fmi2DoStep(C2(inst), t, h, noSetPrior);
  *eventHandlingNeeded = fmi3False;
  *terminate = fmi3False;
  *earlyReturn = fmi3False;
  *lastSuccessfulTime = s == fmi2OK ? t + h : t;
  return st3(s);
}
