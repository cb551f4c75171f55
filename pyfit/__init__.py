"""pyfit: Modelica -> FMU build, FMU simulation, parameter fits and the sim-to-real gap diagnosis of hysteretic
dampers (SI units).

The public names, imported on first use (so that `import pyfit` stays light):

- `diagnose(model, data_dir, out_dir, ...)` -> `Diagnosis`: where a model misfits measured data and which unmodelled
  effect explains it; `DiagnoseConfig` its settings, `Verdict` its verdicts, `diagnose_impedance` the same on a
  damper's impedance table, `check_dataset` what a dataset reads as before any fit;
- `fit(cfg, fmu_dir, out_dir, seed)`: a parameter fit from a study file (`load_fit`);
- `FmuRunner(path)`: one FMU, simulated on a time grid with inputs and parameters;
- `ensure_fmu(name, folder)`: an example FMU, built from the Modelica sources when missing.
"""

import importlib

__version__ = "0.2.0"

_PUBLIC = {
    "diagnose": ("pyfit.gap.diagnose", "diagnose"),
    "Diagnosis": ("pyfit.gap.result", "Diagnosis"),
    "Verdict": ("pyfit.gap.result", "Verdict"),
    "DiagnoseConfig": ("pyfit.gap.config", "DiagnoseConfig"),
    "diagnose_impedance": ("pyfit.gap.impedance_gap", "diagnose_impedance"),
    "check_dataset": ("pyfit.gap.dataset_check", "check_dataset"),
    "fit": ("pyfit.fit.fitting", "run_fit"),
    "load_fit": ("pyfit.io.fit_config", "load_fit"),
    "FmuRunner": ("pyfit.runtime.fmu", "FmuRunner"),
    "ensure_fmu": ("pyfit.runtime.examples", "ensure_fmu"),
}
__all__ = ["__version__", *_PUBLIC]


def __getattr__(name: str):
    if name in _PUBLIC:
        module, attribute = _PUBLIC[name]
        return getattr(importlib.import_module(module), attribute)
    raise AttributeError(f"module 'pyfit' has no attribute {name!r}")


def __dir__():
    return sorted(__all__)
