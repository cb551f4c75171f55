"""The diagnosis's result: a `Diagnosis` built once from the run and never changed after; report.json and report.md
are written from it, and `Diagnosis.from_json` reads a report.json back (the schema: report.schema.json beside this
module). Misfits are dimensionless (NRMSE of the time records, or the relative error of an impedance table),
frequencies in Hz, times in s."""
from __future__ import annotations

import dataclasses
import enum
import json
import pathlib
from dataclasses import dataclass

SCHEMA = pathlib.Path(__file__).with_name("report.schema.json")
SCHEMA_ID = "stockbridge-fmu/diagnosis/1"


class Verdict(str, enum.Enum):
    """What the diagnosis concludes of the gap between the nominal model and the data."""

    NO_GAP = "no significant gap"
    EXPLAINED = "gap explained"
    NOT_EXPLAINED = "gap not explained by the candidate effects"
    NOMINAL_MISFITS = "nominal model does not fit"


@dataclass(frozen=True)
class BandMisfit:
    """The nominal model's held-out misfit in one frequency band [Hz] (one frequency for an impedance table)."""

    band_hz: tuple[float, float]
    nrmse: float


@dataclass(frozen=True)
class LevelMisfit:
    """The nominal model's misfit on one file (one level), and that file's noise floor."""

    file: str
    level: str
    level_value: float
    held_out: bool
    nrmse: float | None  # None: the simulation failed
    noise_floor: float


@dataclass(frozen=True)
class Detection:
    """What the single effects' refits said of a nominal misfit within the noise threshold: the refit that
    leaves the least held-out misfit, its linear values alone (`linear_only`), the share it cuts and whether that
    reaches `min_cut` (then the gap counts)."""

    effect: str
    heldout_after: float
    linear_only: float
    reduced: bool
    cut: float
    min_cut: float
    detected: bool


@dataclass(frozen=True)
class Gap:
    """Where the nominal model misfits: overall on the held-out files, by band, level, channel, harmonic class and
    loop region; the noise floor from the data (and should the sensor noise grow with the level); whether the gap
    is significant; the single refits' detection where the nominal's test found none; the shrink's reference."""

    overall: float
    noise_floor: float
    noise_floor_scaled: float
    noise_floor_method: tuple[str, ...]
    significant: bool
    worst_band_hz: tuple[float, float]
    by_band: tuple[BandMisfit, ...]
    by_level: tuple[LevelMisfit, ...]
    failed_files: tuple[str, ...] = ()
    by_channel: dict = dataclasses.field(default_factory=dict)  # output -> held-out NRMSE
    by_harmonic: dict | None = None  # 'odd_detection' etc. -> {'misfit', 'noise'}
    by_loop_region: dict = dataclasses.field(default_factory=dict)  # region -> NRMSE contribution
    detection: Detection | None = None
    shrink_reference: float | None = None  # what a shrink of 100 % brings the misfit to
    metric: str = "NRMSE"


@dataclass(frozen=True)
class ModelFit:
    """One model the diagnosis refitted (a single effect or a combination of `members`), judged on the held-out
    files: its misfit before and after, the shrink [%] of the gap and the score, its fitted values (SI), cost and
    whether it explains the gap; `kept`: a single effect, or the combination the selection kept."""

    effect: str
    members: tuple[str, ...]
    score: float
    heldout_gap_before: float
    heldout_gap_after: float
    shrink_pct: float
    params: dict
    n_added_params: int
    calibration_nrmse: float
    evaluations: int
    explains: bool
    kept: bool = True
    screening_explained: float | None = None
    wall_s: float | None = None
    from_envelopes: bool = False
    member_shares_pct: dict | None = None
    prediction_band: dict | None = None
    explains_in_band: bool | None = None
    values: dict = dataclasses.field(default_factory=dict)  # every FMU parameter the model sets (SI): to simulate it


@dataclass(frozen=True)
class NominalFit:
    """The calibrated nominal model: its free parameters (SI), calibration misfit and evaluations, and every FMU
    parameter it sets."""

    params: dict
    calibration_nrmse: float
    evaluations: int
    values: dict = dataclasses.field(default_factory=dict)


@dataclass(frozen=True)
class Separation:
    """Where the two close leaders' refitted models differ most (each level tried: `levels`; `measure_next`)."""

    between: tuple[str, str]
    levels: tuple[dict, ...]
    measure_next: dict | None


@dataclass(frozen=True)
class NextTest:
    """The test a report that is not decisive proposes (pyfit.gap.proposal): what to run, its length [s], the two
    models it separates and by how much (the RMS of their predictions' difference over the sensor noise's)."""

    test: str
    duration_s: float
    between: tuple[str, str]
    separation: float


