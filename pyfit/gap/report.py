"""How far: the gap on held-out files before and after each effect, the ranking, the verdict and the
evidence; what would separate close candidates; report.json, report.md and figures."""
from __future__ import annotations

import dataclasses
import json
import pathlib

import numpy as np

from pyfit.report import plots
from pyfit.gap import confidence, localise, selection
from pyfit.gap.band import PredictionBand
from pyfit.gap import simulate as sim
from pyfit.gap.rate import REFERENCE_HZ


def _rms_over(values) -> float:
    return float(np.sqrt(np.mean(np.square(values))))


def _gap(sims: dict, records, held, bands, floors: dict) -> dict:
    """Gap metrics of one model's simulations: held-out overall, per band, channel, harmonic class, loop
    region; per level over every file (with its noise floor from `floors`, see localise.noise_estimates)."""
    hs = [r for r in held if sims[r.name] is not None]
    failed = [r.name for r in held if sims[r.name] is None]
    overall = _rms_over([localise.nrmse(sims[r.name], r) for r in hs]) if hs else float("inf")
    by_band = np.sqrt(np.mean([np.square(localise.by_band(sims[r.name], r, bands)) for r in hs], axis=0)) \
        if hs else np.full(len(bands), np.nan)
    harmonic = [localise.by_harmonic(sims[r.name], r) for r in hs]
    harmonic = [h for h in harmonic if h is not None]
    loops = [localise.by_loop_region(sims[r.name], r) for r in hs]
    return {
        "overall": overall,
        "failed_files": failed,
        "by_band": [{"band_hz": list(b), "nrmse": float(v)} for b, v in zip(bands, by_band)],
        "by_level": [{"file": r.name, "level": r.level, "level_value": r.level_value, "held_out": r in held,
                      "nrmse": None if sims[r.name] is None else localise.nrmse(sims[r.name], r),
                      "noise_floor": floors[r.name][0]} for r in records],
        "by_channel": {k: _rms_over([np.sqrt(np.mean((sims[r.name][k] - r.outputs[k]) ** 2) / np.mean(r.outputs[k] ** 2))
                                     for r in hs]) for k in records[0].outputs} if hs else {},
        "by_harmonic": {c: {q: _rms_over([h[c][q] for h in harmonic]) for q in ("misfit", "noise")}
                        for c in harmonic[0]} if harmonic else None,
        "by_loop_region": {k: _rms_over([d[k] for d in loops]) for k in localise.LOOP_REGIONS} if loops else {},
    }


def _scaled_floor(gap: dict) -> str:
    """The report's words for the floor should the sensor noise grow with the level, where it is higher."""
    scaled = gap.get("noise_floor_scaled", gap["noise_floor"])
    return (f"; {scaled:.4f} should the sensor noise grow with the level (the combinations are judged above it)"
            if scaled > 1.01 * gap["noise_floor"] else "")


def _free_values(fit) -> dict:
    out = {n: fit.params[n] for n in fit.free}
    if "hysteresis" in fit.effect.split(" + ") and "delta" in fit.free:  # the SDOF form: β·γ, β·δ identifiable
        out["beta (set by nu)"] = fit.params["beta"]
        out["beta*gamma"] = fit.params["beta"] * fit.params["gamma"]
        out["beta*delta"] = fit.params["beta"] * fit.params["delta"]
    return out


def nominal_gap(sims: dict, records, held, bands, cfg) -> dict:
    """The nominal model's gap (where), its noise floor from the held-out data, and whether the gap is
    significant: larger than noise_factor x the floor and than the floor + min_gap. Also the floor should the
    sensor noise grow with the level (noise_floor_scaled, localise.noise_estimates(level_scaled=True)): what the
    forward selection measures a model's misfit above."""
    per = localise.channel_noise(records)
    floors = localise.noise_estimates(records, per=per)
    gap = _gap(sims, records, held, bands, floors)
    estimates = [floors[r.name] for r in held]
    floor = _rms_over([e[0] for e in estimates])
    gap["noise_floor"] = floor
    scaled = localise.noise_estimates(records, level_scaled=True, per=per)
    gap["noise_floor_scaled"] = _rms_over([scaled[r.name][0] for r in held])
    gap["noise_floor_method"] = sorted({e[1] for e in estimates})
    worst = int(np.nanargmax([b["nrmse"] for b in gap["by_band"]]))
    gap["worst_band_hz"] = gap["by_band"][worst]["band_hz"]
    gap["significant"] = selection.significant(gap["overall"], floor, cfg.noise_factor, cfg.min_gap)
    return gap


