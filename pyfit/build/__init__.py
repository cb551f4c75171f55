"""Modelica -> FMU build: pymoca front end -> index reduction -> CasADi C code -> FMI 2.0 wrapper (+ FMI 3.0
adapter) -> gcc -> zip.

The .mo files are the single source of truth: nothing here knows any model's equations.
"""
from __future__ import annotations

import concurrent.futures
import multiprocessing
import pathlib
import tempfile
from dataclasses import dataclass

from pyfit.catalog import EXAMPLES, LIBRARY, ModelicaError

__all__ = ["ModelicaError", "EXAMPLES", "LONGEST_BUILDS", "build_fmu", "build_all", "fmi3_path", "LIBRARY", "C_SOURCES"]

# the hand-written C every FMU is compiled with (the FMI 2.0 wrapper with its solvers, the FMI 3.0 adapter)
C_SOURCES = tuple(sorted(pathlib.Path(__file__).parent.glob("*.c")))
# the examples whose builds take longest (a large generated C file, or a long Modelica flattening): started first
LONGEST_BUILDS = ("ConductorSpan", "StockbridgeDamper", "DamperElement")


@dataclass
class BuildResult:
    """What one build produced."""

    fmu: pathlib.Path
    n_states: int
    demoted_states: list[str]
    fmu3: pathlib.Path  # the FMI 3.0 FMU of the same model


def fmi3_path(out_dir: pathlib.Path, ident: str) -> pathlib.Path:
    """Where the FMI 3.0 FMU of `ident` goes: <out_dir>/fmi3/<ident>.fmu (beside the FMI 2.0 one)."""
    return pathlib.Path(out_dir) / "fmi3" / f"{ident}.fmu"


def build_fmu(model_name: str, out_dir: pathlib.Path, ident: str | None = None,
              library: pathlib.Path = LIBRARY) -> BuildResult:
    """Build one Modelica class into `<out_dir>/<ident>.fmu` (FMI 2.0) and `<out_dir>/fmi3/<ident>.fmu` (FMI 3.0),
    both Model Exchange + Co-Simulation, from the same generated C sources."""
    from pyfit.build import codegen, frontend, package, reduce  # the compiler loads only when building

    ident = ident or model_name.split(".")[-1]
    flat = frontend.load(library, model_name)
    model = reduce.reduce_model(flat)
    variables = codegen.layout(model)
    guid = codegen.guid_for(model, variables)
    with tempfile.TemporaryDirectory() as tmp:
        src = pathlib.Path(tmp) / "sources"
        sources = codegen.write_sources(model, ident, guid, variables, src)
        documents = {
            "2.0": {"modelDescription.xml": codegen.model_description(model, ident, guid, variables, sources)},
            "3.0": {"modelDescription.xml": codegen.model_description_fmi3(model, ident, guid, variables),
                    "sources/buildDescription.xml": codegen.build_description_fmi3(ident, sources + [
                        package.FMI3_ADAPTER.name])}}
        fmus = package.compile_and_zip(ident, src, documents, {"2.0": pathlib.Path(out_dir) / f"{ident}.fmu",
                                                               "3.0": fmi3_path(out_dir, ident)})
    return BuildResult(fmus["2.0"], len(model.states), model.demoted, fmus["3.0"])


def build_all(out_dir: pathlib.Path, names: list[str] | None = None, library: pathlib.Path = LIBRARY,
              on_built=None, workers: int = 1) -> list[BuildResult]:
    """Build every exported example (or the ones named: an example's name, or any class's full name in
    `library`, a folder or a list of folders); the library is checked before anything is written. With
    `workers` > 1 the FMUs are built in that many processes at once (the longest builds first); `on_built` is
    called in the order named either way."""
    from pyfit.build import frontend

    frontend.parse_library(library)
    names = names or list(EXAMPLES)
    unknown = [n for n in names if n not in EXAMPLES and "." not in n]
    if unknown:
        raise ValueError(f"unknown example(s) {unknown}; valid: {sorted(EXAMPLES)}, or a class's full name "
                         "(e.g. MyDampers.SDOFMaxwell, with its library given)")
    jobs = [(EXAMPLES[n], n) if n in EXAMPLES else (n, n.split(".")[-1]) for n in names]
    workers = max(1, min(workers, len(jobs)))
    if workers == 1:
        return [_reported(build_fmu(model, out_dir, ident, library), on_built) for model, ident in jobs]
    context = multiprocessing.get_context("forkserver")
    with concurrent.futures.ProcessPoolExecutor(workers, mp_context=context) as pool:
        longest_first = sorted(range(len(jobs)), key=lambda i: jobs[i][1] not in LONGEST_BUILDS)
        futures = {i: pool.submit(build_fmu, jobs[i][0], out_dir, jobs[i][1], library) for i in longest_first}
        return [_reported(futures[i].result(), on_built) for i in range(len(jobs))]


def _reported(result: BuildResult, on_built) -> BuildResult:
    if on_built:
        on_built(result)
    return result
