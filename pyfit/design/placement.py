"""Damper placement on a span: the number of dampers and their distances from the suspension clamp that
minimise the worst-case fatigue use over the aeolian band.

A configuration (positions x_1 < … < x_n [m]) is judged by the energy balance at every frequency of the
damper table (each damper at its own position on the wave, with the dampers' reaction on the string), the
Poffenberger–Swart stress at the clamp (EI_min, the design value) and the endurance stress of the CIGRE
safe border line: fatigue use = max over the band of σ_a / σ_endurance (≤ 1 passes).
The search evaluates every configuration on a grid of positions, then refines the best of each damper count
by Nelder–Mead (positions kept inside the range): its result is never worse than any grid configuration.
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize

from pyfit.design import fatigue
from pyfit.design.conductor import ConductorType
from pyfit.design.energy_balance import Conductor, DamperPowerTable, steady_amplitude
from pyfit.design.wind import WindPower


@dataclass
class Configuration:
    """Dampers at `positions` [m from the clamp]: antinode amplitude [m], stress σ_a [Pa] (EI_min) at each
    frequency of the band, and the worst-case fatigue use max σ_a / σ_endurance [-] (inf if the balance
    leaves the damper table at some frequency)."""

    positions: tuple[float, ...]
    amplitudes: np.ndarray
    stress: np.ndarray
    use: float


def evaluate(span: Conductor, conductor: ConductorType, table: DamperPowerTable, positions,
             wind: WindPower = WindPower()) -> Configuration:
    """Amplitudes, stresses and fatigue use of one configuration over the table's frequencies."""
    positions = tuple(float(x) for x in positions)
    amps = np.array([steady_amplitude(f, span, [(lambda a, i=i: table.impedance_at(i, a), x) for x in positions], wind)
                     for i, f in enumerate(table.frequencies)])
    stress = fatigue.bending_stress(amps, table.frequencies, conductor, span.tension, conductor.ei_min)
    limit = fatigue.endurance_stress(conductor.aluminium_layers)
    use = float(np.max(stress) / limit) if np.all(np.isfinite(stress)) else math.inf
    return Configuration(positions, amps, stress, use)


def position_grid(x_range: tuple[float, float], step: float) -> np.ndarray:
    """Positions [m] from x_range[0] to x_range[1] in steps of `step` (both ends included)."""
    n = int(round((x_range[1] - x_range[0]) / step))
    return x_range[0] + step * np.arange(n + 1)


def grid_search(span: Conductor, conductor: ConductorType, table: DamperPowerTable, n_dampers: int, grid,
                wind: WindPower = WindPower(), min_spacing: float = 0.5) -> list[Configuration]:
    """Every configuration of n_dampers grid positions at least min_spacing [m] apart, best (lowest use)
    first."""
    combos = [c for c in itertools.combinations(sorted(grid), n_dampers)
              if np.all(np.diff(c) >= min_spacing - 1e-9)]
    return sorted((evaluate(span, conductor, table, c, wind) for c in combos), key=lambda c: c.use)


def optimise(span: Conductor, conductor: ConductorType, table: DamperPowerTable, n_dampers: int,
             x_range: tuple[float, float], step: float = 0.25, wind: WindPower = WindPower(),
             min_spacing: float = 0.5) -> Configuration:
    """Best configuration of n_dampers in x_range [m]: grid search at `step` [m], then Nelder–Mead from the
    best grid point (dampers at least `min_spacing` [m] apart, inside the range)."""
    best = grid_search(span, conductor, table, n_dampers, position_grid(x_range, step), wind,
                       min_spacing)[0]
    if not math.isfinite(best.use):
        return best

    def cost(x):
        x = np.sort(np.asarray(x, float))
        if x[0] < x_range[0] or x[-1] > x_range[1] or np.any(np.diff(x) < min_spacing - 1e-9):
            return 1e3
        return evaluate(span, conductor, table, x, wind).use

    res = minimize(cost, np.array(best.positions), method="Nelder-Mead",
                   options={"initial_simplex": _simplex(best.positions, step / 2), "xatol": 1e-3, "fatol": 1e-5,
                            "maxfev": 60 * n_dampers})
    refined = evaluate(span, conductor, table, np.sort(res.x), wind) if res.fun < best.use else best
    return refined if refined.use <= best.use else best


def _simplex(x0, size: float) -> np.ndarray:
    x0 = np.asarray(x0, float)
    return np.vstack([x0] + [x0 + size * np.eye(len(x0))[k] for k in range(len(x0))])
