"""Run one FMU many times through fmpy: extract once, instantiate once, reset between runs.

Co-simulation runs are driven here (not by fmpy.simulate_fmu) so that the input derivatives of a
sampled input reach the FMU: fmpy 0.3.32's simulate_fmu(set_input_derivatives=True) only works for
FMUs with exactly nine real inputs (a fixed-size buffer). Between two samples the input is linear,
and its slope is sent with fmi2SetRealInputDerivatives. The communication loop runs in C
(pyfit/runtime/cs_driver.c through the FMU's own FMI functions, see pyfit.runtime.native), or in Python
where no C compiler is available. Model Exchange runs use fmpy's CVode driver, which applies inputs at
communication points only.
"""
from __future__ import annotations

import ctypes
import pathlib
import shutil
import threading
import time as _time
from dataclasses import dataclass, field

import numpy as np
from fmpy import calloc, extract, free, read_model_description
from fmpy.fmi1 import FMICallException
from pyfit.runtime.native import cs_loop
from fmpy.fmi2 import (FMU2Model, FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                       fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)


_LOADING = threading.Lock()


def load_fmu(cls, **kwargs):
    """An fmpy FMU object (cls: FMU2Model, FMU2Slave, ...) built while no other thread builds one: fmpy changes
    the process's working directory to the FMU's binaries folder while it loads the library and back after,
    so two threads loading at once can leave the process in a folder that is deleted later."""
    with _LOADING:
        return cls(**kwargs)


def _too_slow(max_wall_s: float, t: float) -> str:
    return f"the simulation ran longer than its limit of {max_wall_s:g} s (wall clock), at t = {t:g} s"


class ParameterError(ValueError):
    """A parameter name or value the FMU does not accept."""


def _collecting_callbacks(log: list[str]) -> fmi2CallbackFunctions:
    """FMI callbacks whose logger keeps the FMU's messages (the wrapper sends plain text)."""

    def logger(env, instance, status, category, message):
        log.append(message.decode("utf-8", "replace"))
        del log[:-20]

    cb = fmi2CallbackFunctions()
    cb.logger = fmi2CallbackLoggerTYPE(logger)
    cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
    cb.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
    return cb


@dataclass
class SimulationResult:
    """Outputs on a uniform time grid, or a failure with its reason (never an exception)."""

    time: np.ndarray
    values: dict[str, np.ndarray]
    ok: bool = True
    message: str = ""

    def __getitem__(self, name: str) -> np.ndarray:
        return self.values[name]


