"""The diagnosis's report files, written from its Diagnosis (pyfit.gap.result): report.json, report.md and the
figures (gap map, residual spectra, and where they apply response envelopes and restoring-force loops)."""
from __future__ import annotations

import json
import pathlib

import numpy as np

from pyfit.report import plots
from pyfit.gap import confidence, localise, selection
from pyfit.gap import simulate as sim
from pyfit.gap.rate import REFERENCE_HZ
from pyfit.gap.result import Diagnosis, Verdict


def figures_for(records, nominal_params: dict) -> tuple[str, ...]:
    """The figures beyond the gap map and the overlay that apply to these records: the response envelopes of
    records that are not periodic (sweeps, stepped sines, noise), the restoring-force loops of a force-driven SDOF
    whose first output is a motion."""
    k = next(iter(records[0].outputs))
    return (("envelopes",) if not any(r.periodic for r in records) else ()) + (
        ("loops",) if "u" in records[0].inputs and "m" in nominal_params and k in ("y", "v", "a") else ())


def write(d: Diagnosis, records, held, sims, bands, out_dir) -> pathlib.Path:
    """report.json, report.md, gap_map.png (band x level, nominal model), overlay.png (held-out file), and the
    figures d.figures names."""
    out = pathlib.Path(out_dir)
    # gap map: the nominal model's misfit per band (rows) and file (columns)
    M = np.array([[np.nan] * len(bands) if sims["nominal"][r.name] is None
                  else localise.by_band(sims["nominal"][r.name], r, bands) for r in records]).T
    plots.heat_map(out / "gap_map.png", M, [r.level + (" *" if r in held else "") for r in records],
                   [f"{lo:.1f}-{hi:.1f}" for lo, hi in bands], "band [Hz]",
                   "nominal model: NRMSE contribution per band and level (* held out)")
    # the residual of the nominal model and of the chosen model (else the best-ranked candidate)
    best = d.chosen_name or (d.best.effect if d.best else None)
    models = ["nominal"] + ([best] if best else [])
    k = _overlay(out / "overlay.png", held[0], sims, models, bands)
    if "envelopes" in d.figures:
        _envelopes(out / "envelopes.png", records, sims, models, k)
    if "loops" in d.figures:
        _restoring_force_loops(out / "loops.png", records, sims, models, k, d.nominal.params["m"])
    (out / "report.json").write_text(json.dumps(d.to_json(), indent=1))
    md = out / "report.md"
    md.write_text(markdown(d))
    return md


def _overlay(path, rec, sims, models, bands) -> str:
    """The amplitude spectra of a held-out record's first output and of each model's residual on it; returns that
    output's name."""
    k = next(iter(rec.outputs))
    f = np.fft.rfftfreq(rec.n, 1.0 / rec.fs)
    sel = (f >= 0.5 * bands[0][0]) & (f <= min(rec.fs / 2, 1.5 * bands[-1][1]))
    curves = [("measured", f[sel], np.abs(np.fft.rfft(rec.outputs[k]))[sel], "k-")]
    curves += [(f"residual, {name}", f[sel], np.abs(np.fft.rfft(sims[name][rec.name][k] - rec.outputs[k]))[sel], "-")
               for name in models if sims[name][rec.name] is not None]
    plots.semilogy_curves(path, curves, "frequency [Hz]", f"|DFT| of {k} [SI]",
                          f"held-out file {rec.name}: output and residual spectra")
    return k


UNITS = {"y": "m", "v": "m/s", "a": "m/s²", "x1": "m", "x2": "m"}  # of the outputs the figures label


def _instantaneous_frequency(u: np.ndarray, fs: float) -> np.ndarray:
    """The input's instantaneous frequency [Hz]: the rate of its analytic signal's phase, smoothed over 0.5 s."""
    import scipy.signal

    phase = np.unwrap(np.angle(scipy.signal.hilbert(u - np.mean(u))))
    f = np.gradient(phase) * fs / (2 * np.pi)
    n = max(int(0.5 * fs), 1)
    return np.convolve(f, np.ones(n) / n, mode="same")


def _envelopes(path, records, sims, models, k) -> None:
    """Per level of a sweep: the output's envelope against the input's instantaneous frequency, measured and
    simulated by each of `models` (the nominal and the chosen effect)."""
    panels = []
    for rec in records:
        f = _instantaneous_frequency(next(iter(rec.inputs.values()))[rec.first:], rec.fs)
        inner = slice(int(0.5 * rec.fs), rec.n - int(0.5 * rec.fs))  # the smoothing's edges left out
        curves = [("measured", f[inner], sim.envelope(rec.outputs[k], rec.fs)[inner])]
        curves += [(name, f[inner], sim.envelope(sims[name][rec.name][k], rec.fs)[inner]) for name in models
                   if sims[name].get(rec.name) is not None]
        panels.append((rec.level, curves))
    name = f"envelope of {k}"
    plots.loops(path, panels, "input frequency", name, {"input frequency": "Hz", name: UNITS.get(k, "SI")},
                "response envelope against the input's instantaneous frequency, per level")