def best_calibration_nrmse(gap: dict) -> tuple[float, str]:
    """The nominal model's NRMSE on the calibration file it fits best, and that file: a linear model must fit
    at least the level where an amplitude-dependent effect is weakest; when it fits none, the model (or the
    channels and units) is wrong, not just missing an effect."""
    cal = [d for d in gap["by_level"] if not d["held_out"] and d["nrmse"] is not None]
    best = min(cal, key=lambda d: d["nrmse"], default=None)
    return (best["nrmse"], best["file"]) if best else (float("inf"), "")


def best_refit(fits: dict) -> tuple[float, str]:
    """The lowest calibration NRMSE of the models refitted with an effect, and that model ((inf, '') if none)."""
    return min(((f.calibration_nrmse, name) for name, f in fits.items()), default=(float("inf"), ""))


POOR_LINEAR_NRMSE = 0.5  # a linear model at this NRMSE on a file reproduces 3/4 of its signal's variance (R² 0.75)


def not_explained_lines(best: dict, ranking: list[dict], gap: dict, best_calibration: tuple[float, str],
                        explained_below: float, cfg, outside: str,
                        confined: localise.ConfinedMisfit | None = None) -> list[str]:
    """The evidence of a gap no candidate explains: the best candidate against the criterion, each candidate's
    shrink, where the misfit left is largest, which effects outside the candidates are common in such systems
    (`outside`, System.outside) and what to try next. When the calibrated nominal misfits even its
    best calibration file by more than POOR_LINEAR_NRMSE and no refit removes `cfg.min_shrink_pct` of the
    held-out misfit, that is said first: every refit starts from that nominal and takes its ranges from it (its
    stiffness, its deflection), so it can stop short of an effect that is there. When the best candidate's
    held-out misfit lies in a few seconds (`confined`, localise.confined_misfit) and it meets the criterion over the
    rest, that is said after its numbers."""
    lines = [f"best candidate {best['effect']}: held-out NRMSE {best['heldout_gap_after']:.4f}, shrink "
             f"{best['shrink_pct']:.1f} %; an explanation needs NRMSE <= {explained_below:.4f} (noise "
             f"floor {gap['noise_floor']:.4f}) and shrink >= {cfg.min_shrink_pct:.0f} %",
             "held-out shrink by candidate: " + ", ".join(f"{d['effect']} {d['shrink_pct']:.1f} %"
                                                          for d in ranking[:5]),
             *confined_lines(confined, explained_below),
             f"the misfit left is largest in the band {gap['worst_band_hz'][0]:.1f}-"
             f"{gap['worst_band_hz'][1]:.1f} Hz: an effect outside the candidates acts there ({outside}), or "
             "the description of the system (--nominal) is off there; an effect you can model can be declared "
             "as a candidate of your own (--candidates FILE.toml: FMU parameters, bounds and start rule) and "
             "screened, refitted and ranked with these"]
    nrmse, name = best_calibration
    most = max(d["shrink_pct"] for d in ranking)
    if nrmse > POOR_LINEAR_NRMSE and most < cfg.min_shrink_pct:
        lines.insert(0, f"the calibrated linear nominal misfits even its best calibration file ({name}) at NRMSE "
                        f"{nrmse:.3f} (above {POOR_LINEAR_NRMSE}: it reproduces less than 3/4 of the signal's "
                        f"variance) and no refit removes more than {most:.1f} % of the held-out misfit: the refits "
                        "start from this nominal and take their ranges from it (its stiffness, its deflection), so "
                        "with every level this far from linear they can stop short of an effect that is there. "
                        "Record a level where the response is closer to linear (a smaller one for a stiffening "
                        "spring, a larger one for a friction joint that sticks) and diagnose the files with it")
    return lines


def _windows_text(confined: localise.ConfinedMisfit) -> str:
    """A confined misfit's windows as a reader sees them: 'file start-end s', comma separated."""
    return ", ".join(f"{name} {t0:.1f}-{t1:.1f} s" for name, t0, t1 in confined.windows)


