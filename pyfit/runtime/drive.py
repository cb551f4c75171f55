"""Drive an FMU with measured inputs: the one path from sampled signals to the FMU's response on the
measurement's own time grid (used by the fit objective, the gap diagnosis and the benchmark validation).

A sensor samples at fs; the FMU must see the continuous input the test bench applied. The samples are
upsampled by `upsample` before they drive the FMU (which interpolates linearly between them, with the
slopes sent as input derivatives): band-limited (FFT zero padding) for records of whole periods, a cubic
spline otherwise (linear interpolation of a 750 Hz record with content up to 150 Hz would itself be a
model error of several per cent). With `smooth_inputs`, the FMU follows the cubic spline of the upsampled
samples instead of the lines between them: each step's input is the quadratic through the spline at the
step's start, middle and end (sent as input derivatives of orders 1 and 2): at twice the sensor rate it
errs less than the lines at four times, at lower cost (tests/test_spline_drive.py, bench/input_order.py).
"""
from __future__ import annotations

import pathlib

import numpy as np

from pyfit.analysis.signals import periodic_drive, step_quadratics, upsample_spline
from pyfit.runtime.fmu import FmuRunner, SimulationResult
from pyfit.runtime.memo import BoundedMemo, digest


def fine_inputs(inputs: dict[str, np.ndarray], upsample: int, samples_per_period: int | None = None,
                lead_periods: int = 0) -> tuple[dict[str, np.ndarray], int]:
    """Inputs on the FMU's drive grid (fs·upsample) and the number of leading drive samples to drop.

    samples_per_period: the record is whole periods of this length: the period (averaged over the record's
    periods, which also averages out sensor noise) is upsampled band-limited and repeated, preceded by
    lead_periods periods that bring the FMU to its periodic steady state. None: cubic spline, from rest."""
    q = int(upsample)
    if samples_per_period:
        out = {}
        for k, v in inputs.items():
            v = np.asarray(v, float)
            periods = len(v) // samples_per_period
            period = v[:periods * samples_per_period].reshape(periods, samples_per_period).mean(axis=0)
            out[k] = periodic_drive(period, q, periods + lead_periods) if q > 1 else \
                np.concatenate([np.tile(period, periods + lead_periods), period[:1]])
        return out, lead_periods * samples_per_period * q
    if q == 1:
        return {k: np.asarray(v, float) for k, v in inputs.items()}, 0
    return {k: upsample_spline(np.asarray(v, float), q) for k, v in inputs.items()}, 0


# what a process remembers (pyfit.runtime.memo): inputs upsampled for the FMU (a fit drives the same few records
# hundreds of times; upsampling one is a few per cent of its simulation) and responses (a fit evaluates many
# parameter sets more than once)
FINE_MEMO = BoundedMemo(64 * 2**20)
RESPONSE_MEMO = BoundedMemo(256 * 2**20)


def remembered_fine_inputs(inputs: dict[str, np.ndarray], upsample: int, samples_per_period: int | None = None,
                           lead_periods: int = 0, source: str | None = None) -> tuple[dict[str, np.ndarray], int]:
    """fine_inputs, computed once for inputs equal in value to ones this process upsampled lately (an input
    changed in place is upsampled anew); the arrays returned are shared between calls: read them only.
    source: digest(inputs as float arrays), when the caller has it already."""
    arrays = {k: np.asarray(v, float) for k, v in inputs.items()}
    key = _fine_key(source or digest(arrays), upsample, samples_per_period, lead_periods)
    found = FINE_MEMO.get(key)
    if found is None:
        found = fine_inputs(arrays, upsample, samples_per_period, lead_periods)
        FINE_MEMO.put(key, found, sum(v.nbytes for v in found[0].values()))
    return found


def _fine_key(source: str, upsample: int, samples_per_period: int | None, lead_periods: int) -> str:
    """What names a record's upsampled inputs in FINE_MEMO: its inputs' digest and how they were upsampled."""
    return digest(source, int(upsample), samples_per_period or 0, lead_periods)


