"""Conductor fatigue at the suspension clamp: Poffenberger–Swart bending amplitude and stress, the CIGRE safe
border line, the IEEE strain rule, and yearly damage over a Weibull wind climate. SI units (m, Hz, N, Pa).

Near the clamp a tensioned conductor is a beam with tension: EI y'''' − T y'' = 0 away from inertia, clamped
(y = y' = 0) at the last point of contact x = 0 and leaving with the slope θ of the standing wave,
θ = 2π Y / λ = 2π Y f sqrt(m/T) for an antinode amplitude Y (zero to peak). The solution is
y(x) = θ (x − (1 − e^{−px}) / p), p = sqrt(T / EI), so that

- the Poffenberger–Swart bending amplitude (peak to peak, at x_b = 89 mm) is Y_b = 2 θ (x_b − (1 − e^{−p x_b}) / p);
- the outer-layer wire's bending stress (zero to peak) is σ_a = E_a (d_a / 2) y''(0) = E_a d_a p θ / 2, i.e.
  σ_a = K · Y_b with K = E_a d_a p² / (4 (e^{−p x_b} − 1 + p x_b)) (Poffenberger & Swart, "Differential
  displacement and dynamic conductor strain", IEEE Trans. PAS-84, 1965; EPRI Orange Book eq. 3.2-15).

EI lies between the conductor's bounds; EI_min gives the highest stress for a given antinode amplitude and is
the design value (EPRI Orange Book ch. 3); results at EI_max are reported beside it.

Endurance: the CIGRE safe border line (CIGRE SC22 WG04, "Endurance capability of conductors", 1988; EPRI
Orange Book §3.3): σ_a = A N^b [MPa] with, for ACSR of one aluminium layer, A = 730, b = −0.2 up to N = 2·10⁷
and A = 430, b = −0.17 beyond; for several layers 450/−0.2 up to 1.56·10⁷ and 263/−0.17 beyond. The
endurance stress used for the pass/fail check is the line at 5·10⁸ cycles. Second criterion: IEEE (1966)
"Standardization of conductor vibration measurements": bending strain at 89 mm below 150 µε peak to peak
(ε_pp = 2 σ_a / E_a).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pyfit.design.conductor import ConductorType

X_B = 0.089  # m, Poffenberger–Swart measuring point from the last point of contact
ENDURANCE_CYCLES = 5e8
IEEE_STRAIN_PP = 150e-6  # peak-to-peak bending strain limit
SECONDS_PER_YEAR = 365.25 * 24 * 3600.0
# (knee N, A1 [MPa], b1, A2 [MPa], b2) of the CIGRE safe border line
SBL_ONE_LAYER = (2.0e7, 730.0, -0.20, 430.0, -0.17)
SBL_MULTI_LAYER = (1.56e7, 450.0, -0.20, 263.0, -0.17)


def clamp_slope(Y, f, tension: float, mass_per_length: float):
    """Slope [rad] of the standing wave at a node for antinode amplitude Y [m] at f [Hz] (string wave)."""
    return 2 * np.pi * np.asarray(Y, float) * np.asarray(f, float) * math.sqrt(mass_per_length / tension)


def bending_amplitude(Y, f, tension: float, mass_per_length: float, ei: float, x_b: float = X_B):
    """Poffenberger–Swart bending amplitude Y_b [m], peak to peak at x_b from the clamp."""
    p = math.sqrt(tension / ei)
    return 2 * clamp_slope(Y, f, tension, mass_per_length) * (x_b - (1 - math.exp(-p * x_b)) / p)


def ps_factor(conductor: ConductorType, tension: float, ei: float, x_b: float = X_B) -> float:
    """Poffenberger–Swart K [Pa/m]: outer-wire bending stress (zero to peak) per unit Y_b (peak to peak)."""
    p = math.sqrt(tension / ei)
    return conductor.outer_youngs_modulus * conductor.outer_wire_diameter * p ** 2 / (
        4 * (math.exp(-p * x_b) - 1 + p * x_b))


def bending_stress(Y, f, conductor: ConductorType, tension: float, ei: float, x_b: float = X_B):
    """Outer-wire bending stress σ_a [Pa] (zero to peak) at the clamp for antinode amplitude Y [m] at f [Hz]."""
    return ps_factor(conductor, tension, ei, x_b) * bending_amplitude(Y, f, tension, conductor.mass_per_length,
                                                                      ei, x_b)


def safe_border_line(cycles, aluminium_layers: int):
    """CIGRE safe border line: the stress amplitude [Pa] a conductor endures for `cycles` cycles."""
    knee, a1, b1, a2, b2 = SBL_ONE_LAYER if aluminium_layers <= 1 else SBL_MULTI_LAYER
    n = np.asarray(cycles, float)
    return 1e6 * np.where(n <= knee, a1 * n ** b1, a2 * n ** b2)


def cycles_to_failure(stress, aluminium_layers: int):
    """Inverse of the safe border line: cycles [-] a stress amplitude [Pa] may be applied (the knee's N
    between the two branches' knee stresses; inf at zero stress)."""
    knee, a1, b1, a2, b2 = SBL_ONE_LAYER if aluminium_layers <= 1 else SBL_MULTI_LAYER
    s = np.asarray(stress, float) / 1e6
    with np.errstate(divide="ignore", over="ignore"):
        high, low = (s / a1) ** (1 / b1), (s / a2) ** (1 / b2)
    return np.where(s >= a1 * knee ** b1, high, np.where(s <= a2 * knee ** b2, low, knee))


def endurance_stress(aluminium_layers: int) -> float:
    """The stress [Pa] of the safe border line at 5·10⁸ cycles: the pass/fail limit of the design check."""
    return float(safe_border_line(ENDURANCE_CYCLES, aluminium_layers))


def strain_peak_to_peak(stress, conductor: ConductorType):
    """Bending strain of the outer wire, peak to peak [-], from its stress amplitude [Pa]."""
    return 2 * np.asarray(stress, float) / conductor.outer_youngs_modulus


@dataclass(frozen=True)
class WindClimate:
    """Weibull distribution of the mean wind speed [m/s] across the line, the aeolian speed range, the
    Strouhal numbers bounding the shedding frequency f = St · V / D, and the fraction of the time in that
    range that the wind is steady and across the line enough to excite aeolian vibration."""

    weibull_shape: float = 2.0
    weibull_scale: float = 4.0  # m/s
    speed_range: tuple[float, float] = (1.0, 7.0)  # m/s
    strouhal: tuple[float, float] = (0.185, 0.2)
    aeolian_fraction: float = 1.0

    def band(self, diameter: float) -> tuple[float, float]:
        """Aeolian frequency band [Hz] of a conductor of this diameter [m]."""
        return (self.strouhal[0] * self.speed_range[0] / diameter, self.strouhal[1] * self.speed_range[1] / diameter)

    def probability(self, v_low, v_high):
        """Fraction of the year the wind speed lies in [v_low, v_high) [m/s]."""
        cdf = lambda v: 1 - np.exp(-(np.asarray(v, float) / self.weibull_scale) ** self.weibull_shape)  # noqa: E731
        return cdf(v_high) - cdf(v_low)


def yearly_damage(frequencies, stress, diameter: float, climate: WindClimate, aluminium_layers: int,
                  bins: int = 60) -> tuple[float, float]:
    """Miner's damage per year and cycles per year: the aeolian speed range in `bins` bins; in each, the
    vibration at the worst shedding frequency between St_min·V/D and St_max·V/D (the one with the highest
    damage rate f / N(σ), stress interpolated over the band's frequencies [Hz]) for f cycles per second of
    the bin's share of the year."""
    f_grid, s_grid = np.asarray(frequencies, float), np.asarray(stress, float)
    edges = np.linspace(*climate.speed_range, bins + 1)
    damage = cycles = 0.0
    for v0, v1 in zip(edges[:-1], edges[1:]):
        v = 0.5 * (v0 + v1)
        f_lo, f_hi = climate.strouhal[0] * v / diameter, climate.strouhal[1] * v / diameter
        inside = (f_grid > f_lo) & (f_grid < f_hi)
        f_cand = np.concatenate([[f_lo, f_hi], f_grid[inside]])
        s_cand = np.interp(f_cand, f_grid, s_grid)
        rate = f_cand / cycles_to_failure(s_cand, aluminium_layers)
        k = int(np.argmax(rate))
        n = f_cand[k] * SECONDS_PER_YEAR * climate.aeolian_fraction * float(climate.probability(v0, v1))
        cycles += n
        damage += n / float(cycles_to_failure(s_cand[k], aluminium_layers))
    return damage, cycles
