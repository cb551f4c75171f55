"""Which combination of effects: the diagnosis's model search after the single effects' refits (ModelSearch). How
it decides, rule by rule, is on the documentation's page "How the diagnosis decides"; each method here says what
its step does."""
from __future__ import annotations

import dataclasses
import functools
import itertools
import json
import os
import pathlib
from dataclasses import dataclass

from pyfit.gap import selection
from pyfit.gap import simulate as sim
from pyfit.gap.attribute import STRENGTH_FACTORS, Fit, effect_task, pinned, screen
from pyfit.gap.result import Gap
from pyfit.gap.store import fit_once, fits_of
from pyfit.gap.effect import combine
from pyfit.gap.systems import System, strength_grid


def simulated_on(runner, records, values: dict, system, cfg) -> dict:
    """Each of `records` simulated with `values` (record name -> outputs; None where a simulation failed)."""
    return {r.name: sim.simulate(runner, r, values, cfg.upsample, system.lead_periods) for r in records}


def stem(name: str) -> str:
    """The file stem a model's fit is stored under (a combination 'a + b' as 'a+b')."""
    return name.replace(" + ", "+")


def combination_seeds(system, scale, current: dict, members: list, partner_fit: dict, partner: str,
                      strength: dict) -> tuple[dict, ...]:
    """Starts of a combination's joint refit, each a model the combination holds: the model so far (`current`, the
    partner absent); the partner's own refit; the model so far with the partner's parameters from that refit, with
    the model so far's linear parameters or with the partner's; the model so far with the partner's strength from
    the Gauss-Newton step at that model (`strength`) scaled by STRENGTH_FACTORS; the model so far with each listed
    start of the partner; and the partner's own refit with each listed start of the model so far's `members`. A
    listed start's linear values are shares of the nominal's, applied to the refit it is added to."""
    own = {p.name for p in system.effects[partner].params}
    linear = set(system.linear)

    def added(base: dict, start: dict) -> dict:
        return {**base, **{n: base[n] * v / scale.nominal[n] if n in linear else v for n, v in start.items()}}

    return ((current, partner_fit, {**current, **{n: partner_fit[n] for n in own}},
             {**current, **{n: v for n, v in partner_fit.items() if n in own or n in linear}})
            + tuple({**current, **{n: v * f for n, v in strength.items()}} for f in STRENGTH_FACTORS if strength)
            + tuple(added(current, st) for st in system.effects[partner].starts(scale))
            + tuple(added(partner_fit, st) for m in members for st in system.effects[m].starts(scale)))


@dataclass(frozen=True)
class SearchContext:
    """What the search reads and never changes: the system, settings, FMU and its runner, the calibration and
    held-out records, the calibrated nominal, the data scale, the gap, the screening's shares, where fits are
    stored (OUT and the run's key) and how they run (workers, progress)."""

    system: System
    cfg: object
    fmu: str
    runner: object
    cal: list
    held: list
    nominal: Fit
    scale: object
    gap: Gap
    screening: dict
    out: pathlib.Path
    key: str
    workers: int | None
    progress: bool


@dataclass(frozen=True)
class Trial:
    """A combination tried as the extension of a model: its name, refit task, the model's values held beside it
    (`so_far`) and the partner's own refit values (`side`)."""

    name: str
    task: object
    so_far: dict
    side: dict


