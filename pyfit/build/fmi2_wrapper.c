/* FMI 2.0 Model Exchange and Co-Simulation wrapper around CasADi-generated model functions.
 *
 * Written by pyfit's build (pyfit/build/fmi2_wrapper.c); model-specific data come from
 * model_data.h and the functions in model_functions.c, both generated from the Modelica sources.
 *
 * Value references index one array of doubles laid out as
 *   [independent parameters | calculated parameters | inputs | states | state derivatives | other variables]
 * Co-simulation integrates with an adaptive Dormand-Prince 5(4) method (tolerance from
 * fmi2SetupExperiment, default 1e-8) or, if the parameter cs_step > 0, with classic Runge-Kutta 4 at a
 * fixed sub-step <= cs_step. Inputs are interpolated within a communication step from the derivatives
 * set with fmi2SetRealInputDerivatives (orders 1 and 2). The adaptive integration fails (fmi2Error, "diverged or
 * too stiff") when its step falls below MIN_STEP_SHARE of the communication step (see there).
 *
 * Each model function comes in up to two variants (model_data.h): the general one and, for models with
 * the parameter exc_type, one with exc_type = 0 (no built-in excitation: every run driven by sampled
 * inputs). The variant is chosen, and the parameter-only subexpressions ("hoist") evaluated, whenever a
 * parameter has changed, not at every right-hand side call.
 *
 * Calls are checked against the FMI 2.0 state machine: a call in a state where the standard does not
 * allow it is logged (naming the call and the state) and returns fmi2Error. A failure (non-finite
 * derivative, failed integration) puts the instance in the error state: every later call except
 * fmi2Reset, fmi2FreeInstance and fmi2SetDebugLogging returns fmi2Error until fmi2Reset.
 */
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "model_data.h"
#include "model_functions.h"

#define OFS_CALC (N_PARAMS)
#define OFS_INPUT (OFS_CALC + N_CALC)
#define OFS_STATE (OFS_INPUT + N_INPUTS)
#define OFS_DER (OFS_STATE + N_STATES)
#define OFS_VAR (OFS_DER + N_STATES)
#define DIRTY_DER 1
#define DIRTY_VAR 2
#define DIRTY_ALL (DIRTY_DER | DIRTY_VAR)
#define N_TOTAL (OFS_VAR + N_VARS)
#define N_XU (N_STATES + N_INPUTS)
#define N_OUT (N_STATES + N_VARS) /* rows of the Jacobian: derivatives, then other variables */
#define ARRSZ(n) ((n) > 0 ? (n) : 1)

enum { ST_INSTANTIATED, ST_INIT, ST_STEP, ST_EVENT, ST_CONT, ST_TERMINATED, ST_ERROR };
static const char *STATE_NAME[] = {"the instantiated state", "initialization mode", "step mode", "event mode",
                                   "continuous-time mode", "the terminated state", "the error state"};
#define IN(s) (1 << (s))
#define LIVE (IN(ST_INIT) | IN(ST_STEP) | IN(ST_EVENT) | IN(ST_CONT) | IN(ST_TERMINATED))
#define ANY_BUT_ERROR (IN(ST_INSTANTIATED) | LIVE)
#define CS_ONLY 1
#define ME_ONLY 2

typedef int (*ModelFunction)(const casadi_real **, casadi_real **, casadi_int *, casadi_real *, int);

typedef struct {
  fmi2Type type;
  int state;
  char *name;
  const fmi2CallbackFunctions *cb;
  int logging;
  double v[ARRSZ(N_TOTAL)];
  double du1[ARRSZ(N_INPUTS)];
  double du2[ARRSZ(N_INPUTS)];
  double time;
  double rtol;
  int dirty; /* DIRTY_DER | DIRTY_VAR: the state derivatives, the variables are stale */
  int params_dirty; /* a parameter changed: calculated parameters, variant and hoisted values are stale */
  ModelFunction ode, vars, jac;
  double hoist[ARRSZ(N_HOIST)];
  /* CasADi work memory */
  const double **arg;
  double **res;
  casadi_int *iw;
  double *w;
  /* integrator workspace */
  double k[7][ARRSZ(N_STATES)];
  double xtmp[ARRSZ(N_STATES)], xnew[ARRSZ(N_STATES)], xerr[ARRSZ(N_STATES)];
  double xscale[ARRSZ(N_STATES)];
  double utmp[ARRSZ(N_INPUTS)];
  double h_last;
  /* the last step's final stage, kept for the next step's first (first same as last): its arguments and result */
  int last_valid;
  double last_t, last_x[ARRSZ(N_STATES)], last_u[ARRSZ(N_INPUTS)], last_xdot[ARRSZ(N_STATES)];
  double seed[ARRSZ(N_XU)];       /* directional derivative: the seed over (states, inputs) ... */
  double jacobian[ARRSZ(N_OUT)];  /* ... and J · seed over (state derivatives, variables) */
} Instance;

