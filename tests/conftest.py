"""Shared fixtures: the FMUs are built once per test session from the .mo sources."""
import pathlib

import pytest

from pyfit.build import build_all
from pyfit.runtime.fmu import FmuRunner

ROOT = pathlib.Path(__file__).resolve().parents[1]
SHARED_DATA = ROOT.parent / "shared" / "data" / "boucwen"


@pytest.fixture(scope="session")
def fmu_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("fmus")
    build_all(out)
    return out


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
