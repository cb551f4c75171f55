"""A diagnosis's stated confidence, read from a validation campaign's hit rates (pyfit.gap.campaign).

The campaign counts, per bin of the named model's held-out shrink, how many reports named an effect and how many
of those were right; and how many 'no significant gap' verdicts had nothing withheld. A single report states the
hit rate of its bin as the centre of the Wilson 95 % interval of that count, with the interval (few cases give
a wide interval, and the report says so; the centre keeps a bin of one or two reports from stating 0 or 100 %).
A hit rate is a property of the decision rule and of the system as much as of the data: the package carries one
calibration per system family and set of diagnosis settings a campaign was run with (calibration.json beside
this module, written by `stockbridge diagnose --campaign N [--model M] [--config FILE] --calibrate`), and a
report states the confidence of the one of its own family whose settings equal its own (settings_of: every
setting but the ones that only say where the data are), none when no campaign was run with them. A campaign
with other cases checks how well the stated confidence matches what happens.
"""
from __future__ import annotations

import json
import math
import pathlib
from dataclasses import asdict, dataclass

import numpy as np

from pyfit.gap.config import LAYOUT, settings_with_role
from pyfit.gap.result import Verdict

CALIBRATION = pathlib.Path(__file__).with_name("calibration.json")
SHRINK_BINS = (-np.inf, 50.0, 80.0, 95.0, np.inf)  # the named model's held-out shrink [%]
STATED_BINS = (0.0, 0.5, 0.8, 0.95, 1.0 + 1e-9)  # stated confidence, for the check against the hit rate
# diagnosis settings that say which files are which and what is compared, not how a verdict is reached
LAYOUT_SETTINGS = settings_with_role(LAYOUT)


@dataclass(frozen=True)
class Confidence:
    """The hit rate of the campaign's reports like this one (`alike`: `right` of `of`) as the centre of its Wilson
    95 % interval [low, high], and the campaign it comes from (`source`: its command, `seed`, `cases`)."""

    rate: float
    right: int
    of: int
    low: float
    high: float
    alike: str
    source: str
    seed: int
    cases: int

    def sentence(self) -> str:
        """The report's line: the rate, its interval and where it comes from."""
        return (f"Confidence {100 * self.rate:.0f} % (95 % interval {100 * self.low:.0f}–{100 * self.high:.0f} %): "
                f"in a validation campaign of {self.cases} random cases (`{self.source}`), {self.right} of the "
                f"{self.of} reports {self.alike} were right.")


def wilson_centre(right: int, of: int, z: float = 1.96) -> float:
    """Centre of the Wilson score interval, (right + z²/2) / (of + z²): the hit rate pulled towards 1/2 by as much
    as the count is small (0.5 when of = 0)."""
    return (right + z * z / 2) / (of + z * z)


