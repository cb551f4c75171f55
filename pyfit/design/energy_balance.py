"""Energy balance method (EBM): the industry's design check of a Stockbridge damper on a span.

In steady aeolian vibration at frequency f with antinode amplitude Y (zero to peak), the power the wind
puts into the span equals the power the conductor's self-damping and the damper dissipate:

    P_wind(f, Y) = P_self(f, Y) + Σ P_damper,i,   P_damper = ½ Re(Z) ω² a²   at each damper's clamp amplitude a.

- Wind power input, per unit length: f³ D⁴ fnc(Y/D), fnc the CIGRE polynomial or a published laboratory
  curve, lowered by turbulence (`pyfit.design.wind`).
- Self-damping: a published power law P/L = k Y^l f^m / T^n (`pyfit.design.conductor`), or the span's
  viscous modal damping ζ (the same law the ConductorSpan FMU uses): a standing wave of antinode amplitude Y
  stores ¼ m_l ω² Y² per metre, so P_self = ½ ζ m_l ω³ Y² · L.
- Dampers (any number): the damper FMU's clamp impedance Z = F̂_clamp / v̂_clamp (first harmonics over
  whole periods of the steady state under a clamp sine) and mean power F_clamp · v_clamp, tabulated over
  frequency and clamp amplitude (the IEC 61897 characteristic). Each damper's clamp amplitude comes from the
  string solved with the dampers' forces on it (`clamp_amplitudes`; the basic method, reaction=False, lets
  each damper follow the undisturbed wave, a = Y·|sin(2π x_d / λ)|, λ = sqrt(T / m_l) / f, which
  overestimates a strong damper's effect: see scripts/verify_balance.py).

The steady amplitude is the first root of P_wind - P_self - Σ P_damper going up from Y = 0 (vibration builds
up from rest until the first stable balance).
"""
from __future__ import annotations

import math
import pathlib
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from pyfit.design.conductor import PowerLaw, self_damping_power_per_length
from pyfit.design.span import span_properties
from pyfit.design.wind import WindPower
from pyfit.report import plots
from pyfit.runtime.damper_power import DamperPowerTable, damper_power_table

ETA_MAX = 1.2  # Y/D searched up to here (the CIGRE fnc turns negative above Y/D = 1.02)


DRAKE_DIAMETER = 28.14e-3  # m, ACSR Drake 26/7 (ConductorSpan's default conductor)


@dataclass(frozen=True)
class Conductor:
    """A conductor in a span (SI units)."""

    diameter: float  # m
    mass_per_length: float  # kg/m
    tension: float  # N
    span_length: float  # m
    zeta: float  # viscous self-damping ratio of every mode [-]; used when self_damping is None
    self_damping: tuple[PowerLaw, float] | None = None  # (law, k): the power law P/L = k Y^l f^m / T[kN]^n

    def wavelength(self, f):
        """Wavelength [m] of a travelling wave at frequency f [Hz]."""
        return math.sqrt(self.tension / self.mass_per_length) / np.asarray(f, float)


def conductor_of_span(span_fmu, diameter: float = DRAKE_DIAMETER, **overrides) -> Conductor:
    """The Conductor of a ConductorSpan FMU (its start values of L, T, m_l, zeta), fields overridable."""
    p = span_properties(span_fmu)
    return Conductor(diameter, overrides.get("mass_per_length", p["m_l"]), overrides.get("tension", p["T"]),
                     overrides.get("span_length", p["L"]), overrides.get("zeta", p["zeta"]))


def wind_power(f, Y, conductor: Conductor, wind: WindPower = WindPower()):
    """Wind power input [W] into the whole span at frequency f [Hz] and antinode amplitude Y [m]."""
    return wind.power_per_length(f, Y, conductor.diameter) * conductor.span_length


def self_damping_power(f, Y, conductor: Conductor):
    """Power [W] the span's self-damping dissipates at frequency f [Hz], antinode amplitude Y [m]: the
    conductor's power law if it has one, else its viscous modal damping ζ."""
    if conductor.self_damping is not None:
        law, k = conductor.self_damping
        return self_damping_power_per_length(law, k, f, Y, conductor.tension) * conductor.span_length
    w = 2 * np.pi * np.asarray(f, float)
    return 0.5 * conductor.zeta * conductor.mass_per_length * w ** 3 * np.asarray(Y, float) ** 2 \
        * conductor.span_length


