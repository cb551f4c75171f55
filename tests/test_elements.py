"""Element FMUs (causal interfaces for other FMI tools) against independent computations."""
import pathlib
import shutil
import subprocess

import numpy as np
import pytest
import scipy.integrate
from fmpy.validation import validate_fmu

from pyfit.build import EXAMPLES
from pyfit.analysis.excitation import Excitation
from pyfit.build.element_docs import REFERENCE_RUNS, motion_with_derivatives, write_docs

ROOT = pathlib.Path(__file__).resolve().parents[1]

ELEMENTS = ["BoucWenElement", "BoucWenNormalizedElement", "CubicSpringElement", "MassSpringDamper", "DamperElement"]
A, F_HZ = 2e-3, 10.0  # m, Hz: prescribed relative motion s = A sin(2 pi f t)
W = 2 * np.pi * F_HZ
DT, STOP = 1e-4, 0.3


def sine_inputs():
    t = np.arange(int(round(STOP / DT)) + 1) * DT
    return t, {"s": A * np.sin(W * t), "v": A * W * np.cos(W * t)}


def bouc_wen_force(rhs, force):
    """Independent integration of the hysteretic variable along the exact motion (scipy, tight tolerance)."""
    t, _ = sine_inputs()
    sol = scipy.integrate.solve_ivp(lambda tt, z: [rhs(A * W * np.cos(W * tt), z[0])], (0, STOP), [0.0], t_eval=t,
                                    rtol=1e-11, atol=1e-14, method="DOP853")
    return force(A * np.sin(W * t), sol.y[0])


@pytest.mark.parametrize("name", ELEMENTS)
def test_element_fmus_pass_fmpy_validation(fmu_dir, name):
    assert name in EXAMPLES
    assert validate_fmu(str(fmu_dir / f"{name}.fmu")) == []


def test_bouc_wen_element_force_matches_an_independent_integration(runner):
    t, u = sine_inputs()
    res = runner("BoucWenElement").simulate(STOP, DT, ["f", "z"], {}, inputs=u, input_time=t, tolerance=1e-10)
    al, be, ga, de = 5e4, 1e3, 0.8, -1.1
    f_ref = bouc_wen_force(lambda v, z: al * v - be * (ga * abs(v) * z + de * v * abs(z)), lambda s, z: -z)
    # inputs are linear between 1e-4 s samples: (w dt)^2 / 8 = 5e-6 relative
    assert np.max(np.abs(res["f"] - f_ref)) <= 2e-5 * np.max(np.abs(f_ref))
    assert np.max(np.abs(f_ref)) > 20.0  # N: the loop is well into the nonlinear range (alpha*A = 100 N)


def test_normalized_bouc_wen_element_force_matches_an_independent_integration(runner):
    t, u = sine_inputs()
    res = runner("BoucWenNormalizedElement").simulate(STOP, DT, ["f"], {}, inputs=u, input_time=t, tolerance=1e-10)
    k, a, A_, be, ga, D = 300.0, 0.3, 1.0, 0.6, 0.4, 1e-3
    f_ref = bouc_wen_force(lambda v, z: (A_ * v - be * abs(v) * z - ga * v * abs(z)) / D,
                           lambda s, z: -k * (a * s + (1 - a) * D * z))
    assert np.max(np.abs(res["f"] - f_ref)) <= 2e-5 * np.max(np.abs(f_ref))


def test_cubic_spring_element_is_exact(runner):
    t, u = sine_inputs()
    res = runner("CubicSpringElement").simulate(STOP, DT, ["f"], {"k3": -2e6}, inputs=u, input_time=t)
    np.testing.assert_allclose(res["f"], 2e6 * u["s"] ** 3, rtol=0, atol=1e-12)


def test_damper_element_driven_by_clamp_motion_equals_the_damper_with_its_built_in_shaker(runner):
    exc = Excitation(kind=1, amplitude=5e-4, f_start=12.0, t_ramp=0.1)
    t = np.arange(int(round(STOP / DT)) + 1) * DT
    motion = motion_with_derivatives(exc, t, ("x_base", "v_base", "a_base"))
    element = runner("DamperElement").simulate(STOP, DT, ["F_clamp", "x1"], {}, inputs=motion, input_time=t,
                                               tolerance=1e-10)
    built_in = runner("StockbridgeDamper").simulate(STOP, DT, ["F_clamp", "x1"], {
        "exc_type": 1, "exc_amplitude": 5e-4, "exc_f_start": 12.0, "exc_t_ramp": 0.1}, tolerance=1e-10)
    for o in ("F_clamp", "x1"):
        scale = np.max(np.abs(built_in[o]))
        assert np.max(np.abs(element[o] - built_in[o])) <= 1e-4 * scale, o  # sampled vs exact motion


FMI_SIM = shutil.which("fmi-sim")


@pytest.mark.skipif(FMI_SIM is None, reason="fmi-sim not installed: cargo install fmi-sim@0.7.0 --locked")
@pytest.mark.parametrize("name", list(REFERENCE_RUNS))
def test_element_fmus_run_in_the_second_importer(fmu_dir, runner, tmp_path, name):
    """Every element FMU runs in fmi-sim (co-simulation, inputs from a CSV) and agrees with pyfit's run."""
    _, make_inputs, params, outputs = REFERENCE_RUNS[name]
    t = np.arange(int(round(STOP / DT)) + 1) * DT
    u = make_inputs(t) if make_inputs else {}
    cmd = [FMI_SIM, "--model", str(fmu_dir / f"{name}.fmu"), "-o", str(tmp_path / "out.csv")]
    if u:
        np.savetxt(tmp_path / "in.csv", np.column_stack([t, *u.values()]), delimiter=",",
                   header=",".join(["time", *u]), comments="", fmt="%.17g")
        cmd += ["-i", str(tmp_path / "in.csv")]
    cmd += ["co-simulation", "--output-interval", repr(DT), "-n", "0", "-s", "0", "-f", repr(STOP)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    other = np.genfromtxt(tmp_path / "out.csv", delimiter=",", names=True)
    ours = runner(name).simulate(STOP, DT, outputs[:1], params, inputs=u or None, input_time=t if u else None)
    n = min(len(other), len(t))
    o = outputs[0]
    # fmi-sim holds the inputs over each 1e-4 s step (no input derivatives): differences O(w dt) ~ 1e-2 (2.5 %
    # for the damper's F_clamp, which feeds the held clamp acceleration straight through)
    assert np.max(np.abs(other[o][:n] - ours[o][:n])) <= 3e-2 * np.max(np.abs(ours[o]))


@pytest.mark.parametrize("name", list(REFERENCE_RUNS))
def test_committed_reference_results_are_reproduced(fmu_dir, tmp_path, name):
    """docs/fmus/<name>/<name>_ref.csv (for users of other tools) still matches the FMU built from modelica/."""
    committed = np.genfromtxt(ROOT / "docs" / "fmus" / name / f"{name}_ref.csv", delimiter=",", names=True)
    fresh_dir = write_docs(name, fmu_dir / f"{name}.fmu", tmp_path)
    fresh = np.genfromtxt(fresh_dir / f"{name}_ref.csv", delimiter=",", names=True)
    assert committed.dtype.names == fresh.dtype.names
    for col in committed.dtype.names:
        scale = max(np.max(np.abs(committed[col])), 1e-300)
        assert np.max(np.abs(committed[col] - fresh[col])) <= 1e-8 * scale, col