def confined_lines(confined: localise.ConfinedMisfit | None, explained_below: float) -> list[str]:
    """The best candidate's held-out misfit confined to a few windows while the rest meets the criterion: where,
    and the two reasons a misfit is that confined (an effect acting there alone, or a response with two steady
    states that a model close to the data follows the other one of)."""
    if confined is None or confined.nrmse_rest > explained_below:
        return []
    where = _windows_text(confined)
    return [f"{100 * confined.share:.0f} % of the best candidate's held-out misfit lies in {confined.seconds:.1f} s "
            f"of the {confined.total_seconds:.0f} s held out ({where}); over the rest its held-out NRMSE is "
            f"{confined.nrmse_rest:.4f}, within the criterion. A misfit this confined comes from an effect that acts "
            "there alone, or from a response with two steady states there (a hardening spring or a loop near a "
            "resonance), of which a model this close to the data can follow the other one (most likely on a stepped "
            "sine that dwells at a jump); a sweep through that range, or levels nearer the held-out one, tell which"]


def needs_band(result: dict, min_shrink_pct: float) -> str | None:
    """The model whose prediction band decides the verdict, or None: a report that no candidate explains, whose
    best model removes at least `min_shrink_pct` of the gap and leaves its held-out misfit confined to a few
    windows (localise.confined_misfit) with the rest within the criterion."""
    confined, best = result["confined_misfit"], result["ranking"][0] if result["ranking"] else None
    if not result["verdict"].startswith("gap not explained") or best is None or confined is None:
        return None
    if confined["nrmse_rest"] > result["explained_below"] or best["shrink_pct"] < min_shrink_pct:
        return None
    return best["effect"]


def band_lines(best: dict, confined: localise.ConfinedMisfit | None, explained_below: float) -> list[str]:
    """A model explained within its prediction band: where its fit misfits, and the band's best prediction."""
    b = best["prediction_band"]
    where = _windows_text(confined) if confined else ""
    return [f"at its fit the held-out NRMSE {best['heldout_gap_after']:.4f} is above the criterion "
            f"{explained_below:.4f}" + (f", {100 * confined.share:.0f} % of it in {confined.seconds:.1f} s "
                                        f"({where}), {confined.nrmse_rest:.4f} over the rest" if confined else "")
            + f"; within its prediction band (the parameter sets whose calibration NRMSE is within "
            f"{100 * b['tolerance']:.2f} % of the fit's {b['fit_calibration']:.4f}: {b['kept']} of the {b['ends']} "
            f"ends of its axes) the best predicts the held-out files at {b['heldout_nrmse']:.4f}. The calibration "
            "files do not settle the prediction there: a response with two steady states (a hardening spring or a "
            "loop dwelling near a resonance) that a change of the parameters too small to show on them moves from one "
            "to the other"]


def _detection_lines(gap: dict, cfg) -> list[str]:
    """What the single refits said of a nominal misfit within the noise threshold (gap["detection"], set by the
    diagnosis when the nominal's test found no gap)."""
    d = gap.get("detection")
    if not d:
        return []
    threshold = selection.noise_level(gap["noise_floor"], cfg.noise_factor, cfg.min_gap)
    told = (f"the nominal's held-out NRMSE {gap['overall']:.4f} is within the noise threshold {threshold:.4f}; the "
            f"refit with {d['effect']} leaves {d['heldout_after']:.4f} (its linear values with the effect at zero"
            f"{' or reduced to its linear part' if d['reduced'] else ''} {d['linear_only']:.4f}): it removes "
            + (f"{100 * d['cut']:.1f} % of the held-out misfit" if d["cut"] > 0 else "none of the held-out misfit"))
    if d["detected"]:
        return [told + f", at least {100 * d['min_cut']:.0f} %: a gap below the threshold (a refit of noise alone "
                "carries nothing over to the held-out files)"]
    return [told + f", under the {100 * d['min_cut']:.0f} % that tells an effect from noise: no effect shows"]


