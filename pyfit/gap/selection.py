"""Scores of candidate models on the held-out files, shared by the ranking and the forward selection of
effect combinations (SI units; NRMSE is dimensionless)."""
from __future__ import annotations

import itertools

import numpy as np

from pyfit.gap import localise

PENALTY_POINTS = 5.0  # score points charged per strength parameter beyond the first
CONTROL_SIBLINGS = 3  # extensions of one model needed before the least helpful one serves as a control
ALIKE = 0.03  # two held-out misfits within 3 % of each other: on the held-out files the models are as good
# a leaner partner is refitted jointly only when its refit beside the model cuts at least this share of what the
# best one's cuts (leaner_best): held back by a member held at a refit that made up for it, the leaner partners
# the stored campaigns named still cut 84 % and 97 % of the leader's cut (a quarter: far below that), and none that
# cut under a quarter was named; such a one explains nothing the leader does not (the damper's mass offsets beside
# its cubic springs: 7 %)
LEANER_MIN_SHARE = 0.25


def heldout_nrmse(sims: dict, held) -> float:
    """RMS over the held-out files of a model's NRMSE (inf when a simulation failed)."""
    done = [localise.nrmse(sims[r.name], r) for r in held if sims.get(r.name) is not None]
    return float(np.sqrt(np.mean(np.square(done)))) if done and len(done) == len(held) else float("inf")


def noise_level(floor: float, noise_factor: float, min_gap: float) -> float:
    """The held-out NRMSE a model must exceed to leave a gap: max(noise_factor x the noise floor, floor + min_gap)."""
    return max(noise_factor * floor, floor + min_gap)


def significant(nrmse: float, floor: float, noise_factor: float, min_gap: float) -> bool:
    """Whether a model's held-out misfit is a gap worth explaining: above noise_level (the nominal model's test,
    and the forward selection's test to go on)."""
    return nrmse > noise_level(floor, noise_factor, min_gap)


def explained_below(floor: float, explain_factor: float, explain_margin: float) -> float:
    """The absolute criterion: the held-out NRMSE at or below which a model explains the data,
    max(explain_factor x the noise floor, the floor + explain_margin)."""
    return max(explain_factor * floor, floor + explain_margin)


def explains(shrink: float, after: float, explained_below: float, min_shrink_pct: float) -> bool:
    """The report's test for 'explained': a model whose held-out shrink of the gap [%] reaches `min_shrink_pct` and
    whose held-out NRMSE `after` meets the absolute criterion (explained_below)."""
    return shrink >= min_shrink_pct and after <= explained_below


def detected_by_refit(before: float, after: float, min_cut: float) -> bool:
    """Whether a refit finds a gap below the noise threshold: it removes at least `min_cut` (a share, 0-1) of the
    held-out misfit `before` (the nominal's, or its refit's linear values alone when lower). The held-out files'
    noise is independent of the calibration files', so a refit fitting that noise carries nothing over to them."""
    return before > 0 and after <= (1.0 - min_cut) * before


def shrink_pct(before: float, after: float, reference: float) -> float:
    """How much of the gap above `reference` a model removes, in %: 100 (before - after) / (before - reference)."""
    return 100.0 * (before - after) / (before - reference) if before > reference else 0.0


def worth_a_path(shrink: float, linear: bool, min_shrink_pct: float) -> bool:
    """Whether a single effect that is not the first start of the forward selection starts a path of its own: a
    nonlinear one always; a change of the linear system itself (a sensor delay, the mass offsets) only when its
    refit removes `min_shrink_pct` [%] of the gap. A linear change that removes less holds nothing a nonlinear
    partner needs beside it: every partner is refitted with the linear parameters free on the first path."""
    return not linear or shrink >= min_shrink_pct


def score(before: float, after: float, reference: float, strengths: int) -> float:
    """Shrink [%] less PENALTY_POINTS per strength parameter beyond the first: what a candidate pays for."""
    return shrink_pct(before, after, reference) - PENALTY_POINTS * (strengths - 1)


def member_shares(members: list[str], shrink_of) -> dict[str, float]:
    """Each member's share of a combination's shrink [%]: its Shapley value, what it adds to the model of the
    members before it averaged over every order the members can be added in (the model without any shrinks 0),
    so that the shares sum to the combination's shrink whichever member was found first. `shrink_of(members)`
    gives the shrink of the model of those members (a frozenset), None where it was not refitted: then each
    member's share is what it adds to the members before it in the order given (a model not refitted counted
    at the combination's shrink)."""
    whole = shrink_of(frozenset(members))
    values = {frozenset(s): shrink_of(frozenset(s)) for k in range(1, len(members)) for s in
              itertools.combinations(members, k)}
    orders = list(itertools.permutations(members)) if None not in values.values() else [tuple(members)]
    values.update({frozenset(): 0.0, frozenset(members): whole})

    def value(subset):
        found = values[frozenset(subset)]
        return whole if found is None else found

    shares = dict.fromkeys(members, 0.0)
    for order in orders:
        for k, m in enumerate(order):
            shares[m] += (value(order[:k + 1]) - value(order[:k])) / len(orders)
    return shares


