"""The `stockbridge` command: every job is a subcommand with its own help and an example; the scripts are
the same commands; bad arguments give one clear error."""
import os
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
    for job, arg, value in (("diagnose", "--campaign", "0"), ("diagnose", "--workers", "-2"),
                            ("fit", "--repeats", "x")):
        res = run(sys.executable, "-m", "pyfit.cli", job, arg, value)
        assert res.returncode == 2 and f"argument {arg}: '{value}': a whole number of at least 1" in res.stderr
    res = run(sys.executable, "-m", "pyfit.cli", "diagnose", "--model", "sdfo", "--data", str(tmp_path))
    assert res.returncode == 2 and "invalid choice: 'sdfo' (choose from 'sdof', 'damper')" in res.stderr


def test_the_model_choices_are_the_system_families():
    from pyfit.cli.diagnose import MODELS
    from pyfit.gap.systems import FAMILY

    assert set(MODELS) == set(FAMILY)


def test_a_scheduler_that_does_not_answer_gives_one_clear_error(tmp_path):
    """No Dask scheduler at the address: one error naming it and what to do, not a traceback (the wait for an
    answer shortened from Dask's 30 s)."""
    res = subprocess.run([sys.executable, "-m", "pyfit.cli", "diagnose", "--campaign", "2", "--out", str(tmp_path),
                          "--scheduler", "tcp://127.0.0.1:9"], capture_output=True, text=True, timeout=120,
                         env={**os.environ, "DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT": "2s"})
    assert res.returncode == 2 and "Traceback" not in res.stderr
    assert "error: no Dask scheduler answered at tcp://127.0.0.1:9" in res.stderr and "dask scheduler" in res.stderr


def test_the_bundled_dataset_is_listed_copied_and_read_in_its_units(tmp_path, fmu_dir):
    """`stockbridge examples` lists the bundled shaker test and copies it; the diagnosis reads its accelerometer
    column, written in g, as m/s² (its RMS about the mean, from the file's own numbers, times standard gravity)."""
    import numpy as np

    from pyfit.gap.dataset_check import check_dataset

    listed = run(sys.executable, "-m", "pyfit.cli", "examples")
    assert listed.returncode == 0 and listed.stdout.startswith("lab_sweeps: ")
    copied = run(sys.executable, "-m", "pyfit.cli", "examples", "lab_sweeps", str(tmp_path / "lab"))
    assert copied.returncode == 0, copied.stderr
    unknown = run(sys.executable, "-m", "pyfit.cli", "examples", "lab_sweep")
    assert unknown.returncode == 2 and "allowed: lab_sweeps" in unknown.stderr
    check = check_dataset("sdof", tmp_path / "lab", fmu_dir=fmu_dir)
    assert [f.role for f in check.files] == ["calibration", "held out", "calibration"]
    for f in check.files:
        acc = np.genfromtxt(tmp_path / "lab" / f"{f.name}.csv", delimiter=",", skip_header=2)[:, 2]
        (channel,) = [c for c in f.channels if c.model_variable == "a"]
        assert channel.unit == "g" and channel.rms_si == pytest.approx(9.80665 * np.std(acc), rel=1e-9)