static void logmsg(Instance *c, fmi2Status st, const char *fmt, ...) {
  char buf[1024], out[2048];
  size_t i, j = 0;
  va_list ap;
  if (!c || !c->cb || !c->cb->logger) return;
  if (st == fmi2OK && !c->logging) return;
  va_start(ap, fmt);
  vsnprintf(buf, sizeof buf, fmt, ap);
  va_end(ap);
  /* the logger's message is a format string: pass the text with '%' escaped, and no arguments */
  for (i = 0; buf[i] && j + 2 < sizeof out; i++) {
    if (buf[i] == '%') out[j++] = '%';
    out[j++] = buf[i];
  }
  out[j] = '\0';
  c->cb->logger(c->cb->componentEnvironment, c->name, st, st == fmi2OK ? "logAll" : "logStatusError", out);
}

/* 1 if `fn` may be called now (states in `mask`, interface restriction `only`); else logs why, returns 0 */
static int allowed(Instance *c, int mask, int only, const char *fn) {
  if (!c) return 0;
  if (c->state == ST_ERROR && !(mask & IN(ST_ERROR))) {
    logmsg(c, fmi2Error, "%s: the instance failed earlier and is in the error state; call fmi2Reset", fn);
    return 0;
  }
  if ((only == CS_ONLY && c->type != fmi2CoSimulation) || (only == ME_ONLY && c->type != fmi2ModelExchange)) {
    logmsg(c, fmi2Error, "%s is not available: the instance was instantiated for %s", fn,
           c->type == fmi2CoSimulation ? "Co-Simulation" : "Model Exchange");
    return 0;
  }
  if (!(mask & IN(c->state))) {
    logmsg(c, fmi2Error, "%s called in %s, where FMI 2.0 does not allow it", fn, STATE_NAME[c->state]);
    return 0;
  }
  return 1;
}
#define GUARD(mask, only, fn) do { if (!allowed(c, (mask), (only), (fn))) return fmi2Error; } while (0)

/* ---- calls into the generated functions ----------------------------------------------------- */
static int call_model(Instance *c, ModelFunction f, const double *x, const double *u, const double *t, double *out) {
  c->arg[0] = x; c->arg[1] = u; c->arg[2] = c->v; c->arg[3] = t; c->arg[4] = c->hoist; c->arg[5] = c->seed;
  c->res[0] = out;
  return f(c->arg, c->res, c->iw, c->w, 0);
}

static int call_ode(Instance *c, const double *x, const double *u, double t, double *xdot) {
  return call_model(c, c->ode, x, u, &t, xdot);
}

/* calculated parameters, the model variant and its parameter-only subexpressions, if a parameter changed */
static int update_calculated(Instance *c) {
  ModelFunction hoist = FUN_HOIST;
  if (!c->params_dirty) return 0;
  c->last_valid = 0; /* the derivative kept for the next step was computed with the parameters before */
#if N_CALC > 0
  c->arg[0] = c->v;
  c->res[0] = c->v + OFS_CALC;
  if (FUN_CALC(c->arg, c->res, c->iw, c->w, 0)) return 1;
#endif
  c->ode = FUN_ODE; c->vars = FUN_VARS; c->jac = FUN_JAC;
#if VR_SAMPLED_SWITCH >= 0
  if (c->v[VR_SAMPLED_SWITCH] == 0.0) {
    c->ode = FUN_ODE_S; c->vars = FUN_VARS_S; c->jac = FUN_JAC_S; hoist = FUN_HOIST_S;
  }
#endif
  c->arg[0] = c->v;
  c->res[0] = c->hoist;
  if (hoist(c->arg, c->res, c->iw, c->w, 0)) return 1;
  c->params_dirty = 0;
  return 0;
}

static int finite_all(const double *a, int n) {
  int i;
  for (i = 0; i < n; i++) if (!isfinite(a[i])) return 0;
  return 1;
}

/* the stale ones of `need` (DIRTY_DER: the state derivatives, DIRTY_VAR: the variables) at the current time,
   state and inputs; each is computed only when read (an output read between steps needs no derivatives) */
static fmi2Status update(Instance *c, int need) {
  double t = c->time;
  need &= c->dirty;
  if (!need) return fmi2OK;
  if (update_calculated(c)) return fmi2Error;
  if ((need & DIRTY_DER) &&
      call_ode(c, c->v + OFS_STATE, c->v + OFS_INPUT, c->time, c->v + OFS_DER)) return fmi2Error;
#if N_VARS > 0
  if ((need & DIRTY_VAR) &&
      call_model(c, c->vars, c->v + OFS_STATE, c->v + OFS_INPUT, &t, c->v + OFS_VAR)) return fmi2Error;
#endif
  c->dirty &= ~need;
  if (((need & DIRTY_DER) && !finite_all(c->v + OFS_DER, N_STATES)) ||
      ((need & DIRTY_VAR) && !finite_all(c->v + OFS_VAR, N_VARS))) {
    logmsg(c, fmi2Error, "non-finite state derivative or variable at t = %g: the simulation diverged%s", c->time,
           c->type == fmi2ModelExchange ? " (with Model Exchange: an explicit solver such as forward Euler diverges "
                                          "at a step above about 2*zeta/omega of the fastest mode; use a smaller "
                                          "step or an implicit/adaptive solver such as CVode)" : "");
    c->state = ST_ERROR; /* latched until fmi2Reset */
    return fmi2Error;
  }
  return fmi2OK;
}

/* ---- FMI common functions ------------------------------------------------------------------- */
const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component comp, fmi2Boolean on, size_t n, const fmi2String cats[]) {
  (void)n; (void)cats;
  ((Instance *)comp)->logging = on;
  return fmi2OK;
}

