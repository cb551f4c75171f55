"""A validation campaign of the diagnosis: random truths drawn from a generator independent of the FMUs (the
CasADi reference through pyfit.gap.datasets), written as a lab writes files, diagnosed one per worker (a
process pool or a Dask cluster), and judged against what was withheld.

Each case draws: nothing (a null case), one effect or a pair; each effect's strength log-uniformly from
`STRENGTH_RANGE` times the family's reference strength (a hysteresis loop of random shape, ν from 1 to 3), and its
own size over the sensor noise, log-uniformly from `sizing.SIZE_RANGE`, to which that strength is scaled on the
case's own records when they are written (pyfit.gap.sizing; the summary bins by the size the records show); the
excitation (two periods of a random-odd multisine, or a linear sweep, a stepped sine or band-limited noise
from rest, `record_s` long: records shorter than a test campaign's, to keep 200 cases near two hours on two
cores); the output recorded (displacement or acceleration); the noise seed. The effect-to-noise ratio of a
case is measured, not set: the nominal model's held-out misfit over the noise floor, both from the report.

The summary holds the confusion matrix (withheld × named), top-1 accuracy by effect-to-noise ratio (the
detection limit) and by the weakest withheld effect's own size over the noise (from the truth: a pair's weaker
member may hardly show where the pair stands far above the noise), the misses split by cause (undetected; not
favoured by the data: the named model fits the held-out files at least as well as the truth; the truth itself
failing the report's test for 'explained'; of the search), the false-alarm rate on the null cases, and
the hit rate by the report's margin (the best candidate's held-out shrink): the calibration a single report's
confidence is read from (pyfit.gap.confidence), and the check of the confidence the reports stated against
what happened.
"""
from __future__ import annotations

import dataclasses
import json
import pathlib
import time
from dataclasses import asdict, dataclass, field

import numpy as np

from pyfit.gap import confidence, datasets, follow_up, selection, sizing
from pyfit.gap.diagnose import DiagnoseConfig, diagnose, load_config, misfit_at
from pyfit.gap.result import Verdict
from pyfit.gap.effects import BUILTINS, drawn
from pyfit.gap.systems import FAMILY
from pyfit.io.nominal import NominalModel
from pyfit.runtime.batch import map_tasks

STRENGTH_RANGE = (0.05, 2.0)  # factor on the family's reference strength, drawn log-uniformly: the sizing's start
SHARES = {"none": 0.2, "single": 0.6, "pair": 0.2}  # how often a case withholds nothing, one effect, two
ENR_BINS = (0.0, 2.0, 5.0, 10.0, 20.0, np.inf)  # effect-to-noise ratio bins of the detection-limit table
RECORD_S, PERIODS = 6.0, 2  # a sweep's, stepped sine's or noise record's length [s]; multisine periods kept


@dataclass(frozen=True)
class Case:
    """One drawn case: what is withheld (a '+'-joined name, 'none'), its truth parameters (each effect at its
    drawn strength, scaled to `sizes` when the case is written), how it is recorded; for a damper also its
    geometry (FMU parameters, the messenger's EI among them), the clamp motion recorded and the test band [Hz];
    each withheld effect's size over the sensor noise to be written at."""

    index: int
    withheld: str
    truth: dict
    excitation: str
    outputs: tuple
    seed: int
    model: str = "sdof"
    base: dict | None = None
    motion: str = "xva"
    band_hz: tuple | None = None
    sizes: dict | None = None


def _effect_truth(model: str, effect: str, rng) -> dict:
    """One effect's truth at a random strength: a factor drawn log-uniformly from STRENGTH_RANGE on the family's
    reference, then the effect's own draw (pyfit.gap.effects: a loop's shape across the family)."""
    factor = float(np.exp(rng.uniform(*np.log(STRENGTH_RANGE))))
    return BUILTINS[model][effect].draw(rng, factor)


