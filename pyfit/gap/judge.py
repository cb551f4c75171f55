"""How far, and the verdict: the nominal model's gap on the held-out files (where), every refitted model's shrink
of it and score (the ranking), the verdict with its evidence, and where two close leaders differ most (misfits are
NRMSE, bands in Hz)."""
from __future__ import annotations

import dataclasses

import numpy as np

from pyfit.gap import evidence, localise, selection
from pyfit.gap import simulate as sim
from pyfit.gap.band import PredictionBand
from pyfit.gap.effect import BRANCH
from pyfit.gap.result import BandMisfit, Diagnosis, Gap, LevelMisfit, ModelFit, NominalFit, Separation, Verdict


def _rms_over(values) -> float:
    return float(np.sqrt(np.mean(np.square(values))))


def gap_metrics(sims: dict, records, held, bands, floors: dict) -> dict:
    """Gap metrics of one model's simulations (Gap's fields): held-out overall, per band, channel, harmonic class,
    loop region; per level over every file (with its noise floor from `floors`, see localise.noise_estimates)."""
    hs = [r for r in held if sims[r.name] is not None]
    by_band = np.sqrt(np.mean([np.square(localise.by_band(sims[r.name], r, bands)) for r in hs], axis=0)) \
        if hs else np.full(len(bands), np.nan)
    harmonic = [h for h in (localise.by_harmonic(sims[r.name], r) for r in hs) if h is not None]
    loops = [localise.by_loop_region(sims[r.name], r) for r in hs]

    def channel(k):
        return _rms_over([np.sqrt(np.mean((sims[r.name][k] - r.outputs[k]) ** 2) / np.mean(r.outputs[k] ** 2))
                          for r in hs])

    return {
        "overall": _rms_over([localise.nrmse(sims[r.name], r) for r in hs]) if hs else float("inf"),
        "failed_files": tuple(r.name for r in held if sims[r.name] is None),
        "by_band": tuple(BandMisfit(tuple(b), float(v)) for b, v in zip(bands, by_band)),
        "by_level": tuple(LevelMisfit(r.name, r.level, r.level_value, r in held,
                                      None if sims[r.name] is None else localise.nrmse(sims[r.name], r),
                                      floors[r.name][0]) for r in records),
        "by_channel": {k: channel(k) for k in records[0].outputs} if hs else {},
        "by_harmonic": {c: {q: _rms_over([h[c][q] for h in harmonic]) for q in ("misfit", "noise")}
                        for c in harmonic[0]} if harmonic else None,
        "by_loop_region": {k: _rms_over([d[k] for d in loops]) for k in localise.LOOP_REGIONS} if loops else {},
    }


def nominal_gap(sims: dict, records, held, bands, cfg) -> Gap:
    """The nominal model's gap (where), its noise floor from the held-out data, and whether the gap is
    significant: larger than noise_factor x the floor and than the floor + min_gap. Also the floor should the
    sensor noise grow with the level (noise_floor_scaled, localise.noise_estimates(level_scaled=True)): what the
    forward selection measures a model's misfit above."""
    per = localise.channel_noise(records)
    floors = localise.noise_estimates(records, per=per)
    metrics = gap_metrics(sims, records, held, bands, floors)
    estimates = [floors[r.name] for r in held]
    floor = _rms_over([e[0] for e in estimates])
    scaled = localise.noise_estimates(records, level_scaled=True, per=per)
    worst = int(np.nanargmax([b.nrmse for b in metrics["by_band"]]))
    return Gap(noise_floor=floor, noise_floor_scaled=_rms_over([scaled[r.name][0] for r in held]),
               noise_floor_method=tuple(sorted({e[1] for e in estimates})),
               significant=selection.significant(metrics["overall"], floor, cfg.noise_factor, cfg.min_gap),
               worst_band_hz=metrics["by_band"][worst].band_hz, **metrics)


def best_calibration_nrmse(gap: Gap) -> tuple[float, str]:
    """The nominal model's NRMSE on the calibration file it fits best, and that file: a linear model must fit
    at least the level where an amplitude-dependent effect is weakest; when it fits none, the model (or the
    channels and units) is wrong, not just missing an effect."""
    cal = [d for d in gap.by_level if not d.held_out and d.nrmse is not None]
    best = min(cal, key=lambda d: d.nrmse, default=None)
    return (best.nrmse, best.file) if best else (float("inf"), "")


