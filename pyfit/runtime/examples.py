"""Run one example FMU with its built-in excitation: CSV of the outputs and a time-history plot."""
from __future__ import annotations

import pathlib

import numpy as np
from fmpy import read_model_description

from pyfit.build import C_SOURCES, EXAMPLES, LIBRARY, build_fmu
from pyfit.runtime.fmu import FmuRunner


def ensure_fmu(name: str, fmu_dir: pathlib.Path) -> pathlib.Path:
    """Path of the example's FMU, built from the .mo sources if it is missing or older than any of them (the
    .mo files are the single source of truth) or than the build's own C sources (the FMI wrapper and solver)."""
    path = pathlib.Path(fmu_dir) / f"{name}.fmu"
    sources = [*LIBRARY.rglob("*.mo"), *C_SOURCES]
    newest_source = max(p.stat().st_mtime for p in sources)
    if not path.exists() or path.stat().st_mtime < newest_source:
        build_fmu(EXAMPLES[name], pathlib.Path(fmu_dir), name)
    return path


def run_example(name: str, params: dict, stop: float | None, interval: float, fmu_dir: pathlib.Path,
                out_dir: pathlib.Path) -> tuple[pathlib.Path, pathlib.Path]:
    """Simulate the example (co-simulation) and write <out>/<name>.csv and <out>/<name>.png."""
    from pyfit.report import plots

    path = ensure_fmu(name, fmu_dir)
    md = read_model_description(str(path))
    outputs = [v for v in md.modelVariables if v.causality == "output"]
    stop = float(stop if stop is not None else md.defaultExperiment.stopTime)
    stop = round(stop / interval) * interval
    runner = FmuRunner(str(path))
    res = runner.simulate(stop, interval, [v.name for v in outputs], params)
    runner.close()
    if not res.ok:
        raise RuntimeError(f"{name}: simulation failed: {res.message}")
    out_dir.mkdir(parents=True, exist_ok=True)
    csv = out_dir / f"{name}.csv"
    header = ",".join(["t"] + [v.name for v in outputs])
    np.savetxt(csv, np.column_stack([res.time] + [res[v.name] for v in outputs]), delimiter=",", header=header,
               comments="")
    png = plots.time_histories(out_dir / f"{name}.png", [("", res.time, res.values)], [v.name for v in outputs],
                               {v.name: v.unit for v in outputs},
                               f"{name}: " + ", ".join(f"{k}={v:g}" for k, v in params.items()) if params else name)
    return csv, png
