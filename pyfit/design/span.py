"""A conductor span with a Stockbridge damper at its clamp, by co-simulation of two FMUs.

The span FMU (`ConductorSpan`: taut-string modes, self-damping zeta, the clamp's mass at x_d) and the damper
FMU (`DamperElement`, clamp mass 0 because the span carries it) exchange clamp motion and clamp force.
For each mode, a free decay from a given antinode amplitude gives the energy the span loses, the part its
self-damping takes and the part the damper takes (the integral of F_clamp * v_clamp); the damping ratio
with the damper is zeta * (W_self + W_damper) / W_self over the first cycles, and the resonant amplitude
under a modal (wind-like) force scales as 1 / damping, so the reduction is zeta_with / zeta_self.
"""
from __future__ import annotations

import pathlib
from dataclasses import dataclass

import numpy as np

from pyfit.report import plots
from pyfit.runtime.cosim import Connection, cosimulate
from pyfit.runtime.fmu import FmuRunner

CONNECTIONS = [Connection("span.y_d", "damper.x_base", "span.v_d"),
               Connection("span.v_d", "damper.v_base", "span.a_d"),
               Connection("span.a_d", "damper.a_base"),
               Connection("damper.F_clamp", "span.F_clamp")]


@dataclass
class ModeDecay:
    """One mode's free decay with the damper (energies in J, frequency in Hz)."""

    mode: int
    frequency_hz: float
    x_d: float
    energy_start: float
    energy_loss: float
    self_damping: float
    damper: float
    zeta_self: float
    zeta_with_damper: float

    @property
    def amplitude_ratio(self) -> float:
        """Resonant amplitude with the damper / without it, under the same modal force."""
        return self.zeta_self / self.zeta_with_damper

    @property
    def balance_error(self) -> float:
        """(energy loss - self-damping - damper) / damper: energy conservation of the coupled run."""
        return (self.energy_loss - self.self_damping - self.damper) / self.damper


def span_properties(span_fmu: FmuRunner, overrides: dict | None = None) -> dict:
    """Length L [m], tension T [N], mass per length m_l [kg/m], self-damping zeta of a ConductorSpan FMU:
    its start values unless overridden."""
    return {k: float((overrides or {}).get(k, span_fmu.variables[k].start)) for k in ("L", "T", "m_l", "zeta")}


def mode_decay(span_fmu, damper_fmu, mode: int, x_d: float, amplitude: float = 5e-3, periods: float = 10.0,
               step: float = 1e-4, span_params: dict | None = None, damper_params: dict | None = None) -> ModeDecay:
    """Free decay of `mode` (antinode amplitude [m]) over `periods` of its frequency, damper at x_d [m]."""
    sp = {"exc_type": 0, "x_d": x_d, f"q[{mode}]": amplitude, **(span_params or {})}
    dp = {"m_c": 0.0, **(damper_params or {})}
    span_fmu = span_fmu if isinstance(span_fmu, FmuRunner) else FmuRunner(str(span_fmu))
    L, T, m_l, zeta = (span_properties(span_fmu, sp)[k] for k in ("L", "T", "m_l", "zeta"))
    f = mode * np.sqrt(T / m_l) / (2 * L)
    stop = step * max(1, int(round(periods / f / step)))
    r = cosimulate({"span": span_fmu, "damper": damper_fmu}, CONNECTIONS, stop, step,
                   ["span.E", "span.W_self", "span.v_d", "damper.F_clamp"], {"span": sp, "damper": dp})
    power = r["damper.F_clamp"] * r["span.v_d"]  # into the damper, W
    w_damper = float(np.sum(0.5 * (power[1:] + power[:-1])) * step)  # trapezoidal rule
    loss = float(r["span.E"][0] - r["span.E"][-1])
    w_self = float(r["span.W_self"][-1])
    return ModeDecay(mode, f, x_d, float(r["span.E"][0]), loss, w_self, w_damper, zeta,
                     zeta * (w_self + w_damper) / w_self)


def reduction_table(span_fmu, damper_fmu, modes, positions, **kw) -> list[ModeDecay]:
    """mode_decay for every mode and damper position."""
    return [mode_decay(span_fmu, damper_fmu, n, x, **kw) for x in positions for n in modes]


def write_report(rows: list[ModeDecay], out_dir) -> pathlib.Path:
    """reduction.md (table per mode and position), reduction.csv and reduction.png into out_dir; the .md path."""

    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    header = ["mode", "frequency_hz", "x_d_m", "zeta_self", "zeta_with_damper", "amplitude_ratio",
              "energy_start_J", "self_damping_J", "damper_J", "balance_error"]
    data = [[r.mode, r.frequency_hz, r.x_d, r.zeta_self, r.zeta_with_damper, r.amplitude_ratio, r.energy_start,
             r.self_damping, r.damper, r.balance_error] for r in rows]
    np.savetxt(out / "reduction.csv", np.array(data, float), delimiter=",", header=",".join(header), comments="",
               fmt="%.6g")
    positions = sorted({r.x_d for r in rows})
    modes = sorted({r.mode for r in rows})
    by = {(r.mode, r.x_d): r for r in rows}
    lines = ["| mode | f [Hz] | " + " | ".join(f"x_d = {x:g} m" for x in positions) + " |",
             "|---|---|" + "---|" * len(positions)]
    for n in modes:
        lines.append(f"| {n} | {by[n, positions[0]].frequency_hz:.2f} | "
                     + " | ".join(f"{by[n, x].amplitude_ratio:.3f}" for x in positions) + " |")
    (out / "reduction.md").write_text("Resonant amplitude with the damper / without it (same modal force):\n\n"
                                      + "\n".join(lines) + "\n")
    plots.semilogy_curves(out / "reduction.png", [
        (f"damper at {x:g} m", [by[n, x].frequency_hz for n in modes], [by[n, x].amplitude_ratio for n in modes],
         "o-") for x in positions], "mode frequency [Hz]", "resonant amplitude ratio [-]",
        "Span with a Stockbridge damper: amplitude with / without damper", ylim=(0, 1.05), log=False)
    return out / "reduction.md"


def write_span_ssp(path, span_fmu, damper_fmu, x_d: float) -> pathlib.Path:
    """The span with the damper at x_d [m] as an SSP 1.0 archive for other FMI tools (span excited on its
    built-in mode, damper clamp mass left to the span); returns the archive's path."""
    from pyfit.runtime.ssp import write_ssp

    write_ssp(path, "SpanWithDamper", {"span": span_fmu.path, "damper": damper_fmu.path}, CONNECTIONS,
              {"span": {"exc_type": 1, "x_d": x_d}, "damper": {"m_c": 0.0}}, stop_time=10.0)
    return pathlib.Path(path)
