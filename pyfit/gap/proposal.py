"""Which test would decide, where the data leave two models close: the tests a bench can run (stepped sines over
each band of the excited range, sweeps over all of it, at the recorded input levels and beyond them) simulated with
both models, ranked by how far their predictions differ in units of the sensor noise the data showed (SI units;
a force input in N, a clamp motion's velocity amplitude in m/s)."""
from __future__ import annotations

import pathlib
from dataclasses import dataclass

import numpy as np

from pyfit.analysis.excitation import Excitation, SteppedSine, motion_with_derivatives
from pyfit.gap import localise
from pyfit.gap import simulate as sim
from pyfit.gap.result import Diagnosis, NextTest, Verdict

LEVEL_FACTORS = ((0.5, "lowest"), (1.0, "highest"), (1.5, "highest"))  # of the recorded levels: a bench that
# ran a level can usually run half as much again, and half its lowest; further out, the models only extrapolate
STEPS = 5  # frequencies of a proposed stepped sine, log-spaced over one band
DWELL_PERIODS = 20  # each step's dwell: this many periods of its lowest frequency, at least MIN_DWELL_S
MIN_DWELL_S = 1.0
SWEEP_S = 30.0  # a proposed sweep's length [s] (a lab's sweep over the band: tens of seconds)
CLOSE_DETECTION = 0.5  # a 'no significant gap' whose best refit cut at least this share of min_cut is close


@dataclass(frozen=True)
class TestPlan:
    """One test a bench can run: a stepped sine (`steps` log-spaced frequencies over `band_hz`, each for
    `dwell_s`) or a linear sweep over `band_hz`, at the input amplitude `level` [N, or m/s for a clamp]."""

    kind: str
    level: float
    unit: str
    band_hz: tuple[float, float]
    steps: int
    dwell_s: float

    @property
    def duration_s(self) -> float:
        if self.kind == "stepped sine":
            return self.steps * self.dwell_s
        return SWEEP_S + 1.0  # and a second at the end frequency

    def signal(self, clamp: bool):
        """The test's input signal: a force, or a clamp displacement at constant velocity amplitude."""
        lo, hi = self.band_hz
        if self.kind == "stepped sine":
            return SteppedSine(tuple(np.geomspace(lo, hi, self.steps)), self.dwell_s, self.level,
                               glide_s=0.2 if clamp else 0.0, velocity=clamp)
        return Excitation(4 if clamp else 2, self.level, lo, hi, (hi - lo) / SWEEP_S, t_ramp=1.0)

    def sentence(self) -> str:
        """The test as an engineer would run it: 'stepped sine 30.0-40.0 Hz in 5 steps at 80 N (12 s)'."""
        lo, hi = self.band_hz
        how = f"in {self.steps} steps of {self.dwell_s:.1f} s" if self.kind == "stepped sine" else "linear"
        return f"{self.kind} {lo:.1f}-{hi:.1f} Hz {how} at {self.level:.3g} {self.unit} ({self.duration_s:.0f} s)"


@dataclass(frozen=True)
class Proposal:
    """The test that separates the two models `between` most (`separation`: the RMS of their predictions'
    difference over the RMS of the sensor noise, on the test's outputs) and every test tried with its separation."""

    between: tuple[str, str]
    test: TestPlan
    separation: float
    tried: tuple[tuple[TestPlan, float], ...]


def leaders(d: Diagnosis) -> tuple[str, str] | None:
    """The two models a test should separate where the report is not decisive: a 'no significant gap' whose best
    refit came close to the detection cut (that refit and the nominal); a runner-up scoring close (the first two);
    nothing explained (the two best). None for a decisive report."""
    if d.verdict is Verdict.NO_GAP:
        det = d.gap.detection
        return (det.effect, "nominal") if det and det.cut >= CLOSE_DETECTION * det.min_cut else None
    if d.verdict is Verdict.NOT_EXPLAINED or d.runner_up_close:
        return (d.ranking[0].effect, d.ranking[1].effect) if len(d.ranking) > 1 else None
    return None


def _input_level(rec: sim.Record, clamp: bool) -> float:
    """A record's input amplitude: the force's peak, or the clamp velocity's."""
    return float(np.max(np.abs(rec.compared("v_base" if clamp else next(iter(rec.inputs))))))


def candidate_tests(records, bands, clamp: bool) -> list[TestPlan]:
    """Stepped sines over each band and sweeps over the excited range, at LEVEL_FACTORS of the recorded levels."""
    levels = [_input_level(r, clamp) for r in records]
    unit = "m/s" if clamp else "N"
    plans = []
    for factor, of in LEVEL_FACTORS:
        level = factor * (min(levels) if of == "lowest" else max(levels))
        for lo, hi in bands:
            plans.append(TestPlan("stepped sine", level, unit, (lo, hi), STEPS,
                                  max(MIN_DWELL_S, DWELL_PERIODS / lo)))
        plans.append(TestPlan("linear sweep", level, unit, (bands[0][0], bands[-1][1]), 0, 0.0))
    return plans


def record_of_test(plan: TestPlan, fs: float, clamp: bool, outputs: tuple) -> sim.Record:
    """A Record of the test (inputs from rest; outputs zero: only their names count) at the sample rate fs."""
    t = np.arange(int(round(plan.duration_s * fs))) / fs
    signal = plan.signal(clamp)
    inputs = (motion_with_derivatives(signal, t, ("x_base", "v_base", "a_base")) if clamp else {"u": signal(t)})
    return sim.Record(plan.sentence(), plan.sentence(), plan.level, fs, inputs, dict.fromkeys(outputs, 0 * t), 0,
                      smooth_inputs=clamp)