static void reset_values(Instance *c) {
  memcpy(c->v, START_VALUES, sizeof(double) * N_TOTAL);
  memset(c->du1, 0, sizeof c->du1);
  memset(c->du2, 0, sizeof c->du2);
  c->time = 0.0;
  c->rtol = 1e-8;
  c->dirty = DIRTY_ALL;
  c->params_dirty = 1;
  c->h_last = 0.0;
  c->last_valid = 0;
  c->state = ST_INSTANTIATED;
}

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String location,
                              const fmi2CallbackFunctions *cb, fmi2Boolean visible, fmi2Boolean logging) {
  Instance *c;
  casadi_int sz_arg = 0, sz_res = 0, sz_iw = 0, sz_w = 0, a, r, i, w;
  (void)location; (void)visible;
  if (!guid || strcmp(guid, MODEL_GUID) != 0) {
    if (cb && cb->logger) cb->logger(cb->componentEnvironment, name, fmi2Error, "logStatusError",
                                     "GUID '%s' does not match '%s'", guid ? guid : "", MODEL_GUID);
    return NULL;
  }
  if (type != fmi2ModelExchange && type != fmi2CoSimulation) {
    if (cb && cb->logger) cb->logger(cb->componentEnvironment, name, fmi2Error, "logStatusError",
                                     "fmi2Instantiate: unknown interface type %d", (int)type);
    return NULL;
  }
  c = (Instance *)calloc(1, sizeof(Instance));
  if (!c) {
    if (cb && cb->logger) cb->logger(cb->componentEnvironment, name, fmi2Error, "logStatusError",
                                     "fmi2Instantiate: out of memory");
    return NULL;
  }
  c->type = type;
  c->cb = cb;
  c->logging = logging;
  c->name = (char *)malloc(strlen(name ? name : "") + 1);
  if (c->name) strcpy(c->name, name ? name : "");
#define WORK(F) F##_work(&a, &r, &i, &w); if (a > sz_arg) sz_arg = a; if (r > sz_res) sz_res = r; \
  if (i > sz_iw) sz_iw = i; if (w > sz_w) sz_w = w;
  WORK(FUN_ODE)
  WORK(FUN_VARS)
  WORK(FUN_CALC)
  WORK(FUN_JAC)
  WORK(FUN_HOIST)
#if VR_SAMPLED_SWITCH >= 0
  WORK(FUN_ODE_S)
  WORK(FUN_VARS_S)
  WORK(FUN_JAC_S)
  WORK(FUN_HOIST_S)
#endif
#undef WORK
  c->arg = (const double **)calloc(sz_arg + 1, sizeof(double *));
  c->res = (double **)calloc(sz_res + 1, sizeof(double *));
  c->iw = (casadi_int *)calloc(sz_iw + 1, sizeof(casadi_int));
  c->w = (double *)calloc(sz_w + 1, sizeof(double));
  if (!c->name || !c->arg || !c->res || !c->iw || !c->w) {
    if (cb && cb->logger) cb->logger(cb->componentEnvironment, name, fmi2Error, "logStatusError",
                                     "fmi2Instantiate: out of memory");
    free(c->arg); free(c->res); free(c->iw); free(c->w); free(c->name);
    free(c);
    return NULL;
  }
  reset_values(c);
  return c;
}

void fmi2FreeInstance(fmi2Component comp) {
  Instance *c = (Instance *)comp;
  if (!c) return;
  free(c->arg); free(c->res); free(c->iw); free(c->w); free(c->name);
  free(c);
}

fmi2Status fmi2SetupExperiment(fmi2Component comp, fmi2Boolean tolDefined, fmi2Real tol, fmi2Real t0,
                               fmi2Boolean stopDefined, fmi2Real tStop) {
  Instance *c = (Instance *)comp;
  (void)stopDefined; (void)tStop;
  GUARD(IN(ST_INSTANTIATED), 0, "fmi2SetupExperiment");
  if (tolDefined && tol > 0) c->rtol = tol;
  c->time = t0;
  c->dirty = DIRTY_ALL;
  return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component comp) {
  Instance *c = (Instance *)comp;
  GUARD(IN(ST_INSTANTIATED), 0, "fmi2EnterInitializationMode");
  c->state = ST_INIT;
  c->dirty = DIRTY_ALL;
  c->params_dirty = 1;
  return update_calculated(c) ? fmi2Error : fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component comp) {
  Instance *c = (Instance *)comp;
  int i;
  fmi2Status st;
  GUARD(IN(ST_INIT), 0, "fmi2ExitInitializationMode");
  c->dirty = DIRTY_ALL;
  st = update(c, DIRTY_ALL);
  if (st != fmi2OK) { c->state = ST_ERROR; return st; }
  for (i = 0; i < N_STATES; i++) c->xscale[i] = fabs(c->v[OFS_STATE + i]);
  c->state = (c->type == fmi2CoSimulation) ? ST_STEP : ST_EVENT;
  return st;
}

fmi2Status fmi2Terminate(fmi2Component comp) {
  Instance *c = (Instance *)comp;
  GUARD(IN(ST_STEP) | IN(ST_EVENT) | IN(ST_CONT), 0, "fmi2Terminate");
  c->state = ST_TERMINATED;
  return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component comp) {
  if (!comp) return fmi2Error;
  reset_values((Instance *)comp);
  return fmi2OK;
}

