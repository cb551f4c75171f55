"""Shared fixtures: the FMUs are built once per test run from the .mo sources (shared by the xdist workers)."""
import fcntl
import os
import pathlib
import time

import pytest

from pyfit.build import EXAMPLES, LONGEST_BUILDS, build_fmu
from pyfit.runtime.fmu import FmuRunner

ROOT = pathlib.Path(__file__).resolve().parents[1]


@pytest.fixture(scope="session")
def fmu_dir(tmp_path_factory, worker_id):
    """Every example FMU, built once per test run and shared by the xdist workers (read only): each FMU is
    built by the first worker that claims its lock, so the workers build in parallel, then wait for the rest."""
    root = tmp_path_factory.getbasetemp()
    if worker_id != "master":  # xdist: the workers' temporary folders share this parent
        root = root.parent
    out = root / "fmus_shared"
    out.mkdir(exist_ok=True)
    first = [n for n in LONGEST_BUILDS if n in EXAMPLES]  # started first, so that the workers end together
    for blocking in (False, True):
        for name in first + [n for n in EXAMPLES if n not in first]:
            with open(out / f"{name}.lock", "w") as lock:
                try:
                    fcntl.flock(lock, fcntl.LOCK_EX | (0 if blocking else fcntl.LOCK_NB))
                except BlockingIOError:
                    continue  # another worker is building it
                if not (out / f"{name}.built").is_file():
                    build_fmu(EXAMPLES[name], out, name)
                    (out / f"{name}.built").touch()
    return out


@pytest.fixture(scope="module")
def sdof_system(fmu_dir):
    """The SDOF FMU's runner and the diagnosis's system built on its defaults (pyfit.gap.systems)."""
    from pyfit.gap.diagnose import fmu_defaults
    from pyfit.gap.systems import family_fmu, make_system

    runner = FmuRunner(str(fmu_dir / f"{family_fmu('sdof')}.fmu"))
    yield runner, make_system("sdof", fmu_defaults(runner), None)
    runner.close()


@pytest.fixture(scope="session")
def benchmark_dir():
    """The official Bouc-Wen benchmark validation signals (third-party data, not in the repository): the folder
    named by BOUCWEN_DATA_DIR, which must then hold them; without it the test is skipped, saying how to get
    them (the tests never download)."""
    from pyfit.io import benchmark_data as bd

    named = os.environ.get(bd.ENV_VAR)
    if not named:
        pytest.skip(f"needs the Bouc-Wen benchmark signals: {bd.HOW_TO_GET}")
    folder = pathlib.Path(named)
    missing = [f"{k}val_{s}.mat" for k in "uy" for s in ("multisine", "sinesweep") if not (folder / f"{k}val_{s}.mat").is_file()]
    if missing:
        raise FileNotFoundError(f"{bd.ENV_VAR}={folder} lacks {', '.join(missing)}")
    return folder


@pytest.fixture(scope="session")
def runner(fmu_dir):
    """runner(name, interface='CoSimulation') -> a cached FmuRunner for that FMU."""
    cache = {}

    def get(name, interface="CoSimulation"):
        key = (name, interface)
        if key not in cache:
            cache[key] = FmuRunner(str(fmu_dir / f"{name}.fmu"), interface)
        return cache[key]

    yield get
    for r in cache.values():
        r.close()


# ---- figures the tests measure, for the README's generated table ------------------------------------------
_MEASURED: list[dict] = []
_SESSION_START = time.monotonic()  # this file is imported as the test session starts: the run time's origin
MEASURED_TABLE = ROOT / "results" / "tests.md"


@pytest.fixture
def measured(request):
    """measured(check, value, bar, at_least=False): assert value <= bar (>= with at_least) and record the
    figure, so that a full test run writes results/tests.md (what was checked, measured, allowed)."""

    def record(check: str, value: float, bar: float, at_least: bool = False) -> float:
        value = float(value)
        ok = value >= bar if at_least else value <= bar
        assert ok, f"{check}: measured {value:.4g}, {'at least' if at_least else 'at most'} {bar:.4g} allowed"
        _MEASURED.append({"test": request.node.nodeid, "check": check, "value": value, "bar": bar,
                          "at_least": at_least})
        return value

    return record


