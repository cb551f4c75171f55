"""The diagnosis report's text (pyfit.gap.report): how a candidate's listed starts are written in report.md, and
what a gap no candidate explains is told with."""
from pyfit.gap.diagnose import DiagnoseConfig
from pyfit.gap.evidence import POOR_LINEAR_NRMSE, not_explained_lines
from pyfit.gap.report import LISTED_IN_FULL, starts_text
from pyfit.gap.result import Diagnosis, Gap, ModelFit, NominalFit, Verdict
from pyfit.gap.effect import Scale
from pyfit.gap.effects import candidates
from pyfit.gap.systems import FAMILY


def test_a_few_starts_are_written_one_by_one():
    starts = [{"k3": 2.0e8}, {"k3": -2.0e8}]
    assert starts_text(starts) == "k3 = 2e+08; k3 = -2e+08"


def test_many_starts_are_summarised_by_parameter():
    """The SDOF loop's starts (more than LISTED_IN_FULL): ν's three values, the five hysteretic shares of
    k = 1e5 N/m, the turnover forces' range (at σ_y = 1 mm and ν = 1 F_t = α·σ_y / (width·(|γ| + |δ|)): from the
    weakest element's narrowest loop, 300 N/m·1 mm / 2, to the strongest's widest, 60000 N/m·1 mm / 0.01), the
    five listed branch shapes and where the full list is."""
    scale = Scale(1e-3, 0.2, 1e5, {})
    starts = candidates("sdof")["hysteresis"].starts(scale)
    assert len(starts) > LISTED_IN_FULL
    text = starts_text(starts)
    assert "nu in {1, 2, 3}" in text
    assert "alpha in {300, 3000, 10000, 30000, 60000}" in text
    assert "F_t from 0.15 to 6000 (" in text and "branch in {-0.5, 0.5, 1, 2, 2.5}" in text
    assert text.endswith("(each start in report.json, `listed_starts`)")


def _fit(effect: str, shrink_pct: float, after: float) -> ModelFit:
    return ModelFit(effect, tuple(effect.split(" + ")), shrink_pct, 0.6, after, shrink_pct, {}, 1, 0.1, 100, False)


GAP = Gap(overall=0.6, noise_floor=0.01, noise_floor_scaled=0.01, noise_floor_method=(), significant=True,
          worst_band_hz=(4.7, 6.1), by_band=(), by_level=())


def _unexplained(best_calibration_nrmse: float, shrinks: dict) -> list[str]:
    ranking = [_fit(n, v, 0.5) for n, v in shrinks.items()]
    return not_explained_lines(ranking[0], ranking, GAP, (best_calibration_nrmse, "level1"), 0.05, DiagnoseConfig(),
                               FAMILY["sdof"].outside)


def test_a_nominal_that_misfits_every_file_and_refits_that_remove_little_are_said_first():
    """Both conditions: the linear nominal misfits even its best calibration file beyond POOR_LINEAR_NRMSE and no
    refit removes the required shrink (DiagnoseConfig.min_shrink_pct): the first line says so, with the numbers,
    and what to try; either condition alone leaves the usual three lines."""
    required = DiagnoseConfig().min_shrink_pct
    lines = _unexplained(0.702, {"sensor_delay": 12.1, "hysteresis": 0.2})
    assert len(lines) == 4
    assert "(level1) at NRMSE 0.702" in lines[0] and "more than 12.1 %" in lines[0] and "Record a level" in lines[0]
    assert lines[1].startswith("best candidate sensor_delay")
    assert len(_unexplained(POOR_LINEAR_NRMSE * 0.99, {"sensor_delay": 12.1})) == 3
    assert len(_unexplained(0.702, {"cubic_stiffness": required + 1.0})) == 3


def test_the_effects_outside_the_candidates_named_are_the_family_s():
    """The hint of an unexplained gap names effects common in that family and how to add one of them: an SDOF
    joint's micro-slip, not the damper's messenger."""
    where = _unexplained(0.1, {"hysteresis": 60.0})[-1]
    assert "4.7-6.1 Hz" in where and "a bolted joint's micro-slip" in where and "messenger" not in where
    assert "--candidates FILE.toml" in where
    assert "messenger's frequency-dependent loss" in FAMILY["damper"].outside


