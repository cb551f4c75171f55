"""The FMUs in co-simulation engines this project did not write: libcosim (libcosimpy, Open Simulation
Platform) and Ecos (ecospy), both from PyPI, against fmpy (FmuRunner) with the same communication step.

Every importer calls the same FMU functions in the same order (set parameters, initialise, doStep at a
fixed communication step, read outputs), and the FMU integrates itself, so the results must agree to
rounding. The built-in excitation drives the model (no inputs to interpolate). Ecos needs the Debian
package libtbb12 (.ci/run installs it).
"""
import importlib.util

import numpy as np
import pytest

from pyfit.runtime.fmu import FmuRunner

STEP = 1e-3  # s; libcosim counts time in whole nanoseconds, so the step must be a whole number of them
# name -> (outputs, integer parameters, real parameters, stop time [s]); the FMU's fixed-step Runge-Kutta 4
# (cs_step), so that the result depends on the communication points only, not on an adaptive step history
CASES = {
    "SDOFBoucWen": (["y", "z"], {"exc_type": 2}, {"exc_amplitude": 120.0, "exc_rate": 20.0, "cs_step": 1e-4}, 1.0),
    "StockbridgeDamper": (["x1", "x2", "F_clamp"], {"exc_type": 4},
                          {"exc_amplitude": 0.05, "exc_f_start": 5.0, "exc_rate": 20.0, "cs_step": 1e-4}, 1.0),
}


def libcosim_loadable() -> str:
    """Why libcosimpy cannot be loaded here ('' if it can)."""
    if importlib.util.find_spec("libcosimpy") is None:
        return 'libcosimpy is not installed (pip install -e ".[importers]")'
    return ""


def ecos_loadable() -> str:
    """Why ecospy cannot be loaded here ('' if it can)."""
    if importlib.util.find_spec("ecospy") is None:
        return 'ecospy is not installed (pip install -e ".[importers]")'
    try:
        import ecospy  # noqa: F401
    except OSError as exc:
        return f"ecospy's native library does not load: {exc} (Debian: apt-get install libtbb12)"
    return ""


def reference(fmu, outputs, ints, reals, stop):
    res = FmuRunner(str(fmu)).simulate(stop, STEP, outputs, {**ints, **reals})
    assert res.ok, res.message
    return res


def libcosim_run(fmu, outputs, ints, reals, stop):
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    execution = CosimExecution.from_step_size(step_size=int(round(STEP * 1e9)))
    index = execution.add_local_slave(CosimLocalSlave(fmu_path=str(fmu), instance_name="model"))
    refs = {v.name.decode(): v.reference for v in execution.slave_variables(index)}
    for name, value in ints.items():
        execution.integer_initial_value(index, refs[name], int(value))
    for name, value in reals.items():
        execution.real_initial_value(index, refs[name], float(value))
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    n = int(round(stop / STEP))
    rows = []
    for _ in range(n):
        assert execution.step()
        rows.append(observer.last_real_values(index, [refs[o] for o in outputs]))
    return np.array(rows)


def ecos_run(fmu, outputs, ints, reals, stop):
    from ecospy import EcosSimulation, EcosSimulationStructure

    structure = EcosSimulationStructure()
    structure.add_model("model", str(fmu))
    structure.add_parameter_set("p", {f"model::{k}": v for k, v in {**ints, **reals}.items()})
    rows = []
    with EcosSimulation(structure=structure, step_size=STEP) as sim:
        sim.init(parameter_set="p")
        for _ in range(int(round(stop / STEP))):
            sim.step()
            rows.append([sim.get_real(f"model::{o}") for o in outputs])
        sim.terminate()
    return np.array(rows)


IMPORTERS = {"libcosim": (libcosim_run, libcosim_loadable), "Ecos": (ecos_run, ecos_loadable)}


@pytest.mark.parametrize("importer", list(IMPORTERS))
@pytest.mark.parametrize("name", list(CASES))
def test_importer_runs_the_fmu_as_fmpy_does(fmu_dir, name, importer, measured):
    run, unavailable = IMPORTERS[importer]
    why = unavailable()
    if why:
        pytest.skip(why)
    outputs, ints, reals, stop = CASES[name]
    fmu = fmu_dir / f"{name}.fmu"
    ref = reference(fmu, outputs, ints, reals, stop)
    got = run(fmu, outputs, ints, reals, stop)
    for j, o in enumerate(outputs):
        y = ref[o][1:]
        diff = float(np.max(np.abs(got[:, j] - y)) / np.max(np.abs(y)))
        measured(f"{importer} vs fmpy, {name}.{o}: max difference / max |{o}|", diff, 1e-9)
