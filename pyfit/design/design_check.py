"""The span design check: from a SPAN.toml and the damper FMU to a report an engineer can hand on.

Steps: the aeolian band of the conductor (Strouhal × wind range / D); the damper's clamp impedance over that
band and a range of clamp amplitudes (the DamperElement FMU, `pyfit.runtime.damper_power.damper_power_table`, or a
measured impedance test); steady amplitudes by the energy balance (the wind power curve with turbulence,
the self-damping law, every damper at its own position, with its reaction on the string); the
Poffenberger–Swart stress at the clamp; the best positions for 1…max_dampers dampers
(`placement`); fatigue of the recommended configuration (CIGRE safe border line, IEEE 150 µε, yearly
damage over the Weibull climate). Writes design_check.md, design_check.json, damper_power.csv and figures.
"""
from __future__ import annotations

import json
import math
import pathlib
from dataclasses import dataclass

import numpy as np

from pyfit.design import fatigue, placement
from pyfit.design.energy_balance import Conductor
from pyfit.runtime.damper_power import DamperPowerTable, damper_power_table
from pyfit.io.impedance import read_impedance
from pyfit.io.schema import ConfigError
from pyfit.design.span_config import SpanDesign
from pyfit.report import plots


@dataclass
class DesignResult:
    """What the check found: the bare span, the best configuration per damper count, the recommendation
    (fewest dampers that pass; else the lowest use), the one-damper position sweep and the fatigue figures."""

    design: SpanDesign
    table: DamperPowerTable
    bare: placement.Configuration
    best: dict[int, placement.Configuration]
    recommended: placement.Configuration
    sweep: list[placement.Configuration]
    fatigue: dict


def energy_balance_span(design: SpanDesign) -> Conductor:
    """The span as the energy balance sees it (diameter, mass, tension, length, self-damping)."""
    c = design.conductor
    return Conductor(c.diameter, c.mass_per_length, design.tension, design.length, design.zeta, design.self_damping)


def band_frequencies(design: SpanDesign) -> np.ndarray:
    """n_frequencies log-spaced over the conductor's aeolian band [Hz]."""
    return np.geomspace(*design.climate.band(design.conductor.diameter), design.n_frequencies)


def damper_table(design: SpanDesign, damper_fmu, workers: int | None = None, progress: bool = True) -> DamperPowerTable:
    """The damper over the band: its measured impedance test (the frequencies inside the band) if the design
    names one, else the damper FMU simulated at n_frequencies × n_amplitudes."""
    if design.impedance_file is None:
        return damper_power_table(damper_fmu, band_frequencies(design),
                                  np.geomspace(*design.amplitudes, design.n_amplitudes), design.damper_parameters,
                                  workers=workers, progress=progress)
    test = DamperPowerTable.from_test(read_impedance(design.impedance_file))
    lo, hi = design.climate.band(design.conductor.diameter)
    inside = (test.frequencies >= lo) & (test.frequencies <= hi)
    if np.sum(inside) < 2:
        raise ConfigError(f"{design.impedance_file}: fewer than two test frequencies inside the aeolian band "
                          f"{lo:.1f}–{hi:.1f} Hz; allowed: a test that covers the band")
    return DamperPowerTable(test.frequencies[inside], test.amplitudes[inside], test.power[inside],
                            test.drift[inside], test.impedance[inside])


def fatigue_figures(design: SpanDesign, config: placement.Configuration, frequencies) -> dict:
    """Stress and strain maxima (EI_min and EI_max), use of both criteria, yearly cycles, damage and life."""
    c = design.conductor
    limit = fatigue.endurance_stress(c.aluminium_layers)
    stress_max_ei = fatigue.bending_stress(config.amplitudes, frequencies, c, design.tension, c.ei_max)
    strain = fatigue.strain_peak_to_peak(config.stress, c)
    damage, cycles = fatigue.yearly_damage(frequencies, config.stress, c.diameter, design.climate, c.aluminium_layers)
    ieee_use = float(np.max(strain) / fatigue.IEEE_STRAIN_PP)
    return {"endurance_stress_pa": limit, "max_stress_pa": float(np.max(config.stress)),
            "max_stress_ei_max_pa": float(np.max(stress_max_ei)), "cigre_use": config.use,
            "max_strain_pp": float(np.max(strain)), "ieee_use": ieee_use,
            "yearly_damage": damage, "yearly_cycles": cycles,
            "life_years": math.inf if damage == 0 else 1.0 / damage,
            "passes": bool(config.use <= 1.0 and ieee_use <= 1.0),
            "margin": 1.0 - max(config.use, ieee_use)}


