"""The settings of a diagnosis, declared once (DiagnoseConfig): each with its default, its type and its role, which
says whether it changes how a fit is made (the stored fits' key holds it), only how results are judged, or only which
files are which (a stated confidence holds for every value of it); read from a TOML file's [diagnose] table."""
from __future__ import annotations

import dataclasses
import pathlib
import typing
from dataclasses import dataclass

from pyfit.io.schema import ConfigError, check_sections, check_table, fail, read_toml

FIT, JUDGING, LAYOUT = "fit", "judging", "layout"  # a setting's role (see the module's docstring)


def _setting(default, role: str):
    return dataclasses.field(default=default, metadata={"role": role})


class DiagnoseError(ConfigError):
    """Bad input to a diagnosis; names the file and field and what is allowed."""


@dataclass
class DiagnoseConfig:
    """Settings of a diagnosis (all optional)."""

    # candidate effects to test (default: all of the system's but the opt-in ones)
    effects: list | None = _setting(None, FIT)
    # file stems to calibrate on (default: diagnose.default_calibration)
    calibration: list | None = _setting(None, LAYOUT)
    # [[lo, hi], ...] [Hz] (default: localise.default_bands, 8 over the excited range)
    bands_hz: list | None = _setting(None, LAYOUT)
    nominal_budget: int = _setting(60, FIT)  # FMU evaluations of the nominal calibration
    refit_budget: int = _setting(120, FIT)  # FMU evaluations per refit with an effect
    # FMU input grid = analysis rate x upsample (None: the family's System.upsample, for a file faster than
    # pyfit.gap.rate.REFERENCE_HZ the fewer its rate needs: rate.drive_upsample)
    upsample: int | None = _setting(None, FIT)
    # a record that does not start at rest: seconds simulated from rest, not compared
    transient_s: float = _setting(4.0, LAYOUT)
    min_gap: float = _setting(0.005, JUDGING)  # NRMSE a gap must exceed beyond the noise floor to count
    noise_factor: float = _setting(1.2, JUDGING)  # ... and the noise floor times this
    close_points: float = _setting(15.0, JUDGING)  # runner-up within this many score points: reported as close
    min_shrink_pct: float = _setting(50.0, JUDGING)  # the best effect must shrink the gap by this much to be chosen
    # ... and bring the held-out NRMSE within explain_factor x the noise floor
    explain_factor: float = _setting(3.0, JUDGING)
    # ... or within the floor + explain_margin (the absolute criterion)
    explain_margin: float = _setting(0.02, JUDGING)
    # a nominal whose NRMSE on its best calibration file exceeds this "does not fit"
    nominal_max_nrmse: float = _setting(0.8, JUDGING)
    max_effects: int = _setting(2, JUDGING)  # effects combined at most (the forward selection)
    # candidates tried as the next member of a combination (by the screening at that model)
    partners: int = _setting(4, JUDGING)
    beam: int = _setting(2, JUDGING)  # single effects the forward selection starts from (the best-scoring ones)
    # share of the misfit above the noise floor a larger combination must remove
    min_excess_cut: float = _setting(0.5, JUDGING)
    # a combination's best starts each refitted a while before the best goes on
    combination_probes: int = _setting(3, FIT)
    # NRMSE a model's held-out misfit must exceed beyond the floor to add a member
    combination_min_gap: float = _setting(0.0, JUDGING)
    # ... and the floor (should the noise grow) times this: a weaker test than the nominal's noise_factor
    extend_factor: float = _setting(1.1, JUDGING)
    # a model meeting the absolute criterion is extended only when a candidate's sensitivity explains this share
    # of its calibration residual (the screening at that model)
    min_partner_explained: float = _setting(0.005, JUDGING)
    # when no model meets the absolute criterion: the best ones by held-out misfit, each refitted from the best
    # point of a grid over its members' strengths (systems.strength_grid)
    grid_models: int = _setting(3, JUDGING)
    # refit the single effects also when the nominal's held-out misfit is within the noise threshold (an effect
    # too weak for that test told from noise by its refit; false: a dataset without a gap costs no refits)
    refit_within_noise: bool = _setting(True, JUDGING)
    # with refit_within_noise: the gap counts when a single effect's refit removes this share of the held-out
    # misfit (selection.detected_by_refit)
    min_detect_cut: float = _setting(0.05, JUDGING)


def load_config(path) -> DiagnoseConfig:
    """A DiagnoseConfig from the [diagnose] table of a TOML file; one clear error per problem."""
    path = pathlib.Path(path)
    raw = read_toml(path, DiagnoseError)
    check_sections(raw, path, ("diagnose",), error=DiagnoseError)
    cfg = DiagnoseConfig(**check_table(raw.get("diagnose", {}), path, "diagnose", _spec(), DiagnoseError))
    for lo_hi in cfg.bands_hz or []:
        if not (isinstance(lo_hi, list) and len(lo_hi) == 2 and 0 <= lo_hi[0] < lo_hi[1]):
            fail(path, "diagnose.bands_hz", f"{lo_hi!r} is not [lo, hi]", "0 <= lo < hi [Hz]", DiagnoseError)
    return cfg


def settings_with_role(role: str) -> tuple[str, ...]:
    """The names of the settings of that role (FIT, JUDGING or LAYOUT)."""
    return tuple(f.name for f in dataclasses.fields(DiagnoseConfig) if f.metadata["role"] == role)


def _kind(f: dataclasses.Field):
    """What check_table expects of a setting, from its declared type."""
    hint = typing.get_type_hints(DiagnoseConfig)[f.name]
    args = set(typing.get_args(hint)) - {type(None)} or {hint}
    return list if list in args else bool if bool in args else int if int in args else "number"


def _spec() -> dict:
    return {f.name: (_kind(f), False, f.default) for f in dataclasses.fields(DiagnoseConfig)}
