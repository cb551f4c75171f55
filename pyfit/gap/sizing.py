"""Withheld effects drawn at a size over the sensor noise rather than at a strength.

An effect's size is what datasets.write_dataset records as `member_to_noise`: the RMS of the truth less the truth
with that effect off, over the RMS of the sensor noise, on the very records a case writes. The same strength
shows below the noise on one sensor set and excitation and hundreds of times above it on another, so a campaign
that is to map the detection limit draws the size and scales each withheld effect's strength parameters until the
records show it (`sized`)."""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

from pyfit.gap.effects import BUILTINS

SIZE_RANGE = (0.5, 20.0)  # an effect's own size over the sensor noise, drawn log-uniformly
ROUNDS = 2  # rounds of scaling a single effect (each writes the records once), one more for a pair; the records
# written last measure the size got
MAX_STEP = 100.0  # one round scales a strength by at most this factor either way


def drawn_sizes(effects: list[str], rng) -> dict[str, float]:
    """A size over the noise for each effect, log-uniform over SIZE_RANGE."""
    return {e: float(np.exp(rng.uniform(*np.log(SIZE_RANGE)))) for e in effects}


def max_gain(truth: dict, model: str, effect: str) -> float:
    """The largest factor an effect's strength may take (its declaration's bound: pyfit.gap.effects)."""
    return BUILTINS[model][effect].largest_gain(truth)


def scaled(truth: dict, model: str, gains: dict[str, float]) -> dict:
    """`truth` with each effect scaled by its gain by the effect's size rule (pyfit.gap.effect.Builtin.scale: its
    strengths times the gain; an SDOF loop as a whole), each from the truth given."""
    out = dict(truth)
    for effect, gain in gains.items():
        out.update(BUILTINS[model][effect].scale(truth, gain))
    return out


def sized(truth: dict, model: str, targets: dict[str, float], sizes_of: Callable[[dict], dict]) -> dict:
    """`truth` with each effect of `targets` (effect -> its size over the noise wanted) scaled to show at that
    size: `sizes_of(truth)` measures every effect's size (on the records written with that truth), and each round
    scales a strength by target / size. An effect small beside the noise grows in proportion to its strength, so
    the second round lands near its target wherever the first started (a strong spring's jump or a saturated loop
    far from proportion); a third corrects a pair's members for each other (each one's size is measured with
    the other on): ROUNDS rounds, one more for a pair."""
    gains = {e: 1.0 for e in targets}
    for _ in range(ROUNDS + (len(targets) > 1)):
        now = sizes_of(scaled(truth, model, gains))
        for e, target in targets.items():
            if now.get(e, 0.0) > 0:
                step = float(np.clip(target / now[e], 1.0 / MAX_STEP, MAX_STEP))
                gains[e] = min(gains[e] * step, max_gain(truth, model, e))
    return scaled(truth, model, gains)
