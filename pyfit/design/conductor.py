"""Overhead conductors for the span design check: stranding, bending-stiffness bounds, self-damping laws.

All quantities in SI units (m, kg/m, N, Pa, N·m²) unless a law's own units are stated.

Bending stiffness of a stranded conductor lies between two bounds (Papailiou 1997; CIGRE TB 273, 2005):
- EI_min: every wire bends about its own axis (wires slip freely): Σ E_i π d_i⁴ / 64;
- EI_max: the cross-section bends as one solid (no slip): Σ E_i (π d_i⁴/64 + A_i r_i² / 2) summed over the
  wires of each layer at lay radius r_i (a ring of n wires contributes n A r² / 2 about any diameter).

Self-damping (the power the conductor itself dissipates per metre in a standing wave) follows the empirical
power law P/L = k · Y^l · f^m / T^n [W/m] with the antinode amplitude Y [m] (zero to peak), the frequency f
[Hz] and the tension T [kN]. The exponents (l, m, n) of each laboratory are as tabulated in CIGRE SC22 WG11
TF1, "Modelling of aeolian vibration of single conductors: assessment of the technology", Electra 181 (1998)
and EPRI, "Transmission Line Reference Book: Wind-Induced Conductor Motion" (the Orange Book), 2nd ed. 2006,
ch. 3. k is the conductor's own constant, best measured (IEEE Std 563 span test); without a measurement the
estimate k = D[mm] / sqrt(m[kg/m] · RTS[kN]) is used, the one RTE's open-source pallas-dohl uses.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

ALUMINIUM_E = 68.9e9  # Pa, hard-drawn aluminium wire 1350-H19 (ASTM B230)
STEEL_E = 206.8e9  # Pa, galvanised steel core wire (ASTM B498)


@dataclass(frozen=True)
class Layer:
    """A layer of n identical wires (diameter [m], Young's modulus [Pa]); layers listed from the centre out,
    the first one a single centre wire."""

    n: int
    wire_diameter: float
    youngs_modulus: float
    material: str


@dataclass(frozen=True)
class ConductorType:
    """A conductor: outer diameter [m], mass per length [kg/m], rated tensile strength [N], bending stiffness
    bounds [N·m²], its outer layer's wire diameter [m] and Young's modulus [Pa] (fatigue cracks start there),
    and its number of aluminium layers (the CIGRE safe border line distinguishes one from several)."""

    name: str
    diameter: float
    mass_per_length: float
    rts: float
    ei_min: float
    ei_max: float
    outer_wire_diameter: float
    outer_youngs_modulus: float
    aluminium_layers: int


def stranded(name: str, mass_per_length: float, rts: float, layers: tuple[Layer, ...]) -> ConductorType:
    """A ConductorType from its stranding (layers from the centre out): diameter and EI bounds computed."""
    ei_min, ei_max = bending_stiffness_bounds(layers)
    return ConductorType(name, outer_diameter(layers), mass_per_length, rts, ei_min, ei_max,
                         layers[-1].wire_diameter, layers[-1].youngs_modulus,
                         sum(1 for layer in layers if layer.material != "steel"))


def bending_stiffness_bounds(layers) -> tuple[float, float]:
    """(EI_min, EI_max) [N·m²] of concentric layers of round wires (centre out)."""
    ei_min = ei_max = 0.0
    radius = 0.0  # outer radius of the layers so far
    for k, layer in enumerate(layers):
        d, e = layer.wire_diameter, layer.youngs_modulus
        lay_radius = 0.0 if k == 0 else radius + d / 2
        radius = d / 2 if k == 0 else radius + d
        i_wire, a_wire = math.pi * d ** 4 / 64, math.pi * d ** 2 / 4
        ei_min += layer.n * e * i_wire
        ei_max += layer.n * e * (i_wire + a_wire * lay_radius ** 2 / 2)
    return ei_min, ei_max


def outer_diameter(layers) -> float:
    """Outer diameter [m] of concentric layers of round wires."""
    return layers[0].wire_diameter + 2 * sum(layer.wire_diameter for layer in layers[1:])


# ACSR "Drake" 795 kcmil 26/7 (ASTM B232): 7 steel wires of 3.45 mm, 26 aluminium wires of 4.44 mm in two
# layers (10 + 16), outer diameter 28.1 mm, 1.628 kg/m, rated strength 31 200 lbf = 138.8 kN.
DRAKE = stranded("ACSR Drake 26/7", 1.628, 138.8e3,
                 (Layer(1, 3.45e-3, STEEL_E, "steel"), Layer(6, 3.45e-3, STEEL_E, "steel"),
                  Layer(10, 4.44e-3, ALUMINIUM_E, "aluminium"), Layer(16, 4.44e-3, ALUMINIUM_E, "aluminium")))

CONDUCTORS = {"drake": DRAKE}


@dataclass(frozen=True)
class PowerLaw:
    """Self-damping power law P/L = k · Y^l · f^m / T^n (Y [m], f [Hz], T [kN], P/L [W/m])."""

    label: str
    l: float
    m: float
    n: float


SELF_DAMPING_LAWS = {
    "noiseux1991": PowerLaw("Noiseux (1991)", 2.44, 5.63, 2.76),
    "kraus1991": PowerLaw("Kraus & Hagedorn (1991)", 2.47, 5.38, 2.80),
    "seppa1971": PowerLaw("Seppa (1971)", 2.5, 5.75, 2.8),
    "mocks1989": PowerLaw("Möcks & Schmidt (1989)", 2.45, 5.38, 2.4),
}


def self_damping_constant(conductor: ConductorType) -> float:
    """Estimate of the power law's k without a span test: D[mm] / sqrt(m[kg/m] · RTS[kN])."""
    return conductor.diameter * 1e3 / math.sqrt(conductor.mass_per_length * conductor.rts / 1e3)


def self_damping_power_per_length(law: PowerLaw, k: float, f, Y, tension: float):
    """Power [W/m] the conductor dissipates at frequency f [Hz], antinode amplitude Y [m], tension [N]."""
    return k * np.asarray(Y, float) ** law.l * np.asarray(f, float) ** law.m / (tension / 1e3) ** law.n