def damper_geometry(rng) -> tuple[dict, tuple]:
    """A catalogue damper drawn at random: masses 0.5-4 kg, arms 0.1-0.3 m, mass offsets 0-50 mm, radii of
    gyration 30-60 mm, the messenger's EI 5-60 N·m² (log-uniform); drawn again until its two lowest resonances
    (pyfit.reference.models.damper_modes_hz) lie within 4-60 Hz, as a catalogue damper's do; then the
    messenger's Rayleigh damping, alpha_pd 0.5-6 1/s and beta_pd 5e-5 to 8e-4 s (log-uniform: damping ratios of
    about 0.5-7 % at 10 Hz; never the FMU's start values). Returns the FMU parameters and the test band [Hz] a
    lab would sweep: half the lowest resonance to 2.2 times the second."""
    from pyfit.reference.models import damper_modes_hz

    while True:
        g = {}
        for i in (1, 2):
            g[f"m{i}"], g[f"L{i}"], g[f"a{i}"] = rng.uniform(0.5, 4.0), rng.uniform(0.1, 0.3), rng.uniform(0.0, 0.05)
            g[f"J_G{i}"] = g[f"m{i}"] * rng.uniform(0.03, 0.06) ** 2
        g["EI"] = np.exp(rng.uniform(np.log(5.0), np.log(60.0)))
        f = damper_modes_hz(g)
        if f[0] >= 4.0 and f[1] <= 60.0:
            g["alpha_pd"] = np.exp(rng.uniform(np.log(0.5), np.log(6.0)))
            g["beta_pd"] = np.exp(rng.uniform(np.log(5e-5), np.log(8e-4)))
            return {k: float(v) for k, v in g.items()}, (round(float(0.5 * f[0]), 2), round(float(2.2 * f[1]), 2))


DAMPER_OUTPUTS = (("x1", "x2"), ("acc_x1", "acc_x2"), ("F_clamp", "acc_x1"), ("acc_xg1", "acc_xg2"))
DAMPER_MOTIONS = ("x", "a", "xva")  # clamp displacement, acceleration, or all three (a shaker controller)


def draw(n: int, seed: int = 0, model: str = "sdof", excitation: str | None = None) -> list[Case]:
    """n cases of `model` ('sdof' or 'damper') drawn with numpy's generator from `seed` (the same n, seed and
    model give the same cases). The sizes come from a generator of their own (seeded with (seed, 1)), so that
    every other draw of a case is the one the same seed gave before sizes were drawn. `excitation` (one of
    datasets.excitations of the family) replaces every case's drawn excitation, after it is drawn: the same cases
    otherwise."""
    allowed = datasets.excitations(datasets.FAMILIES[model])
    if excitation is not None and excitation not in allowed:
        raise ValueError(f"campaign excitation '{excitation}' unknown for --model {model}; allowed: "
                         f"{', '.join(allowed)}")
    rng, size_rng = np.random.default_rng(seed), np.random.default_rng((seed, 1))
    cases = []
    for i in range(n):
        kind = rng.choice(list(SHARES), p=list(SHARES.values()))
        effects = [] if kind == "none" else list(rng.choice(drawn(model), 1 if kind == "single" else 2,
                                                            replace=False))
        truth = {}
        for e in effects:
            truth.update(_effect_truth(model, e, rng))
        withheld = "+".join(sorted(effects)) or "none"
        sizes = sizing.drawn_sizes([str(e) for e in effects], size_rng) or None
        if model == "sdof":
            cases.append(Case(i, withheld, truth, str(rng.choice(datasets.EXCITATIONS)),
                              (str(rng.choice(["y", "a"])),), int(rng.integers(1 << 30)), sizes=sizes))
            continue
        base, band = damper_geometry(rng)
        cases.append(Case(i, withheld, truth, str(rng.choice(datasets.CLAMP_EXCITATIONS)),
                          DAMPER_OUTPUTS[rng.integers(len(DAMPER_OUTPUTS))], int(rng.integers(1 << 30)), "damper",
                          base, str(rng.choice(DAMPER_MOTIONS)), band, sizes))
    return [dataclasses.replace(c, excitation=excitation) for c in cases] if excitation else cases


@dataclass(frozen=True)
class CaseJob:
    case: Case
    out: str
    fmu_dir: str
    record_s: float
    cfg: DiagnoseConfig = field(default_factory=DiagnoseConfig)  # the diagnosis's settings
    follow_up: bool = False  # run the test a report that is not decisive proposes, and diagnose again