def best_refit(fits: dict) -> tuple[float, str]:
    """The lowest calibration NRMSE of the models refitted with an effect, and that model ((inf, '') if none)."""
    return min(((f.calibration_nrmse, name) for name, f in fits.items()), default=(float("inf"), ""))


def free_values(fit, members) -> dict:
    """A fit's free parameter values (SI); with a loop's coordinates free (effect.LoopCoordinates,
    BranchCoordinate) also the Bouc-Wen coefficients they give."""
    out = {n: fit.params[n] for n in fit.free}
    if BRANCH in fit.free:
        out.update({n: fit.params[n] for n in ("beta", "gamma", "delta") if n in fit.params})
    return out


@dataclasses.dataclass(frozen=True)
class Judged:
    """What the ranking needs of a diagnosis's run: the gap, the refits and their held-out misfits (`afters`), each
    model's members, the screening's shares, the settings and the model the selection kept."""

    gap: Gap
    fits: dict
    afters: dict
    members: dict
    screening: dict
    cfg: object
    selected: str | None


def ranking(j: Judged, reference: float, explained_below: float, band: PredictionBand | None) -> list[ModelFit]:
    """Every refitted model judged on the held-out files, best first: the model the selection kept if it explains
    the gap, else the best-scoring one that does, else the best-scoring one (of the combinations only the one kept
    counts). `band`: the best model's prediction band, within which it may explain the gap."""
    before, cfg = j.gap.overall, j.cfg
    shrinks = {n: selection.shrink_pct(before, j.afters[n], reference) for n in j.fits}
    by_members = {frozenset(j.members[n]): shrinks[n] for n in j.fits}
    out = []
    for name, fit in j.fits.items():
        members, after, shrink = j.members[name], j.afters[name], shrinks[name]
        explains = selection.explains(shrink, after, explained_below, cfg.min_shrink_pct)
        in_band = band is not None and band.effect == name
        inside = in_band and not explains and selection.explains(shrink, band.heldout_nrmse, explained_below,
                                                                 cfg.min_shrink_pct)
        out.append(ModelFit(
            name, members, selection.score(before, after, reference, fit.n_added), before, after, shrink,
            free_values(fit, members), fit.n_added, fit.calibration_nrmse, fit.evaluations, explains or inside,
            kept=len(members) == 1 or name == j.selected, screening_explained=j.screening.get(name),
            wall_s=fit.wall_s, from_envelopes=fit.from_envelopes,
            member_shares_pct=selection.member_shares(list(members), by_members.get) if len(members) > 1 else None,
            prediction_band=dataclasses.asdict(band) if in_band else None, explains_in_band=inside if in_band else None,
            values=dict(fit.params)))
    out.sort(key=lambda d: (not d.kept, not d.explains, d.effect != j.selected, -d.score))
    return out


def verdict(gap: Gap, best: ModelFit | None, nominal_fits: bool) -> Verdict:
    """The verdict: the nominal fits nothing; no significant gap; the best model explains it; or nothing does."""
    if not nominal_fits:
        return Verdict.NOMINAL_MISFITS
    if not gap.significant:
        return Verdict.NO_GAP
    return Verdict.EXPLAINED if best and best.explains else Verdict.NOT_EXPLAINED