def _held_out(fs: float = 500.0, seconds: float = 35.0, burst: tuple = (14.0, 16.0), burst_rms: float = 0.3,
              noise: float = 0.008):
    """A held-out record (a 12 Hz sine, unit RMS) and a model's simulation of it: noise everywhere and, from
    burst[0] to burst[1] s, a misfit of burst_rms of the output's RMS (a model on the other steady state there)."""
    import numpy as np

    from pyfit.gap.simulate import Record

    rng = np.random.default_rng(5)
    t = np.arange(int(seconds * fs)) / fs
    y = np.sqrt(2) * np.sin(2 * np.pi * 12.0 * t)
    sim = y + noise * rng.normal(size=t.size)
    inside = (t >= burst[0]) & (t < burst[1])
    sim[inside] += burst_rms * np.sqrt(2) * np.sin(2 * np.pi * 12.0 * t[inside] + 1.0)
    return {"level2": {"x1": sim}}, [Record("level2", "", 2.0, fs, {}, {"x1": y}, 0)]


def test_a_misfit_confined_to_a_few_seconds_is_found_with_the_rest_of_the_record():
    """A misfit of 0.3 of the output's RMS in 2 s of a 35 s record over noise of 0.008 elsewhere: 80 % of its
    square lies in the two 1 s windows there (0.09 x 2 s against 6.4e-5 x 35 s: 98.8 %); outside them the NRMSE is
    the noise's; the report says where and that the rest meets the criterion. A misfit spread over the record is
    not confined."""
    import numpy as np

    from pyfit.gap.localise import confined_misfit
    from pyfit.gap.evidence import confined_lines

    sims, held = _held_out()
    found = confined_misfit(sims, held)
    assert found is not None and found.windows == (("level2", 14.0, 16.0),)  # its two windows, joined
    assert found.seconds == 2.0 and found.total_seconds == 35.0 and found.share > 0.8
    assert abs(found.nrmse_rest - 0.008) < 0.0005  # the noise's standard deviation over a unit-RMS output
    line = confined_lines(found, explained_below=0.03)[0]
    assert "lies in 2.0 s of the 35 s held out (level2 14.0-16.0 s)" in line
    assert f"{found.nrmse_rest:.4f}, within the criterion" in line
    assert confined_lines(found, explained_below=0.005) == []  # the rest above the criterion: nothing said
    spread, held = _held_out(burst=(0.0, 35.0), burst_rms=0.05)
    assert confined_misfit(spread, held) is None
    assert np.isclose(0.3 ** 2 * 2 / (0.3 ** 2 * 2 + 0.008 ** 2 * 33), found.share, atol=0.01)


def test_the_prediction_band_is_asked_for_a_confined_misfit_of_a_model_that_removes_most_of_the_gap():
    """report.needs_band: only for a report no candidate explains whose best model removes at least min_shrink_pct
    of the gap and leaves a confined misfit with the rest within the criterion; band_lines states the fit's misfit,
    where it lies and the band's best prediction."""
    import dataclasses

    from pyfit.gap.band import PredictionBand
    from pyfit.gap.localise import confined_misfit
    from pyfit.gap.evidence import band_lines
    from pyfit.gap.judge import needs_band

    sims, held = _held_out()
    confined = confined_misfit(sims, held)
    best = _fit("hysteresis + cubic_stiffness", 92.5, 0.037)
    result = Diagnosis("damper", "StockbridgeDamper", "", Verdict.NOT_EXPLAINED, (), 0.0284, GAP, (best,), (),
                       NominalFit({}, 0.1, 60), (), (), confined_misfit=dataclasses.asdict(confined))

    def but(**changes):
        return dataclasses.replace(result, **changes)

    assert needs_band(result, 50.0) == "hysteresis + cubic_stiffness"
    assert needs_band(but(explained_below=0.005), 50.0) is None  # the rest above the criterion
    assert needs_band(result, 95.0) is None  # removes too little of the gap
    assert needs_band(but(verdict=Verdict.EXPLAINED, chosen=("hysteresis",)), 50.0) is None
    assert needs_band(but(verdict=Verdict.NOMINAL_MISFITS), 50.0) is None
    assert needs_band(but(confined_misfit=None), 50.0) is None  # a misfit spread over the record
    band = PredictionBand("hysteresis + cubic_stiffness", 0.0053, 22, 22, 28, {"k_bw1": 0.017}, {"k_bw1": 610.0},
                          0.01293, 0.01290, 0.0109)
    line, = band_lines(dataclasses.replace(best, prediction_band=dataclasses.asdict(band)), confined, 0.0284)
    assert "held-out NRMSE 0.0370 is above the criterion 0.0284" in line
    assert "in 2.0 s (level2 14.0-16.0 s)" in line
    assert "within 0.53 % of the fit's 0.0129: 22 of the 22 ends of its axes" in line
    assert "predicts the held-out files at 0.0109" in line