def _fmt(x: float) -> str:
    return f"{x:.3g}" if x != 0 else "0"


def _table(rows: list[dict]) -> str:
    lines = ["| check | measured | allowed | test |", "|---|---|---|---|"]
    for m in rows:
        test = m["test"].split("::", 1)
        check = m["check"].replace("|", "\\|")
        lines.append(f"| {check} | {_fmt(m['value'])} | {'≥' if m['at_least'] else '≤'} {_fmt(m['bar'])} | "
                     f"`{test[0].removeprefix('tests/')}::{test[1]}` |")
    return "\n".join(lines) + "\n"


# the test files that run longest (a diagnosis or a fit each, 25-90 s on 2 cores), longest first: collected first,
# so that the workers, which take files in the order collected, do not end on one of them alone (the stuck joint's
# one diagnosis, 60-75 s on one worker, first)
LONGEST_FILES = ("test_gap_stuck_joint.py", "test_gap_loop_friction.py", "test_gap.py", "test_gap_nulls.py",
                 "test_fitting.py", "test_damper_far_nominal.py", "test_records.py", "test_reference.py",
                 "test_design_check.py", "test_unsettled.py", "test_benchmark_fit.py", "test_impedance_fit.py",
                 "test_datasets.py", "test_strength_grid.py")


def pytest_collection_modifyitems(session, config, items):
    """The longest test files first (LONGEST_FILES), the others after them in their own order."""
    rank = {name: i for i, name in enumerate(LONGEST_FILES)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))


def pytest_sessionfinish(session, exitstatus):
    """Write the measured figures of a full run (the default test paths) in which every test passed: with
    pytest-xdist each worker leaves its rows in a JSON file and the controller writes the table, ordered by
    test file and name."""
    import json

    worker = getattr(session.config, "workerinput", None)
    parts = MEASURED_TABLE.parent / "tests_parts"
    if worker is not None:
        parts.mkdir(parents=True, exist_ok=True)
        (parts / f"{worker['workerid']}.json").write_text(json.dumps(_MEASURED))
        return
    rows = list(_MEASURED)
    if parts.is_dir():
        for f in sorted(parts.glob("*.json")):
            rows += json.loads(f.read_text())
            f.unlink()
    full = session.config.args == session.config.getini("testpaths")  # not a run of chosen files
    if not rows or exitstatus != 0 or not full:
        return
    MEASURED_TABLE.parent.mkdir(parents=True, exist_ok=True)
    reporter = session.config.pluginmanager.get_plugin("terminalreporter")
    n_passed = len(reporter.stats.get("passed", [])) if reporter else 0
    wall = time.monotonic() - _SESSION_START
    MEASURED_TABLE.write_text(_table(sorted(rows, key=lambda m: (m["test"].split("::")[0], m["test"])))
                              + f"\nThe default run (`python -m pytest`): {n_passed} tests passed in {wall:.0f} s "
                                f"on {os.cpu_count()} cores.\n")


def check_report(path: pathlib.Path) -> None:
    """A report.json the diagnosis wrote: valid against the schema the package ships (pyfit/gap/report.schema.json),
    and read back into the same Diagnosis (its JSON written again is the file's)."""
    import json

    import jsonschema

    from pyfit.gap.result import SCHEMA, Diagnosis

    written = json.loads(path.read_text())
    jsonschema.validate(written, json.loads(SCHEMA.read_text()))
    assert Diagnosis.from_json(written).to_json() == written, path


@pytest.fixture(scope="session", autouse=True)
def every_report_checked(tmp_path_factory):
    """Every report.json a test of this run made (under the run's temporary folders), checked once the tests of this
    worker end: check_report."""
    yield
    for path in sorted(tmp_path_factory.getbasetemp().rglob("report.json")):
        check_report(path)