def sensor_noise(records) -> dict[str, float]:
    """Each output's sensor noise standard deviation (the smallest any record shows: it does not grow with the
    level)."""
    per = localise.channel_noise(records)
    return {k: float(np.sqrt(min(per[r.name][k][0] for r in records))) for k in records[0].outputs}


def separation(a: dict | None, b: dict | None, noise: dict) -> float:
    """RMS over the outputs of the two predictions' difference over each output's noise (0 where one failed)."""
    if a is None or b is None:
        return 0.0
    return float(np.sqrt(np.mean([np.mean((a[k] - b[k]) ** 2) / noise[k] ** 2 for k in noise])))


def propose(runner, d: Diagnosis, params: dict, records, bands, upsample: int, lead_periods: int,
            clamp: bool) -> Proposal | None:
    """The test that separates the report's two leaders most (leaders), of candidate_tests; `params`: each model's
    FMU parameters by name ('nominal' among them). None for a decisive report."""
    pair = leaders(d)
    if pair is None:
        return None
    noise = sensor_noise(records)
    tried = []
    for plan in candidate_tests(records, bands, clamp):
        rec = record_of_test(plan, records[0].fs, clamp, tuple(noise))
        a, b = (sim.simulate(runner, rec, params[n], upsample, lead_periods) for n in pair)
        tried.append((plan, separation(a, b, noise)))
    best = max(tried, key=lambda ps: ps[1])
    return Proposal(pair, best[0], best[1], tuple(tried))


def proposed_for(runner, d: Diagnosis, records, upsample: int, lead_periods: int, clamp: bool) -> Proposal | None:
    """propose for a report: with each ranked model's and the nominal's values and the gap map's bands."""
    params = {**{f.effect: f.values for f in d.ranking}, "nominal": d.nominal.values}
    return propose(runner, d, params, records, [tuple(b.band_hz) for b in d.gap.by_band], upsample, lead_periods,
                   clamp)


def next_test(runner, d: Diagnosis, records, upsample: int, lead_periods: int, clamp: bool) -> NextTest | None:
    """The report's next test (proposed_for); None for a decisive report."""
    pr = proposed_for(runner, d, records, upsample, lead_periods, clamp)
    return None if pr is None else NextTest(pr.test.sentence(), pr.test.duration_s, pr.between, pr.separation)


def plan_test(diagnosed, cfg=None, fmu_dir="fmus", nominal=None) -> tuple[Proposal | None, object]:
    """The proposal for a finished diagnosis (its OUT folder: report.json holds the models' parameters and the
    dataset's folder), with the dataset read again as the diagnosis read it (the same settings and --nominal);
    returns it and what write_plan takes beside it (the report, the dataset's records, the system)."""
    from pyfit.gap.config import DiagnoseConfig
    from pyfit.gap.diagnose import prepare

    d = Diagnosis.read(pathlib.Path(diagnosed) / "report.json")
    if not d.nominal.values:
        raise ValueError(f"{diagnosed}/report.json holds no model's parameters (written before they were kept): "
                         "diagnose the dataset again into that folder (its stored fits are read, not redone)")
    p = prepare(d.model, d.source, cfg or DiagnoseConfig(), fmu_dir, nominal)
    try:
        pr = proposed_for(p.runner, d, p.data.records, p.cfg.upsample, p.system.lead_periods,
                          bool(p.system.motion_inputs))
    finally:
        p.runner.close()
    return pr, (d, p.data.records, p.system)


def write_plan(pr: Proposal | None, d: Diagnosis, records, system, out_dir) -> pathlib.Path:
    """OUT/plan.md (the proposed test, why, and every test tried) and, with a proposal, the test's drive file as
    the diagnosis reads measurements (OUT/next_test.csv + .toml: the inputs; add the outputs you record)."""
    from pyfit.io.data import write_measurement

    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    lines = [f"# Next test for {d.source} ({d.sentence})", ""]
    if pr is None:
        lines += ["The report is decisive: no test is proposed."]
    else:
        a, b = pr.between
        lines += [f"**{pr.test.sentence()}**: {a} and {b} differ there by {pr.separation:.2f} x the sensor noise "
                  "(the RMS of their predictions' difference over the noise's, per output sample).", "",
                  "Drive file: `next_test.csv` with `next_test.toml` (add the outputs you record, as in the "
                  "dataset's sidecars, and diagnose the dataset with it).", "",
                  "| test | separation [x noise] |", "|---|---|"]
        lines += [f"| {plan.sentence()} | {s:.2f} |" for plan, s in sorted(pr.tried, key=lambda ps: -ps[1])]
        clamp = bool(system.motion_inputs)
        fs = records[0].fs
        rec = record_of_test(pr.test, fs, clamp, ())
        units = {"x_base": "m", "v_base": "m/s", "a_base": "m/s2", "u": "N"}
        t = np.arange(len(next(iter(rec.inputs.values())))) / fs
        write_measurement(out / "next_test.csv", system.fmu, t,
                          {f"{k}_drive": (v, units[k], k) for k, v in rec.inputs.items()}, {},
                          level=pr.test.sentence(), level_value=pr.test.level,
                          notes=f"proposed to separate {a} and {b}")
    md = out / "plan.md"
    md.write_text("\n".join(lines) + "\n")
    return md
