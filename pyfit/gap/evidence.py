"""The evidence a report gives for its verdict, as lines of text: what the chosen model removes and why it was
chosen, or why nothing explains the gap and what to try next (misfits are NRMSE, bands in Hz)."""
from __future__ import annotations

from pyfit.gap import localise, selection
from pyfit.gap.result import Gap, ModelFit

POOR_LINEAR_NRMSE = 0.5  # a linear model at this NRMSE on a file reproduces 3/4 of its signal's variance (R² 0.75)


def not_explained_lines(best: ModelFit, ranking, gap: Gap, best_calibration: tuple[float, str],
                        explained_below: float, cfg, outside: str,
                        confined: localise.ConfinedMisfit | None = None) -> list[str]:
    """The evidence of a gap no candidate explains: the best candidate against the criterion, each candidate's
    shrink, where the misfit left is largest, which effects outside the candidates are common in such systems
    (`outside`, System.outside) and what to try next; first, when the nominal misfits even its best calibration
    file by more than POOR_LINEAR_NRMSE and no refit removes `cfg.min_shrink_pct`, that every refit starts from
    that nominal (poor_linear_line); after the numbers, a misfit confined to a few seconds (confined_lines)."""
    lo, hi = gap.worst_band_hz
    lines = [f"best candidate {best.effect}: held-out NRMSE {best.heldout_gap_after:.4f}, shrink "
             f"{best.shrink_pct:.1f} %; an explanation needs NRMSE <= {explained_below:.4f} (noise "
             f"floor {gap.noise_floor:.4f}) and shrink >= {cfg.min_shrink_pct:.0f} %",
             "held-out shrink by candidate: " + ", ".join(f"{d.effect} {d.shrink_pct:.1f} %" for d in ranking[:5]),
             *confined_lines(confined, explained_below),
             f"the misfit left is largest in the band {lo:.1f}-{hi:.1f} Hz: an effect outside the candidates acts "
             f"there ({outside}), or the description of the system (--nominal) is off there; an effect you can model "
             "can be declared as a candidate of your own (--candidates FILE.toml: FMU parameters, bounds and start "
             "rule) and screened, refitted and ranked with these"]
    return poor_linear_line(best_calibration, max(d.shrink_pct for d in ranking), cfg.min_shrink_pct) + lines


def poor_linear_line(best_calibration: tuple[float, str], most: float, min_shrink_pct: float) -> list[str]:
    """When the calibrated nominal misfits its best calibration file by more than POOR_LINEAR_NRMSE and no refit
    removes `min_shrink_pct` (`most`: the largest shrink [%]): the refits start from that nominal and take their
    ranges from it (its stiffness, its deflection), so they can stop short of an effect that is there."""
    nrmse, name = best_calibration
    if nrmse <= POOR_LINEAR_NRMSE or most >= min_shrink_pct:
        return []
    return [f"the calibrated linear nominal misfits even its best calibration file ({name}) at NRMSE {nrmse:.3f} "
            f"(above {POOR_LINEAR_NRMSE}: it reproduces less than 3/4 of the signal's variance) and no refit removes "
            f"more than {most:.1f} % of the held-out misfit: the refits start from this nominal and take their "
            "ranges from it (its stiffness, its deflection), so with every level this far from linear they can stop "
            "short of an effect that is there. Record a level where the response is closer to linear (a smaller "
            "one for a stiffening spring, a larger one for a friction joint that sticks) and diagnose the files "
            "with it"]


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


def band_lines(best: ModelFit, confined: localise.ConfinedMisfit | None, explained_below: float) -> list[str]:
    """A model explained within its prediction band: where its fit misfits, and the band's best prediction."""
    b = best.prediction_band
    where = _windows_text(confined) if confined else ""
    return [f"at its fit the held-out NRMSE {best.heldout_gap_after:.4f} is above the criterion "
            f"{explained_below:.4f}" + (f", {100 * confined.share:.0f} % of it in {confined.seconds:.1f} s "
                                        f"({where}), {confined.nrmse_rest:.4f} over the rest" if confined else "")
            + f"; within its prediction band (the parameter sets whose calibration NRMSE is within "
            f"{100 * b['tolerance']:.2f} % of the fit's {b['fit_calibration']:.4f}: {b['kept']} of the {b['ends']} "
            f"ends of its axes) the best predicts the held-out files at {b['heldout_nrmse']:.4f}. The calibration "
            "files do not settle the prediction there: a response with two steady states (a hardening spring or a "
            "loop dwelling near a resonance) that a change of the parameters too small to show on them moves from one "
            "to the other"]


