"""Wind power input of aeolian vibration: P/L = f³ D⁴ fnc(Y/D) per unit length of conductor [W/m] (f [Hz],
D [m], Y the antinode amplitude, zero to peak [m]); fnc, the reduced power [W/(m·Hz³·m⁴)], from

- "cigre": the polynomial fnc(η) = -99.73 η³ + 101.62 η² + 0.1627 η + 0.2256 (Foti F., Martinelli L. (2018),
  "An enhanced unified model for the self-damping of stranded cables under aeolian vibrations", J. Wind
  Eng. Ind. Aerodyn. 182, 72-86, eq. (4); the form CIGRE design practice uses), or
- a published laboratory curve, given by its tabulated points (η, fnc) as compiled in the EPRI Transmission
  Line Reference Book: Wind-Induced Conductor Motion (the "Orange Book") and tabulated by RTE's pallas-dohl;
  between points the curve is a power law (linear in log-log), below the first point it continues with the
  first segment's exponent (towards zero), and above the last measured amplitude it is undefined (NaN: an
  energy balance that needs it there is unresolved, never extrapolated).

Turbulence lowers every curve by 1 / sqrt(1 + (I_v / 0.09)²) (Foti & Martinelli 2018, eq. (5); I_v = 0 is
smooth flow, the conservative case and the laboratories' condition).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

CIGRE_FNC = (-99.73, 101.62, 0.1627, 0.2256)  # W/(m·Hz³·m⁴), polynomial in Y/D, highest power first


@dataclass(frozen=True)
class PublishedCurve:
    """A laboratory reduced-power curve: its source and tabulated points (Y/D [-], fnc [W/(m·Hz³·m⁴)])."""

    label: str
    eta: tuple[float, ...]
    fnc: tuple[float, ...]


PUBLISHED_CURVES = {
    "farquharson1956": PublishedCurve("Farquharson & McHugh (1956)", (0.01, 0.03, 0.06, 0.10), (0.02, 0.11, 0.40, 0.84)),
    "carroll1936": PublishedCurve("Carroll (1936)", (0.03, 0.06, 0.10), (0.11, 0.40, 0.85)),
    "rawlins1958": PublishedCurve("Rawlins (1958)", (0.03, 0.06, 0.10, 0.20), (0.18, 0.50, 1.20, 3.20)),
    "bate1930": PublishedCurve("Bate (1930)", (0.06, 0.10, 0.20), (0.65, 1.60, 3.90)),
    "diana1971": PublishedCurve("Diana & Falco (1971)", (0.03, 0.06, 0.10, 0.20, 0.30, 0.40, 0.50, 0.60, 0.70, 0.80),
                                (0.23, 0.70, 1.80, 5.00, 9.00, 14.00, 18.00, 20.00, 21.00, 20.00)),
    "brika1995": PublishedCurve("Brika & Laneville (1995)", (0.01, 0.03, 0.06, 0.10, 0.20, 0.30, 0.40),
                                (0.03, 0.17, 0.49, 1.10, 3.20, 5.50, 6.00)),
    "rawlins1983": PublishedCurve("Rawlins (1983)", (0.03, 0.06, 0.10, 0.20, 0.30, 0.40, 0.50, 0.60, 0.70),
                                  (0.18, 0.60, 1.60, 4.00, 6.50, 9.00, 10.10, 10.70, 10.80)),
    "pon1989": PublishedCurve("Pon et al. (1989)", (0.01, 0.03, 0.06, 0.10, 0.20, 0.30),
                              (0.04, 0.20, 0.60, 1.50, 3.00, 4.50)),
}
CURVES = ("cigre", *PUBLISHED_CURVES)


@dataclass(frozen=True)
class WindPower:
    """The wind power model of an energy balance: a curve of CURVES and the turbulence intensity I_v [-]."""

    curve: str = "cigre"
    turbulence: float = 0.0

    def __post_init__(self):
        if self.curve not in CURVES:
            raise ValueError(f"wind power curve {self.curve!r} unknown; allowed: {', '.join(CURVES)}")

    @property
    def label(self) -> str:
        name = "CIGRE polynomial" if self.curve == "cigre" else PUBLISHED_CURVES[self.curve].label
        return f"{name}, turbulence {self.turbulence:g}"

    @property
    def eta_max(self) -> float:
        """The largest Y/D [-] where the curve is defined (the CIGRE polynomial: its zero at 1.02)."""
        return 1.02 if self.curve == "cigre" else PUBLISHED_CURVES[self.curve].eta[-1]

    def reduced(self, eta):
        """fnc(Y/D) [W/(m·Hz³·m⁴)]; NaN above the last measured amplitude of a published curve."""
        eta = np.asarray(eta, float)
        if self.curve == "cigre":
            fnc = np.polyval(CIGRE_FNC, eta)
        else:
            c = PUBLISHED_CURVES[self.curve]
            x, y = np.log(c.eta), np.log(c.fnc)
            slope = (y[1] - y[0]) / (x[1] - x[0])
            with np.errstate(divide="ignore"):
                le = np.log(eta)
            fnc = np.where(eta < c.eta[0], np.exp(y[0] + slope * (le - x[0])), np.exp(np.interp(le, x, y)))
            fnc = np.where(eta > c.eta[-1] * (1 + 1e-12), np.nan, fnc)
        return fnc / math.sqrt(1.0 + (self.turbulence / 0.09) ** 2)

    def power_per_length(self, f, Y, diameter: float):
        """Wind power input [W/m] at frequency f [Hz], antinode amplitude Y [m], conductor diameter [m]."""
        return np.asarray(f, float) ** 3 * diameter ** 4 * self.reduced(np.asarray(Y, float) / diameter)