def write_case(c: Case, out: pathlib.Path, record_s: float = RECORD_S) -> tuple[Case, pathlib.Path,
                                                                               NominalModel | None]:
    """Write one case's files into `out` as a lab would (records of `record_s` seconds where not periodic);
    returns the case with each withheld effect scaled to its drawn size, the dataset folder and what the user
    describes: for a damper its geometry (the messenger's EI and damping, the family's linear parameters, are
    what the nominal calibrates), else None."""
    family = datasets.FAMILIES[c.model]
    if c.band_hz:
        family = dataclasses.replace(family, band_hz=tuple(c.band_hz))
    style = datasets.LabStyle(c.excitation, tuple(c.outputs), c.motion, record_s=record_s)
    record = dict(seed=c.seed, periods=PERIODS, style=style, base=c.base)
    if c.sizes:  # each withheld effect scaled to its drawn size on the records as they will be written
        c = dataclasses.replace(c, truth=sizing.sized(c.truth, c.model, c.sizes, lambda truth: datasets.effect_sizes(
            family, c.withheld, truth=truth, **record)))
    data = datasets.write_dataset(out, family, c.withheld, truth=c.truth or None, **record)
    linear = FAMILY[c.model].linear
    described = NominalModel(c.model, {k: v for k, v in c.base.items() if k not in linear}) if c.base else None
    return c, data, described


def run_case(job: CaseJob) -> dict:
    """Write one case's files, diagnose them (one core), return the outcome; a finished case (its outcome.json)
    is read, not redone: an interrupted campaign resumes."""
    folder = pathlib.Path(job.out) / f"case{job.case.index:04d}"
    done = folder / "outcome.json"
    if done.is_file():
        return json.loads(done.read_text())
    t0 = time.perf_counter()
    c, data, described = write_case(job.case, folder / "data", job.record_s)
    written = time.perf_counter() - t0
    # fits an earlier run of this case stored (its outcome removed to diagnose it again): read, not run, so this
    # case's time is not a diagnosis's from scratch
    reused = any((folder / "diagnosis" / "fits").glob("*.json"))
    try:
        rep = diagnose(c.model, data, folder / "diagnosis", job.cfg, job.fmu_dir, workers=1,
                       progress=False, nominal=described)
        outcome = {"named": "+".join(sorted(rep.chosen)) or "none", "verdict": rep.verdict.value,
                   "enr": rep.gap.overall / rep.gap.noise_floor,
                   "top_shrink_pct": rep.best.shrink_pct if rep.best else None,
                   "stated": rep.confidence["rate"] if rep.confidence else None}
        # from the truth (the diagnosis never reads it): each withheld effect's own size over the noise, and the
        # truth's own misfit on the diagnosis's split (the FMU at the true parameters over the calibrated
        # nominal's others), against which a miss is one the data cannot decide or one of the search
        truth = json.loads((data / "truth.json").read_text())
        outcome["member_to_noise"] = truth["member_to_noise"]
        at_truth = misfit_at(c.model, data, {**rep.nominal.params, **truth["params"]}, job.cfg,
                             fmu_dir=job.fmu_dir, nominal=described)
        named = rep.fit_of(rep.chosen_name).heldout_gap_after if rep.chosen else rep.gap.overall
        outcome.update(truth_held_out=at_truth.held_out, truth_calibration=at_truth.calibration,
                       named_held_out=named, noise_floor=rep.gap.noise_floor, explained_below=rep.explained_below,
                       **truth_test(rep.gap.overall, rep.gap.shrink_reference, at_truth.held_out, job.cfg))
        if job.follow_up:
            outcome["follow_up"] = follow_up.run(folder, c, data, job.cfg, job.fmu_dir, described)
    except Exception as exc:  # a case that breaks the diagnosis is an outcome of the campaign, not its end
        outcome = {"named": "error", "verdict": f"{type(exc).__name__}: {exc}", "enr": None, "top_shrink_pct": None,
                   "stated": None}
    outcome.update({"case": asdict(c), "withheld": c.withheld, "data_s": written,
                    "diagnose_s": time.perf_counter() - t0 - written, "fits_reused": reused})
    done.write_text(json.dumps(outcome, indent=1, default=float))
    return outcome


def wall_of_runs(this_run: dict, n: int, earlier: dict | None) -> dict:
    """The wall time a campaign of `n` cases states (wall_s, resumed, where, earlier_wall_s), from this run's
    (`this_run`: its wall time, the cases it read from earlier runs, where it ran) and the summary the run before
    it wrote (`earlier`, None when there is none or no case was read). Every case read: the earlier run's, as it
    stated it. Else, when the earlier run covered these n cases (some removed since) or exactly the ones read (a
    campaign extended to more cases of the same draw), the earlier runs' wall time (earlier_wall_s): with this
    run's, a full run's at most."""
    if earlier and this_run["resumed"] == n:
        return {k: earlier[k] for k in ("wall_s", "resumed", "where", "earlier_wall_s") if k in earlier}
    if earlier and earlier.get("cases") in (n, this_run["resumed"]):
        return {**this_run, "earlier_wall_s": earlier["wall_s"] + earlier.get("earlier_wall_s", 0.0)}
    return this_run


