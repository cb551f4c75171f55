"""The systems a diagnosis knows: FMU, nominal (linear) free parameters with their start and bounds, and the
candidate effects of theory §6 (declared in pyfit.gap.effects). The nominal model is what the user describes
(pyfit.io.nominal.NominalModel); every dimension not described comes from the FMU's own defaults (the .mo
files), none is written here.

Effect bounds and start values follow from the data scale: sigma_y = RMS of the deflection of the nonlinear
element (SDOF: y; damper: cable end relative to the clamp) as the calibrated nominal model simulates it from
the measured inputs (whatever the sensors were), sigma_v = RMS of its rate, and the nominal stiffness k of
that element (SI units throughout).
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
import scipy.signal

from pyfit.gap.effect import Effect, Scale
from pyfit.gap.effects import candidates, switches
from pyfit.gap.localise import excited_band


@dataclass(frozen=True)
class System:
    """A model family for the diagnosis."""

    name: str
    fmu: str
    nominal_fixed: dict  # switches that make the FMU the nominal model, and the described known parameters
    linear: tuple  # the nominal model's free parameters
    stiffness: str  # the one of them that a hysteretic element's tangent stiffness replaces in part
    start: callable  # records -> start values of `linear`
    data_starts: callable  # (records, modes_of, calibrated=None) -> other starts of `linear` (see make_system)
    bounds: callable  # (start, softened) -> bounds of `linear`
    scale: callable  # (deflections, fs, nominal params, calibration records) -> Scale
    effects: dict
    lead_periods: int = 1  # periods simulated before a periodic record (the decay of the slowest mode)
    deflection_outputs: tuple = ()  # FMU outputs that give the nonlinear element's deflection
    motion_inputs: tuple = ()  # displacement, velocity, acceleration inputs that must be consistent (or ())
    deflection: callable = None  # (simulated outputs, record) -> the element's deflection [m]
    damping: tuple = ()  # the damping parameters among `linear` the nominal's damping scan scales together
    upsample: int = 4  # the FMU's drive grid = the sensor rate x this, for files at pyfit.gap.rate.REFERENCE_HZ (a
    # faster file keeps the grid's points a second: rate.drive_upsample; DiagnoseConfig.upsample overrides it)
    smooth_inputs: bool = False  # drive the FMU with the inputs' cubic spline (pyfit.runtime.drive), not lines
    gains_free: bool = False  # every parameter is fitted from the data (a family that starts from the data, none
    # described): a channel's unknown gain (a voltage read in the model's unit) rescales them and no verdict
    outside: str = ""  # effects outside the candidates that are common in such systems (a report's hint)


GRID_NEAR = np.geomspace(0.8, 1.25, 9)  # a member's strengths at its refit times these ...
GRID_ACROSS = np.geomspace(1e-4, 1.0, 9)  # ... at each end of their range (one that holds zero) times these


def strength_grid(members: list[Effect], scale: Scale, values: dict) -> tuple[dict, ...]:
    """Points spanning the strengths of a model's `members` (each member's strength parameters moved together:
    at `values` x GRID_NEAR, at each nonzero end of their ranges x GRID_ACROSS when the range holds zero, and
    at zero), every other parameter where `values` has it: the product over the members (a grid of a pair's two
    strengths, where two effects trading off, a hardening spring and a damper that both set where a sweep jumps,
    leave a narrow valley a descent from either member's refit does not find)."""
    axes = []
    for e in members:
        ranges = {p.name: p.range(scale) for p in e.params if not p.shape}
        if not ranges:
            continue
        axis = [{n: values[n] * f for n in ranges} for f in GRID_NEAR] if any(values[n] for n in ranges) else []
        if all(lo <= 0.0 <= hi for lo, _, hi in ranges.values()):
            for end in (0, 2):
                if any(r[end] for r in ranges.values()):
                    axis += [{n: r[end] * f for n, r in ranges.items()} for f in GRID_ACROSS]
            axis.append(dict.fromkeys(ranges, 0.0))
        if axis:  # (a member at zero whose range does not hold zero has no points: it stays where it is)
            axes.append(axis)
    return tuple({n: v for point in combo for n, v in point.items()} for combo in itertools.product(*axes))


# ---- SDOF --------------------------------------------------------------------------------------------------
OUTPUT_ORDER = {"y": 0, "v": 1, "a": 2}  # SDOF outputs: displacement, velocity, acceleration


def _frf_lines(rec, name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(ω [rad/s], H of the displacement, weight) on the lines the input excites. Whole periods: the DFT lines
    (exact, no leakage). Otherwise the H1 estimate S_uy/S_uu from Welch segments (noise on the output averages
    out), on the bins where the input has power, within the band that holds nearly all of its energy
    (localise.excited_band: below it an accelerometer's slow drift, divided by ω², would pass for a huge
    displacement FRF) and where the coherence is above 0.5, weighted by the coherence."""
    u, y = rec.compared(next(iter(rec.inputs))), rec.outputs[name]
    if rec.samples_per_period:
        U, Y = np.fft.rfft(u), np.fft.rfft(y)
        w = 2 * np.pi * np.fft.rfftfreq(len(u), 1.0 / rec.fs)
        ex = (np.abs(U) > 1e-3 * np.abs(U).max()) & (w > 0)
        H, weight = Y[ex] / U[ex], np.ones(int(ex.sum()))
    else:
        seg = int(min(len(u), max(rec.fs, len(u) // 8)))
        f, suu = scipy.signal.welch(u, rec.fs, nperseg=seg)
        _, suy = scipy.signal.csd(u, y, rec.fs, nperseg=seg)
        _, coh = scipy.signal.coherence(u, y, rec.fs, nperseg=seg)
        w = 2 * np.pi * f
        lo, hi = excited_band(rec)
        ex = (suu > 1e-3 * suu[1:].max()) & (f >= lo) & (f <= hi) & (coh > 0.5)
        H, weight = suy[ex] / suu[ex], coh[ex]
    return w[ex], H / (1j * w[ex]) ** OUTPUT_ORDER[name], weight


def sdof_start(records) -> dict:
    """m, c, k of a linear SDOF from the measured FRF (the output converted to displacement: /(iω) per time
    derivative): 1/H = k - ω²m + iωc, solved by least squares weighted by |H| (relative error) and by the
    coherence; any recorded input, sweeps and noise as well as multisines."""
    rows, rhs = [], []
    for rec in records:
        name = next((k for k in rec.outputs if k in OUTPUT_ORDER), None)
        if name is None:
            raise ValueError(f"{rec.name}: the SDOF start needs an output y, v or a; outputs: {', '.join(rec.outputs)}")
        w, H, weight = _frf_lines(rec, name)
        G = 1.0 / H
        wt = weight * np.abs(H)
        rows += [np.column_stack([-w ** 2 * wt, 0 * wt, wt]), np.column_stack([0 * wt, w * wt, 0 * wt])]
        rhs += [G.real * wt, G.imag * wt]
    m, c, k = np.linalg.lstsq(np.vstack(rows), np.concatenate(rhs), rcond=None)[0]
    return {"m": float(abs(m)), "c": float(abs(c)), "k": float(abs(k))}


def sdof_file_starts(records, base: dict, modes_of, calibrated: dict | None = None) -> list[dict]:
    """One FRF start per record (sdof_start of that file alone, whatever `base` is): with an
    amplitude-dependent effect, the pooled FRF mixes levels and the file where the effect is weakest gives the
    linear system."""
    return [{**base, **sdof_start([rec])} for rec in records]


def sdof_bounds(start: dict, softened: bool = False) -> dict:
    """Bounds of m, c, k around a linear estimate (k lower when a hysteretic element shares the stiffness)."""
    return {"m": (0.5 * start["m"], 2.0 * start["m"]), "c": (0.1 * start["c"], 5.0 * start["c"]),
            "k": ((0.05 if softened else 0.5) * start["k"], 2.0 * start["k"])}


def deflection_scale(deflections: list[np.ndarray], fs: float, k: float, params: dict,
                     stuck_force: float = 0.0) -> Scale:
    """RMS of the nonlinear element's deflection (simulated by the calibrated nominal model from the measured
    inputs, whatever the sensors were) and of its rate; the stiffness k; the force it transmits when stuck [N]."""
    y = np.concatenate(deflections)
    v = np.concatenate([np.gradient(d) * fs for d in deflections])
    return Scale(float(np.sqrt(np.mean(y**2))), float(np.sqrt(np.mean(v**2))), k, dict(params), stuck_force)


def sdof_deflection(sim: dict, rec) -> np.ndarray:
    return sim["y"]


def sdof_stiffness(params: dict) -> float:
    return params["k"]


# ---- Stockbridge damper ------------------------------------------------------------------------------------
DAMPER_OUTPUT_ORDER = {"F_clamp": 2}  # FRF of an output over the clamp displacement: /(2πf)^order (else by name)


def _damper_order(name: str) -> int:
    return DAMPER_OUTPUT_ORDER.get(name, 2 if name.startswith(("acc_", "a_")) else 1 if name.startswith("v") else 0)


def damper_modal_starts(records, base: dict, modes_of, calibrated: dict | None = None) -> list[dict]:
    """Starts that put the model's resonances onto the resonance peaks the records show
    (pyfit.analysis.modal.frf_peaks of every output over the clamp displacement, from the whole record and from
    Welch segments; peaks within 2 % of one already taken skipped). Which mode a peak is cannot be told from
    the peak alone (a described damper whose EI is far off has its higher modes in the band, or none; the
    whole-record FRF of a noise record shows spurious peaks), so every pairing of a mode with a peak is a
    start, the k-th mode on the k-th peak first, and the calibration keeps the best; `calibrated`: a calibrated
    model whose modes are near the peaks, and each peak goes onto its nearest mode of it only (its EI is
    scaled; its damping is not used: a nominal calibrated on records with a strong effect can carry damping
    far off, and the starts' damping comes from `base`, as do the modes' damping ratios). Each start scales
    EI by (f_peak / f_mode)^2 (the stiffness matrix is proportional to EI) and `base`'s Rayleigh coefficients
    alpha_pd, beta_pd by zeta_peak / zeta_mode, zeta_mode taken at the scaled EI (each mode's damping ratio is
    linear in them); starts within 4 % in EI of one already taken are skipped. modes_of: params -> the model's
    modes (linearised FMU)."""
    from pyfit.analysis.modal import frf_peaks
    from pyfit.gap.localise import excited_range

    lo, hi = excited_range(records)
    # the calibrated model names the modes by its EI alone (its damping can be far enough off to leave modes
    # overdamped)
    identity = {**base, "EI": calibrated["EI"]} if calibrated and "EI" in base else base
    modes = modes_of(identity)
    if not modes or "EI" not in base:
        return []
    peaks = []
    for rec in records:
        u = rec.compared("x_base")
        for name, y in rec.outputs.items():
            for segment_s in (None, 8.0):  # the whole record (a sweep from rest), Welch segments (noise)
                for p in frf_peaks(u, y, rec.fs, (lo, hi), _damper_order(name), segment_s):
                    if all(abs(p.f_n / q.f_n - 1.0) > 0.02 for q in peaks):
                        peaks.append(p)
    peaks.sort(key=lambda p: p.f_n)
    if calibrated:
        pairings = [(min(range(len(modes)), key=lambda i: abs(np.log(p.f_n / modes[i].f_n))), j)
                    for j, p in enumerate(peaks)]
    else:
        pairings = sorted(((i, j) for i in range(len(modes)) for j in range(len(peaks))),
                          key=lambda ij: (abs(ij[0] - ij[1]), ij))
    starts = []
    for i, j in pairings:
        ei = identity["EI"] * (peaks[j].f_n / modes[i].f_n) ** 2
        if any(abs(ei / s["EI"] - 1.0) < 0.04 for s in starts):
            continue
        s = {**base, "EI": ei}
        moved = modes_of(s)
        ratio = float(np.clip(peaks[j].zeta / moved[i].zeta, 0.2, 5.0)) if len(moved) > i else 1.0
        for n in ("alpha_pd", "beta_pd"):
            if n in s:
                s[n] = base[n] * ratio
        starts.append(s)
    return starts


def damper_bounds(start: dict, softened: bool = False) -> dict:
    """Default bounds of EI, alpha_pd, beta_pd around their start."""
    return {"EI": ((0.1 if softened else 0.3) * start["EI"], 3.0 * start["EI"]),
            "alpha_pd": (0.1 * start["alpha_pd"], 10.0 * start["alpha_pd"]),
            "beta_pd": (0.1 * start["beta_pd"], 10.0 * start["beta_pd"])}


def damper_deflection(sim: dict, rec) -> np.ndarray:
    """Cable end 1 relative to the clamp [m]."""
    return sim["x1"] - rec.compared("x_base")


def damper_stiffness(params: dict) -> float:
    """3 EI / L1^3 [N/m], the tip stiffness of arm 1 (EI and L1 of the nominal model)."""
    return 3 * params["EI"] / params["L1"] ** 3


def damper_stuck_force(params: dict, peak_acceleration: float) -> float:
    """The scale [N] of the force an arm's joint transmits when it does not slip: the heavier end mass carried at
    the clamp's peak acceleration [m/s²] (a joint that holds moves its arm end with the clamp; the rotation the
    end mass keeps adds the beam's shear, so a friction above this can still slip near a resonance)."""
    return max(params["m1"], params["m2"]) * peak_acceleration


def _damper_stuck_force_of(records, params: dict) -> float:
    """damper_stuck_force at the clamp's peak acceleration over `records`."""
    return damper_stuck_force(params, max(float(np.max(np.abs(r.compared("a_base")))) for r in records))


@dataclass(frozen=True)
class _Family:
    fmu: str
    switches: dict  # FMU parameters that switch every candidate effect off
    linear: tuple  # the default uncertain parameters
    stiffness: str
    data_start: callable | None  # records -> start values from the data (None: the FMU's defaults)
    data_starts: callable  # (records, start, modes_of, calibrated) -> other starts from the data (file, peak)
    bounds: callable
    stiffness_of: callable  # params -> the nonlinear element's nominal stiffness [N/m]
    deflection: callable  # (simulated outputs, record) -> the element's deflection [m]
    deflection_outputs: tuple
    motion_inputs: tuple
    effects: dict
    lead_periods: int
    damping: tuple = ()  # linear parameters scaled together by the nominal's damping scan (attribute.DAMPING_SCAN)
    stuck_force: callable | None = None  # (records, params) -> Scale.stuck_force [N] (None: 0)
    # how the measured inputs drive the FMU: the drive grid's rate over the sensor rate (of a file at
    # pyfit.gap.rate.REFERENCE_HZ), and whether the FMU follows their cubic spline (pyfit.runtime.drive) or the
    # lines between the samples: the damper's spline at
    # twice the sensor rate errs far less than lines at four times, at lower cost (bench/input_order.py); the
    # SDOF family keeps lines at four times, with which its campaign calibrated the stated confidence
    upsample: int = 4
    smooth_inputs: bool = False
    outside: str = ""  # System.outside


FAMILY = {
    "sdof": _Family("SDOFBoucWen", {"exc_type": 0, **switches("sdof")},
                    ("m", "c", "k"), "k", sdof_start, sdof_file_starts, sdof_bounds, sdof_stiffness, sdof_deflection,
                    ("y",), (), candidates("sdof"), 1, outside="a joint whose loops follow another law than the "
                    "hysteresis candidate's, as a bolted joint's micro-slip does; backlash; a delay between the "
                    "channels"),
    "damper": _Family("StockbridgeDamper", {"exc_type": 0, **switches("damper")},
                      ("EI", "alpha_pd", "beta_pd"), "EI", None, damper_modal_starts, damper_bounds, damper_stiffness,
                      damper_deflection, ("x1",), ("x_base", "v_base", "a_base"), candidates("damper"), 2,
                      ("alpha_pd", "beta_pd"), _damper_stuck_force_of, upsample=2, smooth_inputs=True,
                      outside="a delay between the channels; a gain between them (a sensor's sensitivity off by a "
                      "per cent: the candidate sensor_gain, where the configuration's effects name it); the "
                      "messenger's frequency-dependent loss; a loose clamp's backlash"),
}


def family_fmu(name: str) -> str:
    """The FMU a family's diagnosis runs; a clear error listing the known families otherwise."""
    if name not in FAMILY:
        raise ValueError(f"--model '{name}' unknown; allowed: {', '.join(FAMILY)}")
    return FAMILY[name].fmu


def make_system(name: str, defaults: dict, nominal=None) -> System:
    """The System of family `name` for a nominal model (pyfit.io.nominal.NominalModel, or None for the FMU's
    own defaults). defaults: the FMU's parameter start values (name -> value)."""
    fam = FAMILY[name]
    fixed = dict(nominal.fixed) if nominal else {}
    values = {**defaults, **fixed}
    free = dict(nominal.free) if nominal and nominal.free else {}
    linear = tuple(free) or fam.linear
    given = {n: p.start for n, p in free.items() if p.start is not None}

    def start(records) -> dict:
        from_data = fam.data_start(records) if fam.data_start else {}
        return {n: given.get(n, from_data.get(n, values[n])) for n in linear}

    def data_starts(records, modes_of, calibrated: dict | None = None) -> list[dict]:
        """Other starts from the data, beside start() (the user's or the FMU's values): the SDOF: each file's
        FRF; the damper: the model's resonances moved onto the measured peaks (every pairing; with
        `calibrated` linear values, each peak onto its nearest resonance of those). modes_of: params -> the
        model's modes."""
        base = {**values, **start(records)}
        found = fam.data_starts(records, base, lambda p: modes_of({**p, **fixed, **fam.switches}),
                                None if calibrated is None else {**base, **calibrated})
        return [{n: s[n] for n in linear} for s in found]

    def bounds(st: dict, softened: bool = False) -> dict:
        rule = fam.bounds({**values, **st}, softened)
        out = {}
        for n in linear:
            p = free.get(n)
            if p is not None and p.lower is not None:
                out[n] = (p.lower, p.upper)
            elif n in rule:
                out[n] = rule[n]
            else:  # an uncertain parameter without bounds: a factor 3 either way around its start
                out[n] = tuple(sorted((st[n] / 3.0, st[n] * 3.0)))
        return out

    def scale(deflections: list[np.ndarray], fs: float, params: dict, records=()) -> Scale:
        p = {**values, **params}
        stuck = fam.stuck_force(records, p) if fam.stuck_force and records else 0.0
        return deflection_scale(deflections, fs, fam.stiffness_of(p), p, stuck)

    return System(name, fam.fmu, {**fam.switches, **fixed}, linear, fam.stiffness, start, data_starts, bounds,
                  scale, fam.effects, fam.lead_periods, fam.deflection_outputs, fam.motion_inputs, fam.deflection,
                  tuple(n for n in fam.damping if n in linear), fam.upsample, fam.smooth_inputs,
                  fam.data_start is not None and not fixed, fam.outside)