def assemble(system, cfg, records, cal, held, nominal, fits, sims, screening, bands, scale, gap: Gap,
             selected: str | None = None, band: PredictionBand | None = None) -> Diagnosis:
    """The diagnosis's judgement: verdict, chosen effects, gap, ranking, evidence. `selected`: the model the
    forward selection kept. `band`: the best model's prediction band (band.prediction_band, when `needs_band`
    asks for it): that model explains the data when the best prediction within its band meets the criterion."""
    afters = {name: selection.heldout_nrmse(sims[name], held) for name in fits}
    # the floor should the sensor noise grow with the level is an upper bound of the noise (it counts distortion
    # as noise); so is any model's held-out misfit: the shrink is measured against the smaller of the two
    gap = dataclasses.replace(gap, shrink_reference=min([gap.noise_floor_scaled] + list(afters.values())))
    explained_below = selection.explained_below(gap.noise_floor, cfg.explain_factor, cfg.explain_margin)
    members = {n: tuple(system.effects[n].members or (n,)) if n in system.effects else (n,) for n in fits}
    ranked = ranking(Judged(gap, fits, afters, members, screening, cfg, selected), gap.shrink_reference,
                     explained_below, band)
    best = ranked[0] if ranked else None
    confined = localise.confined_misfit(sims[best.effect], held) \
        if gap.significant and best and best.heldout_gap_after > explained_below else None
    best_cal = best_calibration_nrmse(gap)
    refit_cal, refit_name = best_refit(fits)
    # the model fits when the nominal fits some calibration file, or (a strong amplitude-dependent effect, which
    # leaves no linear model fitting any level) a model with an effect fits the calibration files
    nominal_fits = min(best_cal[0], refit_cal) <= cfg.nominal_max_nrmse
    found = verdict(gap, best, nominal_fits)
    lines = evidence.detection_lines(gap, cfg)
    if nominal_fits and best_cal[0] > cfg.nominal_max_nrmse:
        lines = [f"the nominal model fits none of its calibration files (NRMSE {best_cal[0]:.3f} on the best one) but "
                 f"the model with {refit_name} fits them at {refit_cal:.3f}: the response changes strongly with "
                 "amplitude"] + lines
    if found is Verdict.NOMINAL_MISFITS:
        lines += evidence.nominal_misfits_lines(best_cal, gap, cfg.nominal_max_nrmse)
    elif found is Verdict.NOT_EXPLAINED and best:
        lines += evidence.not_explained_lines(best, ranked, gap, best_cal, explained_below, cfg, system.outside,
                                              confined)
    elif found is Verdict.EXPLAINED:
        lines += evidence.chosen_lines(best, gap, screening, system.effects[best.effect].signature, confined,
                                       explained_below)
    listed_starts = {name: [d for d in [{p.name: p.range(scale)[1] for p in e.params if p.shape}] if d]
                     + list(e.starts(scale))
                     for name, e in system.effects.items() if name in fits and e.starts(scale) and not e.members}
    return Diagnosis(
        model=system.name, fmu=system.fmu, source="", verdict=found,
        chosen=best.members if found is Verdict.EXPLAINED else (), explained_below=explained_below, gap=gap,
        ranking=tuple(ranked), evidence=tuple(lines),
        nominal=NominalFit(free_values(nominal, ()), nominal.calibration_nrmse, nominal.evaluations,
                           dict(nominal.params)),
        calibration_files=tuple(r.name for r in cal), held_out_files=tuple(r.name for r in held),
        runner_up_close=bool(len(ranked) > 1 and gap.significant
                             and ranked[0].score - ranked[1].score < cfg.close_points),
        confined_misfit=dataclasses.asdict(confined) if confined else None, listed_starts=listed_starts,
        data_scale={"sigma_y": scale.sigma_y, "sigma_v": scale.sigma_v, "k": scale.k})


def needs_band(d: Diagnosis, min_shrink_pct: float) -> str | None:
    """The model whose prediction band decides the verdict, or None: a report that no candidate explains, whose
    best model removes at least `min_shrink_pct` of the gap and leaves its held-out misfit confined to a few
    windows (localise.confined_misfit) with the rest within the criterion."""
    confined, best = d.confined_misfit, d.best
    if d.verdict is not Verdict.NOT_EXPLAINED or best is None or confined is None:
        return None
    if confined["nrmse_rest"] > d.explained_below or best.shrink_pct < min_shrink_pct:
        return None
    return best.effect


def separation(runner, d: Diagnosis, records, fits, bands, upsample, lead_periods=1) -> Separation | None:
    """When the first two effects score close: where their refitted models differ most, over the measured
    levels and beyond them (the lowest input x0.3, the highest x2): the level and band to measure next."""
    if not d.runner_up_close:
        return None
    a, b = (d.ranking[i].effect for i in (0, 1))
    lo = min(records, key=lambda r: r.level_value)
    hi = max(records, key=lambda r: r.level_value)
    rows = []
    for rec in [sim.scaled(lo, 0.3)] + list(records) + [sim.scaled(hi, 2.0)]:
        ya, yb = (sim.simulate(runner, rec, fits[e].params, upsample, lead_periods) for e in (a, b))
        if ya is None or yb is None:
            continue
        ref = dataclasses.replace(rec, outputs=ya)
        band = int(np.argmax(localise.by_band(yb, ref, bands)))
        rows.append({"level": rec.level, "input_scale_of": rec.name, "difference_nrmse": localise.nrmse(yb, ref),
                     "band_hz": list(bands[band])})
    return Separation((a, b), tuple(rows), max(rows, key=lambda r: r["difference_nrmse"]) if rows else None)
