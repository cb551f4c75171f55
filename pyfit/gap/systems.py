"""The systems a diagnosis knows: FMU, nominal (linear) free parameters with their start and bounds, and
the candidate effects of theory §6. The nominal model is what the user describes
(pyfit.io.nominal.NominalModel); every dimension not described comes from the FMU's own defaults (the .mo
files), none is written here.

Effect bounds and start values follow from the data scale: sigma_y = RMS of the deflection of the nonlinear
element (SDOF: y; damper: cable end relative to the clamp) as the calibrated nominal model simulates it from
the measured inputs (whatever the sensors were), sigma_v = RMS of its rate, and the nominal stiffness k of
that element (SI units throughout).
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import numpy as np
import scipy.signal

from pyfit.gap.localise import excited_band


@dataclass(frozen=True)
class Scale:
    """Data scale for bounds: element deflection RMS [m], its velocity RMS [m/s], nominal stiffness [N/m],
    the nominal model's parameter values (SI) for effects that are deviations from them, and the scale of the
    force [N] a joint transmits when it does not slip (the damper's heavier mass carried at the clamp's peak
    acceleration, damper_stuck_force; 0 where the family has none)."""

    sigma_y: float
    sigma_v: float
    k: float
    nominal: dict = field(default_factory=dict)
    stuck_force: float = 0.0


@dataclass(frozen=True)
class Param:
    """A fitted parameter: name in the FMU and a function of the Scale giving (lower, start, upper). A `shape`
    parameter is held at its start in the screening, which probes the effect's strength only; a `log` one
    (positive, spanning decades) is fitted on a log scale."""

    name: str
    range: callable
    shape: bool = False
    log: bool = False


@dataclass(frozen=True)
class ExponentScaled:
    """A fixed parameter whose unit depends on a fitted exponent: target = value · reference^(1 − exponent).
    The SDOF Bouc-Wen β [m⁻¹·N^(1−ν)] (theory §1.1): value 1/σ_y and reference the force 0.3·k·σ_y keep
    β·|z|^ν / α of order one at the data's deflection for every ν, so γ and δ stay of order one."""

    target: str
    value: float
    reference: float
    exponent: str

    def __call__(self, params: dict) -> dict:
        return {**params, self.target: self.value * self.reference ** (1.0 - params[self.exponent])}


def with_derived(params: dict, rules: tuple) -> dict:
    """params with every rule (e.g. ExponentScaled) applied in turn."""
    for rule in rules:
        params = rule(params)
    return params


@dataclass(frozen=True)
class Effect:
    """A candidate unmodelled effect: its free parameters, the fixed values that switch it on, the signature
    it leaves (used as evidence in the report), and other starts of its shape parameters spanning the family
    (`starts`: Scale -> list of {parameter: value}; the refit begins from the best of them)."""

    name: str
    params: tuple[Param, ...]
    fixed: callable = field(default=lambda s: {})
    signature: str = ""
    shift_stiffness: float = 0.0  # the effect's start adds this fraction of the stiffness, taken off the nominal
    starts: callable = field(default=lambda s: [])
    members: tuple = ()  # the single effects of a combination (see `combine`); () for a single effect
    signal_only: bool = False  # acts on the recorded channels, not in the FMU (pyfit.gap.simulate applies it)
    derived: callable = field(default=lambda s: ())  # Scale -> rules giving fixed values from fitted ones
    basin: callable = None  # start values -> the basin they lie in (the refit descends from each basin's best)
    # fitted values -> overrides that keep only the effect's linear part (a loop closed to a spring): what a linear
    # element there buys, where the nominal lacks that freedom ([] where it has it, or the effect has no linear part)
    linear_parts: callable = field(default=lambda params: [])
    # a change of the linear system itself (a geometry): within the noise threshold its refit can take up the linear
    # difference between the model and the lab's sensor chain or another simulator, which carries over to the
    # held-out files as well, so it does not tell a gap there (diagnose._detection)
    linear: bool = False
    opt_in: bool = False  # a candidate only where the diagnosis's `effects` name it (DiagnoseConfig.effects)

    @property
    def strengths(self) -> int:
        """How many strength (not shape) parameters the effect adds: what the ranking's score charges for."""
        return sum(not p.shape for p in self.params)

    @property
    def free_shape(self) -> bool:
        """Whether the effect fits a shape of its own (two or more shape parameters: a hysteresis loop's), with
        which it can take up part of another effect (a loop stiffening as a hardening spring does)."""
        return sum(p.shape for p in self.params) >= 2

    def absent(self, scale: Scale) -> dict:
        """Parameter values at which the effect is not there (the nominal model): strengths at zero where their
        range holds it, shape parameters and deviations (e.g. the mass offsets) at their start."""
        out = {}
        for p in self.params:
            lo, st, hi = p.range(scale)
            out[p.name] = 0.0 if (not p.shape and lo <= 0.0 <= hi) else st
        return out


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