def truth_test(before: float, shrink_reference: float, truth_held_out: float, cfg: DiagnoseConfig) -> dict:
    """What the report's test for 'explained' would make of the truth at its true parameters, had the search
    found it: its held-out shrink [%] of the gap, against the report's reference (the smaller of the noise floor
    should it grow with the level and every model's held-out misfit, the truth's among them), and the least shrink
    a named model must reach (cfg.min_shrink_pct)."""
    reference = min(shrink_reference, truth_held_out)
    return {"truth_shrink_pct": selection.shrink_pct(before, truth_held_out, reference),
            "min_shrink_pct": cfg.min_shrink_pct}


def stated_with(outcome: dict, calibration: dict | None) -> float | None:
    """The confidence (a rate, 0-1) the report of a campaign outcome states with `calibration`
    (pyfit.gap.confidence.stated; None without a calibration or a like report in it)."""
    chosen = None if outcome["named"] in ("none", "error") else outcome["named"]
    stated = confidence.stated(outcome["verdict"], chosen, outcome["top_shrink_pct"], calibration)
    return stated["rate"] if stated else None


def command(n: int, seed: int, model: str = "sdof", config: str | None = None, excitation: str | None = None,
            record_s: float = RECORD_S, follow: bool = False) -> str:
    """The command line that runs this campaign."""
    return (f"stockbridge diagnose --campaign {n} --campaign-seed {seed}" + ("" if model == "sdof" else
                                                                            f" --model {model}")
            + (f" --excitation {excitation}" if excitation else "")
            + (f" --record-s {record_s:g}" if record_s != RECORD_S else "")
            + (f" --config {config}" if config else "") + (" --follow-up" if follow else ""))


def run(n: int, out, fmu_dir="fmus", seed: int = 0, workers: int = 2, scheduler=None, record_s: float = RECORD_S,
        progress: bool = True, calibrate: bool = False, model: str = "sdof", config: str | None = None,
        excitation: str | None = None, follow: bool = False) -> dict:
    """Draw n cases of `model` (every one under `excitation` when given: draw) and diagnose them: on `scheduler`
    (a Dask scheduler address) when given, else on a Dask LocalCluster of `workers` single-threaded processes.
    Writes OUT/summary.md and OUT/summary.json (a campaign whose every case is stored is summarised again, with
    the wall time of the run that diagnosed them: wall_of_runs); with `calibrate`, its hit rates become the
    package's confidence calibration of `model` with its settings (pyfit.gap.confidence), and the summary states
    every report's confidence with it (in-sample); `config`: a TOML file of diagnosis settings
    (pyfit.gap.diagnose.load_config; default: the defaults); with `follow`, each case whose report is not decisive
    runs the test it proposes on the truth and is diagnosed again (pyfit.gap.follow_up)."""
    if calibrate and excitation:
        raise ValueError("--calibrate takes a campaign of every excitation (a report's confidence is read from it "
                         "whatever its records); drop --excitation")
    cases = draw(n, seed, model, excitation)
    for kind in {c.excitation for c in cases}:  # a record too short for an excitation: refused here, not per case
        datasets.LabStyle(kind, record_s=record_s)
    out = pathlib.Path(out)
    out.mkdir(parents=True, exist_ok=True)
    cfg = load_config(config) if config else DiagnoseConfig()
    settings = confidence.settings_of(asdict(cfg))
    stated_from = confidence.load(settings, model)
    jobs = [CaseJob(c, str(out), str(fmu_dir), record_s, cfg, follow) for c in cases]
    # cases an earlier run finished (interrupted, or a rerun of only some cases): read, not diagnosed again, so this
    # run's wall time does not cover them
    stored = [out / f"case{c.index:04d}" / "outcome.json" for c in cases]
    for path, c in zip(stored, cases):
        if path.is_file():
            _check_same_case(path, c)
    resumed = sum(path.is_file() for path in stored)
    t0 = time.perf_counter()
    if scheduler is None:
        from distributed import Client, LocalCluster

        with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None) as lc, \
                Client(lc) as client:
            outcomes = map_tasks(run_case, jobs, scheduler=client, progress=progress, desc="campaign")
        where = f"Dask LocalCluster, {workers} workers"
    else:
        outcomes = map_tasks(run_case, jobs, scheduler=scheduler, progress=progress, desc="campaign")
        where = f"Dask scheduler {scheduler}"
    before = out / "summary.json"
    earlier = json.loads(before.read_text()) if resumed and before.is_file() else None
    run_by = wall_of_runs({"wall_s": time.perf_counter() - t0, "resumed": resumed, "where": where}, n, earlier)
    if calibrate:
        stated_from = confidence.calibration_of(outcomes, command(n, seed, model, config, excitation, record_s, follow),
                                                seed, settings, model)
        confidence.write(stated_from)
    # every report's confidence as stated with the calibration this run reads or writes (an outcome read from an
    # earlier run holds the one that run read)
    outcomes = [{**o, "stated": stated_with(o, stated_from)} for o in outcomes]
    summary = summarise(outcomes)
    summary.update({"cases": n, "seed": seed, "record_s": record_s, "excitation": excitation, **run_by,
                    "command": command(n, seed, model, config, excitation, record_s, follow),
                    "model": model,
                    "stated_from": {k: stated_from[k] for k in ("source", "seed", "cases")} if stated_from else None})
    (out / "summary.json").write_text(json.dumps({**summary, "outcomes": outcomes}, indent=1, default=float))
    (out / "summary.md").write_text(markdown(summary))
    return summary


