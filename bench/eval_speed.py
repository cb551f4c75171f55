"""One FMU evaluation against the compiled limit, measured in one run.

For the SDOF Bouc-Wen benchmark system (3 periods of the benchmark multisine, 750 Hz samples) and the
theory §1.3 Stockbridge damper (a 35 s constant-velocity clamp sweep 5-40 Hz, 750 Hz samples), the same
run is timed three ways:

- the co-simulation FMU through FmuRunner (inputs linear between samples, sent as input derivatives;
  Runge-Kutta 4 at a fixed internal step);
- a bare C loop of the same equations (the published model with the candidate-effect terms the FMU
  carries, at their default zero values), the same input interpolation and the same Runge-Kutta 4 step,
  written here and compiled with gcc -O2 (the compiled limit: no FMI layer, constant matrices
  precomputed);
- CasADi's own CVODES integrator on the project's reference model (rtol 1e-8), as a user of CasADi would.

Printed: median wall times, ratios FMU / bare loop and FMU / CVODES, and the RMS difference between the
FMU and the bare loop (they integrate the same equations with the same steps, so it must be at rounding
level). Goal: FMU / bare loop <= 3.

    python bench/eval_speed.py [--repeats 5]
"""
import argparse
import ctypes
import pathlib
import statistics
import subprocess
import tempfile
import time

import casadi as ca
import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]

from pyfit.analysis.excitation import Excitation, motion_with_derivatives
from pyfit.io import benchmark_data as bd
from pyfit.reference.integrate import simulate_cvodes
from pyfit.reference.models import DAMPER_DEFAULTS, SDOF_DEFAULTS, by_name, damper_matrices
from pyfit.report.generated import BenchReport
from pyfit.runtime.examples import ensure_fmu
from pyfit.runtime.fmu import FmuRunner

