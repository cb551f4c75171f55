/* Co-simulation master loop of FmuRunner, compiled once per machine (pyfit/runtime/native.py).
 *
 * It calls the FMU's own FMI 2.0 functions (passed as pointers, so any FMI 2.0 co-simulation FMU
 * works) for every communication point: set the inputs, read the outputs, send the input slopes (and
 * curvatures), do the step. This is the loop FmuRunner runs in Python when no C compiler is available;
 * here it costs nanoseconds per point instead of microseconds.
 */
#define _POSIX_C_SOURCE 199309L
#include <stddef.h>
#include <time.h>

typedef void *fmi2Component;
typedef unsigned int fmi2ValueReference;
typedef int fmi2Status; /* fmi2OK = 0, fmi2Warning = 1, fmi2Discard = 2, fmi2Error = 3, fmi2Fatal = 4 */
typedef fmi2Status (*SetRealF)(fmi2Component, const fmi2ValueReference *, size_t, const double *);
typedef fmi2Status (*GetRealF)(fmi2Component, const fmi2ValueReference *, size_t, double *);
typedef fmi2Status (*SetDerF)(fmi2Component, const fmi2ValueReference *, size_t, const int *, const double *);
typedef fmi2Status (*DoStepF)(fmi2Component, double, double, int);

static double seconds(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Drive n_time communication points. u_at, slope and curv are row-major (n_time x n_in): the input at each
 * point, its first time derivative over the step that starts there (slope == NULL: inputs held) and its
 * second (curv == NULL: none sent; the input is then linear over the step).
 * result is row-major (n_time x n_out). Returns -1 on success, else the index of the point whose call
 * failed; *status gets that call's FMI status, *call which call it was (1 set, 2 get, 3 derivatives,
 * 4 step), or *call = 5 when the loop has run longer than max_wall_s seconds (checked every 16 points;
 * max_wall_s <= 0: no limit). */
int pyfit_cs_run(fmi2Component comp, SetRealF set_real, GetRealF get_real, SetDerF set_der, DoStepF do_step,
                 int n_time, const double *time, int n_in, const fmi2ValueReference *in_vr, const double *u_at,
                 const double *slope, const double *curv, int n_out, const fmi2ValueReference *out_vr,
                 double *result, int *status, int *call, double max_wall_s) {
  int i, j, order[64], order2[64];
  fmi2Status st;
  double t0 = max_wall_s > 0 ? seconds() : 0.0;
  if (n_in > 64) { *status = 3; *call = 1; return 0; }
  for (j = 0; j < n_in; j++) { order[j] = 1; order2[j] = 2; }
  for (i = 0; i < n_time; i++) {
    if (max_wall_s > 0 && (i & 15) == 0 && seconds() - t0 > max_wall_s) {
      *status = 0; *call = 5; return i;
    }
    if (n_in > 0 && (st = set_real(comp, in_vr, (size_t)n_in, u_at + (size_t)i * n_in)) > 1) {
      *status = st; *call = 1; return i;
    }
    if ((st = get_real(comp, out_vr, (size_t)n_out, result + (size_t)i * n_out)) > 1) {
      *status = st; *call = 2; return i;
    }
    if (i + 1 == n_time) break;
    if (n_in > 0 && slope && (st = set_der(comp, in_vr, (size_t)n_in, order, slope + (size_t)i * n_in)) > 1) {
      *status = st; *call = 3; return i;
    }
    if (n_in > 0 && slope && curv &&
        (st = set_der(comp, in_vr, (size_t)n_in, order2, curv + (size_t)i * n_in)) > 1) {
      *status = st; *call = 3; return i;
    }
    if ((st = do_step(comp, time[i], time[i + 1] - time[i], 1)) > 1) {
      *status = st; *call = 4; return i;
    }
  }
  return -1;
}
