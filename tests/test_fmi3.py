"""The FMI 3.0 FMUs (fmus/fmi3/, built from the same C sources as the FMI 2.0 ones plus an adapter): valid for
fmpy's checker, simulated by fmpy's FMI 3.0 importer in Co-Simulation and Model Exchange, and equal to the FMI 2.0
FMUs run the same way. Same compiled equations and integrators, so "equal" means bit for bit."""
import ctypes
import pathlib

import fmpy
import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi3 import FMU3Slave
from fmpy.validation import validate_fmu

from pyfit.build import EXAMPLES, fmi3_path

ROOT = pathlib.Path(__file__).resolve().parents[1]
STOP, STEP = 0.2, 1e-3  # s


@pytest.mark.parametrize("name", list(EXAMPLES))
def test_fmi3_fmu_is_valid_and_equals_fmi2(name, fmu_dir, measured):
    """fmpy's validation finds no problem; CS (the FMU's DOPRI5) and ME (fmpy's CVode) agree with FMI 2.0."""
    fmu3 = fmi3_path(fmu_dir, name)
    assert validate_fmu(str(fmu3)) == []
    md = read_model_description(str(fmu3))
    assert md.fmiVersion == "3.0" and md.guid == read_model_description(str(fmu_dir / f"{name}.fmu")).guid
    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    driven = any(v.causality == "input" for v in md.modelVariables)  # zero inputs: zero response (next test)
    for interface in ("CoSimulation", "ModelExchange"):
        r3, r2 = (fmpy.simulate_fmu(str(f), fmi_type=interface, stop_time=STOP, output_interval=STEP,
                                    output=outputs) for f in (fmu3, fmu_dir / f"{name}.fmu"))
        assert len(r3) == len(r2) == round(STOP / STEP) + 1
        assert driven or max(np.max(np.abs(r3[o])) for o in outputs) > 0  # the built-in excitation acts
        measured(f"{name} FMI 3.0 vs FMI 2.0 ({interface}): max |Δ| over outputs",
                 max(np.max(np.abs(r3[o] - r2[o])) for o in outputs), 0.0)


# element -> its outputs that are functions of the states only; the others (df, F_clamp, the normalised and
# cubic elements' f) also depend directly on an input and so on whether an importer reads them before or after
# setting the next input (fmpy: after; the committed held-input reference: before)
STATE_OUTPUTS = {"BoucWenElement": ["f", "z"], "BoucWenNormalizedElement": ["z"], "CubicSpringElement": [],
                 "DamperElement": ["x1", "x2"]}


@pytest.mark.parametrize("name", sorted(STATE_OUTPUTS))
def test_fmi3_cosimulation_with_held_inputs(name, fmu_dir, measured):
    """FMI 3.0 co-simulation holds inputs over a step (no input-derivative call). Driven by fmpy with the inputs
    of the committed held-input reference: every output equals the FMI 2.0 FMU's under the same importer, and
    the state outputs reproduce docs/fmus/<name>/<name>_ref_held.csv to the CSV's 12 significant digits."""
    ref = np.genfromtxt(ROOT / "docs" / "fmus" / name / f"{name}_ref_held.csv", delimiter=",", names=True)
    md = read_model_description(str(fmi3_path(fmu_dir, name)))
    inputs = [v.name for v in md.modelVariables if v.causality == "input"]
    outputs = [n for n in ref.dtype.names if n != "time" and n not in inputs]
    signal = np.array(list(zip(ref["time"], *(ref[i] for i in inputs))),
                      dtype=[("time", float)] + [(i, float) for i in inputs])
    r3, r2 = (fmpy.simulate_fmu(str(f), fmi_type="CoSimulation", stop_time=float(ref["time"][-1]),
                                output_interval=float(ref["time"][1]), relative_tolerance=1e-10, input=signal,
                                output=outputs) for f in (fmi3_path(fmu_dir, name), fmu_dir / f"{name}.fmu"))
    measured(f"{name} FMI 3.0 vs FMI 2.0, fmpy co-simulation with held inputs: max |Δ|",
             max(np.max(np.abs(r3[o] - r2[o])) for o in outputs), 0.0)
    for o in STATE_OUTPUTS[name]:
        measured(f"{name}.{o} FMI 3.0 co-simulation (fmpy, inputs held) vs the held-input reference CSV",
                 np.max(np.abs(r3[o] - ref[o])) / np.max(np.abs(ref[o])), 1e-9)


def test_fmi3_state_replay_error_latch_and_time(fmu_dir):
    """Through the FMI 3.0 functions: a restored FMU state replays bit for bit, the independent variable
    reads the communication time, and after a divergence every call fails until fmi3Reset."""
    path = fmi3_path(fmu_dir, "SDOFBoucWen")
    md = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    log = []
    fmu = FMU3Slave(guid=md.guid, unzipDirectory=extract(str(path)),
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="fmi3")
    fmu.instantiate(logMessage=lambda env, status, category, message: log.append(message.decode()))
    fmu.setInt32([vr["exc_type"]], [2])
    fmu.setFloat64([vr["exc_amplitude"]], [120.0])
    fmu.enterInitializationMode(tolerance=1e-8)
    fmu.exitInitializationMode()
    for k in range(50):
        fmu.doStep(k * 1e-3, 1e-3)
    state = fmu.getFMUState()
    runs = []
    for _ in range(2):
        fmu.setFMUState(state)
        for k in range(50, 100):
            fmu.doStep(k * 1e-3, 1e-3)
        runs.append(fmu.getFloat64([vr["y"], vr["z"], vr["time"]]))
    fmu.freeFMUState(state)
    assert runs[0] == runs[1] and runs[0][0] != 0.0
    assert runs[0][2] == pytest.approx(0.1, abs=1e-12)
    # diverge: a negative stiffness makes the response grow like exp(2.2e4 t), it overflows within 0.1 s
    fmu.reset()
    fmu.setFloat64([vr["k"], vr["alpha"]], [-1e9, 0.0])
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    dll = fmu.dll
    status = 0
    for k in range(100):
        status = dll.fmi3DoStep(ctypes.c_void_p(fmu.component), ctypes.c_double(k * 1e-3), ctypes.c_double(1e-3),
                                ctypes.c_bool(True), *(ctypes.byref(ctypes.c_bool()) for _ in range(3)),
                                ctypes.byref(ctypes.c_double()))
        if status:
            break
    assert status == 3, "the run should diverge"
    out = (ctypes.c_double * 1)()
    again = dll.fmi3GetFloat64(ctypes.c_void_p(fmu.component), (ctypes.c_uint32 * 1)(vr["y"]), 1, out, 1)
    assert again == 3 and any("fmi2Reset" in m for m in log)
    fmu.reset()  # a working instance again, default parameters
    fmu.setInt32([vr["exc_type"]], [2])
    fmu.setFloat64([vr["exc_amplitude"]], [120.0])
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    for k in range(100):
        fmu.doStep(k * 1e-3, 1e-3)  # fmpy raises on any status but OK
    assert fmu.getFloat64([vr["y"]]) == runs[0][:1]
    fmu.terminate()
    fmu.freeInstance()