def combine(effects: list[Effect]) -> Effect:
    """Several effects at once: their parameters, fixed values and shape starts together (named 'a + b'); the
    basins of a member that has them (a free-shape loop's: a weak loop beside a strong spring lies in another
    basin than the loop alone, and its refit descends from each basin's best start as the loop's does)."""
    names = [e.name for e in effects]
    params, seen = [], set()
    for e in effects:
        params += [p for p in e.params if p.name not in seen]
        seen |= {p.name for p in e.params}
    return Effect(" + ".join(names), tuple(params),
                  fixed=lambda s: {k: v for e in effects for k, v in e.fixed(s).items()},
                  signature="; ".join(f"{e.name}: {e.signature}" for e in effects),
                  shift_stiffness=max(e.shift_stiffness for e in effects),
                  starts=lambda s: [st for e in effects for st in e.starts(s)], members=tuple(names),
                  derived=lambda s: tuple(r for e in effects for r in e.derived(s)),
                  basin=next((e.basin for e in effects if e.basin), None))


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


def _sym(scale_fn):
    return lambda s: (-scale_fn(s), 0.0, scale_fn(s))


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


# the friction's smoothing velocity v_s [m/s] (F = F_c tanh(v / v_s)): from near-ideal Coulomb (1e-3 of the
# velocity RMS) to a friction that is still rounding off at half of it; started at 1e-2
_stick_velocity = Param("v_s", lambda s: (1e-3 * s.sigma_v, 1e-2 * s.sigma_v, 0.5 * s.sigma_v), shape=True, log=True)

# Shapes of the Bouc-Wen loop the refit starts from, spanning the family (theory §1.1 and §1.3): with β set
# to (1/sigma_y)·(0.3·k·sigma_y)^(1-ν) (SDOF) or D to sigma_y (damper), the loading branch softens when
# γ + δ > 0 (SDOF) or β + γ > 0 (damper) and hardens otherwise; the unloading branch likewise with γ - δ or
# β - γ; ν from 1 (smooth) to 3 (sharp). The refit begins from the best of them on the calibration records and
# fits the shape. The SDOF's five branch shapes are each taken at ν = 1, 2 and 3: a loop's branches and its
# sharpness vary independently (a sharp loop that softens on both branches lies in no basin a smooth one's
# descent reaches).
SDOF_LOOP_BRANCHES = ({"gamma": 0.5, "delta": 0.5},    # softening loading, elastic unloading, wide loop
                      {"gamma": 1.5, "delta": -0.5},   # softening loading, sharp unloading
                      {"gamma": 0.5, "delta": -1.5},   # hardening loading, narrow loop
                      {"gamma": 1.0, "delta": 0.0},    # symmetric
                      {"gamma": 0.25, "delta": 0.75})  # nearly elastic-plastic
SDOF_LOOP_STARTS = tuple({**branch, "nu": nu} for nu in (1.0, 2.0, 3.0) for branch in SDOF_LOOP_BRANCHES)
DAMPER_LOOP_STARTS = ({"a_bw": 0.5, "beta": 0.75, "gamma": 0.25, "nu": 1.0},
                      {"a_bw": 0.1, "beta": 0.5, "gamma": 0.5, "nu": 1.0},
                      {"a_bw": 0.5, "beta": 1.5, "gamma": -0.5, "nu": 1.0},
                      {"a_bw": 0.2, "beta": 0.25, "gamma": 0.75, "nu": 2.0},
                      {"a_bw": 0.7, "beta": 1.0, "gamma": 0.0, "nu": 3.0})

DEFAULT_SHARE = 0.1  # share of the stiffness the hysteretic element holds at small amplitude: the default start
BETA_SHARE = 0.3  # the share that sets β's scale (ExponentScaled)
# the shares each loop width starts from. As listed (width 1: a loop that saturates within the data's deflection),
# from a very weak element (0.3 %: a loop whose hysteretic force is a few times the noise's; from 3 % up its refit
# ends at a nearly linear loop several times as strong) and a weak one (3 %: it saturates early and adds a little
# stiffness and damping) to a strong one; with γ, δ scaled by 0.1 (the shares from 3 % up) and by 0.01 (the
# larger shares: wide loops that barely saturate there, turning over at 10^(1/ν) and 100^(1/ν) times the force
# β's scale refers to, a mostly elastic element with a little hysteretic damping), and by 0.3 at the smaller
# shares (a weak element whose loop turns over within a few times that force). A strong element with a wide loop
# and a weak one with a narrow loop share the first-order nonlinearity (α·β·γ) but lie in separate basins of the
# least squares, so the refit descends from the best start of each
LOOP_SHARES = {1.0: (0.003, 0.03, DEFAULT_SHARE, 0.3, 0.6), 0.3: (0.003, 0.03, DEFAULT_SHARE),
               0.1: (0.03, DEFAULT_SHARE, 0.3, 0.6), 0.01: (0.3, 0.6)}
