"""How the measured inputs drive the FMU in a diagnosis: error and cost of each drive, measured in one run.

The records are the diagnosis-time bench's damper pair (three levels of 35 s constant-velocity clamp sweeps of the
design damper at 500 Hz, hysteresis and cubic springs in the truth, clamp displacement recorded) and its SDOF case
(force sweeps, hysteresis). Each drive simulates the truth on every record; its error is the RMS over the outputs of
the difference to a run driven by the spline on a grid 32 times the sensor rate at tolerance 1e-9, over the output's
RMS (the worst record); its cost is the wall time of the three records on one core (the mean of three runs after one
that upsamples the inputs, as a diagnosis does once per drive). Lines: the FMU interpolates linearly between the
upsampled samples; spline: each step's input is the quadratic through the samples' cubic spline
(pyfit.runtime.drive, smooth_inputs).

    python bench/input_order.py
"""
import dataclasses
import json
import pathlib
import tempfile
import time

import numpy as np

from pyfit.gap import simulate as sim
from pyfit.gap.datasets import FAMILIES, LabStyle, write_dataset
from pyfit.gap.diagnose import fmu_defaults
from pyfit.gap.systems import family_fmu, make_system
from pyfit.io.data import read_dataset_with_order
from pyfit.report.generated import BenchReport
from pyfit.runtime import drive
from pyfit.runtime.examples import ensure_fmu
from pyfit.runtime.fmu import FmuRunner
from pyfit.runtime.memo import BoundedMemo

ROOT = pathlib.Path(__file__).resolve().parents[1]
CASES = {"damper": ("cubic_stiffness+hysteresis", LabStyle(excitation="sweep", motion="x")),
         "sdof": ("hysteresis", LabStyle(excitation="sweep"))}
DRIVES = (("lines", 4, sim.TOLERANCE), ("lines", 2, sim.TOLERANCE), ("spline", 2, sim.SPLINE_TOLERANCE),
          ("spline", 1, sim.SPLINE_TOLERANCE), ("spline", 2, sim.TOLERANCE))


def main():
    drive.RESPONSE_MEMO = BoundedMemo(0)  # every run simulated: none returned from memory
    report = BenchReport("input_order", ROOT)
    for model, (withheld, style) in CASES.items():
        with tempfile.TemporaryDirectory() as tmp:
            data = write_dataset(pathlib.Path(tmp) / "data", FAMILIES[model], withheld, style=style)
            runner = FmuRunner(str(ensure_fmu(family_fmu(model), ROOT / "fmus")))
            system = make_system(model, fmu_defaults(runner), None)
            records = [sim.record_of(m, system.motion_inputs, smooth_inputs=system.smooth_inputs)
                       for m in read_dataset_with_order(data)[0]]
            truth = {**system.nominal_fixed, **json.loads((data / "truth.json").read_text())["params"]}
            fine = [sim.simulate(runner, dataclasses.replace(r, smooth_inputs=True), truth, 32, system.lead_periods,
                                 1e-9) for r in records]
            rows = []
            for kind, upsample, tolerance in DRIVES:
                recs = [dataclasses.replace(r, smooth_inputs=kind == "spline") for r in records]
                walls = []
                for _ in range(4):  # the first also upsamples the inputs (once per drive in a diagnosis): not timed
                    t0 = time.perf_counter()
                    outs = [sim.simulate(runner, r, truth, upsample, system.lead_periods, tolerance) for r in recs]
                    walls.append(time.perf_counter() - t0)
                walls = walls[1:]
                error = max(np.sqrt(np.mean([np.mean((o[k] - f[k]) ** 2) / np.mean(f[k] ** 2) for k in f]))
                            for o, f in zip(outs, fine))
                chosen = (kind == "spline") == system.smooth_inputs and upsample == system.upsample and \
                    tolerance == sim.tolerance_of(records[0])
                rows.append([kind, f"{upsample} x", f"{tolerance:g}", f"{error:.1e}", f"{np.mean(walls):.3f}",
                             "yes" if chosen else ""])
            runner.close()
        report.table(f"{model}: {withheld.replace('+', ' + ')} withheld, three 35 s sweeps",
                     ["drive", "grid (sensor rate x)", "tolerance", "error (worst record)", "cost [s]",
                      "the diagnosis's"], rows)


if __name__ == "__main__":
    main()