static fmi2Status check_vr(Instance *c, fmi2ValueReference vr, int type) {
  if (vr >= N_TOTAL) {
    logmsg(c, fmi2Error, "value reference %u out of range", (unsigned)vr);
    return fmi2Error;
  }
  if (VAR_TYPE[vr] != type) {
    logmsg(c, fmi2Error, "value reference %u has another type", (unsigned)vr);
    return fmi2Error;
  }
  return fmi2OK;
}

/* where the value of `vr` is kept: a variable that equals an input or a state (VAR_ALIAS) is read from it */
static fmi2ValueReference source_of(fmi2ValueReference vr) {
  return vr >= OFS_VAR && vr < N_TOTAL && VAR_ALIAS[vr - OFS_VAR] >= 0 ? OFS_INPUT + VAR_ALIAS[vr - OFS_VAR] : vr;
}

static fmi2Status get_values(Instance *c, const fmi2ValueReference vr[], size_t n, double *out, int type) {
  size_t i;
  int need = 0; /* the variables are computed only when one that is not an input or state is read */
  GUARD(ANY_BUT_ERROR, 0, "fmi2Get<Type>");
  for (i = 0; i < n; i++) {
    if (vr[i] >= OFS_DER && vr[i] < OFS_VAR) need = DIRTY_ALL;
    else if (source_of(vr[i]) >= OFS_VAR) need |= DIRTY_VAR;
  }
  if (c->state != ST_INSTANTIATED && update(c, need) != fmi2OK) {
    for (i = 0; i < n; i++) if (vr[i] < N_TOTAL) out[i] = c->v[source_of(vr[i])];
    return fmi2Error;
  }
  for (i = 0; i < n; i++) {
    if (check_vr(c, vr[i], type) != fmi2OK) return fmi2Error;
    out[i] = c->v[source_of(vr[i])];
  }
  return fmi2OK;
}

static fmi2Status set_values(Instance *c, const fmi2ValueReference vr[], size_t n, const double *in, int type) {
  size_t i;
  GUARD(IN(ST_INSTANTIATED) | IN(ST_INIT) | IN(ST_STEP) | IN(ST_EVENT) | IN(ST_CONT), 0, "fmi2Set<Type>");
  for (i = 0; i < n; i++) {
    int kind;
    if (check_vr(c, vr[i], type) != fmi2OK) return fmi2Error;
    kind = VAR_SETTABLE[vr[i]];
    if (kind == 0 || ((kind == 1 || kind == 3) && c->state != ST_INSTANTIATED && c->state != ST_INIT)) {
      logmsg(c, fmi2Error, "variable with value reference %u cannot be set now", (unsigned)vr[i]);
      return fmi2Error;
    }
    c->v[vr[i]] = in[i];
    if (kind == 1) c->params_dirty = 1;
  }
  c->dirty = DIRTY_ALL;
  return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t n, fmi2Real value[]) {
  return get_values((Instance *)comp, vr, n, value, 0);
}

fmi2Status fmi2GetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t n, fmi2Integer value[]) {
  size_t i;
  double tmp;
  for (i = 0; i < n; i++) {
    if (get_values((Instance *)comp, &vr[i], 1, &tmp, 1) != fmi2OK) return fmi2Error;
    value[i] = (fmi2Integer)tmp;
  }
  return fmi2OK;
}

fmi2Status fmi2GetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t n, fmi2Boolean value[]) {
  size_t i;
  double tmp;
  for (i = 0; i < n; i++) {
    if (get_values((Instance *)comp, &vr[i], 1, &tmp, 2) != fmi2OK) return fmi2Error;
    value[i] = tmp != 0.0;
  }
  return fmi2OK;
}

fmi2Status fmi2GetString(fmi2Component comp, const fmi2ValueReference vr[], size_t n, fmi2String value[]) {
  (void)vr; (void)value;
  if (n == 0) return fmi2OK;
  logmsg((Instance *)comp, fmi2Error, "the model has no String variables");
  return fmi2Error;
}

fmi2Status fmi2SetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t n, const fmi2Real value[]) {
  return set_values((Instance *)comp, vr, n, value, 0);
}

fmi2Status fmi2SetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t n, const fmi2Integer value[]) {
  size_t i;
  for (i = 0; i < n; i++) {
    double tmp = (double)value[i];
    if (set_values((Instance *)comp, &vr[i], 1, &tmp, 1) != fmi2OK) return fmi2Error;
  }
  return fmi2OK;
}

fmi2Status fmi2SetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t n, const fmi2Boolean value[]) {
  size_t i;
  for (i = 0; i < n; i++) {
    double tmp = value[i] ? 1.0 : 0.0;
    if (set_values((Instance *)comp, &vr[i], 1, &tmp, 2) != fmi2OK) return fmi2Error;
  }
  return fmi2OK;
}

fmi2Status fmi2SetString(fmi2Component comp, const fmi2ValueReference vr[], size_t n, const fmi2String value[]) {
  (void)vr; (void)value;
  if (n == 0) return fmi2OK;
  logmsg((Instance *)comp, fmi2Error, "the model has no String variables");
  return fmi2Error;
}

