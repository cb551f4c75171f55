"""Wall time of a full gap diagnosis with the default budgets on 2 workers, per stage, measured in one run.

The cases are the ones a test bench produces: three levels of 35 s linear sweeps sampled at the family's rate
(500 Hz; the SDOF: force sweeps, displacement recorded; the damper: constant-velocity clamp sweeps of the design
1.3 damper, clamp displacement only and both cable-end displacements recorded), with hysteresis withheld; and
the damper with hysteresis and cubic springs withheld together (a pair: the forward selection's joint refits
run too); an SDOF with Coulomb friction withheld, and one with a sharp loop that turns over early (ν = 3); and, as a lab acquisition would record them, the damper hysteresis case at 2500 Hz (the diagnosis
decimates it) and the pair at 1 kHz (analysed at that rate, the FMU driven on the 1 kHz grid a 500 Hz file has:
pyfit.gap.rate), each with its time over the same case's at 500 Hz when both ran. Goals on 2 cores: an SDOF
case <= 20 s, a damper case with one effect withheld <= 30 s, with a pair <= 90 s.

    python bench/diagnose_time.py [--only sdof|damper|damper_pair|damper_fast|damper_pair_fast] [--fits]

With --only, the other cases' lines of the results file an earlier run wrote are kept as they were. With --fits,
each case's fits are printed too, in the order they ended (evaluations, wall time, calibration NRMSE): where a
stage's time goes.
"""
import argparse
import dataclasses
import json
import pathlib
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]

from pyfit.gap.datasets import FAMILIES, LabStyle, write_dataset
from pyfit.gap.diagnose import diagnose
from pyfit.report.generated import BenchReport

# a sharp SDOF loop that turns over early (ν = 3, the loading branch saturating at 8 N under drives of 10-50 N):
# the corner of the loop family a box on β, γ, δ kept out of reach (theory §1.1)
SHARP_LOOP = {"k": 5e4, "alpha": 5e4, "beta": 5e4 / 8.0 ** 3, "gamma": 1.25, "delta": -0.25, "nu": 3.0}
# case -> (model, withheld, how it is recorded, sampling rate [Hz]: None for the family's, truth: None for the
# family's reference)
CASES = {"sdof": ("sdof", "hysteresis", LabStyle(excitation="sweep"), None),
         "sdof_sharp_loop": ("sdof", "hysteresis", LabStyle(excitation="sweep"), None, SHARP_LOOP),
         "sdof_friction": ("sdof", "coulomb_friction", LabStyle(excitation="sweep"), None),
         "damper": ("damper", "hysteresis", LabStyle(excitation="sweep", motion="x"), None),
         "damper_pair": ("damper", "cubic_stiffness+hysteresis", LabStyle(excitation="sweep", motion="x"), None),
         "damper_fast": ("damper", "hysteresis", LabStyle(excitation="sweep", motion="x"), 2500.0),
         "damper_pair_fast": ("damper", "cubic_stiffness+hysteresis", LabStyle(excitation="sweep", motion="x"), 1000.0)}
SLOWER = {"damper_fast": "damper", "damper_pair_fast": "damper_pair"}  # a case at a lab's rate -> the same at 500 Hz
GOAL_S = {"sdof": 20.0, "damper": 30.0, "damper_pair": 90.0}  # on 2 cores


def print_fits(fits_dir: pathlib.Path) -> None:
    """Every fit a diagnosis stored, in the order they ended: evaluations, wall time [s], calibration NRMSE."""
    for path in sorted(fits_dir.glob("*.json"), key=lambda f: f.stat().st_mtime):
        fit = json.loads(path.read_text()).get("fit", {})
        if "wall_s" in fit:
            print(f"  {path.stem:70s} {fit['evaluations']:5d} evaluations {fit['wall_s']:6.1f} s "
                  f"calibration NRMSE {fit['calibration_nrmse']:.4f}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--only", choices=list(CASES))
    ap.add_argument("--fmus", default=str(ROOT / "fmus"))
    ap.add_argument("--fits", action="store_true", help="print each case's fits (where a stage's time goes)")
    args = ap.parse_args()
    report = BenchReport("diagnose_time", ROOT)
    earlier = report.path.read_text(encoding="utf-8").splitlines() if args.only and report.path.is_file() else []
    walls = {}
    for case in CASES:
        model, withheld, style, fs, *truth = CASES[case]
        family = dataclasses.replace(FAMILIES[model], fs=fs or FAMILIES[model].fs)
        opening = (f"{model} diagnosis (three 35 s sweeps sampled at {family.fs:g} Hz, "
                   f"{withheld.replace('+', ' + ')}{' (a sharp loop, nu = 3, turning over at 8 N)' if truth else ''} "
                   "withheld, ")
        if args.only and case != args.only:
            for line in earlier:  # kept as that run wrote it
                if line.startswith(f"- {opening}"):
                    report.line(line[2:])
            continue
        with tempfile.TemporaryDirectory() as tmp:
            data = write_dataset(pathlib.Path(tmp) / "data", family, withheld, style=style,
                                 truth=truth[0] if truth else None)
            t0 = time.perf_counter()
            rep = diagnose(model, data, pathlib.Path(tmp) / "out", fmu_dir=args.fmus, workers=2, progress=False)
            wall = walls[case] = time.perf_counter() - t0
            if args.fits:
                print(f"{case}:")
                print_fits(pathlib.Path(tmp) / "out" / "fits")
        goal = GOAL_S["damper_pair" if "+" in withheld and model == "damper" else model]
        stages = ", ".join(f"{k} {v:.0f} s" for k, v in rep.stage_s.items())
        rate = rep.analysis_rate
        same = SLOWER.get(case)
        analysed = (f"analysed at {rate['file_hz'] / rate['factor']:g} Hz, FMU driven at "
                    f"{rate['file_hz'] / rate['factor'] * rate['drive_upsample']:g} Hz, "
                    + (f"{wall / walls[same]:.2f} x the {FAMILIES[model].fs:g} Hz case's time, "
                       if same in walls else "") if same else "")
        report.line(f"{opening}{len(rep.ranking)} candidates and combinations refitted): {wall:.0f} s "
                    f"({analysed}{wall / goal:.2f} x the goal of {goal:.0f} s; {stages}); "
                    f"verdict: {rep.sentence}")


if __name__ == "__main__":
    main()