def interpolated_rows(table: np.ndarray, input_time: np.ndarray, time: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inputs sampled at input_time (one row per input) at each communication point of `time`, and the slope of
    the linear input on the segment that starts there (the last point: its segment's) [unit/s]."""
    u_at = np.vstack([np.interp(time, input_time, row) for row in table])
    # (a communication point within 1e-6 of an input sample counts as that sample: rounding of the two time grids
    # must not select the previous segment)
    tol = 1e-6 * np.min(np.diff(input_time))
    idx = np.clip(np.searchsorted(input_time, time + tol, side="right") - 1, 0, len(input_time) - 2)
    return u_at, (table[:, idx + 1] - table[:, idx]) / (input_time[idx + 1] - input_time[idx])


def input_rows(table: np.ndarray, input_time: np.ndarray, time: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """interpolated_rows, without interpolating when the inputs are sampled on the communication grid (a
    measured drive: the same values to the bit, a few per cent of a simulation sooner)."""
    if not np.array_equal(input_time, time):
        return interpolated_rows(table, input_time, time)
    slope = np.diff(table) / np.diff(input_time)
    return table, np.hstack([slope, slope[:, -1:]])


@dataclass
class FmuRunner:
    """Picklable handle to one FMU file; the FMU itself is loaded lazily in the process that runs it."""

    path: str
    interface: str = "CoSimulation"  # or "ModelExchange"
    _state: dict = field(default_factory=dict, repr=False, compare=False)

    def __post_init__(self):
        # absolute from the start: fmpy changes the working directory while it loads an FMU's library, so a relative
        # path read by another thread at that moment (a fit simulating its records on several threads) names nothing
        self.path = str(pathlib.Path(self.path).absolute())

    def __getstate__(self):
        return {"path": self.path, "interface": self.interface, "_state": {}}

    # ---- loading ---------------------------------------------------------------------------------
    @property
    def model_description(self):
        if "md" not in self._state:
            if not pathlib.Path(self.path).is_file():
                raise FileNotFoundError(f"{self.path}: FMU file not found")
            with _LOADING:  # libxml2 parses fmpy's XML schema: not while another thread parses it or loads an FMU
                self._state["md"] = read_model_description(self.path)
        return self._state["md"]

    @property
    def variables(self) -> dict:
        """name -> fmpy ScalarVariable."""
        if "vars" not in self._state:
            self._state["vars"] = {v.name: v for v in self.model_description.modelVariables}
        return self._state["vars"]

    def parameter_names(self) -> list[str]:
        """Names of the parameters that can be set before a run."""
        return list(self.parameters())

    def parameters(self) -> dict:
        """The parameters that can be set before a run: name -> fmpy ScalarVariable (unit, min, max, start)."""
        return {v.name: v for v in self.model_description.modelVariables if v.causality == "parameter"}

    def instance(self):
        """The loaded fmpy FMU instance of this process (instantiated on first use; reset between runs)."""
        if "fmu" not in self._state:
            md = self.model_description
            unzip = extract(self.path)
            cls = FMU2Slave if self.interface == "CoSimulation" else FMU2Model
            ident = (md.coSimulation if self.interface == "CoSimulation" else md.modelExchange).modelIdentifier
            fmu = load_fmu(cls, guid=md.guid, unzipDirectory=unzip, modelIdentifier=ident, instanceName="pyfit")
            log: list[str] = []
            callbacks = _collecting_callbacks(log)
            fmu.instantiate(callbacks=callbacks)
            self._state.update(fmu=fmu, unzip=unzip, log=log, callbacks=callbacks)
        return self._state["fmu"]

    def close(self):
        """Free the instance and delete the extracted files."""
        fmu = self._state.pop("fmu", None)
        if fmu is not None:
            fmu.freeInstance()
        unzip = self._state.pop("unzip", None)
        if unzip:
            shutil.rmtree(unzip, ignore_errors=True)

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass

    # ---- parameters ------------------------------------------------------------------------------
    def check_parameters(self, params: dict) -> None:
        """Reject unknown names (listing the valid ones) and values outside declared min/max."""
        if "settable" not in self._state:  # every simulation checks its parameters: the names once per process
            self._state["settable"] = set(self.parameter_names()) | {
                v.name for v in self.model_description.modelVariables
                if v.causality == "local" and v.initial == "exact"}
        for name, value in params.items():
            if name not in self._state["settable"]:
                valid = self.parameter_names()
                raise ParameterError(f"{pathlib.Path(self.path).name}: unknown parameter '{name}'; "
                                     f"valid parameters: {', '.join(sorted(valid))}")
            v = self.variables[name]
            lo = float(v.min) if v.min is not None else -np.inf
            hi = float(v.max) if v.max is not None else np.inf
            if not np.isfinite(value) or not lo <= value <= hi:
                raise ParameterError(f"{pathlib.Path(self.path).name}: parameter '{name}' = {value} outside "
                                     f"[{lo}, {hi}]")

    def _check_inputs(self, inputs: dict, input_time) -> None:
        """Input samples must be finite and on one uniform, increasing time column."""
        from pyfit.analysis.signals import assert_uniform

        if input_time is None:
            raise ValueError("inputs given without input_time")
        try:
            assert_uniform(input_time)
        except ValueError as exc:
            raise ValueError(f"input time column: {exc}") from exc
        for name, values in inputs.items():
            values = np.asarray(values, float)
            if values.shape != np.shape(input_time):
                raise ValueError(f"input '{name}' has {values.shape} samples, its time column {np.shape(input_time)}")
            bad = np.flatnonzero(~np.isfinite(values))
            if bad.size:
                raise ValueError(f"input '{name}' is not finite at {bad.size} sample(s), first at "
                                 f"t = {input_time[bad[0]]:g} s")

    def set_parameters(self, fmu, params: dict) -> None:
        """Set parameters (Real, Integer or Boolean by their declared type) on a loaded instance."""
        for name, value in params.items():
            v = self.variables[name]
            if v.type == "Integer":
                fmu.setInteger([v.valueReference], [int(value)])
            elif v.type == "Boolean":
                fmu.setBoolean([v.valueReference], [bool(value)])
            else:
                fmu.setReal([v.valueReference], [float(value)])

    # ---- simulation ------------------------------------------------------------------------------
    def simulate(self, stop_time: float, output_interval: float, outputs: list[str],
                 params: dict | None = None, inputs: dict[str, np.ndarray] | None = None,
                 input_time: np.ndarray | None = None, tolerance: float = 1e-8,
                 start_time: float = 0.0, hold_inputs: bool = False,
                 max_wall_s: float | None = None, input_derivatives: tuple[dict, dict] | None = None
                 ) -> SimulationResult:
        """Simulate from start_time to stop_time; outputs sampled every output_interval (uniform grid).

        inputs: name -> samples at input_time (linear in between, sent with their slopes as input derivatives;
        hold_inputs=True holds each communication point's value over the step instead, as importers without input
        derivatives do). input_derivatives: (slopes, curvatures), name -> each step's input slope and curvature at
        its start [unit/s, unit/s²] (pyfit.analysis.signals.step_quadratics): each step's input is then the
        quadratic they give, sent as input derivatives of orders 1 and 2 (co-simulation only, with input_time the
        communication grid). A failing or diverging run, or one still running after max_wall_s seconds (None: no
        limit; a parameter set so stiff that the integrator crawls), returns SimulationResult(ok=False) with the
        reason; invalid parameter names raise ParameterError.
        """
        params = dict(params or {})
        self.check_parameters(params)
        for name in outputs + list(inputs or {}):
            if name not in self.variables:
                raise ParameterError(f"{pathlib.Path(self.path).name}: no variable '{name}'")
        if inputs:
            self._check_inputs(inputs, input_time)
        n = int(round((stop_time - start_time) / output_interval))
        if n < 1 or abs(start_time + n * output_interval - stop_time) > 1e-9 * max(1.0, abs(stop_time)):
            raise ValueError(f"stop_time - start_time = {stop_time - start_time} is not a whole number of "
                             f"output intervals {output_interval}")
        time = start_time + output_interval * np.arange(n + 1)
        if input_derivatives is not None and (
                self.interface != "CoSimulation" or hold_inputs or np.shape(input_time) != time.shape
                or not np.allclose(input_time, time, rtol=0, atol=1e-9 * output_interval)):
            raise ValueError("input_derivatives need co-simulation with the inputs on the communication grid")
        try:
            fmu = self.instance()
            self._state["log"].clear()
            fmu.reset()
            if self.interface == "CoSimulation":
                vals = self._run_cs(fmu, time, outputs, params, inputs, input_time, tolerance, hold_inputs,
                                    max_wall_s, input_derivatives)
            else:
                vals = self._run_me(fmu, time, outputs, params, inputs, input_time, tolerance, max_wall_s)
        except (FMICallException, OSError, RuntimeError) as exc:
            log = self._state.get("log", [])
            message = "; ".join(log[-2:] + [str(exc)]) if log else str(exc)
            self.close()  # the instance may be unusable: make a fresh one next time
            return SimulationResult(time, {o: np.full(len(time), np.nan) for o in outputs}, False, message)
        dt = np.diff(time)
        assert np.allclose(dt, output_interval, rtol=1e-9, atol=0), "output grid is not uniform"
        return SimulationResult(time, vals)

    def _run_cs(self, fmu, time, outputs, params, inputs, input_time, tolerance, hold_inputs=False,
                max_wall_s=None, input_derivatives=None):
        fmu.setupExperiment(tolerance=tolerance, startTime=time[0])
        self.set_parameters(fmu, params)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        out_vr = (ctypes.c_uint * len(outputs))(*[self.variables[o].valueReference for o in outputs])
        out_buf = (ctypes.c_double * len(outputs))()
        result = np.empty((len(time), len(outputs)))
        in_names = list(inputs or {})
        k = len(in_names)
        if k:
            in_vr = (ctypes.c_uint * k)(*[self.variables[nm].valueReference for nm in in_names])
            table = np.vstack([np.asarray(inputs[nm], float) for nm in in_names])
            u_at, slope = input_rows(table, np.asarray(input_time, float), time)
        curv = None
        if k and input_derivatives is not None:
            first, second = input_derivatives
            slope = np.vstack([np.asarray(first[nm], float) for nm in in_names])
            curv = np.vstack([np.asarray(second[nm], float) for nm in in_names])
        loop = cs_loop()
        if loop is not None:
            self._run_cs_compiled(loop, fmu, time, out_vr, result, in_vr if k else None,
                                  u_at if k else None, None if (hold_inputs or not k) else slope, max_wall_s, curv)
        else:  # the same loop in Python
            in_buf, der_buf = (ctypes.c_double * k)(), (ctypes.c_double * k)()
            order, order2 = (ctypes.c_int * k)(*([1] * k)), (ctypes.c_int * k)(*([2] * k))
            get_real, do_step = fmu.fmi2GetReal, fmu.fmi2DoStep
            set_real, set_der = fmu.fmi2SetReal, fmu.fmi2SetRealInputDerivatives
            comp = fmu.component
            t0 = _time.perf_counter()
            for i, t in enumerate(time):
                if max_wall_s and i % 16 == 0 and _time.perf_counter() - t0 > max_wall_s:
                    raise RuntimeError(_too_slow(max_wall_s, t))
                if k:
                    in_buf[:] = u_at[:, i]
                    set_real(comp, in_vr, k, in_buf)
                get_real(comp, out_vr, len(outputs), out_buf)
                result[i] = out_buf[:]
                if i + 1 < len(time):
                    if k and not hold_inputs:
                        der_buf[:] = slope[:, i]
                        set_der(comp, in_vr, k, order, der_buf)
                        if curv is not None:
                            der_buf[:] = curv[:, i]
                            set_der(comp, in_vr, k, order2, der_buf)
                    do_step(comp, t, time[i + 1] - t, 1)
        fmu.terminate()
        return {o: result[:, j].copy() for j, o in enumerate(outputs)}

    @staticmethod
    def _run_cs_compiled(loop, fmu, time, out_vr, result, in_vr, u_at, slope, max_wall_s=None, curv=None):
        """The communication loop of _run_cs in C (pyfit/runtime/cs_driver.c), through the FMU's own functions."""
        def fn(name):
            return ctypes.cast(getattr(fmu.dll, name), ctypes.c_void_p)

        def ptr(a):
            return None if a is None else a.ctypes.data_as(ctypes.c_void_p)

        time = np.ascontiguousarray(time, float)
        u_rows = None if u_at is None else np.ascontiguousarray(u_at.T)
        s_rows = None if slope is None else np.ascontiguousarray(slope.T)
        c_rows = None if curv is None or slope is None else np.ascontiguousarray(curv.T)
        status, call = ctypes.c_int(0), ctypes.c_int(0)
        failed = loop(fmu.component, fn("fmi2SetReal"), fn("fmi2GetReal"), fn("fmi2SetRealInputDerivatives"),
                      fn("fmi2DoStep"), len(time), ptr(time), 0 if in_vr is None else len(in_vr),
                      in_vr, ptr(u_rows), ptr(s_rows), ptr(c_rows), len(out_vr), out_vr, ptr(result),
                      ctypes.byref(status), ctypes.byref(call), float(max_wall_s or 0.0))
        if failed >= 0 and call.value == 5:
            raise RuntimeError(_too_slow(max_wall_s, time[failed]))
        if failed >= 0:
            what = {1: "fmi2SetReal", 2: "fmi2GetReal", 3: "fmi2SetRealInputDerivatives", 4: "fmi2DoStep"}[call.value]
            raise RuntimeError(f"{what} returned status {status.value} at t = {time[failed]:g} s")

    def _run_me(self, fmu, time, outputs, params, inputs, input_time, tolerance, max_wall_s=None):
        from fmpy import simulate_fmu

        sig = None
        if inputs:
            names = list(inputs)
            sig = np.zeros(len(input_time), dtype=[("time", float)] + [(nm, float) for nm in names])
            sig["time"] = input_time
            for nm in names:
                sig[nm] = inputs[nm]
        res = simulate_fmu(self.path, fmi_type="ModelExchange", fmu_instance=fmu,
                           model_description=self.model_description, start_time=time[0], stop_time=time[-1],
                           output_interval=time[1] - time[0], relative_tolerance=tolerance,
                           start_values=params, input=sig, output=outputs, terminate=True, validate=False,
                           timeout=max_wall_s)
        rt = res["time"]
        if max_wall_s and rt[-1] < time[-1] - 1e-9 * max(1.0, abs(time[-1])):  # fmpy stops at its timeout
            raise RuntimeError(_too_slow(max_wall_s, rt[-1]))
        # fmpy may add points at events; keep the uniform grid
        return {o: np.interp(time, rt, res[o]) for o in outputs}
