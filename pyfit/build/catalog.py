"""What the build exports, readable without loading the Modelica compiler (pymoca, CasADi)."""
from __future__ import annotations

import pathlib


class ModelicaError(Exception):
    """A problem in the Modelica sources, naming the file (and line where known)."""


LIBRARY = pathlib.Path(__file__).resolve().parents[2] / "modelica"

# Exported examples: FMU file stem -> Modelica class
EXAMPLES = {
    "SDOFBoucWen": "StockbridgeDamper.Examples.SDOFBoucWen",
    "TwoDOFa": "StockbridgeDamper.Examples.TwoDOFa",
    "TwoDOFb": "StockbridgeDamper.Examples.TwoDOFb",
    "TwoDOFc": "StockbridgeDamper.Examples.TwoDOFc",
    "TwoDOFd": "StockbridgeDamper.Examples.TwoDOFd",
    "StockbridgeDamper": "StockbridgeDamper.Examples.StockbridgeDamper",
    # element FMUs for exchange and co-simulation (causal interfaces)
    "BoucWenElement": "StockbridgeDamper.Elements.BoucWenElement",
    "BoucWenNormalizedElement": "StockbridgeDamper.Elements.BoucWenNormalizedElement",
    "CubicSpringElement": "StockbridgeDamper.Elements.CubicSpringElement",
    "MassSpringDamper": "StockbridgeDamper.Elements.MassSpringDamper",
    "DamperElement": "StockbridgeDamper.Elements.DamperElement",
    "ConductorSpan": "StockbridgeDamper.Elements.ConductorSpan",
}