class ModelSearch:
    """The forward selection of combinations of effects, from the single effects' refits: paths from the best single
    effects, each extended by the partners whose sensitivity explains most of its residual (extend), checked
    backward (prune), their ends compared (choose); the envelope-led stage and the strength grid where nothing
    explains the data. Owns the fits (`fits`), the held-out simulations (`sims`) and their misfits (`after`)."""

    def __init__(self, ctx: SearchContext, fits: dict, sims: dict):
        self.ctx, self.cfg, self.system = ctx, ctx.cfg, ctx.system
        self.fits, self.sims = fits, sims
        self.before, self.floor = ctx.gap.overall, ctx.gap.noise_floor
        self.above = ctx.gap.noise_floor_scaled  # the noise the selection measures a misfit above
        self.explained_below = selection.explained_below(self.floor, self.cfg.explain_factor, self.cfg.explain_margin)
        self.alone = ctx.workers or os.cpu_count() or 1  # a fit that runs alone simulates its records at once
        self.after = {n: selection.heldout_nrmse(sims[n], ctx.held) for n in fits}
        self.effects = dict(self.system.effects)
        self.named = {frozenset([n]): n for n in fits}  # members -> the name their model is stored under
        self.settled = set()  # models that explain the data and leave nothing a candidate's sensitivity explains
        self.beside_only = set()  # combinations whose fit so far is a refit beside one path's model
        self.controls = {}  # a combination -> what refitting on alone bought the model it extends

    # --- small helpers -------------------------------------------------------------------------------------------
    def members(self, name) -> tuple:
        return self.effects[name].members or (name,)

    def left(self, name) -> bool:
        """A model's held-out misfit is above the noise (a weaker test than the nominal's): go on adding."""
        return selection.significant(self.after[name], self.above, self.cfg.extend_factor,
                                     self.cfg.combination_min_gap)

    def score(self, name) -> float:
        return selection.score(self.before, self.after[name], self.floor, self.fits[name].n_added)

    def on_held(self, values) -> dict:
        return simulated_on(self.ctx.runner, self.ctx.held, values, self.system, self.cfg)

    def simulated(self, name) -> None:
        self.sims[name] = self.on_held(self.fits[name].params)
        self.after[name] = selection.heldout_nrmse(self.sims[name], self.ctx.held)

    def path(self, stored_as: str) -> pathlib.Path:
        return self.ctx.out / "fits" / f"{stored_as}.json"

    def task(self, name, budget=None, seeds=(), **kw):
        """The refit task of model `name` with `seeds` among its starts."""
        c = self.ctx
        return effect_task(self.system, self.effects[name], c.fmu, c.cal, c.nominal, c.scale,
                           budget or self.cfg.refit_budget, self.cfg.upsample, seeds=seeds, **kw)

    def fits_of(self, jobs, desc) -> dict[str, Fit]:
        return fits_of(jobs, self.ctx.key, self.alone, self.ctx.workers, self.ctx.progress, desc)

    def take(self, name, fit: Fit, *costs: Fit, **changes) -> None:
        """`fit` becomes the model's fit, its cost counting the fits it went on from; simulated on the held out."""
        self.fits[name] = dataclasses.replace(fit, evaluations=fit.evaluations + sum(f.evaluations for f in costs),
                                              wall_s=fit.wall_s + sum(f.wall_s for f in costs), **changes)
        self.simulated(name)

    def stand_in(self, name) -> bool:
        """A free-shape loop still above the noise: it may hold another's part."""
        return any(self.system.effects[m].free_shape for m in self.members(name)) and self.left(name)

    def basin_free_stand_in(self, name) -> bool:
        """A possible stand-in whose loop has no basins (the damper's)."""
        return self.stand_in(name) and self.effects[name].basin is None

    def found_beside(self, end) -> bool:
        """Such a loop, found beside the lean effect its path began at."""
        return self.basin_free_stand_in(end) and not self.system.effects[self.members(end)[0]].free_shape

    def kept(self, a, b):
        """Of two models, the one kept (selection.simpler_or_better)."""
        sized = [(len(self.members(n)), self.after[n]) for n in (a, b)]
        larger = (a, b)[sized[1][0] > sized[0][0]]
        return (a, b)[selection.simpler_or_better(
            *sized, self.above, self.cfg.min_excess_cut, self.controls.get(larger, float("inf")),
            parameters=(len(self.effects[a].params), len(self.effects[b].params)),
            noise=selection.noise_level(self.above, self.cfg.noise_factor, self.cfg.combination_min_gap),
            linear=any(self.system.effects[m].linear for n in (a, b) for m in self.members(n)))]

    # --- the search ----------------------------------------------------------------------------------------------
    def run(self) -> tuple[System, str | None]:
        """The system with the combinations tried among its effects, and the model selected (None when no single
        effect was refitted)."""
        ranked = sorted(self.fits, key=lambda n: -self.score(n))
        if not ranked:
            return self.system, None
        if not self.left(ranked[0]):
            # a single effect reaches the noise: nothing to add; of the single effects, the one kept by the rule
            return self.system, functools.reduce(self.kept, ranked)
        ends = self.paths(ranked)
        selected = functools.reduce(self.kept, ends)
        singles = [n for n in self.fits if not self.effects[n].members]
        if self.unexplained(singles, selected) and not any(r.periodic for r in self.ctx.cal):
            selected = functools.reduce(self.kept, [selected] + self.enveloped(singles))
        if self.unexplained(singles, selected):
            selected = self.gridded(selected, ends)
        return dataclasses.replace(self.system, effects=self.effects), selected

    def unexplained(self, singles, selected) -> bool:
        """No single effect and not the model selected meets the absolute criterion."""
        return all(self.after[n] > self.explained_below for n in singles + [selected])

    def path_starts(self, ranked) -> tuple[list, str]:
        """The single effects the paths start from (the `beam` best; the one whose sensitivity explains most of the
        nominal residual first when a basin-free loop leads but fits the calibration files worse), and that one."""
        starts = ranked[:self.cfg.beam]
        screened = max(ranked, key=lambda n: self.ctx.screening.get(n, 0.0))
        if (self.basin_free_stand_in(starts[0]) and screened != starts[0]
                and self.fits[screened].calibration_nrmse < self.fits[starts[0]].calibration_nrmse):
            starts = [screened] + [n for n in starts if n != screened]
        return starts, screened

    def paths(self, ranked) -> list[str]:
        """Each path's end, from each start until one reaches the noise or settles."""
        ends = []
        starts, screened = self.path_starts(ranked)
        for rank, start in enumerate(starts):
            if rank and not selection.worth_a_path(selection.shrink_pct(self.before, self.after[start], self.floor),
                                                   self.effects[start].linear, self.cfg.min_shrink_pct):
                continue  # a linear change that removes little of the gap
            if any(self.after[e] <= self.explained_below and start in self.members(e)
                   and (not self.stand_in(e) or self.found_beside(e)) for e in ends):
                break  # an earlier path's end explains the data and holds this start already
            ends.append(self.polished(self.grow(start)))
            if self.basin_free_stand_in(ends[-1]) and screened not in starts:
                starts.append(screened)  # the effect the loop may stand in for, by its sensitivity
            if not self.left(ends[-1]) or (ends[-1] in self.settled and not self.stand_in(ends[-1])):
                break
        return ends

    def grow(self, current) -> str:
        """A path: the model extended one member at a time while its misfit is above the noise; then pruned."""
        while len(self.members(current)) < self.cfg.max_effects and self.left(current):
            step = self.extend(current)
            if step is None:
                break
            current = step
        return self.prune(current)

    # --- extend --------------------------------------------------------------------------------------------------
    def refit_on(self, current) -> None:
        """The model so far refitted on from its own result with a combination's budget (a combination must beat
        more evaluations of its first member(s)); taken when it fits the calibration files better."""
        task = dataclasses.replace(self.task(current, seeds=(self.fits[current].params,)), threads=self.alone)
        again = fit_once(task, self.path(f"{stem(current)}.continued"), self.ctx.key)
        if again.calibration_nrmse < self.fits[current].calibration_nrmse:
            self.fits[current] = again
            self.simulated(current)

    def extend(self, current) -> str | None:
        """One step of a path: the next member chosen among the partners; None when the path ends here."""
        self.refit_on(current)
        if not self.left(current):
            return None  # the model so far, refitted on, reaches the noise
        members = list(self.members(current))
        others = [n for n in self.system.effects if n not in members and n in self.fits]
        explained, strength = self.screened_at(current, others)
        if selection.nothing_to_add(self.after[current], self.explained_below, list(explained.values()),
                                    self.cfg.min_partner_explained):
            self.settled.add(current)
            return None
        partners = sorted(others, key=lambda n: -explained[n])[:self.cfg.partners]
        names, new, again = self.trials(current, members, partners, strength)
        self.rejoined(current, again)
        return self.step(current, names, new)

    def screened_at(self, current, others) -> tuple[dict, dict]:
        """The screening repeated at the model so far (attribute.screen: each candidate's share of its calibration
        residual, and the strength of its Gauss-Newton step), stored as fits/<model>.screened.json with the model's
        values, its misfits and the thresholds it was judged by (a resumed diagnosis reads it)."""
        c, fit = self.ctx, self.fits[current]
        path = self.path(f"{stem(current)}.screened")
        kept = json.loads(path.read_text()) if path.is_file() else {}
        if kept.get("key") == c.key and kept.get("params") == fit.params and set(kept["fractions"]) == set(others):
            return kept["fractions"], kept["strengths"]
        explained, strength = screen(self.system, c.fmu, c.cal, fit, c.scale, self.cfg.upsample, others)
        path.write_text(json.dumps({"key": c.key, "params": fit.params, "fractions": explained, "strengths": strength,
                                    "heldout_nrmse": self.after[current], "calibration_nrmse": fit.calibration_nrmse,
                                    "explained_below": self.explained_below, "noise": self.above}, indent=1))
        return explained, strength

    def trials(self, current, members, partners, strength) -> tuple[list, list, list]:
        """The combinations of the model so far with each partner (names); those to refit beside and jointly
        (`new`), and those refitted jointly on the partner's path that added too little there (`again`)."""
        names, new, again = [], [], []
        for partner in partners:
            together = frozenset(members + [partner])
            combo = self.effects[self.named[together]] if together in self.named else combine(
                [self.system.effects[m] for m in members + [partner]])
            self.effects[combo.name], self.named[together] = combo, combo.name
            names.append(combo.name)
            trial = self.trial(current, members, partner, combo.name, strength.get(partner, {}))
            if combo.name not in self.fits or combo.name in self.beside_only:
                new.append(trial)
            elif len(together) == 2 and not selection.adds_enough(self.after[partner], self.after[combo.name],
                                                                  self.above, self.cfg.min_excess_cut):
                again.append(trial)
        return names, new, again

    def trial(self, current, members, partner, name, strength) -> Trial:
        """The joint refit of `name` from the combination's seeds, never worse than the model it extends (the
        partner at zero), with what each side holds when refitted beside the other."""
        seeds = combination_seeds(self.system, self.ctx.scale, self.fits[current].params, members,
                                  self.fits[partner].params, partner, strength)
        task = self.task(name, seeds=seeds)
        added = {q.name for q in self.system.effects[partner].params}
        at_zero = {**task.floor, **{n: v for n, v in self.fits[current].params.items()
                                    if n in task.floor and n not in added}}
        task = dataclasses.replace(task, floor=at_zero, probes=self.cfg.combination_probes)
        so_far = {n: v for n, v in self.fits[current].params.items()
                  if n in task.start and n not in added and n not in self.system.linear}
        return Trial(name, task, so_far, {n: self.fits[partner].params[n] for n in added})

    def joint_set(self, current, names, beside) -> set:
        """The combinations refitted jointly after the refits beside: the best and (as the control) the worst, the
        best leaner one that cuts enough, the best richer one with a basin-free loop."""
        order = sorted(beside, key=lambda n: beside[n].calibration_nrmse)
        joint = {order[0], order[-1]} if len(names) >= selection.CONTROL_SIBLINGS else set(order[:1])
        sizes = {n: len(self.effects[n].params) for n in order}
        cuts = {n: self.fits[current].calibration_nrmse - beside[n].calibration_nrmse for n in order}
        joint |= set(selection.leaner_best(order, sizes, cuts))
        rough = {n for n in order if (lambda e: e.free_shape and e.basin is None)(
            self.system.effects[self.effects[n].members[-1]])}
        return joint | set(selection.richer_best(order, sizes, rough))

    def step(self, current, names, new) -> str | None:
        """Every partner refitted beside the model so far, the chosen ones jointly; the best combination, when it
        adds enough over the model (and its control), is where the path goes on."""
        beside = self.beside_refits(new, current, "partners beside")
        own = dict(beside)
        for name, fit in own.items():  # a refit beside another path's model stays when it fits better
            if name in self.fits and self.fits[name].calibration_nrmse <= fit.calibration_nrmse:
                beside[name] = self.fits[name]
        order = sorted(beside, key=lambda n: beside[n].calibration_nrmse)
        joint = self.joint_set(current, names, beside)
        for name in set(beside) - joint:  # its fit is the best one beside a path's model so far
            if self.fits.get(name) is not beside[name]:
                self.fits[name] = beside[name]
                self.sims.pop(name, None)
            self.beside_only.add(name)
        jointly = self.fits_of([self.joint_job(t.task, t.side, beside[t.name], own[t.name], stem(t.name))
                                for t in new if t.name in joint], "combinations")
        for name, fit in jointly.items():  # its cost includes the refit beside the model so far
            self.fits[name] = dataclasses.replace(fit, evaluations=fit.evaluations + beside[name].evaluations,
                                                  wall_s=fit.wall_s + beside[name].wall_s)
            self.sims.pop(name, None)
            self.beside_only.discard(name)
        for name in names:
            if name not in self.after or name not in self.sims:
                self.simulated(name)
        least = order[-1] if order else None
        self.against_loop(jointly, least)
        best = functools.reduce(self.kept, names) if names else None
        self.control(current, names, best, least, {t.name: t for t in new})
        if best is None or not selection.adds_enough(min(self.after[current], self.controls[best]),
                                                     self.after[best], self.above, self.cfg.min_excess_cut):
            return None
        return best

    def against_loop(self, jointly, least) -> None:
        """The best jointly refitted pair without a free-shape loop, when one with a loop fits the held-out files
        better, refitted on with a path end's polish budget (selection.lean_rival)."""
        rival = selection.lean_rival(
            jointly, {n for n in jointly if any(self.system.effects[m].free_shape for m in self.effects[n].members)},
            self.after, least)
        if rival is not None:
            self.onward(rival, self.fits[rival].params, 2 * self.cfg.refit_budget, f"{stem(rival)}.against_loop")

    def control(self, current, names, best, least, tried: dict) -> None:
        """The control: the least helpful combination's joint refit with its partner at zero. Where it fits the
        held-out files better than the model so far, that model is refitted on from there; every combination of
        the step records the lowest control it met (selection.budget_control)."""
        at_zero = float("inf")
        if least not in (None, best):
            t = tried[least]
            at_zero = selection.heldout_nrmse(self.on_held({**self.fits[least].params,
                                                            **{n: t.task.floor[n] for n in t.side}}), self.ctx.held)
        if at_zero < self.after[current]:
            t = tried[least]
            self.onward(current, {**self.fits[least].params, **{n: t.task.floor[n] for n in t.side}},
                        self.cfg.refit_budget // 2, f"{stem(current)}.from.{stem(least)}")
        control = selection.budget_control(at_zero, len(names))
        for name in names:
            self.controls[name] = min(self.controls.get(name, float("inf")), control)

    def beside_refits(self, tried: list[Trial], current, desc) -> dict[str, Fit]:
        """Each combination of `tried` refitted beside the model `current` held (half a refit's budget)."""
        return self.fits_of([(pinned(t.task, t.so_far, self.cfg.refit_budget // 2),
                              self.path(f"{stem(t.name)}.beside.{stem(current)}")) for t in tried], desc)

    def joint_job(self, task, side, start: Fit, probe: Fit, stored_as):
        """A combination's joint refit job that also starts from `start`'s values and probes from `probe`'s, after
        its members refitted beside the partner's own values (`side`) as a stage."""
        return (dataclasses.replace(task, alternatives=task.alternatives + ({n: start.params[n] for n in task.start},),
                                    probed=({n: probe.params[n] for n in task.start},)),
                self.path(stored_as), pinned(task, side, self.cfg.refit_budget // 2))

    def rejoined(self, current, again: list[Trial]) -> None:
        """Each pair refitted jointly on its partner's path where it added too little, refitted beside this path's
        model and jointly from this path's starts; its fit replaced when that fits the calibration files better."""
        beside = self.beside_refits(again, current, "pairs again beside")
        jobs = [self.joint_job(t.task, t.side, beside[t.name], beside[t.name], f"{stem(t.name)}.on.{stem(current)}")
                for t in again]
        for name, fit in self.fits_of(jobs, "pairs again").items():
            if fit.calibration_nrmse < self.fits[name].calibration_nrmse:
                self.take(name, fit, beside[name], self.fits[name])

    def onward(self, name, values, budget, stored_as, grid=()) -> None:
        """The model refitted from `values` (or the best of `grid`), with `budget` evaluations on every core; it
        replaces the model's fit when its calibration misfit is lower."""
        task = self.task(name, budget, seeds=(values,))
        task = dataclasses.replace(task, start=task.alternatives[-1], alternatives=grid, basin=None,
                                   threads=self.alone)
        fit = fit_once(task, self.path(stored_as), self.ctx.key)
        if fit.calibration_nrmse < self.fits[name].calibration_nrmse:
            self.take(name, fit, self.fits[name])

    # --- prune and choose ----------------------------------------------------------------------------------------
    def prune(self, end) -> str:
        """The backward step: the model without each of its members, refitted from the larger one's values with
        half a refit's budget; the larger stays only when it still adds enough to every such refit."""
        members = self.effects[end].members or ()
        rests = {self.named[frozenset(members) - {m}]: self.controls.get(end, float("inf")) if m == members[-1]
                 else float("inf") for m in members if frozenset(members) - {m} in self.named}
        for rest in rests:
            self.onward(rest, self.fits[end].params, self.cfg.refit_budget // 2, f"{stem(end)}.reduced_to.{stem(rest)}")
        short = [r for r, bar in rests.items()
                 if not selection.adds_enough(min(self.after[r], bar), self.after[end], self.above,
                                              self.cfg.min_excess_cut)]
        return min(short, key=lambda r: self.after[r]) if short else end

    def polished(self, end) -> str:
        """A path's end still above the absolute criterion, refitted on with twice a refit's budget."""
        if self.after[end] > self.explained_below:
            self.onward(end, self.fits[end].params, 2 * self.cfg.refit_budget, f"{stem(end)}.polished")
        return end

    def gridded(self, selected, ends) -> str:
        """Nothing explains the data: the best models, each refitted from the best point of a grid over its
        members' strengths; then selected again among the paths' ends."""
        gridded = sorted(self.after, key=self.after.get)[:self.cfg.grid_models]
        for name in gridded:
            members = [self.system.effects[m] for m in self.members(name)]
            self.onward(name, self.fits[name].params, self.cfg.refit_budget, f"{stem(name)}.gridded",
                        strength_grid(members, self.ctx.scale, self.fits[name].params))
        return functools.reduce(self.kept, list(dict.fromkeys([selected] + ends + gridded)))

    # --- the envelope-led stage ----------------------------------------------------------------------------------
    def envelope_fits(self, models, seeds_of, probes=1, stored_as="envelopes") -> dict[str, Fit]:
        """Each model fitted to the calibration files' amplitude envelopes from its starts and `seeds_of(model)`."""
        return self.fits_of([(dataclasses.replace(self.task(n, seeds=seeds_of(n)), envelopes=True, probes=probes),
                              self.path(f"{stem(n)}.{stored_as}")) for n in models], "envelope fits")

    def envelope_pairs(self, best) -> list[str]:
        """The pairs of the models `best`, declared as combinations where new."""
        pairs = []
        for a, b in itertools.combinations(best, 2):
            together = frozenset([a, b])
            if together not in self.named:
                combo = combine([self.system.effects[a], self.system.effects[b]])
                self.effects[combo.name], self.named[together] = combo, combo.name
            pairs.append(self.named[together])
        return pairs

    def pair_seeds(self, members_fits):
        """A pair's starts from its members' fits (combination_seeds)."""
        def seeds(pair):
            first, second = self.effects[pair].members
            return combination_seeds(self.system, self.ctx.scale, members_fits[first].params, [first],
                                     members_fits[second].params, second, {})
        return seeds

    def enveloped(self, singles) -> list[str]:
        """Each single effect fitted to the envelopes; each pair of the `grid_models` best of them twice (from the
        members' waveform refits and from their envelope fits); each model then refitted on the waveforms from its
        envelope fit(s), replacing its fit when better. Returns the pairs (the selection also weighs them)."""
        alone_fits = self.envelope_fits(singles, lambda n: (self.fits[n].params,))
        best = sorted(alone_fits, key=lambda n: alone_fits[n].calibration_nrmse)[:self.cfg.grid_models]
        pairs = self.envelope_pairs(best)
        on_envelopes = {n: [f] for n, f in alone_fits.items()}
        for members_fits, stored_as in ((self.fits, "envelopes"), (alone_fits, "envelopes_from_envelopes")):
            for name, fit in self.envelope_fits(pairs, self.pair_seeds(members_fits), self.cfg.combination_probes,
                                                stored_as).items():
                on_envelopes.setdefault(name, []).append(fit)
        jobs = []
        for name, found in on_envelopes.items():
            task = self.task(name, seeds=tuple(f.params for f in found))
            values = task.alternatives[-len(found):]
            jobs.append((dataclasses.replace(task, start=values[0], alternatives=values[1:], basin=None,
                                             probes=len(values), continuation=False),
                         self.path(f"{stem(name)}.from_envelopes")))
        for name, fit in self.fits_of(jobs, "waveforms from the envelopes").items():
            if name not in self.fits or fit.calibration_nrmse < self.fits[name].calibration_nrmse:
                self.take(name, fit, *on_envelopes[name], from_envelopes=True)
        return pairs
