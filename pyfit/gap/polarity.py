"""A measured channel whose sign convention is the model's opposite (a load cell that reads tension where the
model's force is compression, an accelerometer mounted upside down): the linear nominal then fits no
calibration file, and fits them once that channel's sign is changed.

Only asked when the calibrated nominal does not fit (its calibration NRMSE above `nominal_max_nrmse`): each output
alone, then every output at once (the same as the input's sign changed), is changed in sign and the nominal
calibrated again; the first change after which the nominal fits is the answer.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from pyfit.gap.attribute import nominal_task, run_fit


@dataclass(frozen=True)
class SignChange:
    """Outputs (model variables) whose sign changed lets the nominal fit, and its calibration NRMSE then."""

    outputs: tuple[str, ...]
    every_output: bool  # all of them: the input's sign convention may be the one that differs
    nrmse_changed: float


def with_signs_changed(records: list, outputs: tuple[str, ...]) -> list:
    """The records with the listed outputs' samples changed in sign."""
    return [dataclasses.replace(r, outputs={k: -y if k in outputs else y for k, y in r.outputs.items()})
            for r in records]


def sign_change(system, fmu: str, cal: list, budget: int, upsample: int, threads: int,
                max_nrmse: float) -> SignChange | None:
    """The outputs whose sign changed lets the nominal model fit the calibration records `cal` (its calibration
    NRMSE at most `max_nrmse`); None when no such change does. Each output alone is tried first, then all of
    them."""
    names = tuple(cal[0].outputs)
    trials = [(k,) for k in names] + ([names] if len(names) > 1 else [])
    for outputs in trials:
        fit = run_fit(nominal_task(system, fmu, with_signs_changed(cal, outputs), budget, upsample, threads))
        if fit.calibration_nrmse <= max_nrmse:
            return SignChange(outputs, outputs == names, fit.calibration_nrmse)
    return None

