"""Run the FMU on measured files: the input as measured (band-limited upsampling for periodic records,
a cubic spline otherwise), outputs on the file's time grid. A periodic record is taken as steady state:
periods are simulated in front of it and dropped. A failed or diverging run returns None."""
from __future__ import annotations

import functools
import time
from dataclasses import dataclass, field, replace

import numpy as np

from pyfit.analysis import kinematics
from pyfit.analysis.kinematics import ORDER
from pyfit.analysis.signals import high_passed, without_offset
from pyfit.gap.effect import COORDINATES
from pyfit.gap.effects import output_effects
from pyfit.io.data import Measurement
from pyfit.runtime.fmu import FmuRunner
from pyfit.runtime.drive import drive


# the candidates' parameters that act on the recorded channels, not in the FMU (a channel skew, a gain), each with
# how it changes them (pyfit.gap.effects: Builtin.on_outputs), applied in this order
ON_OUTPUTS = output_effects()

# wall-clock limit of one simulation in a diagnosis [s]: a record simulates in well under a second to a few
# seconds; a parameter set so stiff that the integrator crawls (a friction smoothed over a tiny velocity beside a
# hard spring) counts as failed, as a diverging one does, instead of holding a fit for hours
MAX_WALL_S = 60.0
# ... and, once the nominal is calibrated, SLOW_FACTOR times that nominal's simulation of the same record (at least
# MIN_WALL_S, at most MAX_WALL_S): the fits of the effects named in the stored campaigns took at most 6.2 times
# the nominal's time per evaluation, while a stiff loop's evaluations ran into the 60 s limit (6,700 times it on
# damper calibration campaign case 78, where 6 of 141 simulations took 335 of the 336 s)
SLOW_FACTOR = 50.0
MIN_WALL_S = 0.5


@dataclass
class Record:
    """One measurement prepared for simulation and comparison (SI units)."""

    name: str
    level: str
    level_value: float
    fs: float
    inputs: dict  # model variable -> samples, less their mean
    outputs: dict  # model variable -> the compared samples (from `first` on), less their mean
    samples_per_period: int  # 0: not periodic
    weights: dict = field(default_factory=dict)  # output model variable -> weight in the fits (default 1)
    derived: tuple = ()  # inputs derived from the recorded motion (not measured)
    first: int = 0  # samples of a record that does not start at rest, simulated from rest but not compared
    support: tuple = ()  # (displacement, velocity) inputs of a support motion whose displacement was integrated:
    # the model is simulated from rest relative to that support (simulate)
    smooth_inputs: bool = False  # the FMU is driven by the inputs' cubic spline (pyfit.runtime.drive)
    max_wall_s: float = MAX_WALL_S  # a simulation of it still running after this many seconds [s] counts as failed
    # (a diagnosis sets it from the calibrated nominal's own simulation time: with_time_limits)
    compared_from_hz: float = 0.0  # outputs compared above this [Hz] only (measured and simulated through the same
    # high-pass: a motion input integrated from a velocity or an acceleration carries a drift below it)

    def compared(self, name: str) -> np.ndarray:
        """An input over the samples that are compared (from `first` on)."""
        return self.inputs[name][self.first:]

    @property
    def periodic(self) -> bool:
        return self.samples_per_period > 0

    @property
    def n(self) -> int:
        return len(next(iter(self.outputs.values())))


def starts_at_rest(m: Measurement, samples: int = 5, fraction: float = 0.05) -> bool:
    """Whether the record starts from rest: over the first `samples` samples every output stays within
    `fraction` of its RMS of the sensor's rest reading, zero (a zeroed sensor) or the record's mean (a sensor
    with its own zero). A response from rest grows from there; a segment cut from a long record starts at
    whatever phase the motion had."""
    def near(v, rest):
        return np.max(np.abs(v[:samples] - rest)) <= fraction * np.sqrt(np.mean((v - rest) ** 2))

    return all(near(v, 0.0) or near(v, np.mean(v)) for c, v in m.values.items() if c in m.outputs)


