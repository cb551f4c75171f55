"""What the package ships, readable without loading the Modelica compiler (pymoca, CasADi): the Modelica
library, the example models the build exports, and the bundled study files."""
from __future__ import annotations

import pathlib


class ModelicaError(Exception):
    """A problem in the Modelica sources, naming the file (and line where known)."""


PACKAGE = pathlib.Path(__file__).resolve().parent
LIBRARY = PACKAGE / "modelica"  # the Modelica library (inside the package: a wheel carries it)
CONFIGS = PACKAGE / "configs"  # bundled study, span and nominal files
DATASETS = PACKAGE / "examples"  # bundled datasets (a folder of measurement files each, with a README.txt)

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


def datasets() -> dict[str, str]:
    """The bundled datasets: name -> the first line of its README.txt."""
    return {d.name: (d / "README.txt").read_text(encoding="utf-8").splitlines()[0]
            for d in sorted(DATASETS.iterdir()) if (d / "README.txt").is_file()}


def copy_dataset(name: str, to: pathlib.Path) -> pathlib.Path:
    """Copy the bundled dataset `name` into the folder `to` (made; files there already are kept unless a bundled
    file has the same name); ValueError naming the datasets for an unknown name."""
    import shutil

    known = datasets()
    if name not in known:
        raise ValueError(f"no bundled dataset '{name}'; allowed: {', '.join(known)}")
    to.mkdir(parents=True, exist_ok=True)
    for f in sorted((DATASETS / name).iterdir()):
        shutil.copyfile(f, to / f.name)
    return to