def run_design_check(design: SpanDesign, damper_fmu, workers: int | None = None,
                     progress: bool = True) -> DesignResult:
    """The whole check (the damper table takes most of the time: n_frequencies × n_amplitudes FMU runs)."""
    table = damper_table(design, damper_fmu, workers, progress)
    freqs = table.frequencies
    span = energy_balance_span(design)
    args = (span, design.conductor, table)
    bare = placement.evaluate(*args, (), design.wind)
    best = {n: placement.optimise(*args, n, design.x_range, design.step, design.wind, design.min_spacing)
            for n in range(1, design.max_dampers + 1)}
    passing = [cfg for n, cfg in sorted(best.items()) if cfg.use <= 1.0]
    recommended = passing[0] if passing else min(best.values(), key=lambda cfg: cfg.use)
    sweep = sorted(placement.grid_search(*args, 1, placement.position_grid(design.x_range, design.step),
                                         design.wind), key=lambda cfg: cfg.positions)
    return DesignResult(design, table, bare, best, recommended, sweep, fatigue_figures(design, recommended, freqs))


def _unresolved(cfg: placement.Configuration, freqs) -> str:
    return ", ".join(f"{f:.1f}" for f in freqs[~np.isfinite(cfg.stress)]) + " Hz"


def _positions(cfg: placement.Configuration) -> str:
    return ", ".join(f"{x:.2f}" for x in cfg.positions) + " m"


def write_report(result: DesignResult, out_dir) -> pathlib.Path:
    """design_check.md (+ .json, damper_power.csv and the figures) into out_dir; returns the md path."""
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    d, fat, freqs = result.design, result.fatigue, result.table.frequencies
    result.table.save(out / "damper_power.csv")
    md = out / "design_check.md"
    md.write_text("\n".join(_summary_lines(result) + _fatigue_lines(result)) + "\n")
    (out / "design_check.json").write_text(json.dumps({
        "conductor": d.conductor.name, "span_m": d.length, "tension_n": d.tension, "band_hz": [freqs[0], freqs[-1]],
        "bare_use": result.bare.use,
        "best": {str(n): {"positions_m": list(cfg.positions), "use": cfg.use} for n, cfg in result.best.items()},
        "recommended_positions_m": list(result.recommended.positions), **fat}, indent=2, default=float))
    _figures(result, out)
    return md


def _summary_lines(result: DesignResult) -> list[str]:
    """The verdict, the span, conductor, damper, self-damping and wind, and the best configuration per count."""
    d, c, fat = result.design, result.design.conductor, result.fatigue
    freqs = result.table.frequencies
    law = f"{d.self_damping[0].label}, k = {d.self_damping[1]:.4g}" if d.self_damping else f"viscous ζ = {d.zeta:g}"
    verdict = "PASSES" if fat["passes"] else "FAILS"
    damper = (f"measured impedance `{d.impedance_file.name}`" if d.impedance_file else "DamperElement FMU" + (
        " with " + ", ".join(f"{k} = {v:g}" for k, v in sorted(d.damper_parameters.items()))
        if d.damper_parameters else " (the reference damper of theory §1.3)"))
    lines = [f"# Span design check: {c.name}, {d.length:g} m at {d.tension / 1e3:.1f} kN ({d.tension / c.rts:.0%} RTS)",
             "", f"**The span {verdict} with {len(result.recommended.positions)} damper(s) at "
             f"{_positions(result.recommended)} from the suspension clamp: the worst fatigue use is "
             f"{1 - fat['margin']:.2f} of the limit, a margin of {fat['margin']:.0%}** (use: the larger of the CIGRE "
             "and IEEE uses below).", "",
             f"Conductor: D = {c.diameter * 1e3:.2f} mm, {c.mass_per_length:g} kg/m, RTS {c.rts / 1e3:.1f} kN, "
             f"EI {c.ei_min:.1f}–{c.ei_max:.0f} N·m², outer wires {c.outer_wire_diameter * 1e3:.2f} mm, "
             f"{c.aluminium_layers} aluminium layer(s). Damper: {damper}. Self-damping: {law}. Wind: {d.wind.label}; "
             f"Weibull k = {d.climate.weibull_shape:g}, c = {d.climate.weibull_scale:g} m/s; "
             f"aeolian {d.climate.speed_range[0]:g}–{d.climate.speed_range[1]:g} m/s, St "
             f"{d.climate.strouhal[0]:g}–{d.climate.strouhal[1]:g}: band {freqs[0]:.1f}–{freqs[-1]:.1f} Hz.", "",
             "| dampers | positions from the clamp | max σ_a [MPa] | CIGRE use (σ_a / σ_endurance) |",
             "|---|---|---|---|",
             f"| 0 | — | {np.max(result.bare.stress) / 1e6:.2f} | {result.bare.use:.2f} |"]
    for n, cfg in sorted(result.best.items()):
        if math.isfinite(cfg.use):
            lines.append(f"| {n} | {_positions(cfg)} | {np.max(cfg.stress) / 1e6:.2f} | {cfg.use:.3f} |")
        else:
            lines.append(f"| {n} | unresolved at every position: at {_unresolved(cfg, freqs)} the balance needs "
                         "clamp amplitudes beyond those the damper FMU ran at | — | — |")
    return lines


