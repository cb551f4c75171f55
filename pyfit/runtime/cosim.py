"""A co-simulation master for FMI 2.0 co-simulation FMUs (fmpy), fixed communication step.

Coupling schemes (Kübler & Schiehlen 2000; Gomes et al., ACM Comput. Surv. 51, 2018):
- "gauss-seidel" (default): the FMUs step one after another in the given order. An input whose source
  FMU has already stepped in this macro step is interpolated linearly between the source's outputs at
  t_k and t_k+1; an input whose source has not stepped yet is extrapolated.
- "jacobi": every FMU steps from t_k with inputs extrapolated from t_k; all can step in parallel.
Extrapolation "linear" (default) sends the input's slope with fmi2SetRealInputDerivatives (order 1):
the source's derivative output when the connection names one (e.g. v for a position), otherwise the
backward difference of the last two communication values. "constant" holds the input over the step.
With linear extrapolation both schemes converge with order 2 in the step; with constant, order 1.
FMUs that cannot interpolate inputs (canInterpolateInputs = false) get held inputs.
"""
from __future__ import annotations

import ctypes
from dataclasses import dataclass

import numpy as np

from pyfit.runtime.fmu import FmuRunner, ParameterError

SCHEMES = ("gauss-seidel", "jacobi")
EXTRAPOLATIONS = ("linear", "constant")


@dataclass(frozen=True)
class Connection:
    """Output `source` ("fmu.variable") drives input `target`; `derivative` names an output holding
    d(source)/dt, used for extrapolation (optional)."""

    source: str
    target: str
    derivative: str | None = None


@dataclass
class CoSimResult:
    """Recorded variables ("fmu.variable") at the communication points."""

    time: np.ndarray
    values: dict[str, np.ndarray]

    def __getitem__(self, name: str) -> np.ndarray:
        return self.values[name]


def _split(ref: str, fmus: dict) -> tuple[str, str]:
    fmu, _, var = ref.partition(".")
    if fmu not in fmus or not var:
        raise ValueError(f"'{ref}' is not 'fmu.variable' with fmu one of {', '.join(fmus)}")
    if var not in fmus[fmu].variables:
        raise ParameterError(f"FMU '{fmu}' has no variable '{var}'")
    return fmu, var


class _Vars:
    """A fixed list of one FMU's real variables, read and written through the raw FMI functions with
    buffers allocated once (this runs at every communication step)."""

    def __init__(self, runner: FmuRunner, names: list[str]):
        self.fmu = runner.instance()
        self.comp = self.fmu.component
        self.names = names
        self.n = len(names)
        self.vr = (ctypes.c_uint * self.n)(*[runner.variables[v].valueReference for v in names])
        self.buf = (ctypes.c_double * self.n)()
        self.order = (ctypes.c_int * self.n)(*([1] * self.n))

    def get(self) -> dict[str, float]:
        self.fmu.fmi2GetReal(self.comp, self.vr, self.n, self.buf)
        return dict(zip(self.names, self.buf[:]))

    def set(self, values):
        self.buf[:] = values
        self.fmu.fmi2SetReal(self.comp, self.vr, self.n, self.buf)

    def set_slopes(self, slopes):
        self.buf[:] = slopes
        self.fmu.fmi2SetRealInputDerivatives(self.comp, self.vr, self.n, self.order, self.buf)


def _check_request(scheme: str, extrapolation: str, stop_time: float, step: float) -> int:
    """The number of communication steps; ValueError on an unknown scheme or extrapolation, or a stop time that is
    not a whole number of steps."""
    if scheme not in SCHEMES:
        raise ValueError(f"scheme '{scheme}' unknown; allowed: {', '.join(SCHEMES)}")
    if extrapolation not in EXTRAPOLATIONS:
        raise ValueError(f"extrapolation '{extrapolation}' unknown; allowed: {', '.join(EXTRAPOLATIONS)}")
    n = int(round(stop_time / step))
    if n < 1 or abs(n * step - stop_time) > 1e-9 * max(stop_time, 1.0):
        raise ValueError(f"stop_time {stop_time} s is not a whole number of communication steps {step} s")
    return n