def wilson(right: int, of: int, z: float = 1.96) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion right/of (z = 1.96: 95 %), about wilson_centre."""
    if of == 0:
        return 0.0, 1.0
    p, centre = right / of, wilson_centre(right, of, z)
    half = z * math.sqrt(p * (1 - p) / of + z * z / (4 * of * of)) / (1 + z * z / of)
    return max(0.0, centre - half), min(1.0, centre + half)


def bin_of(value: float | None, edges) -> int | None:
    """Index of the bin of `edges` holding value (None for None)."""
    return None if value is None else int(np.searchsorted(edges, value, side="right") - 1)


def range_label(lo: float, hi: float) -> str:
    """'≥ 95', '80–95', '< 50' for the bin [lo, hi) (an open end: ±inf; a bin from 0: '< hi')."""
    return f"≥ {lo:g}" if hi == np.inf else f"< {hi:g}" if lo in (0.0, -np.inf) else f"{lo:g}–{hi:g}"


def shrink_label(k: int) -> str:
    """The label of the shrink bin k."""
    return range_label(SHRINK_BINS[k], SHRINK_BINS[k + 1])


def settings_of(config: dict) -> dict:
    """The settings a calibration is of: a diagnosis's settings (dataclasses.asdict of its DiagnoseConfig) but
    the LAYOUT_SETTINGS."""
    return {k: v for k, v in config.items() if k not in LAYOUT_SETTINGS}


def calibration_of(outcomes: list[dict], source: str, seed: int, settings: dict | None = None,
                   model: str = "sdof") -> dict:
    """The calibration table of a campaign's outcomes (each: named, withheld, verdict, top_shrink_pct) of
    `model` cases (a system family: pyfit.gap.systems.FAMILY), run with `settings` (settings_of)."""
    named = [o for o in outcomes if o["named"] not in ("none", "error")]
    by_shrink = []
    for k in range(len(SHRINK_BINS) - 1):
        inside = [o for o in named if bin_of(o["top_shrink_pct"], SHRINK_BINS) == k]
        by_shrink.append({"shrink_pct": [SHRINK_BINS[k], SHRINK_BINS[k + 1]], "named": len(inside),
                          "right": sum(o["named"] == o["withheld"] for o in inside)})
    quiet = [o for o in outcomes if o["verdict"] == Verdict.NO_GAP.value]
    return {"source": source, "seed": seed, "cases": len(outcomes), "model": model, "settings": settings or {},
            "by_shrink": by_shrink,
            "no_gap": {"verdicts": len(quiet), "right": sum(o["withheld"] == "none" for o in quiet)}}


def _stored(path: pathlib.Path) -> list[dict]:
    return json.loads(path.read_text())["calibrations"] if path.is_file() else []


def write(calibration: dict, path: pathlib.Path = CALIBRATION) -> pathlib.Path:
    """Store a calibration (in the package's file by default), in place of one of the same family and settings;
    those made before a setting was added or after one was removed (other setting names) are dropped: no
    diagnosis can read them any more."""
    kept = [c for c in _stored(path) if c["settings"].keys() == calibration["settings"].keys()
            and (c["model"], c["settings"]) != (calibration["model"], calibration["settings"])]
    path.write_text(json.dumps({"calibrations": kept + [calibration]}, indent=1, default=float) + "\n")
    return path


def load(settings: dict, model: str = "sdof", path: pathlib.Path = CALIBRATION) -> dict | None:
    """The stored calibration of `model` cases with these settings (settings_of), None when no campaign of that
    family was run with them (a setting added since a calibration was made counts as another setting)."""
    return next((c for c in _stored(path) if c["model"] == model and c["settings"] == settings), None)


def stated(verdict: str, chosen: str | None, shrink_pct: float | None, calibration: dict | None) -> dict | None:
    """The confidence a report states (a Confidence as a dict), or None when there is no calibration or the
    campaign holds no report like this one (an effect named with a shrink in this bin; 'no significant gap')."""
    if calibration is None:
        return None
    if chosen and shrink_pct is not None:
        k = bin_of(shrink_pct, SHRINK_BINS)
        row = calibration["by_shrink"][k]
        right, of = row["right"], row["named"]
        alike = f"that named an effect with a held-out shrink of {shrink_label(k)} %"
    elif verdict == Verdict.NO_GAP.value:
        right, of = calibration["no_gap"]["right"], calibration["no_gap"]["verdicts"]
        alike = "with the verdict 'no significant gap' (right: nothing was withheld)"
    else:
        return None
    if of == 0:
        return None
    low, high = wilson(right, of)
    return asdict(Confidence(wilson_centre(right, of), right, of, low, high, alike, calibration["source"],
                             calibration["seed"], calibration["cases"]))


def check(outcomes: list[dict]) -> list[dict]:
    """Stated confidence against the hit rate: per STATED_BINS bin, the reports that stated a confidence in it,
    their mean stated rate and how many were right (a named effect equal to the withheld one; 'no significant
    gap' with nothing withheld)."""
    rows = []
    for k in range(len(STATED_BINS) - 1):
        inside = [o for o in outcomes if o.get("stated") is not None and bin_of(o["stated"], STATED_BINS) == k]
        hi = np.inf if k == len(STATED_BINS) - 2 else 100 * STATED_BINS[k + 1]
        rows.append({"stated_pct": range_label(100 * STATED_BINS[k], hi), "reports": len(inside),
                     "mean_stated": float(np.mean([o["stated"] for o in inside])) if inside else None,
                     "right": sum(o["named"] == o["withheld"] for o in inside)})
    return rows
