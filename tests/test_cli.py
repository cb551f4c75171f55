"""The `stockbridge` command: every job is a subcommand with its own help and an example; the scripts are
the same commands; bad arguments give one clear error."""
import pathlib
import shutil
import subprocess
import sys

import pytest

from pyfit.cli import COMMANDS

ROOT = pathlib.Path(__file__).resolve().parents[1]
SCRIPTS = {p.stem.replace("_fmus", "").replace("_", "-"): p for p in (ROOT / "scripts").glob("*.py")}


def run(*args, timeout=120):
    return subprocess.run(args, capture_output=True, text=True, timeout=timeout)


def test_the_console_command_lists_every_job():
    exe = shutil.which("stockbridge")
    assert exe, "the package installs the console command `stockbridge`"
    out = run(exe, "--help").stdout
    for name in COMMANDS:
        assert f"    {name}" in out


@pytest.mark.parametrize("name", list(COMMANDS))
def test_each_job_has_help_with_an_example(name):
    res = run(sys.executable, "-m", "pyfit.cli", name, "--help")
    assert res.returncode == 0, res.stderr
    assert f"usage: stockbridge {name}" in res.stdout
    example = res.stdout.split("example", 1)[1]
    assert f"stockbridge {name}" in example


def test_every_script_is_a_subcommand():
    assert set(SCRIPTS) == set(COMMANDS)
    res = run(sys.executable, str(ROOT / "scripts" / "diagnose.py"), "--help")
    assert res.returncode == 0 and "usage: stockbridge diagnose" in res.stdout


def test_bad_arguments_give_one_clear_error(tmp_path):
    res = run(sys.executable, "-m", "pyfit.cli", "fitt")
    assert res.returncode == 2 and "invalid choice: 'fitt'" in res.stderr
    res = run(sys.executable, "-m", "pyfit.cli", "diagnose", "--data", str(tmp_path / "nowhere"))
    assert res.returncode == 2 and "nowhere" in res.stderr and "Traceback" not in res.stderr
    res = run(sys.executable, "-m", "pyfit.cli", "simulate", "SDOFBoucWen", "--set", "beta=abc")
    assert res.returncode == 2 and "--set takes NAME=VALUE with a numeric VALUE" in res.stderr