/* FMU state: everything the next step depends on: the value array, time, input derivatives, the
   tolerance and the adaptive integrator's memory (last step size, error scale of each state) */
typedef struct {
  double v[ARRSZ(N_TOTAL)];
  double du1[ARRSZ(N_INPUTS)], du2[ARRSZ(N_INPUTS)];
  double time, rtol, h_last;
  double xscale[ARRSZ(N_STATES)];
  int state;
} Snapshot;

fmi2Status fmi2GetFMUstate(fmi2Component comp, fmi2FMUstate *s) {
  Instance *c = (Instance *)comp;
  Snapshot *sn;
  GUARD(ANY_BUT_ERROR, 0, "fmi2GetFMUstate");
  sn = *s ? (Snapshot *)*s : (Snapshot *)calloc(1, sizeof(Snapshot));
  if (!sn) { logmsg(c, fmi2Error, "fmi2GetFMUstate: out of memory"); return fmi2Error; }
  memcpy(sn->v, c->v, sizeof sn->v);
  memcpy(sn->du1, c->du1, sizeof sn->du1);
  memcpy(sn->du2, c->du2, sizeof sn->du2);
  memcpy(sn->xscale, c->xscale, sizeof sn->xscale);
  sn->time = c->time;
  sn->rtol = c->rtol;
  sn->h_last = c->h_last;
  sn->state = c->state;
  *s = sn;
  return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component comp, fmi2FMUstate s) {
  Instance *c = (Instance *)comp;
  Snapshot *sn = (Snapshot *)s;
  GUARD(ANY_BUT_ERROR, 0, "fmi2SetFMUstate");
  if (!sn) { logmsg(c, fmi2Error, "fmi2SetFMUstate: no state given"); return fmi2Error; }
  memcpy(c->v, sn->v, sizeof sn->v);
  memcpy(c->du1, sn->du1, sizeof sn->du1);
  memcpy(c->du2, sn->du2, sizeof sn->du2);
  memcpy(c->xscale, sn->xscale, sizeof c->xscale);
  c->time = sn->time;
  c->rtol = sn->rtol;
  c->h_last = sn->h_last;
  c->state = sn->state;
  c->dirty = DIRTY_ALL;
  c->params_dirty = 1;
  return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component comp, fmi2FMUstate *s) {
  (void)comp;
  if (s && *s) { free(*s); *s = NULL; }
  return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component comp, fmi2FMUstate s, size_t *size) {
  (void)comp; (void)s;
  *size = sizeof(Snapshot);
  return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component comp, fmi2FMUstate s, fmi2Byte out[], size_t size) {
  (void)comp;
  if (size < sizeof(Snapshot)) return fmi2Error;
  memcpy(out, s, sizeof(Snapshot));
  return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component comp, const fmi2Byte in[], size_t size, fmi2FMUstate *s) {
  (void)comp;
  if (size < sizeof(Snapshot)) return fmi2Error;
  if (!*s) *s = calloc(1, sizeof(Snapshot));
  if (!*s) return fmi2Error;
  memcpy(*s, in, sizeof(Snapshot));
  return fmi2OK;
}

/* Directional derivatives d(unknown)/d(known) * seed, knowns = states and inputs,
   unknowns = state derivatives and other variables (outputs, locals). */
fmi2Status fmi2GetDirectionalDerivative(fmi2Component comp, const fmi2ValueReference vUnknown[], size_t nU,
                                        const fmi2ValueReference vKnown[], size_t nK, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[]) {
  Instance *c = (Instance *)comp;
  double t;
  size_t i, j;
  GUARD(LIVE, 0, "fmi2GetDirectionalDerivative");
  t = c->time;
  if (update_calculated(c)) return fmi2Error;
  /* one forward-mode sweep: J · seed, the seed holding dvKnown at the knowns' positions */
  for (j = 0; j < N_XU; j++) c->seed[j] = 0.0;
  for (j = 0; j < nK; j++) {
    long col;
    if (vKnown[j] >= OFS_STATE && vKnown[j] < OFS_DER) col = (long)(vKnown[j] - OFS_STATE);
    else if (vKnown[j] >= OFS_INPUT && vKnown[j] < OFS_STATE) col = N_STATES + (long)(vKnown[j] - OFS_INPUT);
    else { logmsg(c, fmi2Error, "value reference %u is not a known", (unsigned)vKnown[j]); return fmi2Error; }
    c->seed[col] += dvKnown[j];
  }
  for (i = 0; i < nU; i++) {
    if (!((vUnknown[i] >= OFS_DER && vUnknown[i] < OFS_VAR) || (vUnknown[i] >= OFS_VAR && vUnknown[i] < N_TOTAL))) {
      logmsg(c, fmi2Error, "value reference %u is not an unknown", (unsigned)vUnknown[i]);
      return fmi2Error;
    }
  }
  if (call_model(c, c->jac, c->v + OFS_STATE, c->v + OFS_INPUT, &t, c->jacobian)) return fmi2Error;
  for (i = 0; i < nU; i++) {
    long row = vUnknown[i] < OFS_VAR ? (long)(vUnknown[i] - OFS_DER) : N_STATES + (long)(vUnknown[i] - OFS_VAR);
    dvUnknown[i] = c->jacobian[row];
  }
  return fmi2OK;
}

