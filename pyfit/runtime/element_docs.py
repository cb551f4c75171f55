"""Per-FMU documentation in the style of the Modelica Reference-FMUs: a README (what it is, variables with
units) and a reference result CSV from a defined run, for users of other FMI tools."""
from __future__ import annotations

import pathlib

import numpy as np

from pyfit.analysis.excitation import Excitation, motion_with_derivatives
from pyfit.runtime.fmu import FmuRunner

STEP = 1e-3  # s, output interval of the reference runs and spacing of their (linear) input samples
STOP = 0.5  # s


SINE_2MM = Excitation(kind=1, amplitude=2e-3, f_start=10.0)  # m, Hz
CLAMP_SINE = Excitation(kind=1, amplitude=5e-4, f_start=12.0, t_ramp=0.1)

# element -> (what the reference run does, input builder(t) or None, parameters, recorded outputs)
REFERENCE_RUNS = {
    "BoucWenElement": ("relative motion s = 2 mm sin(2π·10 Hz·t), default parameters",
                       lambda t: motion_with_derivatives(SINE_2MM, t, ("s", "v")), {}, ["f", "df", "z"]),
    "BoucWenNormalizedElement": ("relative motion s = 2 mm sin(2π·10 Hz·t), default parameters",
                                 lambda t: motion_with_derivatives(SINE_2MM, t, ("s", "v")), {},
                                 ["f", "df", "z"]),
    "CubicSpringElement": ("relative motion s = 2 mm sin(2π·10 Hz·t), k3 = 1e6 N/m³",
                           lambda t: motion_with_derivatives(SINE_2MM, t, ("s", "v")), {}, ["f"]),
    "MassSpringDamper": ("built-in linear force sweep 120 N, 0 → 60 Hz at 0.5 Hz/s, input f = 0", None, {},
                         ["y", "v", "a"]),
    "DamperElement": ("clamp motion 0.5 mm sin(2π·12 Hz·t) with a 0.1 s ramp-in, default damper",
                      lambda t: motion_with_derivatives(CLAMP_SINE, t, ("x_base", "v_base", "a_base")), {},
                      ["F_clamp", "x1", "x2"]),
    "ConductorSpan": ("built-in shaker sine 5 N at 10 Hz at x_e = 14.1 m, input F_clamp = 0", None, {},
                      ["y_d", "v_d", "a_d", "y_e", "E"]),
}


def _table(md, causality: str) -> list[str]:
    rows = [v for v in md.modelVariables if v.causality == causality]
    if not rows:
        return []
    lines = [f"### {causality}s", "", "| name | unit | start | description |", "|---|---|---|---|"]
    for v in rows:
        lines.append(f"| `{v.name}` | {v.unit or v.declaredType and v.declaredType.unit or '1'} | "
                     f"{v.start if v.start is not None else ''} | {(v.description or '').replace('|', chr(92) + '|')} |")
    return lines + [""]


def write_docs(name: str, fmu: str | pathlib.Path, out_dir: str | pathlib.Path) -> pathlib.Path:
    """Write out_dir/<name>/README.md and <name>_ref.csv (the reference run of REFERENCE_RUNS[name]); for an
    element driven by inputs also <name>_ref_held.csv, the same run with each input held over a
    communication step (what an importer that sets no input derivatives computes)."""
    what, make_inputs, params, outputs = REFERENCE_RUNS[name]
    folder = pathlib.Path(out_dir) / name
    folder.mkdir(parents=True, exist_ok=True)
    runner = FmuRunner(str(fmu))
    md = runner.model_description
    t = np.arange(int(round(STOP / STEP)) + 1) * STEP
    inputs = make_inputs(t) if make_inputs else None
    res = runner.simulate(STOP, STEP, outputs, params, inputs=inputs, input_time=t if inputs else None,
                          tolerance=1e-10)
    if not res.ok:
        raise RuntimeError(f"{name}: reference run failed: {res.message}")
    cols = {"time": t, **(inputs or {}), **{o: res[o] for o in outputs}}
    csv = folder / f"{name}_ref.csv"
    np.savetxt(csv, np.column_stack(list(cols.values())), delimiter=",", header=",".join(cols), comments="",
               fmt="%.12g")
    held_note = ""
    if inputs:
        held = runner.simulate(STOP, STEP, outputs, params, inputs=inputs, input_time=t, tolerance=1e-10,
                               hold_inputs=True)
        if not held.ok:
            raise RuntimeError(f"{name}: held-input reference run failed: {held.message}")
        np.savetxt(folder / f"{name}_ref_held.csv",
                   np.column_stack([t, *inputs.values(), *(held[o] for o in outputs)]), delimiter=",",
                   header=",".join(cols), comments="", fmt="%.12g")
        gaps = ", ".join(f"{o} {np.max(np.abs(held[o] - res[o])) / np.max(np.abs(res[o])) * 100:.1f} %" for o in outputs)
        held_note = (f"An importer that holds each input constant over a communication step (one that sets no "
                     f"input derivatives, e.g. fmi-sim 0.7) computes a different, coarser input: it "
                     f"reproduces [`{name}_ref_held.csv`]({name}_ref_held.csv) (same run, inputs held), not "
                     f"`{csv.name}`. They differ by (max |difference| / max |output|): {gaps}. To get the "
                     "linear-input result from such an importer, sample the inputs finer (the difference "
                     "falls with the square of the step). Outputs that depend directly on an input are "
                     "recorded there as read before the next input is set; an importer that reads them after "
                     "setting it (fmpy does) sees them with the new input. The FMI 3.0 FMU "
                     f"(`fmus/fmi3/{name}.fmu`) always holds inputs over a step.")
    runner.close()
    lines = [f"# {name}", "", md.description or "", "",
             f"FMI {md.fmiVersion} Model Exchange and Co-Simulation, generated from "
             f"`modelica/` by `stockbridge build` (pyfit); GUID `{md.guid}`.",
             "Co-simulation: adaptive DOPRI5 inside each communication step (tolerance from fmi2SetupExperiment), "
             "inputs linear over a step when their derivatives are set (canInterpolateInputs). The same model "
             f"as FMI 3.0: `fmus/fmi3/{name}.fmu`.", ""]
    lines += ["## Variables (SI units)", ""] + _table(md, "input") + _table(md, "output") + _table(md, "parameter")
    lines += ["## Reference result", "", f"[`{csv.name}`]({csv.name}): {what}; output interval {STEP} s, "
              f"{STOP} s, tolerance 1e-10, inputs linear between samples. Regenerate with "
              "`stockbridge element-docs`.", ""] + ([held_note, ""] if held_note else [])
    (folder / "README.md").write_text("\n".join(lines))
    return folder
