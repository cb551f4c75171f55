"""The built-in candidate effects, one declaration each (effect.Builtin): what the diagnosis fits, the FMU switch,
the truth the generator adds and draws, the size rule and the peers' term. Adding a built-in effect takes its
Modelica element (or, for an effect on the recorded channels, its `on_outputs`) and one entry of SDOF or DAMPER.
Ranges follow the data Scale (SI units)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pyfit.analysis.signals import delayed
from pyfit.gap.effect import (BRANCH, TURNOVER, BranchCoordinate, Builtin, Effect, LoopCoordinates, Param, Scale,
                              branch_of, loop_coordinates)

def _sym(scale_fn):
    return lambda s: (-scale_fn(s), 0.0, scale_fn(s))


# the friction's smoothing velocity v_s [m/s] (F = F_c tanh(v / v_s)): from near-ideal Coulomb (1e-3 of the
# velocity RMS) to a friction that is still rounding off at half of it; started at 1e-2
_stick_velocity = Param("v_s", lambda s: (1e-3 * s.sigma_v, 1e-2 * s.sigma_v, 0.5 * s.sigma_v), shape=True, log=True)

# The SDOF loop is fitted in physically named coordinates (theory §1.1; effect.LoopCoordinates): α, the turnover
# force F_t [N] (log-scaled over TURNOVER_RANGE times the spring force k·σ_y at the data's deflection: from a loop
# that turns over at a few times the noise's force to one stronger than the linear spring), the branch coordinate
# (effect.branch_slopes: hardening to softening loading, stiffening to elastic unloading) and ν up to MAX_NU. No
# corner of the family lies beyond a bound a real loop reaches.
TURNOVER_RANGE = (1e-4, 1e2)
BRANCH_RANGE = (-2.0, 3.0)
DAMPER_BRANCH_FROM = -1.0  # the damper form's β = (s + d)/2 is declared non-negative (the element's minimum)
MAX_NU = 6.0

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
BETA_SHARE = 0.3  # the share that sets the listed shapes' β (_reference_beta)
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


def _reference_beta(s: Scale, nu: float) -> float:
    """The β the listed loop shapes are scaled by: (1/σ_y)·(BETA_SHARE·k·σ_y)^(1−ν), which keeps β·|z|^ν / α of
    order one at the data's deflection for every ν (a start's γ, δ of order one)."""
    return (BETA_SHARE * s.k * s.sigma_y) ** (1.0 - nu) / s.sigma_y


def _sdof_loop(s: Scale, share: float, width: float, shape: dict) -> dict:
    """A loop start: the hysteretic element holding `share` of the calibrated stiffness (k + α = the nominal k),
    a listed shape (γ, δ, ν) with γ, δ times `width` at the reference β, in the fitted coordinates."""
    alpha = share * s.k
    return {"k": (1.0 - share) * s.k, "alpha": alpha, "nu": shape["nu"],
            **loop_coordinates(alpha, _reference_beta(s, shape["nu"]), width * shape["gamma"],
                               width * shape["delta"], shape["nu"])}


def _default_sdof_loop(s: Scale) -> dict:
    """The default start: the first listed shape at the default share."""
    return _sdof_loop(s, DEFAULT_SHARE, 1.0, SDOF_LOOP_STARTS[0])


def _sdof_loop_starts(s: Scale) -> list[dict]:
    """Every loop shape at every width and each of its hysteretic shares of the calibrated stiffness, but the
    default start (the first shape, as listed, at the default share)."""
    return [_sdof_loop(s, f, w, shape) for w, shares in LOOP_SHARES.items() for f in shares
            for shape in SDOF_LOOP_STARTS if (w, f, shape) != (1.0, DEFAULT_SHARE, SDOF_LOOP_STARTS[0])]


@dataclass(frozen=True)
class SdofLoopBasin:
    """The basin an SDOF loop start lies in: its ν and whether it is narrow (|γ| + |δ| ≥ NARROW_FROM at the
    reference β of the data's deflection `sigma_y` [m] and stiffness `k` [N/m]) or wide. Picklable: a refit task
    carries it to a worker."""

    sigma_y: float
    k: float

    def __call__(self, values: dict) -> tuple:
        nu = values["nu"]
        reach = values["alpha"] / (_reference_beta(Scale(self.sigma_y, 0.0, self.k), nu) * values[TURNOVER] ** nu)
        return round(nu, 6), reach >= NARROW_FROM


def sdof_loop_basin(s: Scale) -> SdofLoopBasin:
    """The SDOF loop's basins at the data scale `s`."""
    return SdofLoopBasin(s.sigma_y, s.k)


# Strengths of the cubic spring the refit starts from, as the share k3·σ_y²/k of the linear stiffness it adds at
# the RMS deflection (either sign: hardening and softening), log-spaced over the two and a half decades below its
# bound (0.3): a strong cubic spring under a sweep or stepped sine jumps between branches, and a least squares
# started at zero stops at a fraction of it
CUBIC_SHARES = (0.001, 0.003, 0.01, 0.03, 0.1)


def _cubic_starts(*names):
    """Scale -> the cubic strengths of CUBIC_SHARES, both signs, for each of the spring parameters `names`."""
    return lambda s: [{n: sign * f * s.k / s.sigma_y**2 for n in names} for f in CUBIC_SHARES for sign in (1, -1)]


def _friction_range(s: Scale) -> tuple:
    """Range of a damper joint's friction force [N]: up to half the spring force at the deflection scale or,
    when larger, the force the joint transmits stuck (a friction that holds the arms at the lowest level leaves
    the nominal model almost no deflection to scale it by)."""
    return (0.0, 0.0, max(0.5 * s.k * s.sigma_y, s.stuck_force))


def _pair(name1, name2, rng):
    return (Param(name1, rng), Param(name2, rng))


# ---- effects on the recorded channels (both families) -----------------------------------------------------
def _delay_outputs(values: np.ndarray, delay: float, fs: float, periodic: bool) -> np.ndarray:
    return delayed(values, fs, delay, periodic)


def _gain_outputs(values: np.ndarray, gain: float, fs: float, periodic: bool) -> np.ndarray:
    return (1.0 + gain) * values


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


# ---- SDOF ----------------------------------------------------------------------------------------------------
SDOF_STIFFNESS = 1e5  # a drawn SDOF loop's small-amplitude stiffness k + α [N/m], kept as α is scaled
MAX_LOOP_SHARE = 0.95  # of it, the most α may take (k stays positive)


def hysteresis_loop(rng) -> dict:
    """An SDOF Bouc-Wen loop drawn across the family (theory §1.1), independent of the candidate's starts:
    ν uniform in 1-3 (never one of the starts' whole values); the hysteretic element holds 20-70 % of the
    stiffness SDOF_STIFFNESS (1e5 N/m) and turns over at 30-500 N; loading branch softening (γ + δ from
    0.1 to 1.5, or mildly hardening for ν below 1.5), γ − δ from 0.2 to 2.5."""
    nu = float(rng.uniform(1.0, 3.0))
    s = rng.uniform(-0.5, 1.5) if nu < 1.5 else rng.uniform(0.1, 1.5)
    d = rng.uniform(0.2, 2.5)
    alpha = SDOF_STIFFNESS * rng.uniform(0.2, 0.7)
    z_y = 10.0 ** rng.uniform(1.5, 2.7)
    return {"k": SDOF_STIFFNESS - alpha, "alpha": alpha, "beta": alpha / z_y ** nu, "gamma": (s + d) / 2,
            "delta": (s - d) / 2, "nu": nu}


def _sdof_loop_drawn(rng, factor: float) -> dict:
    """A loop drawn across the family (hysteresis_loop), its α (the strength) times the factor where below 1."""
    loop = hysteresis_loop(rng)
    loop["alpha"] *= min(factor, 1.0)
    loop["k"] = SDOF_STIFFNESS - loop["alpha"]
    return loop


def _sdof_loop_scaled(truth: dict, gain: float) -> dict:
    """An SDOF loop (theory §1.1) scaled as a whole: z and α by the gain g, β by g^(1-ν), so that z/g obeys the
    loop's law unchanged (the displacement where it turns over stays) and its force is g times the loop's; k
    then at SDOF_STIFFNESS - α."""
    alpha = truth["alpha"] * gain
    return {"alpha": alpha, "beta": truth["beta"] * gain ** (1.0 - truth["nu"]), "k": SDOF_STIFFNESS - alpha}


def _drawn_strength(truth: dict, strength: str):
    """A draw of the reference truth with its strength times the factor (the factor is the draw's only number)."""
    return lambda rng, factor: {**truth, strength: truth[strength] * factor}


_SDOF_CUBIC = {"k3": 3e8}
_SDOF_FRICTION = {"F_c": 1.0, "v_s": 1e-3}
_SDOF_QUADRATIC = {"c2": 10.0}
SDOF = {b.name: b for b in (
    Builtin(Effect(
        "hysteresis",
        (Param("alpha", lambda s: (0.0, DEFAULT_SHARE * s.k, 2.0 * s.k)),
         Param(TURNOVER, shape=True, log=True, range=lambda s: (
             TURNOVER_RANGE[0] * s.k * s.sigma_y, _default_sdof_loop(s)[TURNOVER],
             TURNOVER_RANGE[1] * s.k * s.sigma_y)),
         Param(BRANCH, shape=True, range=lambda s: (BRANCH_RANGE[0], _default_sdof_loop(s)[BRANCH], BRANCH_RANGE[1])),
         Param("nu", shape=True, range=lambda s: (1.0, SDOF_LOOP_STARTS[0]["nu"], MAX_NU))),
        derived=lambda s: (LoopCoordinates(),),
        basin=sdof_loop_basin,
        signature="amplitude-dependent stiffness and damping (hysteresis loops), odd distortion",
        shift_stiffness=0.1, starts=lambda s: _sdof_loop_starts(s)),
        off={"alpha": 0.0}, truth={"k": 5e4, "alpha": 5e4, "beta": 100.0, "gamma": 0.8, "delta": -1.1},
        tangent={"beta": 0.0}, strengths=("alpha",), draw=_sdof_loop_drawn, scaled=_sdof_loop_scaled,
        max_gain=lambda truth: MAX_LOOP_SHARE * SDOF_STIFFNESS / truth["alpha"]),
    Builtin(Effect(
        "cubic_stiffness", (Param("k3", _sym(lambda s: 0.3 * s.k / s.sigma_y**2)),),
        signature="resonance shift with amplitude squared, odd distortion", starts=_cubic_starts("k3")),
        off={"k3": 0.0}, truth=_SDOF_CUBIC, tangent={"k3": 0.0}, strengths=("k3",),
        draw=_drawn_strength(_SDOF_CUBIC, "k3"), peer_term="y^3"),
    Builtin(Effect(
        "coulomb_friction", (Param("F_c", lambda s: (0.0, 0.0, 0.5 * s.k * s.sigma_y)), _stick_velocity),
        signature="damping that falls with amplitude (largest misfit at the lowest level)"),
        off={"F_c": 0.0}, truth=_SDOF_FRICTION, tangent={"F_c": 0.0}, strengths=("F_c",),
        draw=_drawn_strength(_SDOF_FRICTION, "F_c"), peer_term="tanh(v/v_s)"),
    Builtin(Effect(
        "quadratic_damping", (Param("c2", lambda s: (0.0, 0.0, 0.5 * s.k * s.sigma_y / s.sigma_v**2)),),
        signature="damping that grows with amplitude (largest misfit at the highest level)"),
        off={"c2": 0.0}, truth=_SDOF_QUADRATIC, tangent={"c2": 0.0}, strengths=("c2",),
        draw=_drawn_strength(_SDOF_QUADRATIC, "c2"), peer_term="v|v|"),
    Builtin(SENSOR_DELAY, truth={"sensor_delay": 1.3e-3}, on_outputs=_delay_outputs),
)}


# ---- Stockbridge damper ------------------------------------------------------------------------------------
def _drawn_pair(truth: dict, strengths: tuple, shape=None):
    """A damper effect's draw: the reference with its strengths times the factor; `shape(rng)`: the shape
    parameters drawn after it."""
    def draw(rng, factor: float) -> dict:
        drawn = {**truth, **{k: truth[k] * factor for k in strengths}}
        if shape:
            drawn.update(shape(rng))
        return {k: float(v) for k, v in drawn.items()}
    return draw


def _damper_loop_shape(rng) -> dict:
    """A loop shape drawn across the family (a_bw 0.1-0.6, β 0.3-1.2, γ −0.2-0.6, ν 1-2.5, D 0.15-0.4 mm), away
    from the candidate's starts."""
    return dict(a_bw=rng.uniform(0.1, 0.6), beta=rng.uniform(0.3, 1.2), gamma=rng.uniform(-0.2, 0.6),
                nu=rng.uniform(1.0, 2.5), D=rng.uniform(1.5e-4, 4e-4))


def _damper_loop(s: Scale, start: dict) -> dict:
    """A listed damper loop shape (a_bw, β, γ, ν at D = σ_y) in the fitted coordinates: the same loop with its
    β, γ scaled to the branch coordinate's edge and D to the deflection it then turns over at."""
    branch, m = branch_of(start["beta"] + start["gamma"], start["beta"] - start["gamma"])
    return {"a_bw": start["a_bw"], "D": s.sigma_y * m ** (-1.0 / start["nu"]), BRANCH: branch, "nu": start["nu"]}


def _damper(effect: Effect, truth: dict, strengths: tuple, shape=None) -> Builtin:
    """A damper effect on both arms: switched off (and reduced to its tangent) at zero strength."""
    off = dict.fromkeys(strengths, 0.0)
    return Builtin(effect, off=off, truth=truth, tangent=off, strengths=strengths,
                   draw=_drawn_pair(truth, strengths, shape))


DAMPER = {b.name: b for b in (
    _damper(Effect(  # A = 1; β, γ from the branch coordinate, D the deflection the loop turns over at (theory §1.3)
        "hysteresis", _pair("k_bw1", "k_bw2", lambda s: (0.0, 0.05 * s.k, 0.5 * s.k))
        + (Param("a_bw", shape=True, range=lambda s: (0.0, DAMPER_LOOP_STARTS[0]["a_bw"], 1.0)),
           Param("D", shape=True, log=True, range=lambda s: (
               TURNOVER_RANGE[0] * s.sigma_y, _damper_loop(s, DAMPER_LOOP_STARTS[0])["D"],
               TURNOVER_RANGE[1] * s.sigma_y)),
           Param(BRANCH, shape=True, range=lambda s: (DAMPER_BRANCH_FROM, _damper_loop(
               s, DAMPER_LOOP_STARTS[0])[BRANCH], BRANCH_RANGE[1])),
           Param("nu", shape=True, range=lambda s: (1.0, DAMPER_LOOP_STARTS[0]["nu"], MAX_NU))),
        fixed=lambda s: {"A": 1.0}, derived=lambda s: (BranchCoordinate(),),
        signature="amplitude-dependent stiffness and damping of the cable (hysteresis loops), odd distortion",
        starts=lambda s: [_damper_loop(s, st) for st in DAMPER_LOOP_STARTS[1:]],
        # the nominal has one EI for both arms: a loop's linear part, a stiffness per arm, is a freedom it lacks (the
        # SDOF's k holds an SDOF loop's); closed to a spring of its stiffness before and after yield
        linear_parts=lambda p: [{"a_bw": 1.0}, {"a_bw": 1.0, "k_bw1": p["a_bw"] * p["k_bw1"],
                                                "k_bw2": p["a_bw"] * p["k_bw2"]}]),
        {"k_bw1": 600.0, "k_bw2": 1000.0, "D": 2e-4}, ("k_bw1", "k_bw2"), _damper_loop_shape),
    _damper(Effect(
        "cubic_stiffness", _pair("k_cs1", "k_cs2", _sym(lambda s: 0.3 * s.k / s.sigma_y**2)),
        signature="resonance shifts with amplitude squared, odd distortion", starts=_cubic_starts("k_cs1", "k_cs2")),
        {"k_cs1": 8e8, "k_cs2": 2.4e9}, ("k_cs1", "k_cs2")),  # hardening: the thesis's softening diverges here
    _damper(Effect(
        "coulomb_friction", _pair("F_c1", "F_c2", _friction_range) + (_stick_velocity,),
        signature="damping that falls with amplitude (largest misfit at the lowest level)"),
        {"F_c1": 0.08, "F_c2": 0.12, "v_s": 1e-3}, ("F_c1", "F_c2")),
    _damper(Effect(
        "quadratic_damping", _pair("c2_1", "c2_2", lambda s: (0.0, 0.0, 0.5 * s.k * s.sigma_y / s.sigma_v**2)),
        signature="damping that grows with amplitude (largest misfit at the highest level)"),
        {"c2_1": 12.0, "c2_2": 20.0}, ("c2_1", "c2_2")),
    Builtin(Effect(  # a deviation of the mass offsets from the nominal's, up to 30 mm
        "mass_eccentricity", (Param("a1", lambda s: (s.nominal["a1"] - 0.03, s.nominal["a1"], s.nominal["a1"] + 0.03)),
                              Param("a2", lambda s: (s.nominal["a2"] - 0.03, s.nominal["a2"], s.nominal["a2"] + 0.03))),
        signature="amplitude-independent shift of the modes (the same misfit at every level)", linear=True),
        truth={"a1": lambda p: p["a1"] + 0.015, "a2": lambda p: p["a2"] + 0.015}),  # 15 mm further out
    Builtin(SENSOR_DELAY, truth={"sensor_delay": 0.9e-3},  # the clamp channels 0.9 ms ahead of the responses
            on_outputs=_delay_outputs),
    Builtin(SENSOR_GAIN, on_outputs=_gain_outputs),
)}

BUILTINS = {"sdof": SDOF, "damper": DAMPER}


def candidates(family: str) -> dict[str, Effect]:
    """The family's candidate effects, in declaration order."""
    return {n: b.candidate for n, b in BUILTINS[family].items()}


def switches(family: str) -> dict:
    """The FMU parameters that switch every built-in effect of the family off."""
    return {k: v for b in BUILTINS[family].values() for k, v in b.off.items()}


def tangent(family: str) -> dict:
    """The truth parameters that reduce every effect to its linear tangent."""
    return {k: v for b in BUILTINS[family].values() for k, v in b.tangent.items()}


def drawn(family: str) -> tuple[str, ...]:
    """The effects a campaign of the family draws, in declaration order."""
    return tuple(n for n, b in BUILTINS[family].items() if b.draw)


def peer_terms(family: str = "sdof") -> dict[str, str]:
    """The equation-error peers' library: term -> the effect it stands for."""
    return {b.peer_term: n for n, b in BUILTINS[family].items() if b.peer_term}


def output_effects() -> dict:
    """The effects on the recorded channels, by their parameter: name -> on_outputs (each family's the same)."""
    return {b.candidate.params[0].name: b.on_outputs for fam in BUILTINS.values() for b in fam.values()
            if b.on_outputs}
