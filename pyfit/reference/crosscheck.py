"""Cross-check every FMU against the independent CasADi reference at three levels:
right-hand side at sampled states and parameters, Jacobian (FMU directional derivatives vs CasADi AD),
and trajectories (a sweep and a multisine, Model Exchange and Co-Simulation, vs CVODES).

FMU states are whatever the Modelica build kept; the physical states of the reference (positions,
velocities, hysteretic variables) are read from FMU variables listed in PHYSICAL. The map between the
two is affine and found by probing the FMU with unit state vectors.
"""
from __future__ import annotations

import ctypes
import json
import pathlib
from dataclasses import asdict, dataclass

import casadi as ca
import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Model

from pyfit.analysis import signals
from pyfit.analysis.excitation import Excitation, multisine
from pyfit.runtime.fmu import FmuRunner, load_fmu
from pyfit.reference import integrate
from pyfit.reference import models

# FMU variable names of the reference states x = [q, qdot, z] and of their rates [qdot, qddot, zdot]
_TWO_DOF = (["y1", "y2", "v1", "v2", "z"], ["v1", "v2", "mass1.a", "mass2.a", "der(boucWen.z)"])
PHYSICAL = {
    "SDOFBoucWen": (["y", "v", "z"], ["v", "mass.a", "der(boucWen.z)"]),
    "TwoDOFa": _TWO_DOF, "TwoDOFb": _TWO_DOF, "TwoDOFc": _TWO_DOF, "TwoDOFd": _TWO_DOF,
    "StockbridgeDamper": (
        ["x1", "phi1", "x2", "phi2", "mass1.v", "mass1.w", "mass2.v", "mass2.w", "boucWen1.z", "boucWen2.z"],
        ["mass1.v", "mass1.w", "mass2.v", "mass2.w", "mass1.acc", "mass1.alp", "mass2.acc", "mass2.alp",
         "der(boucWen1.z)", "der(boucWen2.z)"]),
}
# typical magnitudes of the physical states (for sampling) and the excitations of the trajectory level
_SCALE = {"SDOFBoucWen": [1e-3, 0.2, 50.0], "TwoDOF": [5e-3, 5e-3, 0.2, 0.2, 2.0],
          "StockbridgeDamper": [2e-3, 0.03, 2e-3, 0.05, 0.1, 2.0, 0.1, 3.0, 0.5, 0.5]}
SWEEPS = {
    "SDOFBoucWen": (Excitation(2, 120.0, 0.0, 60.0, 6.0), 6.0),
    "TwoDOF": (Excitation(2, 10.0, 0.0, 60.0, 6.0), 6.0),
    "StockbridgeDamper": (Excitation(4, 0.05, 5.0, 40.0, 10.0, t_ramp=1.0), 3.4),
}
TOLERANCE = {"rhs": 1e-10, "jacobian": 1e-8, "trajectory": {"SDOFBoucWen": 1e-6, "default": 1e-5}}


@dataclass
class CheckResult:
    """One comparison: model, level, the error figures and whether they are within tolerance."""

    model: str
    level: str
    figures: dict
    tolerance: float
    passed: bool
    notes: str = ""


def _family(name):
    return "TwoDOF" if name.startswith("TwoDOF") else name


def _fmu_params(name: str, ref: models.ReferenceModel, p: np.ndarray) -> dict:
    vals = dict(zip(ref.param_names, p))
    if name.startswith("TwoDOF") and name[-1] in "ab":
        vals.pop("k_nl")
    return vals