class _Coupling:
    """The FMUs coupled: each one's reads (every output a connection or the record needs, in one call), writes
    (its connected inputs), the connections into it and whether it interpolates its inputs."""

    def __init__(self, runners: dict, conns: list, rec: list):
        needed = [src for src, _, _ in conns] + [d for _, _, d in conns if d] + rec
        self.runners = runners
        self.reads = {name: _Vars(r, sorted({v for f, v in needed if f == name})) for name, r in runners.items()}
        self.inputs_of = {name: [(s, d) for s, t, d in conns if t[0] == name] for name in runners}
        self.writes = {name: _Vars(r, [t[1] for _, t, _ in conns if t[0] == name]) for name, r in runners.items()}
        self.interpolates = {name: bool(r.model_description.coSimulation.canInterpolateInputs)
                             for name, r in runners.items()}

    def now(self) -> dict:
        return {name: self.reads[name].get() for name in self.runners}

    def initialise(self) -> dict:
        """Two fixed-point sweeps over the connections (direct feedthrough at t = 0), then out of initialisation;
        returns every FMU's reads."""
        now = self.now()
        for _ in range(2):
            for name in self.runners:
                if self.inputs_of[name]:
                    self.writes[name].set([now[s[0]][s[1]] for s, _ in self.inputs_of[name]])
            now = self.now()
        for name in self.runners:
            self.runners[name].instance().exitInitializationMode()
        return self.now()

    def inputs(self, name, k, now, prev, new, step, scheme, extrapolation) -> tuple[list, list]:
        """The values and slopes of FMU `name`'s inputs for step k: a source already stepped (Gauss-Seidel)
        interpolated between t and t + h (or its newest value held), else extrapolated from t."""
        values, slopes = [], []
        for (sf, sv), d in self.inputs_of[name]:
            if scheme == "gauss-seidel" and sf in new:
                linear = extrapolation == "linear"
                values.append(now[sf][sv] if linear else new[sf][sv])
                slopes.append((new[sf][sv] - now[sf][sv]) / step if linear else 0.0)
            else:
                values.append(now[sf][sv])
                slopes.append(now[d[0]][d[1]] if d is not None else
                              (now[sf][sv] - prev[sf][sv]) / step if k else 0.0)
        return values, slopes

    def step(self, k, now, prev, step, scheme, extrapolation) -> dict:
        """Every FMU stepped from t = k step to t + step, in the dict's order; returns their reads at t + step."""
        t, new = k * step, {}
        for name in self.runners:
            if self.inputs_of[name]:
                values, slopes = self.inputs(name, k, now, prev, new, step, scheme, extrapolation)
                self.writes[name].set(values)
                if extrapolation == "linear" and self.interpolates[name]:
                    self.writes[name].set_slopes(slopes)
            w = self.reads[name]
            status = w.fmu.fmi2DoStep(w.comp, t, step, 1)
            if status != 0:
                raise RuntimeError(f"FMU '{name}' failed in the step from t = {t:g} s (status {status})")
            new[name] = w.get()
        return new


def cosimulate(fmus: dict[str, str | FmuRunner], connections: list[Connection], stop_time: float, step: float,
               record: list[str], params: dict[str, dict] | None = None, scheme: str = "gauss-seidel",
               extrapolation: str = "linear", tolerance: float = 1e-8) -> CoSimResult:
    """Couple co-simulation FMUs (name -> file or FmuRunner) with a fixed communication step [s].

    The dict order of `fmus` is the Gauss-Seidel order. Returns the `record`ed variables ("fmu.variable")
    at every communication point from 0 to stop_time.
    """
    n = _check_request(scheme, extrapolation, stop_time, step)
    runners = {k: v if isinstance(v, FmuRunner) else FmuRunner(str(v)) for k, v in fmus.items()}
    params = params or {}
    for name in params:
        if name not in runners:
            raise ValueError(f"parameters given for unknown FMU '{name}'; FMUs: {', '.join(runners)}")
    conns = [(_split(c.source, runners), _split(c.target, runners),
              _split(c.derivative, runners) if c.derivative else None) for c in connections]
    rec = [_split(r, runners) for r in record]
    targets = [t for _, t, _ in conns]
    if len(set(targets)) != len(targets):
        raise ValueError("an input is driven by more than one connection")
    for name, r in runners.items():
        r.check_parameters(params.get(name, {}))
        fmu = r.instance()
        fmu.reset()
        fmu.setupExperiment(tolerance=tolerance, startTime=0.0)
        r.set_parameters(fmu, params.get(name, {}))
        fmu.enterInitializationMode()
    coupling = _Coupling(runners, conns, rec)
    now = prev = coupling.initialise()
    out = np.empty((n + 1, len(rec)))
    out[0] = [now[f][v] for f, v in rec]
    for k in range(n):
        prev, now = now, coupling.step(k, now, prev, step, scheme, extrapolation)
        out[k + 1] = [now[f][v] for f, v in rec]
    for r in runners.values():
        r.instance().terminate()
    return CoSimResult(np.arange(n + 1) * step, {ref: out[:, j] for j, ref in enumerate(record)})