def restoring_force(u: np.ndarray, recorded: np.ndarray, kind: str, fs: float, mass: float, periodic: bool,
                    window: slice) -> tuple[np.ndarray, np.ndarray]:
    """Displacement y [m] and restoring force u - m·a [N] over `window`, y and a derived from the recorded
    output of `kind` ('x', 'v' or 'a'; pyfit.analysis.kinematics, band-limited to the excited band's lower
    edge and 0.4 fs so that the harmonics stay)."""
    from pyfit.analysis import kinematics

    band = (kinematics.excited_band(u, fs)[0], 0.4 * fs)
    full = kinematics.complete({kind: recorded}, fs, band, periodic=periodic)
    return full["x"][window], (u - mass * full["a"])[window]


def _restoring_force_loops(path, records, sims, models, k, mass: float) -> None:
    """Per level: the restoring force against the displacement over a period either side of the largest
    response (for a sweep: at the resonance), measured and simulated by each of `models`; m is the nominal
    calibration's mass."""
    kind = {"y": "x", "v": "v", "a": "a"}[k]
    panels = []
    for rec in records:
        u = rec.compared("u")
        peak = int(np.argmax(sim.envelope(rec.outputs[k], rec.fs)))
        f = max(float(_instantaneous_frequency(u, rec.fs)[peak]), 1.0)
        half = int(rec.fs / f)
        window = slice(max(peak - half, 0), min(peak + half, rec.n))
        curves = [(name, *restoring_force(u, y, kind, rec.fs, mass, rec.periodic, window))
                  for name, y in [("measured", rec.outputs[k])] + [(n, sims[n][rec.name][k]) for n in models
                                                                   if sims[n].get(rec.name) is not None]]
        panels.append((rec.level, curves))
    plots.loops(path, panels, "y", "u - m a", {"y": "m", "u - m a": "N"},
                "restoring force against displacement at the largest response, per level")


LISTED_IN_FULL = 12  # starts written out one by one in report.md; more are summarised by parameter
VALUES_IN_FULL = 6  # a summarised parameter's values written out; more are given as their range and count


def starts_text(starts: list[dict]) -> str:
    """A candidate's listed starts for report.md: each start when there are at most LISTED_IN_FULL, else each
    parameter's values (its range when there are more than VALUES_IN_FULL) and where the full list is
    (report.json)."""
    if len(starts) <= LISTED_IN_FULL:
        return "; ".join(", ".join(f"{k} = {v:g}" for k, v in st.items()) for st in starts)
    names = list(dict.fromkeys(k for st in starts for k in st))
    parts = []
    for n in names:
        values = sorted({float(f"{st[n]:.6g}") for st in starts if n in st})
        parts.append(f"{n} in {{{', '.join(f'{v:g}' for v in values)}}}" if len(values) <= VALUES_IN_FULL
                     else f"{n} from {values[0]:g} to {values[-1]:g} ({len(values)} values)")
    return "; ".join(parts) + " (each start in report.json, `listed_starts`)"


def _set_aside_lines(aside: dict) -> list[str]:
    """The files the default split left out (localise.unsettled), with why, as markdown lines."""
    return [f"Set aside: {name} (its response differs from one period to the next by {100 * d['period_scatter']:.1f} "
            f"% of its RMS, {d['period_scatter'] / d['lower_floor']:.0f} x the noise floor of a lower level: no "
            "steady state, chaotic or still settling, which no simulation follows sample by sample; calibrating on "
            "it would pull every parameter off).\n" for name, d in aside.items()]


CLIPPED_NOTE = ("Held at the channel's largest or smallest value, as a range limit holds it (an overloaded sensor, "
                "amplifier or ADC: no model follows the signal there; a lower level or a wider range records it)")


def clipped_lines(clipped: dict[str, int]) -> list[str]:
    """The channels held at an extreme value (pyfit.analysis.signals.clipped_samples), as markdown lines."""
    if not clipped:
        return []
    return [f"{CLIPPED_NOTE}: " + ", ".join(f"{name} ({n} samples)" for name, n in clipped.items()) + ".", ""]


