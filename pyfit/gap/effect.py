"""What a candidate effect is (Effect, its Params, the data Scale its ranges follow) and what a built-in one declares
beside it (Builtin: its FMU switch, the generator's truth and draws, its size rule, its peers' term). SI units."""
from __future__ import annotations

from dataclasses import dataclass, field


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


# A Bouc-Wen loop's physically named coordinates (theory §1.1, §1.3), fitted in place of its shape coefficients:
# the turnover force F_t [N] of the §1.1 form and the branch coordinate of both forms. Not FMU parameters
# (pyfit.gap.simulate leaves them out): LoopCoordinates and BranchCoordinate give the coefficients from them
TURNOVER, BRANCH = "F_t", "branch"
COORDINATES = (TURNOVER, BRANCH)


def branch_slopes(branch: float) -> tuple[float, float]:
    """(s, d) of a branch coordinate, s the loading branch's softening coefficient and d the unloading branch's
    stiffening one (§1.1: γ + δ and γ − δ; §1.3: β + γ and β − γ): the square's edge max(|s|, |d|) = 1 walked
    from (−1, −1) through (−1, 1) and (1, 1) to (1, −1): (−1, branch + 2) below −1, (branch, 1) up to 1,
    (1, 2 − branch) above."""
    if branch < -1.0:
        return -1.0, branch + 2.0
    return (branch, 1.0) if branch <= 1.0 else (1.0, 2.0 - branch)


def branch_of(s: float, d: float) -> tuple[float, float]:
    """The branch coordinate of the slopes (s, d) and their scale max(|s|, |d|) (the inverse of branch_slopes).
    ValueError for a linear element (s = d = 0) and for the one edge the walk leaves out (an unloading branch
    that softens at the full rate while the loading one changes less: d = −m, |s| < m)."""
    m = max(abs(s), abs(d))
    if m == 0.0 or (d / m <= -1.0 + 1e-12 and abs(s) / m < 1.0 - 1e-12):
        raise ValueError(f"loading slope {s:g}, unloading slope {d:g}: a loop the branch coordinate does not hold")
    s, d = s / m, d / m
    return (s if d >= 1.0 - 1e-12 else (2.0 - d if s > 0 else d - 2.0)), m


def _odd_even(branch: float) -> tuple[float, float]:
    """The law's coefficients of |v|·|z|^(ν−1)·z and of v·|z|^ν at a branch coordinate: ((s + d)/2, (s − d)/2)."""
    s, d = branch_slopes(branch)
    return 0.5 * (s + d), 0.5 * (s - d)


def loop_coordinates(alpha: float, beta: float, gamma: float, delta: float, nu: float) -> dict:
    """The turnover force F_t [N] and branch coordinate of a §1.1 loop given by α [N/m], β, γ, δ, ν (the inverse
    of LoopCoordinates; ValueError as branch_of)."""
    branch, m = branch_of(gamma + delta, gamma - delta)
    return {TURNOVER: (alpha / (beta * m)) ** (1.0 / nu), BRANCH: branch}


@dataclass(frozen=True)
class LoopCoordinates:
    """β, γ, δ of the §1.1 Bouc-Wen law (FMU parameters) from α, ν and the loop's physically named coordinates:
    the turnover force F_t [N], at which the more nonlinear branch's tangent has changed by α (a softening
    loading branch saturates there), and the branch coordinate (branch_slopes): β = α / F_t^ν, γ = (s + d)/2,
    δ = (s − d)/2. The loading tangent at |z| = F_t is then (1 − s)·α, the unloading one (1 + d)·α."""

    def __call__(self, params: dict) -> dict:
        if TURNOVER not in params:
            return params
        gamma, delta = _odd_even(params[BRANCH])
        return {**params, "beta": params["alpha"] / params[TURNOVER] ** params["nu"], "gamma": gamma,
                "delta": delta}


@dataclass(frozen=True)
class BranchCoordinate:
    """β, γ of the §1.3 (normalised) Bouc-Wen law from the branch coordinate: (s + d)/2 and (s − d)/2 with
    max(|s|, |d|) = 1, so that z turns over near 1 and the fitted D [m] is the deflection the loop turns over at."""

    def __call__(self, params: dict) -> dict:
        if BRANCH not in params:
            return params
        beta, gamma = _odd_even(params[BRANCH])
        return {**params, "beta": beta, "gamma": gamma}


def with_derived(params: dict, rules: tuple) -> dict:
    """params with every rule (e.g. LoopCoordinates) applied in turn."""
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
    # Scale -> a picklable (start values -> the basin they lie in): the refit descends from each basin's best
    basin: callable = None
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


def _scaled_strengths(strengths: tuple):
    """The default size rule: every strength parameter of the truth times the gain (the values changed)."""
    def scaled(truth: dict, gain: float) -> dict:
        return {n: truth[n] * gain for n in strengths}
    return scaled


@dataclass(frozen=True)
class Builtin:
    """A built-in effect of a family, declared once: the candidate the diagnosis fits; the FMU parameters that
    switch it off (`off`: the nominal model); the truth the generator adds for it (`truth`: the family's
    reference, pyfit.gap.datasets) and the values that reduce that truth to its linear tangent (`tangent`: what an
    effect's size on the records is measured against); the truth parameters a campaign scales to a size
    (`strengths`), how (`scaled(truth, gain)`: the values it changes; default: every strength times the gain) and
    up to what gain
    (`max_gain(truth)`); how a campaign draws it (`draw(rng, factor)`: a truth across the family at a strength
    factor on the reference; None: never drawn); the term the equation-error peers fit for it (`peer_term`); and
    for an effect on the recorded channels, how it changes them (`on_outputs(values, value, fs, periodic)`)."""

    candidate: Effect
    off: dict = field(default_factory=dict)
    truth: dict = field(default_factory=dict)
    tangent: dict = field(default_factory=dict)
    strengths: tuple = ()
    draw: callable = None
    scaled: callable = None
    max_gain: callable = None
    peer_term: str | None = None
    on_outputs: callable = None

    @property
    def name(self) -> str:
        return self.candidate.name

    def scale(self, truth: dict, gain: float) -> dict:
        """The truth's values this effect's size rule changes to scale it by `gain`."""
        return (self.scaled or _scaled_strengths(self.strengths))(truth, gain)

    def largest_gain(self, truth: dict) -> float:
        """The largest gain this effect's strength may take from `truth` (inf: no bound)."""
        return self.max_gain(truth) if self.max_gain else float("inf")
