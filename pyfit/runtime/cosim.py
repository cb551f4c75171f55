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


def cosimulate(fmus: dict[str, str | FmuRunner], connections: list[Connection], stop_time: float, step: float,
               record: list[str], params: dict[str, dict] | None = None, scheme: str = "gauss-seidel",
               extrapolation: str = "linear", tolerance: float = 1e-8) -> CoSimResult:
    """Couple co-simulation FMUs (name -> file or FmuRunner) with a fixed communication step [s].

    The dict order of `fmus` is the Gauss-Seidel order. Returns the `record`ed variables ("fmu.variable")
    at every communication point from 0 to stop_time.
    """
    if scheme not in SCHEMES:
        raise ValueError(f"scheme '{scheme}' unknown; allowed: {', '.join(SCHEMES)}")
    if extrapolation not in EXTRAPOLATIONS:
        raise ValueError(f"extrapolation '{extrapolation}' unknown; allowed: {', '.join(EXTRAPOLATIONS)}")
    n = int(round(stop_time / step))
    if n < 1 or abs(n * step - stop_time) > 1e-9 * max(stop_time, 1.0):
        raise ValueError(f"stop_time {stop_time} s is not a whole number of communication steps {step} s")
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
    # every output any connection or the record reads, per FMU, read in one call
    needed = [src for src, _, _ in conns] + [d for _, _, d in conns if d] + rec
    reads = {name: _Vars(r, sorted({v for f, v in needed if f == name})) for name, r in runners.items()}
    inputs_of = {name: [(s, d) for s, t, d in conns if t[0] == name] for name in runners}
    writes = {name: _Vars(r, [t[1] for _, t, _ in conns if t[0] == name]) for name, r in runners.items()}
    interpolates = {name: bool(r.model_description.coSimulation.canInterpolateInputs)
                    for name, r in runners.items()}

    # initial values: two fixed-point sweeps over the connections (direct feedthrough at t = 0)
    now = {name: reads[name].get() for name in runners}
    for _ in range(2):
        for name in runners:
            if inputs_of[name]:
                writes[name].set([now[s[0]][s[1]] for s, _ in inputs_of[name]])
        now = {name: reads[name].get() for name in runners}
    for name in runners:
        runners[name].instance().exitInitializationMode()
    now = {name: reads[name].get() for name in runners}
    prev = now
    out = np.empty((n + 1, len(rec)))
    out[0] = [now[f][v] for f, v in rec]

    for k in range(n):
        t = k * step
        new = {}
        for name in runners:
            if inputs_of[name]:
                values, slopes = [], []
                for (sf, sv), d in inputs_of[name]:
                    if scheme == "gauss-seidel" and sf in new:  # source already at t + h
                        if extrapolation == "linear":  # interpolate between t and t + h
                            values.append(now[sf][sv])
                            slopes.append((new[sf][sv] - now[sf][sv]) / step)
                        else:  # hold the newest value
                            values.append(new[sf][sv])
                            slopes.append(0.0)
                    else:  # extrapolate from t
                        values.append(now[sf][sv])
                        if d is not None:
                            slopes.append(now[d[0]][d[1]])
                        else:
                            slopes.append((now[sf][sv] - prev[sf][sv]) / step if k else 0.0)
                writes[name].set(values)
                if extrapolation == "linear" and interpolates[name]:
                    writes[name].set_slopes(slopes)
            w = reads[name]
            status = w.fmu.fmi2DoStep(w.comp, t, step, 1)
            if status != 0:
                raise RuntimeError(f"FMU '{name}' failed in the step from t = {t:g} s (status {status})")
            new[name] = w.get()
        prev, now = now, new
        out[k + 1] = [now[f][v] for f, v in rec]
    for r in runners.values():
        r.instance().terminate()
    return CoSimResult(np.arange(n + 1) * step, {ref: out[:, j] for j, ref in enumerate(record)})
