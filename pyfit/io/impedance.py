"""Damper characteristic test data as the industry has it (IEC 61897 / IEEE 664): the clamp impedance,
magnitude and phase, versus frequency at one or more clamp velocity (or displacement) amplitudes. A CSV (read
like any lab export: comment lines, extra columns, ',' or tab) and a TOML sidecar of the same stem:

    kind = "damper_impedance"
    [columns]
    frequency = { name = "f", unit = "Hz" }
    velocity = { name = "v0", unit = "mm/s" }        # clamp velocity amplitude; or displacement = {name, unit}
    impedance = { name = "Z", unit = "N.s/m" }       # |F̂| / |v̂|, first harmonics
    phase = { name = "phi", unit = "deg" }            # of the force relative to the velocity
    notes = "..."
    uncertainty = 0.01    # optional: the test's relative error, RMS of |Z_meas / Z_true - 1| (for diagnose.py)

A unit may be any unit of its column's quantity (`pyfit.io.units`: SI prefixes, in, ft, lbf, and the forms
people write, 'N·s/m', 'Ns/m'); the phase in deg or rad. Every frequency must have been tested at the same
number of levels. The result, an `ImpedanceTest` (each
frequency with its own clamp amplitudes a = v / 2πf), becomes the damper table of the energy balance and the
span design check in place of the damper FMU's (`DamperPowerTable.from_test`); `DamperPowerTable.save`
writes the FMU's table in the same columns (`*_impedance.csv`).
"""
from __future__ import annotations

import json
import pathlib
from dataclasses import dataclass

import numpy as np

from pyfit.io.data import MeasurementError, read_csv_columns
from pyfit.io.schema import check_table, fail, read_toml
from pyfit.io.units import parse_unit

# each column's quantity: a unit of its dimension (pyfit.io.units: any SI prefix, in, ft, lbf, the written forms
# 'N·s/m', 'N s/m', 'N*s/m'), named in an error by the examples given here; a phase in deg or rad (an angle, which
# the dimension alone does not tell from a plain number)
QUANTITIES = {"frequency": "Hz", "velocity": "m/s", "displacement": "m", "impedance": "N.s/m"}
EXAMPLES = {"frequency": "Hz, kHz, 1/min", "velocity": "m/s, mm/s, in/s", "displacement": "m, mm, in",
            "impedance": "N.s/m, N·s/m, Ns/m, kg/s, lbf.s/in"}
ANGLES = {"deg": np.pi / 180, "rad": 1.0}
COLUMNS = (*QUANTITIES, "phase")
COLUMN = {"name": (str, True, None), "unit": (str, True, None)}


def _factor(key: str, unit: str) -> float | None:
    """The factor taking a value of column `key` in `unit` to SI; None when the unit is not one of its quantity."""
    if key == "phase":
        return ANGLES.get(unit.strip())
    try:
        u = parse_unit(unit)
    except ValueError:
        return None
    return u.factor if u.dimension == parse_unit(QUANTITIES[key]).dimension else None


@dataclass(frozen=True)
class ImpedanceTest:
    """A damper's measured clamp impedance: impedance[i, j] in N·s/m (complex, force over velocity) at
    frequencies[i] in Hz and clamp displacement amplitude amplitudes[i, j] in m."""

    path: pathlib.Path
    frequencies: np.ndarray
    amplitudes: np.ndarray
    impedance: np.ndarray
    uncertainty: float | None = None  # stated relative measurement error (RMS of |Z_meas / Z_true − 1|)