/* ---- Model Exchange ------------------------------------------------------------------------- */
fmi2Status fmi2EnterEventMode(fmi2Component comp) {
  Instance *c = (Instance *)comp;
  GUARD(IN(ST_EVENT) | IN(ST_CONT), ME_ONLY, "fmi2EnterEventMode");
  c->state = ST_EVENT;
  return fmi2OK;
}

fmi2Status fmi2NewDiscreteStates(fmi2Component comp, fmi2EventInfo *info) {
  Instance *c = (Instance *)comp;
  GUARD(IN(ST_EVENT), ME_ONLY, "fmi2NewDiscreteStates");
  info->newDiscreteStatesNeeded = fmi2False;
  info->terminateSimulation = fmi2False;
  info->nominalsOfContinuousStatesChanged = fmi2False;
  info->valuesOfContinuousStatesChanged = fmi2False;
  info->nextEventTimeDefined = fmi2False;
  info->nextEventTime = 0.0;
  return fmi2OK;
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component comp) {
  Instance *c = (Instance *)comp;
  GUARD(IN(ST_EVENT), ME_ONLY, "fmi2EnterContinuousTimeMode");
  c->state = ST_CONT;
  return fmi2OK;
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component comp, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation) {
  Instance *c = (Instance *)comp;
  (void)noSetFMUStatePriorToCurrentPoint;
  GUARD(IN(ST_CONT), ME_ONLY, "fmi2CompletedIntegratorStep");
  *enterEventMode = fmi2False;
  *terminateSimulation = fmi2False;
  return fmi2OK;
}

fmi2Status fmi2SetTime(fmi2Component comp, fmi2Real time) {
  Instance *c = (Instance *)comp;
  GUARD(IN(ST_EVENT) | IN(ST_CONT), ME_ONLY, "fmi2SetTime");
  c->time = time;
  c->dirty = DIRTY_ALL;
  return fmi2OK;
}

fmi2Status fmi2SetContinuousStates(fmi2Component comp, const fmi2Real x[], size_t nx) {
  Instance *c = (Instance *)comp;
  GUARD(IN(ST_EVENT) | IN(ST_CONT), ME_ONLY, "fmi2SetContinuousStates");
  if (nx != N_STATES) return fmi2Error;
  memcpy(c->v + OFS_STATE, x, sizeof(double) * nx);
  c->dirty = DIRTY_ALL;
  return fmi2OK;
}

fmi2Status fmi2GetDerivatives(fmi2Component comp, fmi2Real dx[], size_t nx) {
  Instance *c = (Instance *)comp;
  fmi2Status st;
  GUARD(IN(ST_INIT) | IN(ST_EVENT) | IN(ST_CONT) | IN(ST_TERMINATED), ME_ONLY, "fmi2GetDerivatives");
  if (nx != N_STATES) return fmi2Error;
  st = update(c, DIRTY_DER); /* a solver's right-hand side: no variables */
  memcpy(dx, c->v + OFS_DER, sizeof(double) * nx);
  return st;
}

fmi2Status fmi2GetEventIndicators(fmi2Component comp, fmi2Real ind[], size_t ni) {
  Instance *c = (Instance *)comp;
  (void)ind;
  GUARD(IN(ST_INIT) | IN(ST_EVENT) | IN(ST_CONT) | IN(ST_TERMINATED), ME_ONLY, "fmi2GetEventIndicators");
  return ni == 0 ? fmi2OK : fmi2Error;
}

fmi2Status fmi2GetContinuousStates(fmi2Component comp, fmi2Real x[], size_t nx) {
  Instance *c = (Instance *)comp;
  GUARD(IN(ST_INIT) | IN(ST_EVENT) | IN(ST_CONT) | IN(ST_TERMINATED), ME_ONLY, "fmi2GetContinuousStates");
  if (nx != N_STATES) return fmi2Error;
  memcpy(x, c->v + OFS_STATE, sizeof(double) * nx);
  return fmi2OK;
}

/* the state nominals declared in the Modelica sources (nominal attribute; 1 where none is declared) */
fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component comp, fmi2Real nom[], size_t nx) {
  Instance *c = (Instance *)comp;
  GUARD(IN(ST_INSTANTIATED) | IN(ST_INIT) | IN(ST_EVENT) | IN(ST_CONT) | IN(ST_TERMINATED), ME_ONLY, "fmi2GetNominalsOfContinuousStates");
  if (nx != N_STATES) return fmi2Error;
  memcpy(nom, STATE_NOMINALS, sizeof(double) * nx);
  return fmi2OK;
}

/* ---- Co-Simulation -------------------------------------------------------------------------- */
fmi2Status fmi2SetRealInputDerivatives(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                                       const fmi2Integer order[], const fmi2Real value[]) {
  Instance *c = (Instance *)comp;
  size_t i;
  GUARD(IN(ST_INSTANTIATED) | IN(ST_INIT) | IN(ST_STEP), CS_ONLY, "fmi2SetRealInputDerivatives");
  for (i = 0; i < n; i++) {
    if (vr[i] < OFS_INPUT || vr[i] >= OFS_STATE) {
      logmsg(c, fmi2Error, "value reference %u is not an input", (unsigned)vr[i]);
      return fmi2Error;
    }
    if (order[i] == 1) c->du1[vr[i] - OFS_INPUT] = value[i];
    else if (order[i] == 2) c->du2[vr[i] - OFS_INPUT] = value[i];
    else { logmsg(c, fmi2Error, "input derivative order %d not supported (1 or 2)", (int)order[i]); return fmi2Error; }
  }
  return fmi2OK;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                                        const fmi2Integer order[], fmi2Real value[]) {
  Instance *c = (Instance *)comp;
  (void)vr; (void)order; (void)value;
  GUARD(IN(ST_STEP), CS_ONLY, "fmi2GetRealOutputDerivatives");
  if (n == 0) return fmi2OK;
  logmsg(c, fmi2Error, "output derivatives are not provided");
  return fmi2Error;
}