NARROW_FROM = 0.5  # |γ| + |δ| of a loop start from which it counts as narrow (the listed shapes: 1 to 2)


def _sdof_loop_starts(s: Scale) -> list[dict]:
    """Every loop shape at every width and each of its hysteretic shares of the calibrated stiffness (k + alpha =
    the nominal k), but the default start (the first shape, as listed, at the default share)."""
    return [{"k": (1.0 - f) * s.k, "alpha": f * s.k, **{n: v * w if n != "nu" else v for n, v in shape.items()}}
            for w, shares in LOOP_SHARES.items() for f in shares for shape in SDOF_LOOP_STARTS
            if (w, f, shape) != (1.0, DEFAULT_SHARE, SDOF_LOOP_STARTS[0])]


def sdof_loop_basin(values: dict) -> tuple:
    """The basin an SDOF loop start lies in: its ν (β's scale follows ν) and whether it is narrow or wide."""
    return round(values["nu"], 6), abs(values["gamma"]) + abs(values["delta"]) >= NARROW_FROM


# Strengths of the cubic spring the refit starts from, as the share k3·σ_y²/k of the linear stiffness it adds at
# the RMS deflection (either sign: hardening and softening), log-spaced over the two and a half decades below its
# bound (0.3): a strong cubic spring under a sweep or stepped sine jumps between branches, and a least squares
# started at zero stops at a fraction of it
CUBIC_SHARES = (0.001, 0.003, 0.01, 0.03, 0.1)


def _cubic_starts(*names):
    """Scale -> the cubic strengths of CUBIC_SHARES, both signs, for each of the spring parameters `names`."""
    return lambda s: [{n: sign * f * s.k / s.sigma_y**2 for n in names} for f in CUBIC_SHARES for sign in (1, -1)]


# a lag of the output channels behind the inputs (unsynchronised DAQ modules, different anti-alias filters):
# up to half a radian at the data's dominant frequency (sigma_y / sigma_v ~ 1/ω), either sign. Linear: within the
# noise threshold its refit takes up the group delay of the lab's anti-alias filters as well
SENSOR_DELAY = Effect(
    "sensor_delay", (Param("sensor_delay", _sym(lambda s: 0.5 * s.sigma_y / s.sigma_v)),),
    signature="a phase error that grows in proportion to frequency, the same at every level", signal_only=True,
    linear=True)

# the output channels read in another proportion to the inputs than the model says (a sensor's sensitivity off by a
# per cent or so, an amplifier's gain): a relative gain of up to 10 %, either sign. Linear, and of a damper only (a
# family whose every parameter is fitted takes a gain up in them); offered where the configuration's effects name it
SENSOR_GAIN = Effect(
    "sensor_gain", (Param("sensor_gain", lambda s: (-0.1, 0.0, 0.1)),),
    signature="a misfit in proportion to the response, the same share at every level and frequency",
    signal_only=True, linear=True, opt_in=True)

SDOF_EFFECTS = {
    "hysteresis": Effect(
        "hysteresis",
        (Param("alpha", lambda s: (0.0, DEFAULT_SHARE * s.k, 2.0 * s.k)),
         Param("gamma", shape=True, range=lambda s: (-5.0, SDOF_LOOP_STARTS[0]["gamma"], 5.0)),
         Param("delta", shape=True, range=lambda s: (-5.0, SDOF_LOOP_STARTS[0]["delta"], 5.0)),
         Param("nu", shape=True, range=lambda s: (1.0, SDOF_LOOP_STARTS[0]["nu"], 3.0))),
        derived=lambda s: (ExponentScaled("beta", 1.0 / s.sigma_y, BETA_SHARE * s.k * s.sigma_y, "nu"),),
        basin=sdof_loop_basin,
        signature="amplitude-dependent stiffness and damping (hysteresis loops), odd distortion",
        shift_stiffness=0.1, starts=lambda s: _sdof_loop_starts(s)),
    "cubic_stiffness": Effect(
        "cubic_stiffness", (Param("k3", _sym(lambda s: 0.3 * s.k / s.sigma_y**2)),),
        signature="resonance shift with amplitude squared, odd distortion", starts=_cubic_starts("k3")),
    "coulomb_friction": Effect(
        "coulomb_friction", (Param("F_c", lambda s: (0.0, 0.0, 0.5 * s.k * s.sigma_y)), _stick_velocity),
        signature="damping that falls with amplitude (largest misfit at the lowest level)"),
    "quadratic_damping": Effect(
        "quadratic_damping", (Param("c2", lambda s: (0.0, 0.0, 0.5 * s.k * s.sigma_y / s.sigma_v**2)),),
        signature="damping that grows with amplitude (largest misfit at the highest level)"),
    "sensor_delay": SENSOR_DELAY,
}

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


