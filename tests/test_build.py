"""The build: every example becomes a valid FMI 2.0 FMU (ME + CS) whose two interfaces agree."""
import os
import pathlib
import shutil
import subprocess
import sys
import zipfile

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu

from pyfit.build import EXAMPLES, LIBRARY, ModelicaError, build_all
from pyfit.runtime.fmu import ParameterError

ROOT = pathlib.Path(__file__).resolve().parents[1]

# name -> (outputs compared, parameters for a short nonlinear run, stop time [s])
RUNS = {
    "SDOFBoucWen": (["y", "z"], {"exc_rate": 6.0}, 6.0),
    "TwoDOFa": (["y1", "y2", "z"], {"exc_rate": 6.0}, 6.0),
    "TwoDOFb": (["y1", "y2", "z"], {"exc_rate": 6.0}, 6.0),
    "TwoDOFc": (["y1", "y2", "z"], {"exc_rate": 6.0}, 6.0),
    "TwoDOFd": (["y1", "y2", "z"], {"exc_rate": 6.0}, 6.0),
    "StockbridgeDamper": (["x1", "x2", "F_clamp"], {"exc_rate": 10.0}, 3.5),
    "MassSpringDamper": (["y", "a"], {"exc_rate": 6.0}, 4.0),
    "DamperElement": (["x1", "F_clamp"], {"exc_type": 4, "exc_rate": 10.0}, 1.5),
}  # the elements driven only by inputs are checked in test_elements.py


@pytest.mark.parametrize("name", list(EXAMPLES))
def test_fmu_is_valid_fmi2_with_me_and_cs(fmu_dir, name):
    path = fmu_dir / f"{name}.fmu"
    assert validate_fmu(str(path)) == []
    md = read_model_description(str(path))
    assert md.fmiVersion == "2.0"
    assert md.modelExchange is not None and md.coSimulation is not None
    assert md.coSimulation.canInterpolateInputs
    names = {v.name for v in md.modelVariables}
    with zipfile.ZipFile(path) as z:
        files = z.namelist()
    assert "sources/model_functions.c" in files and "sources/fmi2_wrapper.c" in files
    # every parameter carries a description; physical ones carry a unit
    params = [v for v in md.modelVariables if v.causality == "parameter"]
    assert params and all(v.description for v in params)
    if name == "StockbridgeDamper":
        assert {"EI", "mu", "L1", "L2", "k_bw1", "k_cs2", "x_base", "v_base", "a_base", "F_clamp"} <= names
        assert next(v for v in md.modelVariables if v.name == "EI").unit == "N.m2"
    if name == "SDOFBoucWen":
        assert {"m", "c", "k", "alpha", "beta", "gamma", "delta", "nu", "u", "y", "v", "z"} <= names


@pytest.mark.parametrize("name", list(RUNS))
def test_model_exchange_and_co_simulation_agree(runner, name, measured):
    outputs, params, stop = RUNS[name]
    cs = runner(name).simulate(stop, 1e-3, outputs, params, tolerance=1e-11)
    me = runner(name, "ModelExchange").simulate(stop, 1e-3, outputs, params, tolerance=1e-11)
    assert cs.ok and me.ok, (cs.message, me.message)
    assert all(np.max(np.abs(cs[o])) > 0 for o in outputs)
    measured(f"{name}: Model Exchange (fmpy CVode, rtol 1e-11) vs Co-Simulation (DOPRI5, tol 1e-11), nonlinear "
             f"sweep: max|Δ|/max over {', '.join(outputs)}",
             max(np.max(np.abs(cs[o] - me[o])) / np.max(np.abs(cs[o])) for o in outputs), 1e-6)


def test_unknown_parameter_lists_the_valid_names(runner):
    with pytest.raises(ParameterError) as err:
        runner("SDOFBoucWen").simulate(0.1, 1e-3, ["y"], {"kk": 1.0})
    msg = str(err.value)
    assert "'kk'" in msg and "alpha" in msg and "exc_amplitude" in msg


def test_syntax_error_names_file_and_line_and_builds_nothing(tmp_path):
    lib = tmp_path / "modelica"
    shutil.copytree(LIBRARY, lib)
    bad = lib / "StockbridgeDamper" / "Components" / "Spring.mo"
    lines = bad.read_text().splitlines()
    eq_line = next(i for i, l in enumerate(lines) if "f = k*s_rel" in l)
    lines[eq_line] = "  f = k*s_rel +;"
    bad.write_text("\n".join(lines) + "\n")
    out = tmp_path / "out"
    with pytest.raises(ModelicaError) as err:
        build_all(out, library=lib)
    assert f"{bad}:{eq_line + 1}" in str(err.value)
    assert not out.exists() or not list(out.iterdir())