def read_impedance(csv_path) -> ImpedanceTest:
    """An impedance test file in SI units; errors name the file and the key or row."""
    csv_path = pathlib.Path(csv_path)
    side = csv_path.with_suffix(".toml")
    doc = read_toml(side, MeasurementError)
    top = check_table(doc, side, "", {"kind": (str, True, None), "columns": (dict, True, None),
                                      "notes": (str, False, ""), "uncertainty": ("number", False, None)},
                      MeasurementError)
    if top["uncertainty"] is not None and not 0 < top["uncertainty"] < 1:
        fail(side, "uncertainty", f"{top['uncertainty']!r}", "the relative error, 0 < uncertainty < 1",
             MeasurementError)
    if top["kind"] != "damper_impedance":
        fail(side, "kind", f"{top['kind']!r} is not an impedance test", "damper_impedance", MeasurementError)
    spec = {k: (dict, k in ("frequency", "impedance", "phase"), None) for k in COLUMNS}
    cols = check_table(top["columns"], side, "columns", spec, MeasurementError)
    if (cols["velocity"] is None) == (cols["displacement"] is None):
        fail(side, "columns", "give exactly one of velocity and displacement (the clamp's amplitude)",
             error=MeasurementError)
    used = {}
    for key, entry in cols.items():
        if entry is None:
            continue
        c = check_table(entry, side, f"columns.{key}", COLUMN, MeasurementError)
        factor = _factor(key, c["unit"])
        if factor is None:
            fail(side, f"columns.{key}.unit", f"unit {c['unit']!r}", ", ".join(ANGLES) if key == "phase" else
                 f"a unit of {parse_unit(QUANTITIES[key]).describe()}, e.g. {EXAMPLES[key]}", MeasurementError)
        used[key] = (c["name"], factor)
    values = read_csv_columns(csv_path, [name for name, _ in used.values()])
    si = {key: values[name] * scale for key, (name, scale) in used.items()}
    f = si["frequency"]
    if np.any(f <= 0):
        raise MeasurementError(f"{csv_path}: row {int(np.argmax(f <= 0)) + 1} of the data: frequency "
                               f"{f[f <= 0][0]} Hz; allowed: > 0")
    amplitude = si["displacement"] if "displacement" in si else si["velocity"] / (2 * np.pi * f)
    z = si["impedance"] * np.exp(1j * si["phase"])
    freqs = np.unique(f)
    counts = {float(x): int(np.sum(f == x)) for x in freqs}
    if len(set(counts.values())) != 1:
        fail(csv_path, "frequency", f"levels per frequency differ ({counts})",
             "every frequency tested at the same number of levels", MeasurementError)
    order = np.lexsort((amplitude, f))
    shape = (len(freqs), len(f) // len(freqs))
    return ImpedanceTest(csv_path, freqs, amplitude[order].reshape(shape), z[order].reshape(shape),
                         top["uncertainty"])


def write_impedance(csv_path, frequencies, amplitudes, impedance, notes: str = "",
                    uncertainty: float | None = None) -> pathlib.Path:
    """An impedance test file (CSV + sidecar) in the format read_impedance reads: one row per frequency [Hz]
    and clamp amplitude amplitudes[i, j] in m, with the clamp velocity amplitude [m/s], |Z| [N·s/m], the phase
    of Z [deg] and the mean power ½ Re Z ω² a² [W]; `uncertainty`: the stated relative error, if known."""
    csv_path = pathlib.Path(csv_path)
    f = np.repeat(np.asarray(frequencies, float)[:, None], np.shape(amplitudes)[1], axis=1)
    a, z = np.asarray(amplitudes, float), np.asarray(impedance, complex)
    w = 2 * np.pi * f
    np.savetxt(csv_path, np.column_stack([f.ravel(), a.ravel(), (w * a).ravel(), np.abs(z).ravel(),
                                          np.degrees(np.angle(z)).ravel(), (0.5 * z.real * w ** 2 * a ** 2).ravel()]),
               delimiter=",", header="frequency_hz,clamp_amplitude_m,velocity_amplitude_m_s,impedance_abs_n_s_m,"
                                     "impedance_phase_deg,power_w", comments="", fmt="%.9g")
    csv_path.with_suffix(".toml").write_text(
        'kind = "damper_impedance"\n'
        f"notes = {json.dumps(notes)}\n" + (f"uncertainty = {uncertainty!r}\n" if uncertainty else "") + "[columns]\n"
        'frequency = { name = "frequency_hz", unit = "Hz" }\n'
        'displacement = { name = "clamp_amplitude_m", unit = "m" }\n'
        'impedance = { name = "impedance_abs_n_s_m", unit = "N.s/m" }\n'
        'phase = { name = "impedance_phase_deg", unit = "deg" }\n')
    return csv_path