def clamp_amplitudes(Y, f: float, conductor: Conductor, dampers, reaction: bool = True, iterations: int = 60):
    """Clamp amplitude [m] of each damper when the span vibrates at f [Hz] with antinode amplitude Y [m]
    (array) away from the dampers. `dampers`: (impedance, x_d) pairs, impedance(a) [N·s/m] at clamp
    amplitude a (vectorised), x_d [m] from the suspension clamp (a fixed point of the string).

    Without the dampers' reaction (the basic method) a damper follows the undisturbed standing wave,
    a = Y·|sin(kx_d)|. With it, the string between the clamp and the dampers is solved exactly: y = 0 at the
    clamp, y'(x) jumps by iωZ·y/T at each damper (its force on the string), and beyond the last damper the wave
    y cos θ + (y'/k) sin θ has the envelope maximum Y; amplitude-dependent impedances are iterated to a fixed
    point."""
    Y = np.asarray(Y, float)
    k = 2 * math.pi / float(conductor.wavelength(f))
    z_c = math.sqrt(conductor.tension * conductor.mass_per_length)  # characteristic impedance of the string
    order = sorted(range(len(dampers)), key=lambda j: dampers[j][1])
    amps = [Y * abs(math.sin(k * x)) for _, x in dampers]
    if not reaction or not dampers:
        return amps
    for _ in range(iterations):
        y, slope = np.zeros_like(Y, complex), np.ones_like(Y, complex)  # y and y'/k from the clamp
        at, x_prev = [None] * len(dampers), 0.0
        for j in order:
            impedance, x = dampers[j]
            c, s = math.cos(k * (x - x_prev)), math.sin(k * (x - x_prev))
            y, slope = y * c + slope * s, -y * s + slope * c
            at[j] = y
            slope = slope + 1j * impedance(amps[j]) / z_c * y
            x_prev = x
        # largest envelope of y cos θ + slope sin θ: the largest singular value of [[Re y, Re s], [Im y, Im s]]
        fro = np.abs(y) ** 2 + np.abs(slope) ** 2
        det = y.real * slope.imag - slope.real * y.imag
        envelope = np.sqrt(0.5 * (fro + np.sqrt(np.maximum(fro ** 2 - 4 * det ** 2, 0.0))))
        new = [np.abs(at[j]) * Y / envelope for j in range(len(dampers))]
        change = max((np.nanmax(np.abs(n - a) / np.maximum(a, 1e-300)) if np.any(np.isfinite(n)) else 0.0)
                     for n, a in zip(new, amps))
        amps = new
        if change < 1e-10:
            break
    return amps


def steady_amplitude(f: float, conductor: Conductor, dampers=(), wind: WindPower = WindPower(),
                     reaction: bool = True, n_grid: int = 400) -> float:
    """Steady antinode amplitude Y [m] at frequency f [Hz]: the first root, going up from 0, of
    P_wind - P_self - Σ P_damper, P_damper = ½ Re Z ω² a² at each damper's clamp amplitude a
    (`clamp_amplitudes`; `dampers`: (impedance, x_d) pairs; a NaN impedance, outside the damper's table,
    makes the result NaN if the root lies there; so does a wind curve not measured up to the root)."""
    D = conductor.diameter
    w = 2 * math.pi * f

    def net(Y):
        out = wind_power(f, Y, conductor, wind) - self_damping_power(f, Y, conductor)
        for (impedance, _), a in zip(dampers, clamp_amplitudes(Y, f, conductor, dampers, reaction)):
            out = out - 0.5 * np.real(impedance(a)) * w ** 2 * a ** 2
        return out

    ys = np.concatenate([[0.0], D * np.geomspace(1e-5, ETA_MAX, n_grid)])
    vals = net(np.concatenate([[ys[1] * 1e-3], ys[1:]]))
    bad = np.flatnonzero(np.isnan(vals))
    cross = np.flatnonzero((vals[:-1] > 0) & (vals[1:] <= 0)) + 1
    if cross.size == 0 or (bad.size and bad[0] <= cross[0]):
        return math.nan
    k = cross[0]
    return brentq(lambda y: float(net(np.array([y]))[0]), ys[k - 1], ys[k], xtol=1e-12 * D, rtol=1e-10)

@dataclass
class BalanceRow:
    """Steady amplitudes at one frequency: without damper and with it at each position (m, Hz, m/s)."""

    frequency_hz: float
    wind_speed: float  # m/s, from the Strouhal number 0.185
    y_without: float
    y_with: dict  # x_d [m] -> Y [m]


STROUHAL = 0.185