def record_of(m: Measurement, motion: tuple = (), transient_s: float = 4.0, smooth_inputs: bool = False) -> Record:
    """A Record from a measurement; periodic when its excitation says so (kind multisine, samples_per_period);
    with smooth_inputs, the FMU is driven by its inputs' cubic spline (pyfit.runtime.drive).

    motion: the model's displacement, velocity and acceleration inputs (e.g. x_base, v_base, a_base): the
    ones not recorded are derived from the recorded one (pyfit.analysis.kinematics, band-limited to the
    excited band). A displacement integrated from a velocity or an acceleration has unknown integration
    constants (the drift removal leaves its start, and the velocity's, off by up to a few per cent of the
    motion): the model is then simulated from rest relative to its support (Record.support), not from rest
    with the support displaced, which would ring from that offset.
    Every channel, input and output, is taken less its mean (without_offset): a sensor's zero is neither a
    load nor a motion (the model's equilibrium is the loaded rest position).
    A non-periodic record that does not start at rest (a segment cut from a long record) is simulated from
    rest and its first transient_s seconds (at most a quarter of the record) are not compared (the start-up
    transient of the simulation)."""
    spp = m.samples_per_period
    n = len(m.t)
    if spp and n % spp:
        raise ValueError(f"{m.path}: {n} samples is not a whole number of periods of {spp} "
                         "([excitation] samples_per_period)")
    inputs = {k: without_offset(v) for k, v in m.by_variable("inputs").items()}  # a sensor's zero is no load
    inputs, derived, compared_from = _with_motion(m, inputs, motion, spp)
    weights = {ch.model_variable: ch.weight for ch in m.outputs.values()}
    # at most a quarter of a short record is given up to the start-up transient: of a record that does not start at
    # rest, and of one whose displacement was integrated from a drifting sensor (the drift's start, an acceleration
    # the model at rest meets as a step, sets it ringing)
    settled = starts_at_rest(m) and not compared_from
    first = 0 if spp or settled else min(int(round(transient_s * m.sample_rate_hz)), n // 4)
    support = motion[:2] if motion and motion[0] in derived and not spp else ()  # x integrated
    outputs = {k: without_offset(_compared(v, m.sample_rate_hz, compared_from)[first:])
               for k, v in m.by_variable("outputs").items()}
    # a file without a `level` label is named by its file in every table and figure
    return Record(m.name, m.level or m.name, float(m.level_value if m.level_value is not None else 0.0),
                  m.sample_rate_hz, inputs, outputs, spp, weights, derived, first, support, smooth_inputs,
                  compared_from_hz=compared_from)


COMPARED_FROM = 0.5  # outputs compared above this share of the excited band's lower edge where x drifts
# a recorded motion with more than this share of its energy below that frequency drifts (an accelerometer whose slow
# noise is 2 % of its RMS: 1e-3 of its energy there, kinematics.share_below; the generator's exact clamp motion under
# a sweep, a stepped sine or band-limited noise: 2e-7 to 1.1e-5, tests/test_integrated_drift.py)
DRIFT_SHARE = 1e-4


def _with_motion(m: Measurement, inputs: dict, motion: tuple, spp: int) -> tuple[dict, tuple, float]:
    """The inputs with the model's displacement, velocity and acceleration (`motion`) each derived from the
    recorded one where not recorded (kinematics.complete); the ones derived; and the frequency [Hz] above which the
    record is compared (0: all of it). A displacement integrated from a record that is not periodic drifts below the
    excited band where its sensor drifts (an accelerometer's offset and slow noise, integrated twice): where the
    recorded motion holds more than DRIFT_SHARE of its energy below COMPARED_FROM of the lower edge of the band
    that holds nearly all of it (kinematics.energy_band, share_below), the outputs are compared above that
    frequency only."""
    if not motion:
        return inputs, (), 0.0
    recorded = {kind: inputs[var] for kind, var in zip("xva", motion) if var in inputs}
    if not recorded:
        raise ValueError(f"{m.path.with_suffix('.toml')}: [inputs] needs the motion as one of "
                         f"{', '.join(motion)} (model_variable), in m, mm, m/s, m/s2 or g")
    fs, lowest = m.sample_rate_hz, min(recorded, key=ORDER.get)
    cut = 0.0 if spp or lowest == "x" else COMPARED_FROM * kinematics.energy_band(recorded[lowest], fs)[0]
    compared_from = cut if cut and kinematics.share_below(recorded[lowest], fs, cut) > DRIFT_SHARE else 0.0
    band = kinematics.excited_band(next(iter(recorded.values())), fs, samples_per_period=spp)
    full = kinematics.complete(recorded, fs, band, periodic=bool(spp))
    derived = tuple(var for kind, var in zip("xva", motion) if var not in inputs)
    return {**inputs, **{var: full[kind] for kind, var in zip("xva", motion)}}, derived, compared_from


def _compared(y: np.ndarray, fs: float, from_hz: float) -> np.ndarray:
    """An output as it is compared: above from_hz only (signals.high_passed; 0: as it is)."""
    return high_passed(y, fs, from_hz) if from_hz > 0 else y


def scaled(rec: Record, factor: float) -> Record:
    """The same record with its inputs multiplied by factor (outputs unchanged: for predictions only)."""
    return replace(rec, name=f"{rec.name}x{factor:g}", level=f"{rec.level} x{factor:g}",
                   level_value=rec.level_value * factor, inputs={k: v * factor for k, v in rec.inputs.items()})


# relative error bound of the FMU's adaptive integrator in a diagnosis run: the outputs stay within 1e-4 of their
# RMS of a 1e-10 run (test_records.py), a tenth or less of a record's sensor noise
TOLERANCE = 1e-6
# the same for a record driven by its inputs' cubic spline: its input error no longer dominates, and the outputs
# stay within 2e-4 of their RMS of a run at 1e-9 at 16 times the sensor rate (tests/test_spline_drive.py), for
# less than a 1e-6 run costs on the damper (bench/input_order.py)
SPLINE_TOLERANCE = 1e-5


def tolerance_of(rec: Record) -> float:
    """The integrator's relative tolerance a diagnosis simulates a record at: SPLINE_TOLERANCE when its inputs'
    spline drives the FMU, else TOLERANCE."""
    return SPLINE_TOLERANCE if rec.smooth_inputs else TOLERANCE


def simulate(runner: FmuRunner, rec: Record, params: dict, upsample: int = 4, lead_periods: int = 1,
             tolerance: float | None = None, outputs=None, remembered: bool = True) -> dict | None:
    """Outputs (model variable -> the compared samples of the record's grid, less their mean; default: the
    record's outputs, through the record's high-pass where it has one: Record.compared_from_hz) for FMU parameters
    params; None on failure. A periodic record is driven by its period
    averaged over the record (pyfit.runtime.drive): its steady state, one period simulated after lead_periods
    (at least one) and repeated over the record's periods. tolerance: the integrator's (None: the record's,
    tolerance_of). remembered=False: the FMU runs even where this process made the same run before
    (pyfit.runtime.drive), to time it."""
    if tolerance is None:
        tolerance = tolerance_of(rec)
    on_outputs = {n: params[n] for n in ON_OUTPUTS if n in params}  # not FMU parameters, nor are the coordinates
    params = {n: v for n, v in params.items() if n not in on_outputs and n not in COORDINATES}
    inputs, repeat = rec.inputs, 1
    rigid = None
    if rec.support:  # from rest relative to the support: its start moved to rest, the outputs moved back
        xs, vs = rec.support
        x0, v0 = inputs[xs][0], inputs[vs][0]
        rigid = (x0 + v0 * np.arange(len(inputs[xs])) / rec.fs, v0)
        inputs = {**inputs, xs: inputs[xs] - rigid[0], vs: inputs[vs] - v0}
    if rec.periodic:  # one averaged period in: the drive repeats it over the lead and the one period out
        repeat = rec.n // rec.samples_per_period
        inputs = {k: v.reshape(repeat, rec.samples_per_period).mean(axis=0) for k, v in rec.inputs.items()}
    res = drive(runner, inputs, rec.fs, list(outputs or rec.outputs), params, upsample, rec.samples_per_period,
                max(lead_periods, 1) if rec.periodic else 0, tolerance, rec.max_wall_s, rec.smooth_inputs, remembered)
    if not res.ok:
        return None
    values = res.values if rigid is None else {k: _moved_back(runner, k, v, *rigid) for k, v in res.values.items()}
    from_hz = rec.compared_from_hz if outputs is None else 0.0  # the record's own outputs: as they are compared
    return {k: without_offset(_compared(_on_outputs(np.tile(v, repeat), on_outputs, rec), rec.fs, from_hz)[rec.first:])
            for k, v in values.items()}


def _on_outputs(values: np.ndarray, effects: dict, rec: Record) -> np.ndarray:
    """A simulated output as the recorded channel reads it with the effects on the channels `effects` (parameter ->
    value) applied to it."""
    for name, value in effects.items():
        values = ON_OUTPUTS[name](values, value, rec.fs, rec.periodic)
    return values


def with_time_limits(runner: FmuRunner, records: list[Record], params: dict, upsample: int = 4,
                     lead_periods: int = 1, repeats: int = 3) -> list[Record]:
    """The records, each with max_wall_s set to SLOW_FACTOR times its simulation's wall time at `params` (the
    fastest of `repeats` runs), within [MIN_WALL_S, MAX_WALL_S] [s]: a parameter set whose simulation takes that
    much longer than the calibrated nominal's crawls through a stiff integration and counts as failed. Each of
    the runs is made (not returned from the process's memory of runs, which would time a look-up)."""
    limited = []
    for rec in records:
        took = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            simulate(runner, rec, params, upsample, lead_periods, remembered=False)
            took.append(time.perf_counter() - t0)
        limited.append(replace(rec, max_wall_s=min(MAX_WALL_S, max(MIN_WALL_S, SLOW_FACTOR * min(took)))))
    return limited


def _moved_back(runner: FmuRunner, name: str, values: np.ndarray, x_rigid: np.ndarray, v_rigid: float
                ) -> np.ndarray:
    """An output of a run in the frame of the support's rigid start motion (x_rigid [m] over the samples,
    v_rigid [m/s]) back in the fixed frame: displacements [m] and velocities [m/s] (the FMU's units) move with
    the frame; accelerations, forces and rotations do not."""
    unit = runner.variables[name].unit
    return values + x_rigid if unit == "m" else values + v_rigid if unit == "m/s" else values


def residuals(sim: dict | None, rec: Record, penalty: float = 10.0, of=None) -> np.ndarray:
    """Stacked sqrt(w) (y_sim - y_meas) / RMS(y_meas) / sqrt(n) per channel (w: the channel's weight, default
    1): its sum of squares is the weighted sum of the channels' squared NRMSE. `of`: a transform of each
    channel's samples applied to both first (None: the samples themselves). A failed simulation gives the
    finite penalty vector."""
    parts = []
    for k, y in rec.outputs.items():
        meas = y if of is None else of(y, rec.fs)
        scale = np.sqrt(np.mean(meas**2)) * np.sqrt(len(y)) / np.sqrt(rec.weights.get(k, 1.0))
        parts.append(np.full(len(y), penalty / np.sqrt(len(y))) if sim is None
                     else ((sim[k] if of is None else of(sim[k], rec.fs)) - meas) / scale)
    return np.concatenate(parts)


@functools.lru_cache(maxsize=16)
def _low_pass(normalised_cutoff: float) -> tuple[np.ndarray, np.ndarray]:
    """The envelope's 2nd-order Butterworth (b, a) at a cutoff over Nyquist: designed once, not per residual."""
    import scipy.signal

    return scipy.signal.butter(2, normalised_cutoff)


def envelope(y: np.ndarray, fs: float, cutoff_hz: float = 2.0) -> np.ndarray:
    """Amplitude envelope of a record: |analytic signal| (Hilbert) of y minus its mean, low-passed at
    cutoff_hz (2nd-order Butterworth, zero phase)."""
    import scipy.signal

    e = np.abs(scipy.signal.hilbert(y - np.mean(y)))
    b, a = _low_pass(min(cutoff_hz / (fs / 2), 0.5))
    return scipy.signal.filtfilt(b, a, e)


def envelope_residuals(sim: dict | None, rec: Record, penalty: float = 10.0) -> np.ndarray:
    """residuals() of the amplitude envelopes. Where the waveform residual of a sweep through a jump (a
    hardening spring) or a narrow resonance changes by a whole cycle for a parameter change of a few per
    cent, the envelope residual grows in proportion to it: a smooth target that finds the basin the
    waveform fit then refines."""
    return residuals(sim, rec, penalty, of=envelope)