def _fatigue_lines(result: DesignResult) -> list[str]:
    """The recommended configuration's fatigue table and the figures."""
    fat, d = result.fatigue, result.design
    return ["", f"Recommended (fewest dampers that pass, else the lowest use): {_positions(result.recommended)}.", "",
            "| fatigue of the recommended configuration | value |", "|---|---|",
            f"| endurance stress, CIGRE safe border line at 5·10⁸ cycles | {fat['endurance_stress_pa'] / 1e6:.2f} MPa |",
            f"| max bending stress σ_a at the clamp (EI_min; EI_max) | {fat['max_stress_pa'] / 1e6:.2f} MPa; "
            f"{fat['max_stress_ei_max_pa'] / 1e6:.2f} MPa |",
            f"| CIGRE use | {fat['cigre_use']:.3f} |",
            f"| max bending strain at 89 mm, peak to peak (IEEE limit 150 µε) | {fat['max_strain_pp'] * 1e6:.1f} µε |",
            f"| IEEE use | {fat['ieee_use']:.3f} |",
            f"| cycles per year (aeolian fraction {d.climate.aeolian_fraction:g}) | {fat['yearly_cycles']:.3g} |",
            f"| Miner damage per year (safe border line as S-N curve) | {fat['yearly_damage']:.3g} |",
            f"| life at that rate | {fat['life_years']:.3g} years |", "",
            "![antinode amplitude over the band, without and with the best configurations](design_amplitude.png)",
            "", "![stress at the clamp and the endurance line](design_stress.png)", "",
            "![worst-case use of one damper against its position](design_positions.png)"]


def _figures(result: DesignResult, out: pathlib.Path) -> None:
    """The antinode amplitude and the clamp stress over the band, and one damper's use against its position."""
    freqs, d = result.table.frequencies, result.design
    styles = ["o-", "s-", "^-", "d-"]
    configs = [("no damper", result.bare, "k-")] + [
        (f"{n} at {_positions(cfg)}", cfg, styles[n - 1]) for n, cfg in sorted(result.best.items())]
    plots.semilogy_curves(out / "design_amplitude.png", [(lab, freqs, cfg.amplitudes * 1e3, st) for lab, cfg, st in configs],
                          "frequency [Hz]", "steady antinode amplitude Y [mm]", "Energy balance over the aeolian band")
    limit = result.fatigue["endurance_stress_pa"] / 1e6
    plots.semilogy_curves(out / "design_stress.png", [(lab, freqs, cfg.stress / 1e6, st) for lab, cfg, st in configs]
                          + [("endurance (CIGRE SBL, 5e8 cycles)", freqs[[0, -1]], [limit, limit], "r--")],
                          "frequency [Hz]", "bending stress σ_a at the clamp [MPa]",
                          "Poffenberger–Swart stress (EI_min); Y_b at 89 mm")
    plots.semilogy_curves(out / "design_positions.png",
                          [("one damper (unresolved positions not shown)", [cfg.positions[0] for cfg in result.sweep],
                            [cfg.use if math.isfinite(cfg.use) else np.nan for cfg in result.sweep], "o-"),
                           ("limit", list(d.x_range), [1.0, 1.0], "r--")],
                          "damper position from the clamp [m]", "worst-case CIGRE use over the band [-]",
                          "Position sweep, one damper", log=False)