static const double *inputs_at(Instance *c, const double *u0, double dt) {
  int i;
  for (i = 0; i < N_INPUTS; i++) c->utmp[i] = u0[i] + c->du1[i] * dt + 0.5 * c->du2[i] * dt * dt;
  return c->utmp;
}

/* one Runge-Kutta 4 step of size h from (t, x) */
static int rk4_step(Instance *c, const double *u0, double t0, double t, double *x, double h) {
  int i, s;
  static const double a[4] = {0.0, 0.5, 0.5, 1.0};
  for (s = 0; s < 4; s++) {
    for (i = 0; i < N_STATES; i++) c->xtmp[i] = x[i] + (s ? a[s] * h * c->k[s - 1][i] : 0.0);
    if (call_ode(c, c->xtmp, inputs_at(c, u0, t + a[s] * h - t0), t + a[s] * h, c->k[s])) return 1;
  }
  for (i = 0; i < N_STATES; i++) x[i] += h / 6.0 * (c->k[0][i] + 2.0 * c->k[1][i] + 2.0 * c->k[2][i] + c->k[3][i]);
  return !finite_all(x, N_STATES);
}

/* Dormand-Prince 5(4) coefficients */
static const double DP_C[7] = {0.0, 1.0 / 5, 3.0 / 10, 4.0 / 5, 8.0 / 9, 1.0, 1.0};
static const double DP_A[7][6] = {
    {0, 0, 0, 0, 0, 0},
    {1.0 / 5, 0, 0, 0, 0, 0},
    {3.0 / 40, 9.0 / 40, 0, 0, 0, 0},
    {44.0 / 45, -56.0 / 15, 32.0 / 9, 0, 0, 0},
    {19372.0 / 6561, -25360.0 / 2187, 64448.0 / 6561, -212.0 / 729, 0, 0},
    {9017.0 / 3168, -355.0 / 33, 46732.0 / 5247, 49.0 / 176, -5103.0 / 18656, 0},
    {35.0 / 384, 0, 500.0 / 1113, 125.0 / 192, -2187.0 / 6784, 11.0 / 84}};
static const double DP_E[7] = {71.0 / 57600, 0, -71.0 / 16695, 71.0 / 1920, -17253.0 / 339200, 22.0 / 525, -1.0 / 40};

/* the state derivative at (x, u, t) into xdot. The last step's final stage is kept with its arguments: a step
   whose first stage has the same arguments to the bit (the next step of a Dormand-Prince integration starts where
   the last stage of the one before was evaluated; across communication points too, when the input the importer
   sets is the one the step ended with) takes it instead of calling the model: the same values, one call fewer */
static int first_stage(Instance *c, const double *x, const double *u, double t, double *xdot) {
  if (c->last_valid && memcmp(&t, &c->last_t, sizeof t) == 0 &&
      memcmp(x, c->last_x, sizeof(double) * N_STATES) == 0 &&
      memcmp(u, c->last_u, sizeof(double) * N_INPUTS) == 0) {
    memcpy(xdot, c->last_xdot, sizeof(double) * N_STATES);
    return 0;
  }
  return call_ode(c, x, u, t, xdot);
}

static void keep_last_stage(Instance *c, const double *x, const double *u, double t, const double *xdot) {
  c->last_t = t;
  memcpy(c->last_x, x, sizeof(double) * N_STATES);
  memcpy(c->last_u, u, sizeof(double) * N_INPUTS);
  memcpy(c->last_xdot, xdot, sizeof(double) * N_STATES);
  c->last_valid = 1;
}

/* the smallest adaptive step, as a share of the communication step H. A state that escapes to infinity (a softening
   spring past its peak force, a start far from the data in a fit) drives the step down without end, and following
   it on to what the arithmetic resolves (1e-14 t) took many times as long as the whole run up to the escape. A
   step this small resolves rates of change of 3e8/H (2e12 1/s at H = 1/6000 s): the runs that succeed in the test
   suite stay two decades and more above it (the steepest a sharp Bouc-Wen loop at its reversals), and every run
   there that came down to it failed further on. */
#define MIN_STEP_SHARE 1e-8

/* 0 while the step h at time t can go on; STEP_BELOW_SHARE below MIN_STEP_SHARE of the communication step H;
   STEP_BELOW_ARITHMETIC below what the arithmetic resolves at t */
enum { STEP_BELOW_SHARE = 2, STEP_BELOW_ARITHMETIC = 1 };
static int step_too_small(double h, double t, double H) {
  return h < MIN_STEP_SHARE * H ? STEP_BELOW_SHARE : h < 1e-14 * (1.0 + fabs(t)) ? STEP_BELOW_ARITHMETIC : 0;
}