@pytest.mark.parametrize("workers", [1, 2])
def test_semantic_error_builds_nothing(tmp_path, workers):
    """An unbalanced model stops the build with the Modelica error, also when it is raised in a build process."""
    lib = tmp_path / "modelica"
    shutil.copytree(LIBRARY, lib)
    bad = lib / "StockbridgeDamper" / "Components" / "SpringDamper.mo"
    bad.write_text(bad.read_text().replace("f = k*s_rel + c*v_rel;", "f = k*s_rel + c*v_rel;\n  f = 2*c*v_rel;"))
    out = tmp_path / "out"
    with pytest.raises(ModelicaError, match="not balanced: 62 equations for 59 unknowns"):
        build_all(out, ["TwoDOFa"] * workers, library=lib, workers=workers)
    assert not out.exists() or not list(out.glob("*.fmu"))


def test_fmus_built_at_once_are_those_built_one_by_one(fmu_dir, tmp_path):
    """Two build processes give the FMUs the test run built one at a time (the same GUID: a hash of the interface
    and the equations; the same state count), reported in the order named."""
    names = ["CubicSpringElement", "BoucWenElement", "MassSpringDamper"]
    reported = []
    results = build_all(tmp_path, names, workers=2, on_built=lambda r: reported.append(r.fmu.stem))
    assert reported == names and [r.fmu.stem for r in results] == names
    for r in results:
        for built in (r.fmu, r.fmu3):
            assert validate_fmu(str(built)) == []
        alone = fmu_dir / r.fmu.name
        assert read_model_description(str(r.fmu)).guid == read_model_description(str(alone)).guid
        assert read_model_description(str(r.fmu3)).instantiationToken == \
            read_model_description(str(fmu_dir / "fmi3" / r.fmu.name)).instantiationToken


def test_out_of_range_parameter_is_rejected_with_its_range(runner):
    with pytest.raises(ParameterError, match=r"'m' = -1.0 outside \[0.0, inf\]"):
        runner("SDOFBoucWen").simulate(0.1, 1e-3, ["y"], {"m": -1.0})
    with pytest.raises(ParameterError, match=r"'a_bw' = 1.5 outside \[0.0, 1.0\]"):
        runner("StockbridgeDamper").simulate(0.1, 1e-3, ["x1"], {"a_bw": 1.5})


def test_the_build_is_the_same_in_every_process(fmu_dir):
    """A process with another hash seed (Python's set order) reduces the damper to the same equations as the
    build of this test run: the same GUID (a hash of the interface and the equations)."""
    code = ("from pyfit.build import frontend, reduce, codegen, LIBRARY, EXAMPLES; "
            "m = reduce.reduce_model(frontend.load(LIBRARY, EXAMPLES['DamperElement'])); "
            "print(codegen.guid_for(m, codegen.layout(m)))")
    seed = "2" if os.environ.get("PYTHONHASHSEED") == "1" else "1"
    other = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT,
                           env={**os.environ, "PYTHONHASHSEED": seed}).stdout.strip()
    assert other == read_model_description(str(fmu_dir / "DamperElement.fmu")).guid


def test_an_fmu_older_than_the_c_wrapper_is_rebuilt_and_a_current_one_kept(fmu_dir, tmp_path):
    """ensure_fmu rebuilds an FMU older than any of its sources: the .mo files and the build's C (the FMI wrapper
    with its solver), so a clone that pulls a faster or mended wrapper does not keep running the old one."""
    from pyfit.build import C_SOURCES
    from pyfit.runtime.examples import ensure_fmu

    path = tmp_path / "MassSpringDamper.fmu"
    shutil.copy(fmu_dir / "MassSpringDamper.fmu", path)
    newest = max(p.stat().st_mtime for p in [*LIBRARY.rglob("*.mo"), *C_SOURCES])
    os.utime(path, (newest + 10, newest + 10))
    ensure_fmu("MassSpringDamper", tmp_path)
    assert path.stat().st_mtime == newest + 10  # newer than every source: kept
    wrapper = max(C_SOURCES, key=lambda p: p.stat().st_mtime)
    os.utime(path, (wrapper.stat().st_mtime - 10, wrapper.stat().st_mtime - 10))
    ensure_fmu("MassSpringDamper", tmp_path)
    assert path.stat().st_mtime >= wrapper.stat().st_mtime  # older than the C wrapper: rebuilt
    assert read_model_description(str(path)).modelName.endswith(".MassSpringDamper")


def test_processes_building_the_same_fmu_at_once_all_succeed(tmp_path):
    """Workers that each find an FMU out of date rebuild it at the same moment: each writes its own partial file
    and renames it into place, so every build succeeds, the FMU left is whole, and no partial file stays."""
    code = ("import pathlib, sys; from pyfit.build import EXAMPLES, build_fmu; "
            "build_fmu(EXAMPLES['MassSpringDamper'], pathlib.Path(sys.argv[1]), 'MassSpringDamper')")
    procs = [subprocess.Popen([sys.executable, "-c", code, str(tmp_path)], stderr=subprocess.PIPE, text=True)
             for _ in range(3)]
    errors = [p.communicate()[1] for p in procs]
    assert [p.returncode for p in procs] == [0] * len(procs), errors
    assert not list(tmp_path.rglob("*.partial"))
    assert validate_fmu(str(tmp_path / "MassSpringDamper.fmu")) == []
