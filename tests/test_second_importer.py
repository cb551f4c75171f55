"""A second, independent FMI importer (fmi-sim, a Rust FMI simulator from crates.io) runs the FMUs.

Install: apt-get install libclang-dev && cargo install fmi-sim@0.7.0 --locked  (.ci/run does this).
fmi-sim 0.7's Model Exchange solver is forward Euler stepping at the output interval (its --step is
not used), so the comparison with fmpy's Euler uses step = output interval.
"""
import shutil
import subprocess

import fmpy
import numpy as np
import pytest

FMI_SIM = shutil.which("fmi-sim")
pytestmark = pytest.mark.skipif(FMI_SIM is None, reason="fmi-sim not installed: cargo install fmi-sim@0.7.0 --locked")

CASES = {  # name -> (outputs, parameters, stop time [s])
    "SDOFBoucWen": (["y", "z"], {"exc_rate": 6.0}, 1.0),
    "StockbridgeDamper": (["x1", "x2", "F_clamp"], {"exc_rate": 10.0}, 0.5),
}
STEP = 1e-5  # forward Euler is stable here: h*omega^2/2 < zeta*omega for every mode


def fmi_sim(fmu, mode, step, stop, params, tmp_path):
    out = tmp_path / f"{fmu.stem}_{mode}_{step:g}.csv"
    cmd = [FMI_SIM, "--model", str(fmu), "-o", str(out), mode, "--step", repr(step), "--output-interval",
           repr(step), "-n", "0", "-s", "0", "-f", repr(stop)]
    for k, v in params.items():
        cmd += ["--init-values", f"{k}={v}"]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return np.genfromtxt(out, delimiter=",", names=True)


def fmpy_run(fmu, solver, step, stop, params, outputs):
    kw = {"solver": "Euler", "step_size": step} if solver == "Euler" else {"relative_tolerance": 1e-11}
    return fmpy.simulate_fmu(str(fmu), fmi_type="ModelExchange", output_interval=step, stop_time=stop,
                             start_values=params, output=outputs, **kw)


def on_grid(result, name, dt=1e-3):
    return np.interp(np.arange(0, result["time"][-1] + dt / 2, dt), result["time"], result[name])


@pytest.mark.parametrize("name", list(CASES))
def test_fmi_sim_matches_fmpy_with_the_same_fixed_step_method(fmu_dir, tmp_path, name, measured):
    outputs, params, stop = CASES[name]
    fmu = fmu_dir / f"{name}.fmu"
    other = fmi_sim(fmu, "model-exchange", STEP, stop, params, tmp_path)
    ours = fmpy_run(fmu, "Euler", STEP, stop, params, outputs)
    assert len(other) == len(ours)
    np.testing.assert_allclose(other["time"], ours["time"], atol=1e-12)
    measured(f"{name}: fmi-sim 0.7 (Rust) vs fmpy, the same forward-Euler step 1e-5 s: max|Δy|/max|y|",
             max(np.max(np.abs(other[o] - ours[o])) / np.max(np.abs(ours[o])) for o in outputs), 1e-9)


@pytest.mark.parametrize("name", list(CASES))
def test_fmi_sim_euler_converges_to_cvode_at_first_order(fmu_dir, tmp_path, name, measured):
    outputs, params, stop = CASES[name]
    fmu = fmu_dir / f"{name}.fmu"
    ref = on_grid(fmpy_run(fmu, "CVode", 1e-3, stop, params, outputs), outputs[0])
    errors = []
    for h in (2 * STEP, STEP):
        run = on_grid(fmi_sim(fmu, "model-exchange", h, stop, params, tmp_path), outputs[0])
        errors.append(np.max(np.abs(run - ref)) / np.max(np.abs(ref)))
    # forward Euler: global error proportional to the step
    assert errors[0] < 0.05
    measured(f"{name}: fmi-sim Euler vs fmpy CVode, |error ratio for h = 2e-5 → 1e-5 s − 2| (first order: 0)",
             abs(errors[0] / errors[1] - 2), 0.3)


def test_fmi_sim_co_simulation_uses_the_fmus_own_solver(fmu_dir, tmp_path, runner, measured):
    outputs, params, stop = CASES["SDOFBoucWen"]
    fmu = fmu_dir / "SDOFBoucWen.fmu"
    other = fmi_sim(fmu, "co-simulation", 1e-3, stop, params, tmp_path)
    ours = runner("SDOFBoucWen").simulate(stop, 1e-3, outputs, params, tolerance=1e-8)
    measured("SDOFBoucWen: fmi-sim co-simulation (the FMU's own solver) vs pyfit: max|Δy|/max|y|",
             max(np.max(np.abs(other[o] - ours[o])) / np.max(np.abs(ours[o])) for o in outputs), 1e-6)