def detection_lines(gap: Gap, cfg) -> list[str]:
    """What the single refits said of a nominal misfit within the noise threshold (gap.detection)."""
    d = gap.detection
    if not d:
        return []
    threshold = selection.noise_level(gap.noise_floor, cfg.noise_factor, cfg.min_gap)
    told = (f"the nominal's held-out NRMSE {gap.overall:.4f} is within the noise threshold {threshold:.4f}; the "
            f"refit with {d.effect} leaves {d.heldout_after:.4f} (its linear values with the effect at zero"
            f"{' or reduced to its linear part' if d.reduced else ''} {d.linear_only:.4f}): it removes "
            + (f"{100 * d.cut:.1f} % of the held-out misfit" if d.cut > 0 else "none of the held-out misfit"))
    if d.detected:
        return [told + f", at least {100 * d.min_cut:.0f} %: a gap below the threshold (a refit of noise alone "
                "carries nothing over to the held-out files)"]
    return [told + f", under the {100 * d.min_cut:.0f} % that tells an effect from noise: no effect shows"]


def chosen_lines(best: ModelFit, gap: Gap, screening: dict, signature: str, confined, explained_below: float
                 ) -> list[str]:
    """The evidence for the chosen model: its shrink, the prediction band where that decided, each member's share,
    the envelope-led stage where it found it, the screening's rank of each member, where the nominal misfits and
    the signature the effect is expected to show (`signature`: effect.Effect.signature)."""
    lines = [f"held-out NRMSE {gap.overall:.4f} -> {best.heldout_gap_after:.4f} (noise floor {gap.noise_floor:.4f}): "
             f"shrink {best.shrink_pct:.1f} %"]
    if best.explains_in_band:
        lines += band_lines(best, confined, explained_below)
    if len(best.members) > 1:
        lines.append("share of the shrink: " + ", ".join(f"{m} {v:.1f} %" for m, v in best.member_shares_pct.items())
                     + " (what each adds, averaged over the orders they can be added in)")
    if best.from_envelopes:
        lines.append("found by the envelope-led stage: fitted to the amplitude envelopes first, then on the "
                     "waveforms from there (no model refitted on the waveforms alone explained the data)")
    ranked_screen = sorted(screening, key=lambda k: -screening[k])
    lines += [f"screening: the sensitivity of {m} explains {100 * screening[m]:.1f} % of the nominal residual "
              f"(rank {ranked_screen.index(m) + 1} of {len(screening)})" for m in best.members if m in screening]
    levels = [d for d in gap.by_level if d.nrmse is not None]
    lines += ["nominal misfit by level: " + ", ".join(f"{d.level}: {d.nrmse:.3f}" for d in levels),
              f"largest misfit in the band {gap.worst_band_hz[0]:.1f}-{gap.worst_band_hz[1]:.1f} Hz",
              f"expected signature: {signature}"]
    if gap.by_harmonic:
        h = gap.by_harmonic
        lines.append("detection lines: odd misfit {:.2e} (noise {:.2e}), even misfit {:.2e} (noise {:.2e})".format(
            h["odd_detection"]["misfit"], h["odd_detection"]["noise"], h["even_detection"]["misfit"],
            h["even_detection"]["noise"]))
    return lines


def nominal_misfits_lines(best_calibration: tuple[float, str], gap: Gap, nominal_max_nrmse: float) -> list[str]:
    """The evidence of a nominal model that fits none of its calibration files, nor with any candidate effect."""
    best_cal, best_file = best_calibration
    levels = [d for d in gap.by_level if d.nrmse is not None]
    return [f"the nominal model fits none of its calibration files: NRMSE {best_cal:.3f} on the best one "
            f"({best_file}; allowed: {nominal_max_nrmse}; 1.0 is the error of predicting zero), nor does any model "
            "with a candidate effect: describe the system (--nominal FILE.toml) or check the channels and units",
            "nominal misfit by file: " + ", ".join(f"{d.file}: {d.nrmse:.3f}" for d in levels)]