IDENTITY = ("model", "withheld", "excitation", "outputs", "seed")  # what tells one drawn case from another


def _check_same_case(path: pathlib.Path, case: Case) -> None:
    """An outcome stored in the campaign's folder must be of the case this run draws there (not of another
    --campaign-seed, --model or --excitation written to the same --out), else it would be read as this one's."""
    was = json.loads(path.read_text()).get("case", {})
    now = json.loads(json.dumps(asdict(case)))
    differ = [k for k in IDENTITY if k in was and was[k] != now[k]]
    if differ:
        def named(values):
            return ", ".join(f"{'noise seed' if k == 'seed' else k} {values[k]!r}" for k in differ)
        raise ValueError(f"{path}: a case of another campaign ({named(was)}; this run draws {named(now)} there): "
                         "give another --out, or the options that campaign ran with")


def _tally(outcomes: list[dict], size: int) -> dict:
    """Of the outcomes withholding `size` effects: how many, how many named right, how many named as one member."""
    inside = [o for o in outcomes if len(o["withheld"].split("+")) == size]
    return {"cases": len(inside), "hits": sum(o["named"] == o["withheld"] for o in inside),
            "one_member": sum(o["named"] in o["withheld"].split("+") for o in inside)}


def from_scratch(outcomes: list[dict]) -> list[dict]:
    """The outcomes whose diagnosis ran every fit (not those diagnosed again from the fits an earlier run stored)."""
    return [o for o in outcomes if not o.get("fits_reused")]


def times_by_kind(outcomes: list[dict]) -> list[dict]:
    """Per-case time on one core of the null cases, single effects and pairs diagnosed from scratch: how many, the
    median and the longest [s] of writing the files and diagnosing them, and of the diagnosis alone (a user's
    cost; writing the files holds the reference simulations and the sizing of each withheld effect)."""
    rows = []
    for kind, size in (("null cases", 0), ("single effects", 1), ("pairs", 2)):
        inside = [o for o in from_scratch(outcomes)
                  if (0 if o["withheld"] == "none" else len(o["withheld"].split("+"))) == size]
        spent = [o["data_s"] + o["diagnose_s"] for o in inside]
        diagnosing = [o["diagnose_s"] for o in inside]
        rows.append({"kind": kind, "cases": len(spent), "median_s": _median(spent),
                     "longest_s": max(spent, default=None), "diagnose_median_s": _median(diagnosing),
                     "diagnose_longest_s": max(diagnosing, default=None)})
    return rows


def _median(values: list[float]) -> float | None:
    return float(np.median(values)) if values else None


def _truth_named(o: dict) -> bool:
    """Whether the report's test for 'explained' (selection.explains) would name the truth at its true parameters
    (an outcome without truth_test's fields: by the absolute criterion alone)."""
    return selection.explains(o.get("truth_shrink_pct", float("inf")), o["truth_held_out"], o["explained_below"],
                              o.get("min_shrink_pct", 0.0))


