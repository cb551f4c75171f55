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
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq

from pyfit.design.conductor import PowerLaw, self_damping_power_per_length
from pyfit.design.span import span_properties
from pyfit.design.wind import WindPower
from pyfit.io.impedance import write_impedance
from pyfit.report import plots
from pyfit.runtime.batch import RunSpec, run_batch

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


@dataclass
class DamperPowerTable:
    """The damper at frequencies[i] [Hz] and clamp amplitudes[j] [m] (or amplitudes[i, j]: a measured
    table's own amplitudes at each frequency): mean power [W] and clamp impedance [N·s/m], NaN where the
    simulation failed; drift[i, j]: relative change of the power between the two halves of the averaging
    window (how steady the state was)."""

    frequencies: np.ndarray
    amplitudes: np.ndarray
    power: np.ndarray
    drift: np.ndarray = field(default=None)
    impedance: np.ndarray = field(default=None)  # complex Z = F̂_clamp / v̂_clamp [N·s/m], first harmonics

    @classmethod
    def from_test(cls, test) -> "DamperPowerTable":
        """The table of a measured impedance test (`pyfit.io.impedance.ImpedanceTest`): power ½ Re Z ω² a²."""
        power = 0.5 * test.impedance.real * (2 * np.pi * test.frequencies[:, None]) ** 2 * test.amplitudes ** 2
        return cls(test.frequencies, test.amplitudes, power, np.zeros(power.shape), test.impedance)

    def amplitudes_at(self, i: int) -> np.ndarray:
        """Clamp amplitudes [m] of the table's row at frequencies[i]."""
        return self.amplitudes if self.amplitudes.ndim == 1 else self.amplitudes[i]

    def impedance_at(self, i: int, a):
        """Impedance [N·s/m] at frequencies[i] and clamp amplitude(s) a [m]: real and imaginary parts linear in
        log a; the smallest amplitude's below the table (the linear range); NaN above it or next to a failed
        run."""
        a = np.asarray(a, float)
        amps, z = self.amplitudes_at(i), self.impedance[i]
        j = np.clip(np.searchsorted(amps, a), 1, len(amps) - 1)
        s = np.log(np.maximum(a, amps[0]) / amps[j - 1]) / np.log(amps[j] / amps[j - 1])
        out = np.where(a <= amps[0], z[0], (1 - s) * z[j - 1] + s * z[j])
        return np.where(a > amps[-1], np.nan + 0j, out)

    def save(self, path) -> None:
        """CSV: one row per frequency [Hz], one column per clamp amplitude [m], mean power [W]; and, beside it,
        <stem>_impedance.csv + .toml, the IEC 61897 impedance test file that `pyfit.io.impedance` reads."""
        path = pathlib.Path(path)
        if self.amplitudes.ndim == 1:
            header = "frequency_hz," + ",".join(f"P_at_{a:.4g}_m" for a in self.amplitudes)
            np.savetxt(path, np.column_stack([self.frequencies, self.power]), delimiter=",", header=header,
                       comments="", fmt="%.6g")
        if self.impedance is not None:
            amps = np.array([self.amplitudes_at(i) for i in range(len(self.frequencies))])
            write_impedance(path.with_name(path.stem + "_impedance.csv"), self.frequencies, amps, self.impedance,
                            "damper FMU: clamp sine, first harmonics over whole periods of the steady state")


def damper_power_table(fmu, frequencies, amplitudes, params: dict | None = None, settle: float = 6.0,
                       average: float = 2.0, ramp: float = 1.5, workers: int | None = None,
                       progress: bool = True) -> DamperPowerTable:
    """Simulate the damper FMU (DamperElement) under its built-in clamp sine at every frequency [Hz] and
    clamp amplitude [m] (one list for all frequencies, or one row per frequency): smooth ramp-in over the
    first `ramp` s, steady state after `settle` s (the default damper's slowest mode, 10 Hz at ζ ≈ 2.2 %,
    decays to 2e-4 in 6 s), then the mean of F_clamp · v_clamp and the first harmonics of F_clamp and
    v_clamp over the whole periods of the next `average` s."""
    freqs, amps = np.asarray(frequencies, float), np.asarray(amplitudes, float)
    rows = amps if amps.ndim == 2 else np.repeat(amps[None, :], len(freqs), axis=0)  # amplitudes per frequency
    specs, windows = [], []
    for f, row in zip(freqs, rows):
        n_avg = max(2, int(round(average * f)))  # whole periods averaged
        periods = int(math.ceil(settle * f)) + n_avg
        per = 40  # samples per period: the mean over whole periods is exact for harmonics below 20
        windows.append((n_avg * per, per))
        for a in row:
            specs.append(RunSpec(str(fmu), periods / f, 1.0 / (per * f), ("F_clamp", "v_clamp"),
                                 {**(params or {}), "exc_type": 1, "exc_amplitude": float(a),
                                  "exc_f_start": float(f), "exc_t_ramp": ramp},
                                 label=f"{f:g} Hz {a:.3g} m"))
    results = run_batch(specs, workers=workers, progress=progress, desc="damper power")
    power = np.full(rows.shape, np.nan)
    drift = np.full_like(power, np.nan)
    impedance = np.full(power.shape, np.nan + 0j)
    for k, r in enumerate(results):
        i, j = divmod(k, rows.shape[1])
        if not r.ok:
            continue
        n, per = windows[i]
        force, velocity = r["F_clamp"][-n - 1:-1], r["v_clamp"][-n - 1:-1]
        p = force * velocity
        if not np.all(np.isfinite(p)):
            continue
        half = len(p) // 2
        power[i, j] = float(np.mean(p))
        drift[i, j] = float(abs(np.mean(p[:half]) - np.mean(p[half:])) / max(abs(power[i, j]), 1e-300))
        rotor = np.exp(-2j * np.pi * np.arange(n) / per)  # first harmonic over whole periods
        impedance[i, j] = np.sum(force * rotor) / np.sum(velocity * rotor)
    return DamperPowerTable(freqs, amps, power, drift, impedance)


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
