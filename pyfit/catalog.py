"""What the package ships, readable without loading the Modelica compiler (pymoca, CasADi): the Modelica
library, the example models the build exports, and the bundled study files."""
from __future__ import annotations

import pathlib


class ModelicaError(Exception):
    """A problem in the Modelica sources, naming the file (and line where known)."""


PACKAGE = pathlib.Path(__file__).resolve().parent
LIBRARY = PACKAGE / "modelica"  # the Modelica library (inside the package: a wheel carries it)
CONFIGS = PACKAGE / "configs"  # bundled study, span and nominal files

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