def _voltage_lines(channels: list[str]) -> list[str]:
    """What a voltage channel (pyfit.io.data.check_quantities) means for the fitted values."""
    if not channels:
        return []
    return [f"Recorded as voltages: {', '.join(channels)}: read in the model's units with a gain nobody measured "
            "(N/V of a drive, V/m of a sensor). The verdict does not depend on it; every fitted mass, damping, "
            "stiffness and effect strength carries it, the natural frequency sqrt(k/m) and the damping ratio do "
            "not.", ""]


def _compared_lines(compared_from: dict) -> list[str]:
    """Files whose displacement input was integrated from a velocity or an acceleration: the frequency below which
    the data cannot speak."""
    if not compared_from:
        return []
    below = ", ".join(f"{name} ({hz:.2g} Hz)" for name, hz in compared_from.items())
    return [f"The displacement input was integrated from a velocity or an acceleration in {below}: it drifts below "
            "that frequency (a sensor's offset and slow noise, integrated), where the data cannot tell the model's "
            "response from the drift; the outputs are compared above it, and after the first seconds (the drift's "
            "unknown start sets the model ringing).", ""]


def _rate_lines(rate: dict | None) -> list[str]:
    """The files brought to the dataset's rate (pyfit.gap.rate.common_rate), and the rate the records were analysed
    at and the FMU's drive grid, for files faster than the rate the families' drive grids were set at."""
    faster = [f"{name} ({hz:.6g} Hz, decimated by {round(hz / rate['file_hz'])})"
              for name, hz in (rate or {}).get("recorded_hz", {}).items()]
    common = ([f"Files recorded faster than the dataset's {rate['file_hz']:.6g} Hz brought to it after a zero-phase "
               f"anti-alias filter: {', '.join(faster)}.", ""] if faster else [])
    if not rate or rate["file_hz"] <= REFERENCE_HZ:
        return common
    hz = rate["file_hz"] / rate["factor"]
    drive = f"the FMU driven on a {hz * rate['drive_upsample']:.6g} Hz grid ({rate['drive_upsample']} per sample)"
    if rate["factor"] == 1:
        return common + [f"Analysed at the files' {hz:.6g} Hz, {drive}; the inputs excite up to "
                         f"{rate['top_hz']:.1f} Hz.", ""]
    return common + [f"Analysed at {hz:.6g} Hz: the files' {rate['file_hz']:.6g} Hz decimated by {rate['factor']} "
                     f"after a zero-phase anti-alias filter (the inputs excite up to {rate['top_hz']:.1f} Hz; the rate "
                     f"kept is at least {rate['min_ratio']:g} times that), {drive}.", ""]


def markdown(d: Diagnosis) -> str:
    """The report as markdown (tables, evidence, figures)."""
    g = d.gap
    lines = [f"# Gap diagnosis: {d.model} ({d.fmu})", "", f"**Verdict: {d.sentence}.**", ""]
    if d.confidence:
        lines += [confidence.Confidence(**d.confidence).sentence(), ""]
    lines += [f"Calibrated on {', '.join(d.calibration_files)}; held out: {', '.join(d.held_out_files)}. Levels "
              f"ordered by {d.level_order}.", ""]
    lines += _set_aside_lines(d.set_aside) + _voltage_lines(d.voltage_channels) + clipped_lines(d.clipped_channels) \
        + _rate_lines(d.analysis_rate) + _compared_lines(d.compared_from_hz)
    lines += [
        f"Held-out gap (NRMSE) of the nominal model: **{g.overall:.4f}**; noise floor from the data: "
        f"{g.noise_floor:.4f} ({', '.join(g.noise_floor_method)}){_scaled_floor(g)}; nominal calibration NRMSE "
        f"{d.nominal.calibration_nrmse:.4f}. An effect explains the gap when the held-out NRMSE with it is at most "
        f"{d.explained_below:.4f}.", ""]
    lines += _which_lines(d)
    if d.evidence:
        lines += ["", "Evidence:", ""] + [f"- {e}" for e in d.evidence]
    lines += _separation_lines(d) + _next_test_lines(d) + _where_lines(g)
    lines += ["", "![gap map](gap_map.png)", "", "![overlay](overlay.png)", ""]
    lines += [f"![{name}]({name}.png)\n" for name in d.figures]
    return "\n".join(lines)


def _scaled_floor(gap) -> str:
    """The report's words for the floor should the sensor noise grow with the level, where it is higher."""
    return (f"; {gap.noise_floor_scaled:.4f} should the sensor noise grow with the level (the combinations are "
            "judged above it)" if gap.noise_floor_scaled > 1.01 * gap.noise_floor else "")