def split_misses(effects: list[dict], nulls: list[dict]) -> dict:
    """The misses among the effect cases whose outcome holds the truth's misfit, split by what kept the withheld
    effect(s) from being named: undetected (verdict 'no significant gap': the nominal's held-out misfit within the
    noise threshold), undecided (the named model fits the held-out files at least as well as the truth at its true
    parameters: the data do not favour the truth), unnamed (the truth fits them better but would itself fail the
    report's test for 'explained': its misfit above the threshold, or its shrink of the gap below the least a named
    model needs, where the sensor chain's difference holds most of the gap), search (the rest: a miss of the search
    or of the selection). The truth at its true parameters carries the sensor chain's and the simulators'
    difference that a calibration takes up: `handicap` is its size, the median over the null cases of the truth's
    held-out misfit over the calibrated nominal's (the same structure)."""
    judged = [o for o in effects if o["named"] != o["withheld"] and o.get("truth_held_out") is not None]
    causes = [_miss_cause(o) for o in judged]
    same = [o["truth_held_out"] / o["named_held_out"] for o in nulls
            if o["named"] == "none" and o.get("truth_held_out") is not None]
    return {"judged": len(judged), **{c: causes.count(c) for c in ("undetected", "undecided", "unnamed", "search")},
            "handicap": float(np.median(same)) if same else None}


def _miss_cause(o: dict) -> str:
    """What kept a missed case's withheld effect(s) from being named (split_misses): the first that holds of
    undetected, undecided, unnamed; else search."""
    if o["verdict"] == Verdict.NO_GAP.value:
        return "undetected"
    if o["named_held_out"] <= o["truth_held_out"]:
        return "undecided"
    return "search" if _truth_named(o) else "unnamed"


def summarise(outcomes: list[dict]) -> dict:
    """Confusion matrix, top-1 accuracy by effect-to-noise ratio, false alarms on nulls, hit rate by margin (the
    calibration), stated confidence against the hit rate."""
    labels = sorted({o["withheld"] for o in outcomes} | {o["named"] for o in outcomes})
    confusion = {w: {n: sum(o["withheld"] == w and o["named"] == n for o in outcomes) for n in labels}
                 for w in labels}
    effects = [o for o in outcomes if o["withheld"] != "none"]
    nulls = [o for o in outcomes if o["withheld"] == "none"]
    by_enr = []
    for k in range(len(ENR_BINS) - 1):
        inside = [o for o in effects if confidence.bin_of(o["enr"], ENR_BINS) == k]
        by_enr.append({"enr": [ENR_BINS[k], ENR_BINS[k + 1]], "cases": len(inside),
                       "hits": sum(o["named"] == o["withheld"] for o in inside)})
    by_weakest = []  # by the weakest withheld effect's own size over the noise (datasets.write_dataset)
    sized = [o for o in effects if o.get("member_to_noise")]
    for k in range(len(ENR_BINS) - 1):
        inside = [o for o in sized if confidence.bin_of(min(o["member_to_noise"].values()), ENR_BINS) == k]
        by_weakest.append({"size": [ENR_BINS[k], ENR_BINS[k + 1]], "single": _tally(inside, 1),
                           "pair": _tally(inside, 2)})
    calibration = confidence.calibration_of(outcomes, "", 0)
    misses = split_misses(effects, nulls)
    decided = len(effects) - misses["undetected"] - misses["undecided"] - misses["unnamed"]  # what the data decide
    by_size = [{"kind": kind, **_tally(effects, size)} for size, kind in ((1, "single effects"), (2, "pairs"))]
    fresh = from_scratch(outcomes)  # the cases timed
    return {"labels": labels, "confusion": confusion, "by_size": by_size,
            "top1": sum(o["named"] == o["withheld"] for o in effects) / max(len(effects), 1),
            "misses": misses, "decided": decided,
            "top1_decided": sum(o["named"] == o["withheld"] for o in effects) / max(decided, 1),
            "effect_cases": len(effects), "null_cases": len(nulls),
            "false_alarms": sum(o["named"] != "none" for o in nulls), "by_enr": by_enr, "by_weakest": by_weakest,
            "by_shrink": calibration["by_shrink"], "no_gap": calibration["no_gap"], "check": confidence.check(outcomes),
            "errors": sum(o["named"] == "error" for o in outcomes),
            "median_case_s": _median([o["data_s"] + o["diagnose_s"] for o in fresh]),
            "times": times_by_kind(outcomes), "fits_reused": len(outcomes) - len(fresh),
            "follow_up": follow_up.summary(outcomes, _miss_cause)}