def assemble(system, cfg, records, cal, held, nominal, fits, sims, screening, bands, scale, gap,
             selected: str | None = None, band: PredictionBand | None = None) -> dict:
    """The report: verdict, chosen effect, gap (where), ranking (which, how far), evidence. `selected`: the
    model the forward selection kept; the other combinations it tried are reported but not chosen. `band`: the
    prediction band of the best model (band.prediction_band, when `needs_band` says the report asks for it): that
    model explains the data when the best prediction within its band meets the criterion."""
    floor, before, significant = gap["noise_floor"], gap["overall"], gap["significant"]
    afters = {name: selection.heldout_nrmse(sims[name], held) for name in fits}
    # the floor should the sensor noise grow with the level is an upper bound of the noise (it counts distortion
    # as noise; at least the floor); so is any model's held-out misfit: the shrink is measured against the
    # smaller of the two (against the floor alone, a right effect on noise that grows with the level would have
    # to remove a misfit that is noise)
    reference = min([gap.get("noise_floor_scaled", floor)] + list(afters.values()))
    gap["shrink_reference"] = reference
    ranking = []
    for name, fit in fits.items():
        after = afters[name]
        members = list(system.effects[name].members) if name in system.effects else []
        ranking.append({"effect": name, "members": members or [name],
                        "score": selection.score(before, after, reference, fit.n_added),
                        "heldout_gap_before": before, "heldout_gap_after": after,
                        "shrink_pct": selection.shrink_pct(before, after, reference), "params": _free_values(fit),
                        "n_added_params": fit.n_added, "screening_explained": screening.get(name),
                        "calibration_nrmse": fit.calibration_nrmse, "evaluations": fit.evaluations,
                        "wall_s": fit.wall_s, "from_envelopes": fit.from_envelopes})
    explained_below = selection.explained_below(floor, cfg.explain_factor, cfg.explain_margin)
    shrinks = {frozenset(d["members"]): d["shrink_pct"] for d in ranking}
    for d in ranking:
        d["explains"] = selection.explains(d["shrink_pct"], d["heldout_gap_after"], explained_below, cfg.min_shrink_pct)
        if band is not None and band.effect == d["effect"]:
            d["prediction_band"] = dataclasses.asdict(band)
            d["explains_in_band"] = not d["explains"] and selection.explains(
                d["shrink_pct"], band.heldout_nrmse, explained_below, cfg.min_shrink_pct)
            d["explains"] = d["explains"] or d["explains_in_band"]
        if len(d["members"]) > 1:  # each member's share (selection.member_shares)
            d["member_shares_pct"] = selection.member_shares(d["members"], shrinks.get)
    for d in ranking:
        d["kept"] = len(d["members"]) == 1 or d["effect"] == selected
    # the model the selection kept if it explains the gap, else the best-scoring one that does, else the
    # best-scoring one (combinations: only the one kept)
    ranking.sort(key=lambda d: (not d["kept"], not d["explains"], d["effect"] != selected, -d["score"]))
    best = ranking[0] if ranking else None
    # where the best model's held-out misfit lies when it is above the criterion at its fit
    confined = localise.confined_misfit(sims[best["effect"]], held) \
        if significant and best and best["heldout_gap_after"] > explained_below else None
    best_cal, best_file = best_calibration_nrmse(gap)
    # the model fits when the nominal fits some calibration file, or (a strong amplitude-dependent effect, which
    # leaves no linear model fitting any level) a model with an effect fits the calibration files
    refit_cal, refit_name = best_refit(fits)
    nominal_fits = min(best_cal, refit_cal) <= cfg.nominal_max_nrmse
    if not nominal_fits:
        verdict, chosen = "nominal model does not fit", None
    elif not significant:
        verdict, chosen = "no significant gap", None
    elif best and best["explains"]:
        verdict, chosen = f"gap explained by {best['effect']}", best["effect"]
    else:
        verdict, chosen = "gap not explained by the candidate effects", None
    close = (len(ranking) > 1 and significant and ranking[0]["score"] - ranking[1]["score"] < cfg.close_points)
    levels = [d for d in gap["by_level"] if d["nrmse"] is not None]
    evidence = []
    if not nominal_fits:
        evidence = [f"the nominal model fits none of its calibration files: NRMSE {best_cal:.3f} on the best one "
                    f"({best_file}; allowed: {cfg.nominal_max_nrmse}; 1.0 is the error of predicting zero), nor "
                    "does any model with a candidate effect: describe the system (--nominal FILE.toml) or check "
                    "the channels and units",
                    "nominal misfit by file: " + ", ".join(f"{d['file']}: {d['nrmse']:.3f}" for d in levels)]
    amplitude_note = []
    if nominal_fits and best_cal > cfg.nominal_max_nrmse:
        amplitude_note = [f"the nominal model fits none of its calibration files (NRMSE {best_cal:.3f} on the best "
                          f"one) but the model with {refit_name} fits them at {refit_cal:.3f}: the response changes "
                          "strongly with amplitude"]
    if significant and nominal_fits and not chosen and best:
        evidence = not_explained_lines(best, ranking, gap, (best_cal, best_file), explained_below, cfg,
                                       system.outside, confined)
    if chosen:
        sys_effect = system.effects[chosen]
        ranked_screen = sorted(screening, key=lambda k: -screening[k])
        evidence = [
            f"held-out NRMSE {before:.4f} -> {best['heldout_gap_after']:.4f} (noise floor {floor:.4f}): "
            f"shrink {best['shrink_pct']:.1f} %"]
        if best.get("explains_in_band"):
            evidence += band_lines(best, confined, explained_below)
        if len(best["members"]) > 1:
            evidence.append("share of the shrink: " + ", ".join(
                f"{m} {v:.1f} %" for m, v in best["member_shares_pct"].items())
                + " (what each adds, averaged over the orders they can be added in)")
        if best.get("from_envelopes"):
            evidence.append("found by the envelope-led stage: fitted to the amplitude envelopes first, then on the "
                            "waveforms from there (no model refitted on the waveforms alone explained the data)")
        evidence += [
            f"screening: the sensitivity of {m} explains {100 * screening[m]:.1f} % of the nominal residual "
            f"(rank {ranked_screen.index(m) + 1} of {len(screening)})" for m in best["members"] if m in screening]
        evidence += [
            "nominal misfit by level: " + ", ".join(f"{d['level']}: {d['nrmse']:.3f}" for d in levels),
            f"largest misfit in the band {gap['worst_band_hz'][0]:.1f}-{gap['worst_band_hz'][1]:.1f} Hz",
            f"expected signature: {sys_effect.signature}",
        ]
        if gap["by_harmonic"]:
            h = gap["by_harmonic"]
            evidence.append("detection lines: odd misfit {:.2e} (noise {:.2e}), even misfit {:.2e} (noise {:.2e})"
                            .format(h["odd_detection"]["misfit"], h["odd_detection"]["noise"],
                                    h["even_detection"]["misfit"], h["even_detection"]["noise"]))
    evidence = amplitude_note + _detection_lines(gap, cfg) + evidence
    listed_starts = {name: [d for d in [{p.name: p.range(scale)[1] for p in e.params if p.shape}] if d]
                     + list(e.starts(scale))
                     for name, e in system.effects.items() if name in fits and e.starts(scale) and not e.members}
    return {"verdict": verdict, "chosen_effect": chosen, "significant": significant, "explained_below": explained_below,
            "listed_starts": listed_starts, "confined_misfit": dataclasses.asdict(confined) if confined else None,
            "runner_up_close": bool(close), "gap": gap, "ranking": ranking, "evidence": evidence,
            "nominal": {"params": _free_values(nominal), "calibration_nrmse": nominal.calibration_nrmse,
                        "evaluations": nominal.evaluations},
            "calibration_files": [r.name for r in cal], "held_out_files": [r.name for r in held],
            "data_scale": {"sigma_y": scale.sigma_y, "sigma_v": scale.sigma_v, "k": scale.k},
            "model": system.name, "fmu": system.fmu}