def remembered_derivatives(fine: dict[str, np.ndarray], dt: float, key: str) -> tuple[dict, dict]:
    """(slopes, curvatures): each step's input quadratic from the upsampled inputs' cubic splines (interval
    dt [s]; signals.step_quadratics), computed once per `key` (the digest of the inputs and how they were
    upsampled); shared arrays: read them only."""
    key = digest("derivatives", key, dt)
    found = FINE_MEMO.get(key)
    if found is None:
        pairs = {k: step_quadratics(v, dt) for k, v in fine.items()}
        found = ({k: d[0] for k, d in pairs.items()}, {k: d[1] for k, d in pairs.items()})
        FINE_MEMO.put(key, found, sum(2 * v.nbytes for v in fine.values()))
    return found


def drive(runner: FmuRunner, inputs: dict[str, np.ndarray], fs: float, outputs: list[str], params: dict,
          upsample: int = 4, samples_per_period: int | None = None, lead_periods: int = 0,
          tolerance: float = 1e-8, max_wall_s: float | None = None, smooth_inputs: bool = False,
          remembered: bool = True) -> SimulationResult:
    """Simulate the FMU driven by measured inputs (model variable -> samples at fs [Hz]); with smooth_inputs,
    by the cubic spline of the upsampled samples (co-simulation FMUs that take input derivatives of order 2).

    Returns the outputs at the record's own samples (t = 0, 1/fs, ...), as many as the inputs have; a run
    that fails, returns a non-finite value or takes longer than max_wall_s seconds gives ok=False with the
    reason (never an exception). A successful run this process made with the same FMU file, inputs, parameters
    and settings is not made again: its outputs are returned (copies; the same values to the bit); with
    remembered=False the run is made in any case (to time it)."""
    file = pathlib.Path(runner.path).stat()
    source = digest({k: np.asarray(v, float) for k, v in inputs.items()})  # hashed once per run
    key = digest(runner.path, runner.interface, file.st_mtime_ns, file.st_size, source, fs, list(outputs),
                 sorted(params.items()), int(upsample), samples_per_period or 0, lead_periods, tolerance,
                 bool(smooth_inputs))
    known = RESPONSE_MEMO.get(key) if remembered else None
    if known is not None:
        return SimulationResult(known.time.copy(), {k: v.copy() for k, v in known.values.items()})
    res = _driven(runner, inputs, fs, outputs, params, upsample, samples_per_period, lead_periods, tolerance,
                  max_wall_s, source, smooth_inputs)
    if res.ok:  # kept compact (the outputs are strided views of the FMU's finer grid)
        kept = SimulationResult(res.time.copy(), {k: v.copy() for k, v in res.values.items()})
        RESPONSE_MEMO.put(key, kept, kept.time.nbytes + sum(v.nbytes for v in kept.values.values()))
    return res


def _driven(runner: FmuRunner, inputs: dict[str, np.ndarray], fs: float, outputs: list[str], params: dict,
            upsample: int, samples_per_period: int | None, lead_periods: int, tolerance: float,
            max_wall_s: float | None, source: str, smooth_inputs: bool = False) -> SimulationResult:
    """drive's run of the FMU (no response remembered; source: the inputs' digest)."""
    n = len(next(iter(inputs.values())))
    fine, skip = remembered_fine_inputs(inputs, upsample, samples_per_period, lead_periods, source)
    n_fine = len(next(iter(fine.values())))
    dt = 1.0 / (fs * upsample)
    t = np.arange(n_fine) * dt
    derivatives = remembered_derivatives(fine, dt, _fine_key(source, upsample, samples_per_period, lead_periods)) \
        if smooth_inputs else None
    res = runner.simulate(t[-1], dt, list(outputs), params, inputs=fine, input_time=t, tolerance=tolerance,
                          max_wall_s=max_wall_s, input_derivatives=derivatives)
    grid = np.arange(n) / fs
    if not res.ok:
        return SimulationResult(grid, {k: np.full(n, np.nan) for k in outputs}, False, res.message)
    values = {k: res[k][skip::upsample][:n] for k in outputs}
    bad = [k for k, v in values.items() if len(v) != n or not np.all(np.isfinite(v))]
    if bad:
        return SimulationResult(grid, values, False, f"output '{bad[0]}' is not finite: the simulation diverged")
    return SimulationResult(grid, values)
