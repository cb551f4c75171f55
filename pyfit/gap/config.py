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


def _setting(default, role: str, meaning: str):
    return dataclasses.field(default=default, metadata={"role": role, "meaning": meaning})


class DiagnoseError(ConfigError):
    """Bad input to a diagnosis; names the file and field and what is allowed."""


@dataclass
class DiagnoseConfig:
    """Settings of a diagnosis (all optional): each with its default, its role and what it means."""

    effects: list | None = _setting(None, FIT, "candidate effects to test (default: every built-in one but the "
                                     "opt-in ones)")
    calibration: list | None = _setting(None, LAYOUT, "file stems to calibrate on (default: every file of the "
                                        "lowest and highest level)")
    bands_hz: list | None = _setting(None, LAYOUT, "[[lo, hi], ...] Hz the gap is split into (default: 8 over "
                                     "the excited range)")
    nominal_budget: int = _setting(60, FIT, "FMU evaluations of the nominal calibration")
    refit_budget: int = _setting(120, FIT, "FMU evaluations per refit with an effect")
    upsample: int | None = _setting(None, FIT, "the FMU's input grid over the analysis rate (default: the "
                                    "family's, fewer for a file faster than 500 Hz)")
    transient_s: float = _setting(4.0, LAYOUT, "a record that does not start at rest: seconds simulated from "
                                  "rest before it, not compared")
    min_gap: float = _setting(0.005, JUDGING, "NRMSE a gap must exceed beyond the noise floor to count")
    noise_factor: float = _setting(1.2, JUDGING, "... and the noise floor times this")
    close_points: float = _setting(15.0, JUDGING, "a runner-up within this many score points is reported as close")
    min_shrink_pct: float = _setting(50.0, JUDGING, "the share of the gap [%] a model must remove to explain it")
    explain_factor: float = _setting(3.0, JUDGING, "... and its held-out NRMSE at most this times the noise "
                                     "floor")
    explain_margin: float = _setting(0.02, JUDGING, "... or at most the floor plus this (the absolute criterion)")
    nominal_max_nrmse: float = _setting(0.8, JUDGING, "a nominal whose NRMSE on its best calibration file "
                                        "exceeds this does not fit")
    max_effects: int = _setting(2, JUDGING, "effects combined at most")
    partners: int = _setting(4, JUDGING, "candidates tried as the next member of a combination")
    beam: int = _setting(2, JUDGING, "single effects the forward selection starts from")
    min_excess_cut: float = _setting(0.5, JUDGING, "share of the misfit above the noise a larger combination must "
                                     "remove")
    combination_probes: int = _setting(3, FIT, "a combination's best starts each refitted a while before the "
                                       "best goes on")
    combination_min_gap: float = _setting(0.0, JUDGING, "NRMSE a model's held-out misfit must exceed beyond the "
                                          "noise to add a member")
    extend_factor: float = _setting(1.1, JUDGING, "... and the noise times this")
    min_partner_explained: float = _setting(0.005, JUDGING, "a model that explains the data is extended only when "
                                            "a candidate's sensitivity explains this share of its residual")
    grid_models: int = _setting(3, JUDGING, "when nothing explains the data: the models refitted from the best "
                                "point of a grid over their strengths")
    refit_within_noise: bool = _setting(True, JUDGING, "refit the single effects also when the nominal fits "
                                        "within the noise threshold (a weak effect told from noise)")
    min_detect_cut: float = _setting(0.05, JUDGING, "... the gap then counts when a refit removes this share of "
                                     "the held-out misfit")


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


def settings_table() -> str:
    """The settings as a Markdown table: name, default, role and meaning (the documentation's reference)."""
    rows = ["| setting | default | role | meaning |", "|---|---|---|---|"]
    rows += [f"| `{f.name}` | {'—' if f.default is None else repr(f.default).lower()} | {f.metadata['role']} | "
             f"{f.metadata['meaning']} |" for f in dataclasses.fields(DiagnoseConfig)]
    return "\n".join(rows) + "\n"