class _MEProbe:
    """A Model Exchange instance evaluated at chosen states, time and inputs."""

    def __init__(self, path: pathlib.Path, params: dict):
        self.md = read_model_description(str(path))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.types = {v.name: v.type for v in self.md.modelVariables}
        self.dir = extract(str(path))
        self.fmu = load_fmu(FMU2Model, guid=self.md.guid, unzipDirectory=self.dir,
                            modelIdentifier=self.md.modelExchange.modelIdentifier, instanceName="probe")
        self.fmu.instantiate()
        self.fmu.setupExperiment(startTime=0.0)
        params = dict(params, exc_type=0)
        for k, v in params.items():
            if self.types[k] == "Integer":
                self.fmu.setInteger([self.vr[k]], [int(v)])
            else:
                self.fmu.setReal([self.vr[k]], [float(v)])
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()
        self.fmu.enterContinuousTimeMode()
        self.nx = self.md.numberOfContinuousStates
        self.state_vrs = [v.valueReference for v in self.md.modelVariables if v.initial == "exact"
                          and v.causality == "local"]

    def at(self, s, t, inputs: dict):
        self.fmu.setTime(float(t))
        for k, v in inputs.items():
            self.fmu.setReal([self.vr[k]], [float(v)])
        self.fmu.setContinuousStates((ctypes.c_double * self.nx)(*s), self.nx)

    def read(self, names):
        return np.array(self.fmu.getReal([self.vr[n] for n in names]))

    def jacobian(self, unknowns):
        J = np.zeros((len(unknowns), self.nx))
        for j, vr in enumerate(self.state_vrs):
            J[:, j] = self.fmu.getDirectionalDerivative([self.vr[n] for n in unknowns], [vr], [1.0])
        return J

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


def _state_map(probe: _MEProbe, phys: list[str], t, inputs):
    """Affine map physical = A @ s + b of the FMU states s at time t and inputs."""
    n = probe.nx
    probe.at(np.zeros(n), t, inputs)
    b = probe.read(phys)
    A = np.zeros((len(phys), n))
    for j in range(n):
        e = np.zeros(n)
        e[j] = 1.0
        probe.at(e, t, inputs)
        A[:, j] = probe.read(phys) - b
    return A, b


# sampling scale of the candidate-effect parameters (theory §6) in the right-hand-side check (SI units)
_EFFECT_SAMPLES = {"k3": 1e9, "F_c": 2.0, "c2": 10.0, "F_c1": 0.5, "F_c2": 0.5, "c2_1": 5.0, "c2_2": 5.0}


def _samples(name, ref, n, seed):
    rng = np.random.default_rng(seed)
    scale = np.array(_SCALE[_family(name)])
    for _ in range(n):
        x = scale * rng.uniform(0.2, 1.0, scale.size) * rng.choice([-1, 1], scale.size)
        p = ref.param_vector() * rng.uniform(0.8, 1.2, len(ref.param_names))
        for i, n in enumerate(ref.param_names):  # candidate effects are off (0) by default: switch them on
            if n in _EFFECT_SAMPLES and p[i] == 0:
                p[i] = _EFFECT_SAMPLES[n] * rng.uniform(0.2, 1.0)
        u = rng.normal(size=ref.u.numel()) * (10.0 if ref.u.numel() == 1 else np.array([1e-3, 0.05, 5.0]))
        yield x, p, u, rng.uniform(0, 10)


def check_rhs_and_jacobian(name: str, fmu: pathlib.Path, n_samples: int = 10, seed: int = 0) -> list[CheckResult]:
    """Right-hand side and Jacobian of the FMU vs the reference at sampled states, parameters, inputs, times."""
    ref = models.by_name(name)
    phys, rates = PHYSICAL[name]
    f = ref.function()
    jf = ca.Function("J", [ref.x, ref.u, ref.p, ref.t], [ca.jacobian(ref.rhs, ref.x)])
    rhs_err, jac_err = [], []
    for x, p, u, t in _samples(name, ref, n_samples, seed):
        probe = _MEProbe(fmu, _fmu_params(name, ref, p))
        try:
            inputs = dict(zip(ref.input_names, u))
            A, b = _state_map(probe, phys, t, inputs)
            s = np.linalg.solve(A, x - b)
            probe.at(s, t, inputs)
            got = probe.read(rates)
            want = np.array(f(x, u, p, t)).ravel()
            rhs_err.append(np.max(np.abs(got - want)) / np.max(np.abs(want)))
            J_fmu = probe.jacobian(rates) @ np.linalg.inv(A)
            J_ref = np.array(jf(x, u, p, t))
            jac_err.append(np.max(np.abs(J_fmu - J_ref)) / np.max(np.abs(J_ref)))
        finally:
            probe.close()
    out = []
    for level, err in (("rhs", rhs_err), ("jacobian", jac_err)):
        tol = TOLERANCE[level]
        out.append(CheckResult(name, level, {"max_rel_error": float(max(err)), "samples": n_samples}, tol,
                               bool(max(err) <= tol)))
    return out