def _share(part: int, whole: int) -> str:
    return "—" if not whole else f"{100 * part / whole:.0f} %"


def markdown(s: dict) -> str:
    """The campaign summary as Markdown."""
    lines = _headline_lines(s) + _confusion_lines(s) + _size_lines(s) + _miss_lines(s) \
        + follow_up.lines(s.get("follow_up")) + _time_lines(s) + _calibration_lines(s)
    return "\n".join(lines) + "\n"


def _headline_lines(s: dict) -> list[str]:
    """What was run, where, how long it took; top-1 accuracy, false alarms and failures."""
    system = {"sdof": "SDOF", "damper": "damper (random geometry)"}[s.get("model", "sdof")]
    diagnosed = s["cases"] - s.get("resumed", 0)  # by this run
    lo, hi = sizing.SIZE_RANGE
    every = f", every case's excitation: {s['excitation'].replace('_', ' ')}" if s.get("excitation") else ""
    resumed = ""
    if s.get("resumed"):
        earlier = (f", whose runs took {s['earlier_wall_s'] / 60:.1f} min: a full run takes at most "
                   f"{(s['wall_s'] + s['earlier_wall_s']) / 60:.1f} min" if s.get("earlier_wall_s") else "")
        resumed = (f" for the {diagnosed} case{'' if diagnosed == 1 else 's'} this run diagnosed ({s['resumed']} read "
                   f"from an earlier run{earlier})")
    median = (f", median {s['median_case_s']:.0f} s per case diagnosed from scratch (writing the files and "
              "diagnosing)" if s["median_case_s"] is not None else "")
    return [f"{s['cases']} {system} cases (seed {s['seed']}{every}, records {s['record_s']:g} s, each withheld "
            f"effect at {lo:g}–{hi:g} × the sensor noise), {s['where']}: wall {s['wall_s'] / 60:.1f} min{resumed}"
            f"{median}; command: `{s['command']}`.", "",
            f"Top-1 accuracy on the {s['effect_cases']} cases with a withheld effect: {100 * s['top1']:.0f} %; "
            f"false alarms on the {s['null_cases']} null cases: {s['false_alarms']}; diagnoses that failed: "
            f"{s['errors']}.", ""]


def _confusion_lines(s: dict) -> list[str]:
    """The confusion matrix (withheld x named) and the hits by the number withheld."""
    lines = ["**Confusion matrix** (rows: withheld; columns: named)", "",
             "| withheld \\ named | " + " | ".join(s["labels"]) + " |", "|---|" + "---|" * len(s["labels"])]
    lines += [f"| {w} | " + " | ".join(str(s["confusion"][w][n] or "·") for n in s["labels"]) + " |"
              for w in s["labels"] if any(s["confusion"][w].values())]
    lines += ["", "**By the number withheld**", "", "| withheld | cases | named right | a pair named as one of its "
              "members |", "|---|---|---|---|"]
    lines += [f"| {b['kind']} | {b['cases']} | {_share(b['hits'], b['cases'])} | "
              f"{b['one_member'] if b['kind'] == 'pairs' else '—'} |" for b in s["by_size"]]
    return lines


def _size_lines(s: dict) -> list[str]:
    """Top-1 accuracy by effect-to-noise ratio, and by the weakest withheld effect's own size."""
    lines = ["", "**Detection limit**: top-1 accuracy by effect-to-noise ratio (nominal held-out misfit over "
             "the noise floor)", "", "| effect-to-noise ratio | cases | named right |", "|---|---|---|"]
    lines += [f"| {confidence.range_label(*b['enr'])} | {b['cases']} | {_share(b['hits'], b['cases'])} |"
              for b in s["by_enr"]]
    if not any(b["single"]["cases"] + b["pair"]["cases"] for b in s.get("by_weakest", ())):
        return lines
    lines += ["", "**By the weakest withheld effect's own size**: the RMS of the truth less the truth with that "
              "effect off, over the RMS of the sensor noise (every level and output; before any model takes "
              "up part of it, so a pair's weaker member may be largely taken up by a refit of the other)", "",
              "| weakest effect's size over the noise | single effects | named right | pairs | named right | "
              "a pair named as one of its members |", "|---|---|---|---|---|---|"]
    lines += [f"| {confidence.range_label(*b['size'])} | {b['single']['cases']} | "
              f"{_share(b['single']['hits'], b['single']['cases'])} | {b['pair']['cases']} | "
              f"{_share(b['pair']['hits'], b['pair']['cases'])} | {b['pair']['one_member']} |"
              for b in s["by_weakest"]]
    return lines


