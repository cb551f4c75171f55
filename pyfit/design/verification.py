"""The energy balance checked in time: the span driven by the wind on one mode, the damper FMU at its clamp.

The ConductorSpan FMU applies the CIGRE wind power to mode n as an amplitude-dependent negative damping
(the power a standing wave of antinode amplitude A takes from the wind, L·f³·D⁴·fnc(A/D), as c_w·q̇ with
c_w = 2 P / (ω² A²)), and the self-damping law the same way; co-simulated with the DamperElement FMU (which
takes the span's clamp motion and returns its clamp force) from an antinode amplitude near the expected
one until the vibration is steady. The energy balance's steady amplitude at the same frequency, for the
same span, wind, self-damping and damper (its impedance table at that frequency, with the damper's reaction
on the string), should agree up to what each side approximates: the balance takes the span beyond the damper
as one standing wave, the co-simulation keeps the span's first 27 modes (the local bend at the damper is
resolved only that far).
"""
from __future__ import annotations

import pathlib
from dataclasses import dataclass

import numpy as np

from pyfit.design.conductor import PowerLaw
from pyfit.design.energy_balance import Conductor, steady_amplitude
from pyfit.runtime.damper_power import damper_power_table
from pyfit.design.span import CONNECTIONS, span_properties
from pyfit.runtime.cosim import cosimulate
from pyfit.runtime.fmu import FmuRunner


@dataclass
class BalanceCheck:
    """Steady antinode amplitude [m] of mode `mode` (frequency [Hz]) by the energy balance and in time."""

    mode: int
    frequency_hz: float
    x_d: float
    y_energy_balance: float
    y_basic: float  # the basic balance: the damper follows the undisturbed wave (no reaction on the string)
    y_time_domain: float
    settled: float  # relative change of the time-domain amplitude between the last two 2-s windows

    @property
    def relative_difference(self) -> float:
        """(energy balance − time domain) / time domain."""
        return self.y_energy_balance / self.y_time_domain - 1


def check_mode(span_fmu: FmuRunner, damper_fmu, mode: int, x_d: float, span_params: dict | None = None,
               damper_params: dict | None = None, start_fraction: float = 0.8, duration: float = 30.0,
               step: float = 1e-4, amplitudes=np.geomspace(1e-6, 1e-2, 13)) -> BalanceCheck:
    """Energy balance vs co-simulation for the wind on `mode`, damper at x_d [m] from the span end. The run
    starts at start_fraction × the balance's amplitude and lasts `duration` s; the time-domain amplitude is
    the mean envelope sqrt(q² + (q̇/ω)²) over its last 2 s."""
    sp = {"exc_type": 0, "x_d": x_d, "wind_mode": mode, **(span_params or {})}
    props = span_properties(span_fmu, sp)
    diameter = float(sp.get("wind_D", span_fmu.variables["wind_D"].start))
    sd_k = float(sp.get("sd_k", span_fmu.variables["sd_k"].start))
    law = None
    if sd_k > 0:
        exponents = (float(sp.get(k, span_fmu.variables[k].start)) for k in ("sd_l", "sd_m", "sd_n"))
        law = (PowerLaw("span FMU", *exponents), sd_k)
    span = Conductor(diameter, props["m_l"], props["T"], props["L"], props["zeta"], law)
    f = mode * np.sqrt(props["T"] / props["m_l"]) / (2 * props["L"])
    damper_path = damper_fmu.path if isinstance(damper_fmu, FmuRunner) else damper_fmu
    table = damper_power_table(damper_path, [f], amplitudes, damper_params, progress=False, workers=1)
    damper = [(lambda a: table.impedance_at(0, a), x_d)]
    y_ebm, y_basic = (steady_amplitude(f, span, damper, reaction=reaction) for reaction in (True, False))
    sp[f"q[{mode}]"] = start_fraction * y_ebm
    r = cosimulate({"span": span_fmu, "damper": damper_fmu}, CONNECTIONS, duration, step,
                   [f"span.q[{mode}]", f"span.qd[{mode}]"], {"span": sp, "damper": {"m_c": 0.0, **(damper_params or {})}})
    envelope = np.hypot(r[f"span.q[{mode}]"], r[f"span.qd[{mode}]"] / (2 * np.pi * f))
    n_last = int(round(2.0 / step))
    y_time = float(np.mean(envelope[-n_last:]))
    settled = abs(float(np.mean(envelope[-2 * n_last:-n_last])) / y_time - 1)
    return BalanceCheck(mode, float(f), x_d, y_ebm, y_basic, y_time, settled)


def write_table(rows: list[BalanceCheck], out_dir) -> pathlib.Path:
    """verify_balance.md into out_dir: one row per check."""
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    lines = ["| mode | f [Hz] | co-simulation [mm] | energy balance [mm] | vs co-simulation | basic balance, no "
             "reaction [mm] | vs co-simulation | settled (last 2 s vs 2 s before) |", "|---|---|---|---|---|---|---|---|"]
    for c in rows:
        basic = c.y_basic
        lines.append(f"| {c.mode} | {c.frequency_hz:.2f} | {c.y_time_domain * 1e3:.4f} | {c.y_energy_balance * 1e3:.4f} "
                     f"| {c.relative_difference:+.1%} | {basic * 1e3:.4f} | {basic / c.y_time_domain - 1:+.1%} | "
                     f"{c.settled:.1e} |")
    md = out / "verify_balance.md"
    md.write_text("\n".join(lines) + "\n")
    return md
