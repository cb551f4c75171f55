"""Wall time of one SDOF evaluation through fmpy, and its ratio to scipy's solve_ivp (DOP853) at equal accuracy.

One evaluation = 3 periods of the benchmark's 8192-sample multisine (750 Hz), fed to the co-simulation
FMU with input derivatives (linear between samples); the FMU integrates with Runge-Kutta 4 at a 15 kHz
internal step (as the benchmark did), and, second, with its adaptive Dormand-Prince 5(4) at tolerance
1e-9. The same equations and the same piecewise-linear input go to solve_ivp (DOP853); its tolerance
is tightened until its error against a tight reference is no larger than the FMU's. All timings come
from this run.

    python bench/sdof_eval.py [--repeats 5]
"""
import argparse
import pathlib
import statistics
import sys
import tempfile
import time

import numpy as np
from scipy.integrate import solve_ivp

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

from pyfit.io import benchmark_data as bd  # noqa: E402
from pyfit.build import EXAMPLES, build_fmu  # noqa: E402
from pyfit.runtime.fmu import FmuRunner  # noqa: E402
from pyfit.report.readme import BenchReport  # noqa: E402

M, C, K, ALPHA, BETA, GAMMA, DELTA, NU = 2.0, 10.0, 5e4, 5e4, 1e3, 0.8, -1.1, 1.0


def scipy_run(u, fs, rtol):
    n = len(u) - 1
    dt = 1.0 / fs

    def rhs(t, s):
        y, v, z = s
        i = min(int(t * fs), n - 1)
        w = t * fs - i
        f = u[i] + w * (u[i + 1] - u[i])
        az = abs(z) ** NU
        dz = ALPHA * v - BETA * (GAMMA * abs(v) * np.sign(z) * az + DELTA * v * az)
        return [v, (f - C * v - K * y - z) / M, dz]

    t_eval = np.arange(n + 1) * dt
    sol = solve_ivp(rhs, (0, t_eval[-1]), [0.0, 0.0, 0.0], method="DOP853", t_eval=t_eval, rtol=rtol,
                    atol=rtol * 1e-6)
    return sol.y[0]


def timed(f, repeats):
    f()  # warm-up
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    sig = bd.load("multisine")
    u = np.concatenate([np.tile(sig.u, 3), sig.u[:1]])
    fs = bd.FS_HZ
    t = np.arange(len(u)) / fs
    with tempfile.TemporaryDirectory() as tmp:
        fmu = build_fmu(EXAMPLES["SDOFBoucWen"], pathlib.Path(tmp), "SDOFBoucWen").fmu
        runner = FmuRunner(str(fmu))

        def fmu_eval(solver_params, tolerance):
            params = {"exc_type": 0, **solver_params}
            r = runner.simulate(t[-1], 1 / fs, ["y"], params, inputs={"u": u}, input_time=t, tolerance=tolerance)
            assert r.ok, r.message
            return r["y"]

        fmu_runs = {
            "RK4, 15 kHz internal step": timed(lambda: fmu_eval({"cs_step": 1 / 15000.0}, 1e-8), args.repeats),
            "adaptive DOPRI5, tol 1e-9": timed(lambda: fmu_eval({}, 1e-9), args.repeats),
        }
        runner.close()
    y_ref = scipy_run(u, fs, 1e-13)
    report = BenchReport("sdof_eval", pathlib.Path(__file__).resolve().parents[1])
    for label, (t_fmu, y_fmu) in fmu_runs.items():
        err_fmu = bd.rms_db(y_fmu - y_ref)
        for rtol in (1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11):
            t_sp, y_sp = timed(lambda: scipy_run(u, fs, rtol), max(1, args.repeats // 2))
            err_sp = bd.rms_db(y_sp - y_ref)
            if err_sp <= err_fmu:
                break
        report.line(f"FMU via fmpy ({label}): {t_fmu:.3f} s per evaluation, error {err_fmu:.1f} dB re tight reference "
              f"(goal <= 0.5 s: {'met' if t_fmu <= 0.5 else 'NOT met'})")
        report.line(f"solve_ivp DOP853 at equal or better accuracy (rtol={rtol:g}, {err_sp:.1f} dB): {t_sp:.3f} s; "
              f"ratio FMU / solve_ivp = {t_fmu / t_sp:.3f}")


if __name__ == "__main__":
    main()