/* adaptive integration from t0 to t0 + H; returns 0 on success, else a failure's code (step_too_small, or 1) */
static int dopri_integrate(Instance *c, const double *u0, double t0, double H, double *x) {
  double t = t0, tend = t0 + H, h = c->h_last > 0 ? c->h_last : H;
  int i, s, j, small, nsteps = 0;
  if (h > H) h = H;
  while (t < tend - 1e-14 * fabs(tend)) {
    double err = 0.0, fac;
    if (t + h > tend) h = tend - t;
    for (s = 0; s < 7; s++) {
      for (i = 0; i < N_STATES; i++) {
        double acc = 0.0;
        for (j = 0; j < s; j++) acc += DP_A[s][j] * c->k[j][i];
        c->xtmp[i] = x[i] + h * acc;
      }
      const double *u = inputs_at(c, u0, t + DP_C[s] * h - t0);
      if ((s ? call_ode : first_stage)(c, c->xtmp, u, t + DP_C[s] * h, c->k[s])) return 1;
      if (s == 6) keep_last_stage(c, c->xtmp, u, t + DP_C[s] * h, c->k[s]);
    }
    for (i = 0; i < N_STATES; i++) {
      double e = 0.0, sc;
      c->xnew[i] = c->xtmp[i]; /* stage 7 argument is the 5th-order solution (FSAL) */
      for (s = 0; s < 7; s++) e += DP_E[s] * c->k[s][i];
      e *= h;
      /* error relative to the largest magnitude the state has reached (floor 1e-9 in its unit) */
      sc = c->rtol * (fmax(fmax(c->xscale[i], fabs(x[i])), fabs(c->xnew[i])) + 1e-9);
      err = fmax(err, fabs(e) / sc);
    }
    if (!isfinite(err)) {
      h *= 0.25;
      if ((small = step_too_small(h, t, H))) return small;
      continue;
    }
    if (err <= 1.0) {
      t += h;
      memcpy(x, c->xnew, sizeof(double) * N_STATES);
      for (i = 0; i < N_STATES; i++) if (fabs(x[i]) > c->xscale[i]) c->xscale[i] = fabs(x[i]);
      if (t >= tend - 1e-14 * fabs(tend)) break;
    }
    fac = err > 0 ? 0.9 * pow(err, -0.2) : 5.0;
    if (fac > 5.0) fac = 5.0;
    if (fac < 0.2) fac = 0.2;
    h *= fac;
    c->h_last = h;
    if ((small = step_too_small(h, t, H))) return small;
    if (++nsteps > 10000000) return 1;
  }
  return 0;
}

fmi2Status fmi2DoStep(fmi2Component comp, fmi2Real tc, fmi2Real H, fmi2Boolean noSetPrior) {
  Instance *c = (Instance *)comp;
  double *x = c->v + OFS_STATE, u0[ARRSZ(N_INPUTS)];
  double step = c->v[VR_CS_STEP];
  int fail = 0;
  (void)noSetPrior;
  GUARD(IN(ST_STEP), CS_ONLY, "fmi2DoStep");
  if (H <= 0) return H == 0 ? fmi2OK : fmi2Error;
  memcpy(u0, c->v + OFS_INPUT, sizeof(double) * N_INPUTS);
  if (update_calculated(c)) return fmi2Error;
  if (step > 0) {
    int n = (int)ceil(H / step - 1e-9), i;
    double h = H / n;
    for (i = 0; i < n && !fail; i++) fail = rk4_step(c, u0, tc, tc + i * h, x, h);
  } else {
    fail = dopri_integrate(c, u0, tc, H, x);
  }
  c->time = tc + H;
  memcpy(c->v + OFS_INPUT, inputs_at(c, u0, H), sizeof(double) * N_INPUTS);
  memset(c->du1, 0, sizeof c->du1);
  memset(c->du2, 0, sizeof c->du2);
  /* the derivatives and variables at the new time are computed when they are read (update): a driver
     that sets the next inputs first would otherwise pay for them twice; a diverged state fails here */
  c->dirty = DIRTY_ALL;
  if (fail || !finite_all(x, N_STATES)) {
    if (fail == STEP_BELOW_SHARE)
      logmsg(c, fmi2Error, "integration failed in the step from t = %g: the step fell below %g of the communication "
             "step (diverged or too stiff)", tc, MIN_STEP_SHARE);
    else
      logmsg(c, fmi2Error, "integration failed in the step from t = %g (diverged or too stiff)", tc);
    c->state = ST_ERROR;
    return fmi2Error;
  }
  return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component comp) { (void)comp; return fmi2Error; }

fmi2Status fmi2GetStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Status *value) {
  (void)comp; (void)s; *value = fmi2OK; return fmi2OK;
}

fmi2Status fmi2GetRealStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Real *value) {
  if (s == fmi2LastSuccessfulTime) { *value = ((Instance *)comp)->time; return fmi2OK; }
  return fmi2Discard;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Integer *value) {
  (void)comp; (void)s; (void)value; return fmi2Discard;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Boolean *value) {
  (void)comp; (void)s; (void)value; return fmi2Discard;
}

fmi2Status fmi2GetStringStatus(fmi2Component comp, const fmi2StatusKind s, fmi2String *value) {
  (void)comp; (void)s; (void)value; return fmi2Discard;
}