def _friction_range(s: Scale) -> tuple:
    """Range of a damper joint's friction force [N]: up to half the spring force at the deflection scale or,
    when larger, the force the joint transmits stuck (a friction that holds the arms at the lowest level leaves
    the nominal model almost no deflection to scale it by)."""
    return (0.0, 0.0, max(0.5 * s.k * s.sigma_y, s.stuck_force))


def _pair(name1, name2, rng):
    return (Param(name1, rng), Param(name2, rng))


DAMPER_EFFECTS = {
    "hysteresis": Effect(  # A = 1 and D = sigma_y: only β D^-ν, γ D^-ν (with ν) are identifiable (theory §1.3)
        "hysteresis", _pair("k_bw1", "k_bw2", lambda s: (0.0, 0.05 * s.k, 0.5 * s.k))
        + (Param("a_bw", shape=True, range=lambda s: (0.0, DAMPER_LOOP_STARTS[0]["a_bw"], 1.0)),
           Param("beta", shape=True, range=lambda s: (0.0, DAMPER_LOOP_STARTS[0]["beta"], 5.0)),
           Param("gamma", shape=True, range=lambda s: (-5.0, DAMPER_LOOP_STARTS[0]["gamma"], 5.0)),
           Param("nu", shape=True, range=lambda s: (1.0, DAMPER_LOOP_STARTS[0]["nu"], 3.0))),
        fixed=lambda s: {"A": 1.0, "D": s.sigma_y},
        signature="amplitude-dependent stiffness and damping of the cable (hysteresis loops), odd distortion",
        starts=lambda s: [dict(st) for st in DAMPER_LOOP_STARTS[1:]],
        # the nominal has one EI for both arms: a loop's linear part, a stiffness per arm, is a freedom it lacks (the
        # SDOF's k holds an SDOF loop's); closed to a spring of its stiffness before and after yield
        linear_parts=lambda p: [{"a_bw": 1.0}, {"a_bw": 1.0, "k_bw1": p["a_bw"] * p["k_bw1"],
                                                "k_bw2": p["a_bw"] * p["k_bw2"]}]),
    "cubic_stiffness": Effect(
        "cubic_stiffness", _pair("k_cs1", "k_cs2", _sym(lambda s: 0.3 * s.k / s.sigma_y**2)),
        signature="resonance shifts with amplitude squared, odd distortion", starts=_cubic_starts("k_cs1", "k_cs2")),
    "coulomb_friction": Effect(
        "coulomb_friction", _pair("F_c1", "F_c2", _friction_range) + (_stick_velocity,),
        signature="damping that falls with amplitude (largest misfit at the lowest level)"),
    "quadratic_damping": Effect(
        "quadratic_damping", _pair("c2_1", "c2_2", lambda s: (0.0, 0.0, 0.5 * s.k * s.sigma_y / s.sigma_v**2)),
        signature="damping that grows with amplitude (largest misfit at the highest level)"),
    "mass_eccentricity": Effect(  # a deviation of the mass offsets from the nominal's, up to 30 mm
        "mass_eccentricity", (Param("a1", lambda s: (s.nominal["a1"] - 0.03, s.nominal["a1"], s.nominal["a1"] + 0.03)),
                              Param("a2", lambda s: (s.nominal["a2"] - 0.03, s.nominal["a2"], s.nominal["a2"] + 0.03))),
        signature="amplitude-independent shift of the modes (the same misfit at every level)", linear=True),
    "sensor_delay": SENSOR_DELAY,
    "sensor_gain": SENSOR_GAIN,
}

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
    "sdof": _Family("SDOFBoucWen", {"exc_type": 0, "alpha": 0.0, "k3": 0.0, "F_c": 0.0, "c2": 0.0},
                    ("m", "c", "k"), "k", sdof_start, sdof_file_starts, sdof_bounds, sdof_stiffness, sdof_deflection,
                    ("y",), (), SDOF_EFFECTS, 1, outside="a joint whose loops follow another law than the "
                    "hysteresis candidate's, as a bolted joint's micro-slip does; backlash; a delay between the "
                    "channels"),
    "damper": _Family("StockbridgeDamper",
                      {"exc_type": 0, "k_bw1": 0.0, "k_bw2": 0.0, "k_cs1": 0.0, "k_cs2": 0.0, "F_c1": 0.0,
                       "F_c2": 0.0, "c2_1": 0.0, "c2_2": 0.0},
                      ("EI", "alpha_pd", "beta_pd"), "EI", None, damper_modal_starts, damper_bounds, damper_stiffness,
                      damper_deflection, ("x1",), ("x_base", "v_base", "a_base"), DAMPER_EFFECTS, 2,
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