BARE_C = r"""
#include <math.h>
static double sgn(double a) { return (a > 0) - (a < 0); }
/* the exponent nu is 1 for both models: an engineer writing this loop would not call pow() for it */
static double fpow(double x, double y) { return y == 1.0 ? x : y == 2.0 ? x * x : pow(x, y); }

/* SDOF Bouc-Wen (theory §1.1) with the candidate-effect terms the FMU evaluates (cubic spring k3, Coulomb
   friction F_c tanh(v/v_s), quadratic damping c2); state y, v, z;
   p = m, c, k, alpha, beta, gamma, delta, nu, k3, F_c, v_s, c2 */
static void sdof_rhs(const double *x, double u, const double *p, double *dx) {
  double az = fpow(fabs(x[2]), p[7]);
  double extra = p[8] * x[0] * x[0] * x[0] + p[9] * tanh(x[1] / p[10]) + p[11] * x[1] * fabs(x[1]);
  dx[0] = x[1];
  dx[1] = (u - p[1] * x[1] - p[2] * x[0] - x[2] - extra) / p[0];
  dx[2] = p[3] * x[1] - p[4] * (p[5] * fabs(x[1]) * sgn(x[2]) * az + p[6] * x[1] * az);
}

/* damper (theory §1.3) with the clamp motion prescribed, with the candidate-effect terms the FMU evaluates
   (Coulomb friction F_c,i tanh(dr_i/v_s), quadratic damping c2_i); state q(4), qd(4), z(2); u = x_b, v_b, a_b.
   mat: Minv(16) C(16) K(16) Kfc(4) Mfc(4);
   p: k_bw1 k_bw2 k_cs1 k_cs2 a_bw A beta gamma nu D F_c1 F_c2 v_s c2_1 c2_2 */
static void damper_rhs(const double *x, const double *u, const double *mat, const double *p, double *dx) {
  const double *Minv = mat, *C = mat + 16, *K = mat + 32, *Kfc = mat + 48, *Mfc = mat + 52;
  double f[4], rv[4], r[2], rd[2];
  int i, j;
  for (i = 0; i < 4; i++) rv[i] = x[4 + i] - ((i == 0 || i == 2) ? u[1] : 0.0);
  r[0] = x[0] - u[0]; r[1] = x[2] - u[0];
  rd[0] = x[4] - u[1]; rd[1] = x[6] - u[1];
  for (i = 0; i < 4; i++) {
    double s = Mfc[i] * u[2] + Kfc[i] * u[0];
    for (j = 0; j < 4; j++) s += C[4 * i + j] * rv[j] + K[4 * i + j] * x[j];
    f[i] = -s;
  }
  for (i = 0; i < 2; i++) {
    double z = x[8 + i], az = fpow(fabs(z), p[8]);
    f[2 * i] -= p[i] * (p[4] * r[i] + (1 - p[4]) * p[9] * z) + p[2 + i] * r[i] * r[i] * r[i]
                + p[10 + i] * tanh(rd[i] / p[12]) + p[13 + i] * rd[i] * fabs(rd[i]);
    dx[8 + i] = (p[5] * rd[i] - p[6] * fabs(rd[i]) * sgn(z) * az - p[7] * rd[i] * az) / p[9];
  }
  for (i = 0; i < 4; i++) {
    dx[i] = x[4 + i];
    dx[4 + i] = 0.0;
    for (j = 0; j < 4; j++) dx[4 + i] += Minv[4 * i + j] * f[j];
  }
}

/* RK4 with n_sub sub-steps per sample interval; inputs linear between samples (n_u per sample);
   records state index `rec` at every sample */
static void run(int model, int n, double dt, int n_sub, int n_u, const double *u, const double *mat,
                const double *p, int rec, double *out) {
  double x[10] = {0}, k[4][10], xt[10], ut[3], h = dt / n_sub;
  int nx = model == 0 ? 3 : 10, i, s, j, l;
  static const double a[4] = {0.0, 0.5, 0.5, 1.0};
  for (i = 0; i < n; i++) {
    out[i] = x[rec];
    if (i + 1 == n) break;
    for (s = 0; s < n_sub; s++) {
      for (j = 0; j < 4; j++) {
        double w = (s + a[j]) / n_sub;
        for (l = 0; l < nx; l++) xt[l] = x[l] + (j ? a[j] * h * k[j - 1][l] : 0.0);
        for (l = 0; l < n_u; l++) ut[l] = u[i * n_u + l] + w * (u[(i + 1) * n_u + l] - u[i * n_u + l]);
        if (model == 0) sdof_rhs(xt, ut[0], p, k[j]); else damper_rhs(xt, ut, mat, p, k[j]);
      }
      for (l = 0; l < nx; l++) x[l] += h / 6.0 * (k[0][l] + 2 * k[1][l] + 2 * k[2][l] + k[3][l]);
    }
  }
}

void bare_run(int model, int n, double dt, int n_sub, int n_u, const double *u, const double *mat,
              const double *p, int rec, double *out) {
  run(model, n, dt, n_sub, n_u, u, mat, p, rec, out);
}
"""


def compile_bare(tmp: pathlib.Path):
    src, lib = tmp / "bare.c", tmp / "bare.so"
    src.write_text(BARE_C)
    subprocess.run(["gcc", "-O2", "-shared", "-fPIC", str(src), "-o", str(lib), "-lm"], check=True)
    fn = ctypes.CDLL(str(lib)).bare_run
    p = ctypes.c_void_p
    fn.argtypes = [ctypes.c_int, ctypes.c_int, ctypes.c_double, ctypes.c_int, ctypes.c_int, p, p, p, ctypes.c_int, p]
    return fn


def timed(f, repeats):
    f()  # warm-up (loads, compiles, caches)
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def ptr(a):
    return a.ctypes.data_as(ctypes.c_void_p)


