"""What a run that escapes to infinity costs, with and without the co-simulation's smallest-step rule, measured in
one run.

The damper FMU (StockbridgeDamper at its defaults) with softening cubic springs on both arms, its clamp moved by a
12 Hz sine of 2 mm brought in over 1 s, 3 s at 1.5 kHz: with k_cs = -1e9 N/m³ the springs carry the motion; with
-1e10 N/m³ they pass their peak force and the arms run off to infinity. The FMU fails that run once its step falls
below 1e-8 of the communication step (pyfit/build/fmi2_wrapper.c); the same FMU built without the rule
(MIN_STEP_SHARE 0, in a temporary folder) follows the escape on to the limit of the arithmetic.

    python bench/escape_cost.py [--repeats 5]
"""
import argparse
import pathlib
import tempfile
import time

import numpy as np

from pyfit.build import EXAMPLES, build_fmu, package
from pyfit.report.generated import BenchReport
from pyfit.runtime.examples import ensure_fmu
from pyfit.runtime.fmu import FmuRunner

ROOT = pathlib.Path(__file__).resolve().parents[1]
RULE = "#define MIN_STEP_SHARE 1e-8"


def _without_rule(tmp: pathlib.Path) -> pathlib.Path:
    """The damper FMU built from a copy of the wrapper whose MIN_STEP_SHARE is 0 (the step limited by the
    arithmetic alone)."""
    source = package.FMI2_WRAPPER.read_text()
    assert RULE in source
    wrapper = tmp / package.FMI2_WRAPPER.name
    wrapper.write_text(source.replace(RULE, "#define MIN_STEP_SHARE 0.0"))
    kept, package.FMI2_WRAPPER = package.FMI2_WRAPPER, wrapper
    try:
        return build_fmu(EXAMPLES["StockbridgeDamper"], tmp, "StockbridgeDamper").fmu
    finally:
        package.FMI2_WRAPPER = kept


def _fastest(runner: FmuRunner, k_cs: float, repeats: int) -> tuple[float, str]:
    """The fastest of `repeats` runs with both cubic springs at k_cs [N/m³]: wall time [s] and the run's outcome."""
    fs, stop = 1500.0, 3.0
    t = np.arange(int(stop * fs) + 1) / fs
    x = 2e-3 * np.sin(2 * np.pi * 12.0 * t) * np.minimum(t, 1.0) ** 3  # the clamp displacement [m]
    v = np.gradient(x, t)
    inputs = {"x_base": x, "v_base": v, "a_base": np.gradient(v, t)}
    runs = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        res = runner.simulate(stop, 1 / fs, ["x1"], {"exc_type": 0, "k_cs1": k_cs, "k_cs2": k_cs}, inputs, t,
                              tolerance=1e-6)
        runs.append(time.perf_counter() - t0)
    return min(runs), (res.message.split(";")[0] if not res.ok else "carried")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        runners = {"with": FmuRunner(str(ensure_fmu("StockbridgeDamper", ROOT / "fmus"))),
                   "without": FmuRunner(str(_without_rule(pathlib.Path(tmp))))}
        carried = _fastest(runners["with"], -1e9, args.repeats)
        escape, old = (_fastest(runners[rule], -1e10, args.repeats) for rule in ("with", "without"))
        for r in runners.values():
            r.close()
    BenchReport("escape_cost", ROOT).line(
        f"damper, softening springs, 3 s at 1.5 kHz (fastest of {args.repeats}): carried (k_cs = -1e9 N/m³) "
        f"{carried[0] * 1e3:.1f} ms; escaping (-1e10 N/m³) {escape[0] * 1e3:.1f} ms ({escape[1]}), "
        f"{old[0] * 1e3:.1f} ms without the rule ({old[1]}): the rule makes the escaping run {old[0] / escape[0]:.1f} x "
        "faster")


if __name__ == "__main__":
    main()
