"""The package's shape: short functions, the public names, no build output in git."""
import ast
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
LONGEST = 60  # lines a function of pyfit/ may hold, its docstring included: a screen


def _functions(path: pathlib.Path):
    tree = ast.parse(path.read_text(encoding="utf-8"))
    return [n for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))]


def test_no_function_of_the_package_is_longer_than_a_screen():
    long = [f"{path.relative_to(ROOT)}:{n.lineno} {n.name} ({n.end_lineno - n.lineno + 1} lines)"
            for path in sorted((ROOT / "pyfit").rglob("*.py")) for n in _functions(path)
            if n.end_lineno - n.lineno + 1 > LONGEST]
    assert not long, long


def test_the_length_check_sees_a_long_function(tmp_path):
    """The check above counts a function's lines from its def to its last statement (a 61-line one is caught)."""
    source = tmp_path / "long.py"
    source.write_text("def f():\n" + "    x = 1\n" * 59 + "    return x\n")
    (n,) = _functions(source)
    assert n.end_lineno - n.lineno + 1 == 61


def test_the_public_names_resolve_and_unknown_ones_fail():
    import pyfit
    from pyfit.gap.diagnose import diagnose
    from pyfit.gap.result import Diagnosis

    assert pyfit.diagnose is diagnose and pyfit.Diagnosis is Diagnosis
    assert set(pyfit.__all__) <= set(dir(pyfit))
    for name in pyfit.__all__:
        assert getattr(pyfit, name) is not None
    with pytest.raises(AttributeError, match="no attribute 'diagnosis'"):
        pyfit.diagnosis


def test_no_build_output_is_tracked():
    """The documentation site, FMUs and results are made by commands, not committed."""
    tracked = subprocess.run(["git", "ls-files", "site", "fmus", "results"], cwd=ROOT, capture_output=True,
                             text=True)
    if tracked.returncode != 0:
        pytest.skip(f"not a git checkout: {tracked.stderr.strip()}")
    assert tracked.stdout == ""