def _which_lines(d: Diagnosis) -> list[str]:
    """The ranking's table, each candidate's listed starts, and what the scores mean (or why nothing was refitted)."""
    lines = ["## Which effect", "",
             "| effect | score | held-out gap after | shrink [%] | screening [%] | strength params | fitted |",
             "|---|---|---|---|---|---|---|"]
    for r in d.ranking:
        params = ", ".join(f"{k} = {v:.4g}" for k, v in r.params.items())
        screened = "—" if r.screening_explained is None else format(100 * r.screening_explained, ".1f")
        lines.append(f"| {r.effect} | {r.score:.1f} | {r.heldout_gap_after:.4f} | {r.shrink_pct:.1f} | {screened} | "
                     f"{r.n_added_params} | {params} |")
    for name, starts in d.listed_starts.items():
        lines += ["", f"{name}: besides the screening's strengths, the refit began from the best of these "
                  f"{len(starts)} starts on the calibration files, then fitted every parameter: {starts_text(starts)}."]
    if d.ranking and d.verdict is Verdict.NO_GAP:
        lines += ["", "The single effects were refitted to test for an effect below the noise threshold; none "
                  "removes enough of the held-out misfit to tell it from noise (Evidence)."]
    elif d.ranking:
        lines += ["", "Score = shrink − 5 points per added strength parameter beyond the first (shape parameters "
                  "are not charged). Shrink = (gap before − gap after) / (gap before − reference), reference = the "
                  "smaller of the noise floor should the sensor noise grow with the level and the best held-out gap "
                  "after (both are upper bounds of the noise)."]
    elif d.verdict is Verdict.NO_GAP:
        lines += ["", "No effect was refitted: the nominal model fits the held-out files within the noise floor."]
    else:
        lines += ["", "No effect was refitted: the nominal model does not fit its own calibration files."]
    return lines


def _separation_lines(d: Diagnosis) -> list[str]:
    """Where two close leaders differ most, and why the leaner one is named when both reach the noise."""
    sep = d.separation
    if not sep:
        return []
    best = sep.measure_next
    line = (f"**{sep.between[0]} and {sep.between[1]} score close.** Their refitted models differ most at "
            f"{best['level']} (NRMSE of the difference {best['difference_nrmse']:.3f}), in the band "
            f"{best['band_hz'][0]:.1f}-{best['band_hz'][1]:.1f} Hz: measure there to separate them.")
    first, second = d.ranking[:2]
    if (d.chosen_name == first.effect and len(first.members) == len(second.members)
            and first.heldout_gap_after > second.heldout_gap_after):
        line += (f" Both reach the noise with held-out misfits within {100 * selection.ALIKE:.0f} % of each other: "
                 f"{first.effect}, with fewer parameters, is named.")
    return ["", line]


def _next_test_lines(d: Diagnosis) -> list[str]:
    """The test that would decide, where the report is not decisive."""
    nt = d.next_test
    if not nt:
        return []
    return ["", f"**Next test: {nt.test}.** {nt.between[0]} and {nt.between[1]} differ there by {nt.separation:.1f} "
            "× the sensor noise (the RMS of their predictions' difference over the noise's): "
            "`stockbridge plan-test --from` this folder writes its drive file and every test tried."]


def _where_lines(g) -> list[str]:
    """Where the nominal misfits: by band, by file, by DFT line class and by loop region."""
    lines = ["", "## Where", "", "| band [Hz] | nominal NRMSE contribution (held out) |", "|---|---|"]
    lines += [f"| {b.band_hz[0]:.1f}-{b.band_hz[1]:.1f} | {b.nrmse:.4f} |" for b in g.by_band]
    lines += ["", "| file | level | held out | nominal NRMSE | noise floor |", "|---|---|---|---|---|"]
    lines += [f"| {v.file} | {v.level} | {'yes' if v.held_out else 'no'} | "
              f"{v.nrmse if v.nrmse is None else format(v.nrmse, '.4f')} | {v.noise_floor:.4f} |" for v in g.by_level]
    if g.by_harmonic:
        lines += ["", "| DFT lines (held out) | misfit | noise |", "|---|---|---|"]
        lines += [f"| {c} | {v['misfit']:.2e} | {v['noise']:.2e} |" for c, v in g.by_harmonic.items()]
    if g.by_loop_region:
        lines += ["", "| loop region (held out) | NRMSE contribution |", "|---|---|"]
        lines += [f"| {k} | {v:.4f} |" for k, v in g.by_loop_region.items()]
    return lines