def separation(runner, result, records, fits, bands, upsample, lead_periods=1) -> dict | None:
    """When the first two effects score close: where their refitted models differ most, over the measured
    levels and beyond them (the lowest input x0.3, the highest x2): the level and band to measure next."""
    if not result["runner_up_close"]:
        return None
    a, b = (result["ranking"][i]["effect"] for i in (0, 1))
    lo = min(records, key=lambda r: r.level_value)
    hi = max(records, key=lambda r: r.level_value)
    candidates = [sim.scaled(lo, 0.3)] + list(records) + [sim.scaled(hi, 2.0)]
    rows = []
    for rec in candidates:
        ya, yb = (sim.simulate(runner, rec, fits[e].params, upsample, lead_periods) for e in (a, b))
        if ya is None or yb is None:
            continue
        ref = dataclasses.replace(rec, outputs=ya)
        band = int(np.argmax(localise.by_band(yb, ref, bands)))
        rows.append({"level": rec.level, "input_scale_of": rec.name, "difference_nrmse": localise.nrmse(yb, ref),
                     "band_hz": list(bands[band])})
    best = max(rows, key=lambda d: d["difference_nrmse"]) if rows else None
    return {"between": [a, b], "levels": rows, "measure_next": best}


def write(result: dict, records, held, sims, bands, out_dir) -> pathlib.Path:
    """report.json, report.md, gap_map.png (band x level, nominal model), overlay.png (held-out file), and
    where they apply envelopes.png (sweeps) and loops.png (a force-driven SDOF)."""

    out = pathlib.Path(out_dir)
    # gap map: the nominal model's misfit per band (rows) and file (columns)
    M = np.array([[np.nan] * len(bands) if sims["nominal"][r.name] is None
                  else localise.by_band(sims["nominal"][r.name], r, bands) for r in records]).T
    plots.heat_map(out / "gap_map.png", M, [r.level + (" *" if r in held else "") for r in records],
                   [f"{lo:.1f}-{hi:.1f}" for lo, hi in bands], "band [Hz]",
                   "nominal model: NRMSE contribution per band and level (* held out)")
    # overlay on the first held-out file: measured, nominal, chosen effect (amplitude spectra)
    rec = held[0]
    k = next(iter(rec.outputs))
    f = np.fft.rfftfreq(rec.n, 1.0 / rec.fs)
    sel = (f >= 0.5 * bands[0][0]) & (f <= min(rec.fs / 2, 1.5 * bands[-1][1]))
    curves = [("measured", f[sel], np.abs(np.fft.rfft(rec.outputs[k]))[sel], "k-")]
    # the residual of the nominal model and of the chosen model (else the best-ranked candidate)
    best = result["chosen_effect"] or (result["ranking"][0]["effect"] if result["ranking"] else None)
    for name in ["nominal"] + ([best] if best else []):
        if sims[name][rec.name] is not None:
            curves.append((f"residual, {name}", f[sel], np.abs(np.fft.rfft(sims[name][rec.name][k] - rec.outputs[k]))[sel],
                           "-"))
    plots.semilogy_curves(out / "overlay.png", curves, "frequency [Hz]", f"|DFT| of {k} [SI]",
                          f"held-out file {rec.name}: output and residual spectra")
    models = ["nominal"] + ([best] if best else [])
    result["extra_figures"] = []
    if not any(r.periodic for r in records):
        _envelopes(out / "envelopes.png", records, sims, models, k)
        result["extra_figures"].append("envelopes")
    if "u" in records[0].inputs and "m" in result["nominal"]["params"] and k in ("y", "v", "a"):
        _restoring_force_loops(out / "loops.png", records, sims, models, k, result["nominal"]["params"]["m"])
        result["extra_figures"].append("loops")
    (out / "report.json").write_text(json.dumps(result, indent=1))
    md = out / "report.md"
    md.write_text(markdown(result))
    return md


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