def _trajectory_errors(y_ref, y, dt):
    fig = {
        "max_rel_error": float(np.max(np.abs(y - y_ref)) / np.max(np.abs(y_ref))),
        "nrmse": float(signals.nrmse(y_ref, y)),
    }
    f1, _ = signals.psd_peak(y_ref, 1 / dt)
    f2, _ = signals.psd_peak(y, 1 / dt)
    fig["psd_peak_hz_diff"] = float(abs(f1 - f2))
    return fig


def trajectory_cases(name: str):
    """The two trajectory experiments of a model: (label, excitation, inputs, grid, FMU parameters)."""
    ref = models.by_name(name)
    exc, stop = SWEEPS[_family(name)]
    dt = 1e-3
    t = np.arange(round(stop / dt) + 1) * dt
    sweep_params = {"exc_type": exc.kind, "exc_f_start": exc.f_start, "exc_f_end": exc.f_end, "exc_rate": exc.rate,
                    "exc_t_ramp": exc.t_ramp}
    sweep_params["exc_v0" if exc.kind >= 4 else "exc_amplitude"] = exc.amplitude
    cases = [("sweep", exc, None, t, sweep_params)]
    # multisine: one leakage-free period repeated, fed as a sampled input (linear between samples)
    n, fs = 1024, 1 / dt
    if ref.u.numel() == 1:
        rms = 50.0 if name == "SDOFBoucWen" else 5.0
        u = np.tile(multisine(n, fs, 5.0, 150.0, rms, seed=1), 2)
        inputs = {ref.input_names[0]: np.append(u, u[0])}
    else:  # clamp motion: displacement from a velocity multisine, with consistent derivatives
        xs = multisine(n, fs, 5.0, 60.0, 1.0, seed=1)
        spec = np.fft.rfft(xs)
        w = 2j * np.pi * np.fft.rfftfreq(n, dt)
        vel = np.fft.irfft(spec * w, n)
        k = 0.01 / np.sqrt(np.mean(vel**2))  # 0.01 m/s RMS clamp velocity
        x, v, a = (np.tile(np.fft.irfft(spec * w**i, n) * k, 2) for i in (0, 1, 2))
        inputs = {"x_base": np.append(x, x[0]), "v_base": np.append(v, v[0]), "a_base": np.append(a, a[0])}
    tm = np.arange(2 * n + 1) * dt
    cases.append(("multisine", None, inputs, tm, {"exc_type": 0}))
    return cases


def check_trajectories(name: str, fmu: pathlib.Path, out_dir: pathlib.Path | None = None) -> list[CheckResult]:
    """ME and CS trajectories of the FMU vs CVODES on the reference, for a sweep and a multisine."""
    ref = models.by_name(name)
    outputs = list(ref.outputs)
    tol = TOLERANCE["trajectory"].get(name, TOLERANCE["trajectory"]["default"])
    units = {v.name: v.unit for v in read_model_description(str(fmu)).modelVariables}
    results = []
    for label, exc, inputs, t, fmu_params in trajectory_cases(name):
        want = integrate.simulate_cvodes(ref, t, excitation=exc, inputs=inputs, rtol=1e-12, atol=1e-15)
        dt = t[1] - t[0]
        # fmpy's Model Exchange driver holds sampled inputs between communication points, so only
        # co-simulation (linear inputs through input derivatives) sees the reference's input
        for interface in ("CoSimulation",) if inputs else ("ModelExchange", "CoSimulation"):
            runner = FmuRunner(str(fmu), interface)
            res = runner.simulate(t[-1], dt, outputs, fmu_params, inputs=inputs, input_time=t if inputs else None,
                                  tolerance=1e-12)
            runner.close()
            if not res.ok:
                results.append(CheckResult(name, f"trajectory_{label}_{interface}", {}, tol, False, res.message))
                continue
            figs = {o: _trajectory_errors(want[o], res[o], dt) for o in outputs}
            worst = max(v["max_rel_error"] for v in figs.values())
            results.append(CheckResult(name, f"trajectory_{label}_{interface}", figs, tol, bool(worst <= tol)))
            if out_dir is not None and interface == "CoSimulation":
                _overlay(out_dir / f"{name}_{label}.png", t, want, res, outputs, name, label, units)
                if label == "sweep":
                    _write_reference_csv(out_dir, name, t, want, fmu_params)
    return results