def _miss_lines(s: dict) -> list[str]:
    """The misses split by what kept the withheld effect(s) from being named, and the accuracy on the rest."""
    m = s.get("misses")
    if not (m and m["judged"]):
        return []
    lines = ["", "**Misses: the data or the search**: each miss's named model against the truth, both on the "
             "held-out files (the truth: the FMU at the true parameters over the calibrated nominal's others)",
             "", "| misses | cases |", "|---|---|",
             f"| undetected: verdict 'no significant gap' (the nominal within the noise threshold) | "
             f"{m['undetected']} |",
             f"| the named model fits the held-out files at least as well as the truth (the data do not favour "
             f"the truth) | {m['undecided']} |",
             f"| the truth fits them better but would itself not be named (its held-out shrink of the gap "
             f"below the least a named model needs, or its misfit above the explanation threshold) | "
             f"{m['unnamed']} |",
             f"| the truth fits them better and would be named (a miss of the search or of the selection) | "
             f"{m['search']} |", "",
             f"Top-1 accuracy on the {s['decided']} cases detected and decided by the data: "
             f"{100 * s['top1_decided']:.0f} %."]
    if m["handicap"] is not None:
        lines += ["", f"The truth at its true parameters carries the sensor chain (anti-alias filter, decimation) "
                  f"and the other simulator, which a calibration takes up: on the null cases its held-out misfit is "
                  f"{m['handicap']:.2f} × the calibrated nominal's (median), so a model with more freedom can fit "
                  "the held-out files better than the truth; the second row counts those."]
    return lines


def _time_lines(s: dict) -> list[str]:
    """Time per case on one core, by kind (null cases, single effects, pairs)."""
    if not s.get("times"):
        return []
    lines = ["", "**Time per case** on one core, the other cores diagnosing other cases: writing the files "
             "(the reference simulations and sizing each withheld effect) and diagnosing them, and the "
             "diagnosis alone (what a user's costs)", "",
             "| cases | number | writing and diagnosing: median [s] | longest [s] | diagnosis alone: median [s] "
             "| longest [s] |", "|---|---|---|---|---|---|"]
    lines += [f"| {t['kind']} | {t['cases']} | "
              + (f"{t['median_s']:.0f} | {t['longest_s']:.0f} | {t['diagnose_median_s']:.0f} | "
                 f"{t['diagnose_longest_s']:.0f} |" if t["cases"] else "— | — | — | — |")
              for t in s["times"]]
    if s.get("fits_reused"):
        n = s["fits_reused"]
        lines += ["", f"Left out: the {n} case{'' if n == 1 else 's'} diagnosed again from the fits an earlier "
                  "run stored (their outcome removed)."]
    return lines


def _calibration_lines(s: dict) -> list[str]:
    """The hit rate by the named model's shrink (the calibration), and the stated confidence against it."""
    q = s["no_gap"]
    lines = ["", "**Calibration**: when a report names an effect, how often it is right, by the named model's "
             "held-out shrink (a single report states the rate of its row as its confidence)", "",
             "| held-out shrink [%] | named | right |", "|---|---|---|"]
    lines += [f"| {confidence.range_label(*b['shrink_pct'])} | {b['named']} | {_share(b['right'], b['named'])} |"
              for b in s["by_shrink"]]
    lines += [f"| verdict 'no significant gap' | {q['verdicts']} | {_share(q['right'], q['verdicts'])} |"]
    src = s.get("stated_from")
    if not src:
        return lines
    inside = " (the same cases: in-sample, not a check)" if src["seed"] == s["seed"] else ""
    lines += ["", f"**Stated confidence against the hit rate**: the reports stated the confidence of the "
              f"calibration of `{src['source']}` ({src['cases']} cases){inside}", "",
              "| stated confidence | reports | mean stated | right |", "|---|---|---|---|"]
    lines += [f"| {c['stated_pct']} % | {c['reports']} | "
              f"{'—' if c['mean_stated'] is None else format(100 * c['mean_stated'], '.0f') + ' %'} | "
              f"{_share(c['right'], c['reports'])} |" for c in s["check"]]
    return lines