@dataclass(frozen=True)
class Diagnosis:
    """A diagnosis: the verdict, the effects it names, where the gap is, the ranked models, the evidence and the
    stated confidence, with what the data were and how the run went."""

    model: str
    fmu: str
    source: str  # the dataset folder or impedance table diagnosed
    verdict: Verdict
    chosen: tuple[str, ...]  # the effects named (empty unless the verdict is EXPLAINED)
    explained_below: float  # the held-out misfit at or below which a model explains the data
    gap: Gap
    ranking: tuple[ModelFit, ...]
    evidence: tuple[str, ...]
    nominal: NominalFit
    calibration_files: tuple[str, ...]
    held_out_files: tuple[str, ...]
    confidence: dict | None = None  # pyfit.gap.confidence.Confidence as a dict
    runner_up_close: bool = False
    separation: Separation | None = None
    confined_misfit: dict | None = None  # pyfit.gap.localise.ConfinedMisfit as a dict
    listed_starts: dict = dataclasses.field(default_factory=dict)
    data_scale: dict = dataclasses.field(default_factory=dict)
    level_order: str = ""
    set_aside: dict = dataclasses.field(default_factory=dict)
    voltage_channels: tuple[str, ...] = ()
    clipped_channels: dict = dataclasses.field(default_factory=dict)
    analysis_rate: dict | None = None
    compared_from_hz: dict = dataclasses.field(default_factory=dict)  # file -> the frequency its outputs are
    # compared above (a displacement integrated from an accelerometer drifts below it)
    stage_s: dict = dataclasses.field(default_factory=dict)
    figures: tuple[str, ...] = ()  # the figures beyond the gap map and the overlay
    next_test: NextTest | None = None  # where the report is not decisive: the test that would decide

    @property
    def significant(self) -> bool:
        """Whether the gap counts (the nominal's test, or a single refit's detection below it)."""
        return self.gap.significant

    @property
    def chosen_name(self) -> str | None:
        """The chosen model's name as the ranking lists it ('a + b' for a pair), None when none is chosen."""
        return " + ".join(self.chosen) if self.chosen else None

    @property
    def sentence(self) -> str:
        """The verdict as a reader says it: 'gap explained by cubic_stiffness'."""
        return f"{self.verdict.value} by {self.chosen_name}" if self.chosen else self.verdict.value

    @property
    def best(self) -> ModelFit | None:
        """The first-ranked model (the chosen one when one is chosen)."""
        return self.ranking[0] if self.ranking else None

    def fit_of(self, name: str) -> ModelFit:
        """The ranked model of that name."""
        return next(f for f in self.ranking if f.effect == name)

    def to_json(self) -> dict:
        """The report as report.json holds it (report.schema.json)."""
        d = dataclasses.asdict(self)
        d.update(schema=SCHEMA_ID, verdict=self.verdict.value, sentence=self.sentence,
                 chosen_effect=self.chosen_name)
        return json.loads(json.dumps(d, default=float))

    @classmethod
    def from_json(cls, d: dict) -> Diagnosis:
        """The Diagnosis a report.json holds."""
        gap = dict(d["gap"])
        gap.update(by_band=tuple(BandMisfit(tuple(b["band_hz"]), b["nrmse"]) for b in gap["by_band"]),
                   by_level=tuple(LevelMisfit(**v) for v in gap["by_level"]),
                   detection=Detection(**gap["detection"]) if gap.get("detection") else None,
                   worst_band_hz=tuple(gap["worst_band_hz"]), failed_files=tuple(gap["failed_files"]),
                   noise_floor_method=tuple(gap["noise_floor_method"]))
        names = {f.name for f in dataclasses.fields(cls)}
        fields = {k: v for k, v in d.items() if k in names}
        sep = d.get("separation")
        fields.update(
            verdict=Verdict(d["verdict"]), chosen=tuple(d["chosen"]), gap=Gap(**gap),
            ranking=tuple(ModelFit(**{**r, "members": tuple(r["members"])}) for r in d["ranking"]),
            evidence=tuple(d["evidence"]), nominal=NominalFit(**d["nominal"]),
            calibration_files=tuple(d["calibration_files"]), held_out_files=tuple(d["held_out_files"]),
            separation=Separation(tuple(sep["between"]), tuple(sep["levels"]), sep["measure_next"]) if sep else None,
            voltage_channels=tuple(d.get("voltage_channels", ())), figures=tuple(d.get("figures", ())),
            next_test=NextTest(**{**d["next_test"], "between": tuple(d["next_test"]["between"])})
            if d.get("next_test") else None)
        return cls(**fields)

    @classmethod
    def read(cls, path) -> Diagnosis:
        """The Diagnosis of a report.json file."""
        return cls.from_json(json.loads(pathlib.Path(path).read_text()))

    def _repr_markdown_(self) -> str:
        """A notebook's view: the verdict, the confidence and the five best models."""
        lines = [f"**{self.sentence}** ({self.model}; held-out {self.gap.metric} of the nominal "
                 f"{self.gap.overall:.4f}, noise floor {self.gap.noise_floor:.4f})", ""]
        if self.confidence:
            lines += [f"Confidence {100 * self.confidence['rate']:.0f} %", ""]
        if self.ranking:
            lines += ["| model | shrink [%] | held-out after | explains |", "|---|---|---|---|"]
            lines += [f"| {f.effect} | {f.shrink_pct:.1f} | {f.heldout_gap_after:.4f} | "
                      f"{'yes' if f.explains else 'no'} |" for f in self.ranking[:5]]
        return "\n".join(lines)