def markdown(result: dict) -> str:
    """The report as markdown (tables, evidence, figures)."""
    g = result["gap"]
    lines = [f"# Gap diagnosis: {result['model']} ({result['fmu']})", "",
             f"**Verdict: {result['verdict']}.**", ""]
    if result.get("confidence"):
        lines += [confidence.Confidence(**result["confidence"]).sentence(), ""]
    lines += [
        f"Calibrated on {', '.join(result['calibration_files'])}; held out: "
        f"{', '.join(result['held_out_files'])}. Levels ordered by {result['level_order']}.",
        ""] + _set_aside_lines(result.get("set_aside", {})) + _voltage_lines(result.get("voltage_channels", [])) \
        + clipped_lines(result.get("clipped_channels", {})) \
        + _rate_lines(result.get("analysis_rate"))
    lines += [
        f"Held-out gap (NRMSE) of the nominal model: **{g['overall']:.4f}**; noise floor from the data: "
        f"{g['noise_floor']:.4f} ({', '.join(g.get('noise_floor_method', []))}){_scaled_floor(g)}; nominal "
        f"calibration NRMSE {result['nominal']['calibration_nrmse']:.4f}. An effect explains the gap when the held-out NRMSE with "
        f"it is at most {result['explained_below']:.4f}.", "", "## Which effect", "",
        "| effect | score | held-out gap after | shrink [%] | screening [%] | strength params | fitted |",
        "|---|---|---|---|---|---|---|"]
    for r in result["ranking"]:
        params = ", ".join(f"{k} = {v:.4g}" for k, v in r["params"].items())
        lines.append(f"| {r['effect']} | {r['score']:.1f} | {r['heldout_gap_after']:.4f} | {r['shrink_pct']:.1f} | "
                     f"{'—' if r['screening_explained'] is None else format(100 * r['screening_explained'], '.1f')} | "
                     f"{r['n_added_params']} | {params} |")
    for name, starts in result.get("listed_starts", {}).items():
        lines += ["", f"{name}: besides the screening's strengths, the refit began from the best of these "
                  f"{len(starts)} starts on the calibration files, then fitted every parameter: {starts_text(starts)}."]
    if result["ranking"] and result["verdict"] == "no significant gap":
        lines += ["", "The single effects were refitted to test for an effect below the noise threshold; none "
                  "removes enough of the held-out misfit to tell it from noise (Evidence)."]
    elif result["ranking"]:
        lines += ["", "Score = shrink − 5 points per added strength parameter beyond the first (shape parameters "
                  "are not charged). "
                  "Shrink = (gap before − gap after) / (gap before − reference), reference = the smaller of the "
                  "noise floor should the sensor noise grow with the level and the best held-out gap after (both "
                  "are upper bounds of the noise)."]
    elif result["verdict"] == "no significant gap":
        lines += ["", "No effect was refitted: the nominal model fits the held-out files within the noise floor."]
    else:
        lines += ["", "No effect was refitted: the nominal model does not fit its own calibration files."]
    if result["evidence"]:
        lines += ["", "Evidence:", ""] + [f"- {e}" for e in result["evidence"]]
    sep = result.get("separation")
    if sep:
        best = sep["measure_next"]
        lines += ["", f"**{sep['between'][0]} and {sep['between'][1]} score close.** Their refitted models differ "
                  f"most at {best['level']} (NRMSE of the difference {best['difference_nrmse']:.3f}), in the band "
                  f"{best['band_hz'][0]:.1f}-{best['band_hz'][1]:.1f} Hz: measure there to separate them."]
        first, second = result["ranking"][:2]
        if (result["chosen_effect"] == first["effect"] and len(first["members"]) == len(second["members"])
                and first["heldout_gap_after"] > second["heldout_gap_after"]):
            lines[-1] += (f" Both reach the noise with held-out misfits within {100 * selection.ALIKE:.0f} % of each "
                          f"other: {first['effect']}, with fewer parameters, is named.")
    lines += ["", "## Where", "", "| band [Hz] | nominal NRMSE contribution (held out) |", "|---|---|"]
    lines += [f"| {b['band_hz'][0]:.1f}-{b['band_hz'][1]:.1f} | {b['nrmse']:.4f} |" for b in g["by_band"]]
    lines += ["", "| file | level | held out | nominal NRMSE | noise floor |", "|---|---|---|---|---|"]
    lines += [f"| {d['file']} | {d['level']} | {'yes' if d['held_out'] else 'no'} | "
              f"{d['nrmse'] if d['nrmse'] is None else format(d['nrmse'], '.4f')} | {d['noise_floor']:.4f} |"
              for d in g["by_level"]]
    if g["by_harmonic"]:
        lines += ["", "| DFT lines (held out) | misfit | noise |", "|---|---|---|"]
        lines += [f"| {c} | {v['misfit']:.2e} | {v['noise']:.2e} |" for c, v in g["by_harmonic"].items()]
    if g["by_loop_region"]:
        lines += ["", "| loop region (held out) | NRMSE contribution |", "|---|---|"]
        lines += [f"| {k} | {v:.4f} |" for k, v in g["by_loop_region"].items()]
    lines += ["", "![gap map](gap_map.png)", "", "![overlay](overlay.png)", ""]
    lines += [f"![{name}]({name}.png)\n" for name in result.get("extra_figures", [])]
    return "\n".join(lines)