def adds_enough(smaller_after: float, larger_after: float, floor: float, min_excess_cut: float) -> bool:
    """Whether a model with more effects earns them: it removes at least `min_excess_cut` of the held-out misfit
    above the noise floor that the smaller model leaves (never when the smaller one leaves none)."""
    return smaller_after > floor and larger_after - floor <= (1.0 - min_excess_cut) * (smaller_after - floor)


def nothing_to_add(nrmse: float, explained_below: float, partner_explained: list[float],
                   min_partner_explained: float) -> bool:
    """Whether the forward selection ends at a model: its held-out NRMSE meets the absolute criterion
    (explained_below) and no candidate's sensitivity at it explains `min_partner_explained` of its calibration
    residual (the screening repeated at that model: fractions 0-1)."""
    return nrmse <= explained_below and max(partner_explained, default=0.0) < min_partner_explained


def budget_control(least_helpful_nrmse: float, siblings: int, min_siblings: int = CONTROL_SIBLINGS) -> float:
    """What more refit evaluations alone buy a model being extended: the held-out NRMSE of the joint refit of its
    extension whose added effect helped least, evaluated with that effect at zero (of `min_siblings` or more
    extensions tried from the same model, the least helpful one's added effect explains ~nothing, so its gain is
    the model's own parameters refitted on; at zero, an added effect that stands in for the true one does not
    count). inf when fewer extensions were tried (no control)."""
    return least_helpful_nrmse if siblings >= min_siblings else float("inf")


def leaner_best(order: list[str], sizes: dict[str, int], cuts: dict[str, float],
                min_share: float = LEANER_MIN_SHARE) -> list[str]:
    """Of models listed best first, the best one with fewer parameters than the first that cuts (`cuts`: the
    misfit of the model they extend less each one's) at least `min_share` of the first's cut ([] when none
    does)."""
    if not order:
        return []
    return [n for n in order if sizes[n] < sizes[order[0]] and cuts[n] >= min_share * cuts[order[0]]][:1]


def richer_best(order: list[str], sizes: dict[str, int], among: set[str]) -> list[str]:
    """Of models listed best first, the best one of `among` with more parameters than the first ([] when none
    has)."""
    return [n for n in order if n in among and sizes[n] > sizes[order[0]]][:1] if order else []


def lean_rival(joint, loops: set, after: dict, control) -> str | None:
    """Of one selection step's jointly refitted models (`joint`), the one not among `loops` (those with a
    free-shape loop) with the lowest held-out misfit (`after`), when a model among `loops` fits the held-out files
    better; None otherwise, and never the step's control (`control`: its refit stands for what evaluations alone
    buy). A loop of free shape can take up part of any effect, and the descent of a lean pair whose friction is
    near-ideal (a steep tanh) can stall short of its floor where the loop's many starts do not: that rival is
    refitted on before the step's best is chosen."""
    lean = [n for n in joint if n not in loops and n != control]
    if not lean or not any(n in loops for n in joint):
        return None
    rival = min(lean, key=after.__getitem__)
    return rival if min(after[n] for n in joint if n in loops) < after[rival] else None


def simpler_or_better(a: tuple[int, float], b: tuple[int, float], floor: float, min_excess_cut: float,
                      control: float = float("inf"), parameters: tuple[int, int] = (0, 0),
                      noise: float = 0.0, linear: bool = False) -> int:
    """Of two models given as (number of effects, held-out NRMSE), the index (0: a, 1: b) of the one kept: of
    two as large, the lower misfit, but the one with fewer `parameters` (each model's count) when both misfits
    are at or below `noise` (noise_level) and its misfit is within ALIKE of the other's (each under the noise,
    two misfits further apart on the same held-out files still tell the models apart), unless `linear` (either
    model holds a change of the linear system, effect.Effect.linear: within the noise its refit can take up the
    sensor chain's linear difference, so its few parameters are no evidence); else the larger only when it
    adds enough (adds_enough) to the smaller one credited with what refitting on alone buys it (the larger one's
    budget_control, when below its misfit)."""
    if a[0] == b[0]:
        if max(a[1], b[1]) <= noise and parameters[0] != parameters[1] and not linear:
            lean = 0 if parameters[0] < parameters[1] else 1
            if (a, b)[lean][1] <= (1.0 + ALIKE) * (a, b)[1 - lean][1]:
                return lean
        return 0 if a[1] <= b[1] else 1
    small, large = (0, 1) if a[0] < b[0] else (1, 0)
    pair = (a, b)
    return large if adds_enough(min(pair[small][1], control), pair[large][1], floor, min_excess_cut) else small