def _overlay(path, t, want, res, outputs, name, label, units):
    from pyfit.report import plots

    plots.time_histories(path, [("CasADi reference (CVODES)", t, want), ("FMU (co-simulation)", t, res.values)],
                         outputs, units, f"{name}: {label}")


def _write_reference_csv(out_dir: pathlib.Path, name, t, want, params):
    """FMI cross-check layout: <Model>_ref.csv (time + outputs) and <Model>_ref.opt (experiment settings)."""
    cols = ["time"] + list(want)
    data = np.column_stack([t] + [want[c] for c in want])
    np.savetxt(out_dir / f"{name}_ref.csv", data, delimiter=",", header=",".join(f'"{c}"' for c in cols), comments="")
    opt = [f"StartTime, {t[0]:g}", f"StopTime, {t[-1]:g}", f"StepSize, {t[1] - t[0]:g}", "RelTol, 1e-12"]
    (out_dir / f"{name}_ref.opt").write_text("\n".join(opt) + "\n")
    (out_dir / f"{name}_ref_parameters.json").write_text(json.dumps(params, indent=1))


def run(fmu_dir: pathlib.Path, out_dir: pathlib.Path, names: list[str], n_samples: int = 10) -> list[CheckResult]:
    """All levels for every named FMU; writes crosscheck.json, crosscheck.md, overlays and reference CSVs."""
    out_dir.mkdir(parents=True, exist_ok=True)
    results: list[CheckResult] = []
    for name in names:
        fmu = pathlib.Path(fmu_dir) / f"{name}.fmu"
        if not fmu.exists():
            raise FileNotFoundError(f"{fmu}: FMU not found (build it with: stockbridge build {name})")
        results += check_rhs_and_jacobian(name, fmu, n_samples)
        results += check_trajectories(name, fmu, out_dir)
    (out_dir / "crosscheck.json").write_text(json.dumps([asdict(r) for r in results], indent=1))
    (out_dir / "crosscheck.md").write_text(report_markdown(results, names))
    return results


def report_markdown(results: list[CheckResult], names: list[str]) -> str:
    """A Markdown table of every check, with the overlay plots."""
    lines = ["# FMU vs CasADi reference cross-check", "",
             "| model | level | worst max\\|Δy\\|/max\\|y\\| | NRMSE | PSD peak Δf [Hz] | tolerance | result |",
             "|---|---|---|---|---|---|---|"]
    for r in results:
        if "max_rel_error" in r.figures:
            worst, nrmse, dpk = r.figures["max_rel_error"], "", ""
        elif r.figures:
            worst = max(v["max_rel_error"] for v in r.figures.values())
            nrmse = f"{max(v['nrmse'] for v in r.figures.values()):.2e}"
            dpk = f"{max(v['psd_peak_hz_diff'] for v in r.figures.values()):.3g}"
        else:
            worst, nrmse, dpk = float("nan"), "", ""
        verdict = ("pass" if r.passed else "FAIL") + (f" ({r.notes})" if r.notes else "")
        lines.append(f"| {r.model} | {r.level} | {worst:.2e} | {nrmse} | {dpk} | {r.tolerance:g} | {verdict} |")
    lines += ["", "Sampled inputs (multisine) are compared through co-simulation only: fmpy's Model Exchange "
              "driver holds inputs between communication points, the reference interpolates them linearly.", ""]
    for n in names:
        for label in ("sweep", "multisine"):
            lines.append(f"![{n} {label}]({n}_{label}.png)")
    return "\n".join(lines) + "\n"