def sdof_case():
    sig = bd.load("multisine")
    u = np.concatenate([np.tile(sig.u, 3), sig.u[:1]])
    t = np.arange(len(u)) / bd.FS_HZ
    p = np.array([SDOF_DEFAULTS[k] for k in ("m", "c", "k", "alpha", "beta", "gamma", "delta", "nu", "k3", "F_c",
                                             "v_s", "c2")])
    return dict(name="SDOFBoucWen", label="SDOF, 3 periods of the benchmark multisine", t=t, inputs={"u": u},
                n_sub=20, model=0, mat=np.zeros(1), p=p, output="y", rec=0, params={"exc_type": 0})


def damper_case():
    fs, duration = 750.0, 35.0
    t = np.arange(int(duration * fs) + 1) / fs
    exc = Excitation(kind=4, amplitude=0.02, f_start=5.0, f_end=40.0, rate=1.0)
    inputs = motion_with_derivatives(exc, t, ("x_base", "v_base", "a_base"))
    d = dict(DAMPER_DEFAULTS)
    K, M = (np.array(ca.evalf(A)) for A in damper_matrices(d))
    free = [0, 1, 4, 5]
    Kff, Kfc, Mff, Mfc = K[np.ix_(free, free)], K[free, 2], M[np.ix_(free, free)], M[free, 2]
    C = d["alpha_pd"] * Mff + d["beta_pd"] * Kff
    mat = np.concatenate([np.linalg.inv(Mff).ravel(), C.ravel(), Kff.ravel(), Kfc, Mfc])
    p = np.array([d[k] for k in ("k_bw1", "k_bw2", "k_cs1", "k_cs2", "a_bw", "A", "beta", "gamma", "nu", "D",
                                 "F_c1", "F_c2", "v_s", "c2_1", "c2_2")])
    return dict(name="StockbridgeDamper", label="damper, 35 s clamp sweep 5-40 Hz at 20 mm/s", t=t,
                inputs=inputs, n_sub=4, model=1, mat=mat, p=p, output="x1",
                rec=0, params={"exc_type": 0})


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    report = BenchReport("eval_speed", ROOT)
    with tempfile.TemporaryDirectory() as tmp:
        bare = compile_bare(pathlib.Path(tmp))
        for case in (sdof_case(), damper_case()):
            t, inputs = case["t"], case["inputs"]
            dt, n = t[1] - t[0], len(t)
            runner = FmuRunner(str(ensure_fmu(case["name"], ROOT / "fmus")))
            params = {**case["params"], "cs_step": dt / case["n_sub"]}
            t_fmu, y_fmu = timed(lambda: runner.simulate(t[-1], dt, [case["output"]], params, inputs=inputs,
                                                         input_time=t)[case["output"]], args.repeats)
            u_rows = np.ascontiguousarray(np.column_stack(list(inputs.values())))
            out = np.empty(n)

            def bare_eval():
                bare(case["model"], n, dt, case["n_sub"], u_rows.shape[1], ptr(u_rows), ptr(case["mat"]),
                     ptr(case["p"]), case["rec"], ptr(out))
                return out.copy()

            t_bare, y_bare = timed(bare_eval, args.repeats)
            model = by_name(case["name"])
            t_cv, _ = timed(lambda: simulate_cvodes(model, t, inputs=inputs, rtol=1e-8, atol=1e-12),
                            max(1, args.repeats // 2))
            diff = np.sqrt(np.mean((y_fmu - y_bare) ** 2)) / np.sqrt(np.mean(y_bare ** 2))
            steps = (n - 1) * case["n_sub"]
            ratio = t_fmu / t_bare
            report.line(f"{case['label']} ({steps} RK4 steps): FMU via FmuRunner {t_fmu:.4f} s; bare C loop "
                        f"{t_bare:.4f} s; ratio {ratio:.2f}; "
                        f"CasADi CVODES rtol 1e-8 {t_cv:.3f} s, FMU / CVODES {t_fmu / t_cv:.3f}; "
                        f"FMU vs bare loop relative RMS difference {diff:.1e}")
            runner.close()


if __name__ == "__main__":
    main()
