"""What the state nominals do for an importer's CVode at its default tolerance rule (atol = rtol x nominal):
fmpy's CVode at rtol 1e-4 against the FMU's own adaptive solver at tolerance 1e-10, 2 s of each FMU's
default run, once with the nominals the FMUs declare and once with every nominal forced to 1 (what an FMU
without nominals gets). Printed: max |difference| / max |output|.

    python bench/importer_tolerance.py
"""
import pathlib

import fmpy
import fmpy.sundials
import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]

from pyfit.report.generated import BenchReport
from pyfit.runtime.examples import ensure_fmu
from pyfit.runtime.fmu import FmuRunner

CASES = {"ConductorSpan": ["y_d", "y_e"], "MassSpringDamper": ["y"], "SDOFBoucWen": ["y", "z"],
         "StockbridgeDamper": ["x1", "x2", "F_clamp"]}


def unit_nominals(solver_class):
    """A CVodeSolver class that ignores the FMU's nominals (uses 1 for every state)."""
    class UnitNominals(solver_class):
        def __init__(self, *args, **kwargs):
            def ones(buffer, n):
                for i in range(n):
                    buffer[i] = 1.0
                return 0
            kwargs["get_nominals"] = ones
            super().__init__(*args, **kwargs)
    return UnitNominals


def main():
    report = BenchReport("importer_tolerance", ROOT)
    declared = fmpy.sundials.CVodeSolver
    for label, solver in (("declared nominals", declared), ("unit nominals", unit_nominals(declared))):
        fmpy.sundials.CVodeSolver = solver
        errors = []
        for name, outputs in CASES.items():
            path = str(ensure_fmu(name, ROOT / "fmus"))
            loose = fmpy.simulate_fmu(path, fmi_type="ModelExchange", relative_tolerance=1e-4, output=outputs,
                                      stop_time=2.0, output_interval=1e-3)
            tight = FmuRunner(path).simulate(2.0, 1e-3, outputs, tolerance=1e-10)
            errors += [f"{name}.{o} {np.max(np.abs(loose[o] - tight[o])) / np.max(np.abs(tight[o])):.2g}"
                       for o in outputs]
        report.line(f"CVode rtol 1e-4, {label}: " + "; ".join(errors))
    fmpy.sundials.CVodeSolver = declared


if __name__ == "__main__":
    main()