def energy_balance(conductor: Conductor, table: DamperPowerTable, positions, wind: WindPower = WindPower()
                   ) -> list[BalanceRow]:
    """Steady amplitudes with and without the damper at every frequency of the damper power table."""
    rows = []
    for i, f in enumerate(table.frequencies):
        y0 = steady_amplitude(f, conductor, (), wind)
        with_damper = {x: steady_amplitude(f, conductor, [(lambda a, i=i: table.impedance_at(i, a), x)], wind)
                       for x in positions}
        rows.append(BalanceRow(float(f), float(f) * conductor.diameter / STROUHAL, y0, with_damper))
    return rows


def write_report(rows: list[BalanceRow], conductor: Conductor, table: DamperPowerTable, out_dir,
                 name: str = "energy_balance", wind: WindPower = WindPower()) -> pathlib.Path:
    """NAME.md (table), NAME.csv and NAME.png into out_dir (`wind`: the wind power the rows were solved
    with, named in both); returns the md path."""

    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    positions = list(rows[0].y_with)
    D = conductor.diameter
    header = ["frequency_hz", "wind_speed_m_s", "Y_without_m"] + [f"Y_with_x{x:g}_m" for x in positions]
    data = [[r.frequency_hz, r.wind_speed, r.y_without] + [r.y_with[x] for x in positions] for r in rows]
    np.savetxt(out / f"{name}.csv", np.array(data, float), delimiter=",", header=",".join(header),
               comments="", fmt="%.6g")
    c = conductor
    lines = [f"Conductor: D = {c.diameter * 1e3:.2f} mm, m = {c.mass_per_length} kg/m, T = {c.tension / 1e3:g} kN, "
             f"span {c.span_length:g} m, self-damping ζ = {c.zeta:g}, wind: {wind.label}. Steady antinode amplitude Y (zero to peak) "
             "in mm, Y/D in brackets; '—' = the balance lies beyond the damper power table.", "",
             "| f [Hz] | wind [m/s] | no damper | " + " | ".join(f"damper at {x:g} m" for x in positions) + " |",
             "|---|---|---|" + "---|" * len(positions)]

    def cell(y):
        return "—" if not np.isfinite(y) else f"{y * 1e3:.3g} ({y / D:.3f})"

    for r in rows:
        lines.append(f"| {r.frequency_hz:g} | {r.wind_speed:.2f} | {cell(r.y_without)} | "
                     + " | ".join(cell(r.y_with[x]) for x in positions) + " |")
    worst = np.nanmax(table.drift) if np.any(np.isfinite(table.drift)) else math.nan
    lines += ["", f"Damper power table: {len(table.frequencies)} frequencies × {len(table.amplitudes)} clamp "
              f"amplitudes ({table.amplitudes[0] * 1e3:.3g}–{table.amplitudes[-1] * 1e3:.3g} mm), "
              f"{int(np.sum(~np.isfinite(table.power)))} failed runs; largest drift between the two halves "
              f"of an averaging window {worst:.1e}."]
    md = out / f"{name}.md"
    md.write_text("\n".join(lines) + "\n")
    f = [r.frequency_hz for r in rows]
    plots.semilogy_curves(out / f"{name}.png", [("no damper", f, [r.y_without * 1e3 for r in rows], "k-")] + [
        (f"damper at {x:g} m", f, [r.y_with[x] * 1e3 for r in rows], "o-") for x in positions],
        "frequency [Hz]", "steady antinode amplitude Y [mm]",
        f"Energy balance, {c.span_length:g} m span, ζ = {c.zeta:g}: wind input = self-damping + damper")
    return md


def energy_balance_study(damper_fmu, span, cases, positions, freqs, amps, params: dict | None = None,
                         diameter: float = DRAKE_DIAMETER, wind: WindPower = WindPower(), workers: int | None = None,
                         out_dir="docs/figures/energy_balance") -> list[pathlib.Path]:
    """The damper power table over `freqs` [Hz] x clamp amplitudes `amps` [m] (saved as damper_power.csv), then
    one energy-balance report per span case (span length [m], self-damping ratio ζ) for the damper at each of
    `positions` [m]; returns the reports' paths."""
    table = damper_power_table(damper_fmu, freqs, amps, params, workers=workers)
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    table.save(out / "damper_power.csv")
    reports = []
    for length, zeta in cases:
        conductor = conductor_of_span(span, diameter, span_length=length, zeta=zeta)
        rows = energy_balance(conductor, table, positions, wind)
        reports.append(write_report(rows, conductor, table, out, name=f"span_{length:g}m_zeta_{zeta:g}", wind=wind))
    return reports
