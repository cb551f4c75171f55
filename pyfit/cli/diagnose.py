"""stockbridge diagnose: where the nominal model misfits a measured dataset, which candidate effect explains
it, and how far the misfit shrinks on held-out files once that effect is added."""
from __future__ import annotations

import json
import pathlib
import sys

from pyfit.cli import count

MODELS = ("sdof", "damper")  # the system families (pyfit.gap.systems.FAMILY), named here to keep start-up light

EXAMPLE = """examples:
  stockbridge diagnose --model damper --data my_sweeps/ --nominal my_damper.toml --out results/diagnose
  stockbridge diagnose --model sdof --data my_tests/
  stockbridge diagnose --model sdof --data my_tests/ --check  # what would be read, in seconds, before any fit
  stockbridge diagnose --model sdof --data my_tests/ --candidates my_candidates.toml  # your own effects too
  stockbridge diagnose --impedance damper_test.csv --uncertainty 0.01      # an IEC 61897 impedance test
  stockbridge diagnose --make-datasets cases/ --excitation sweep --record a # withheld-effect test cases
  stockbridge diagnose --cases cases/ --out results/cases                   # every dataset under cases/
  stockbridge diagnose --benchmark --config configs/diagnose_benchmark.toml # official Bouc-Wen signals
  stockbridge diagnose --campaign 200 --out results/campaign                # random truths, a Dask LocalCluster
  stockbridge diagnose --campaign 200 --scheduler tcp://10.0.0.5:8786       # ... on a Dask cluster
  stockbridge diagnose --campaign 40 --model damper --excitation stepped_sine --record-s 35  # one excitation

A dataset is a folder of measurement files (CSV + TOML sidecar, one per level; docs: measurement files).
Writes report.md (verdict, ranked effects, shrink on held-out files), report.json and figures into --out."""


def add_arguments(ap) -> None:
    """Arguments of `stockbridge diagnose`."""
    ap.add_argument("--model", default="sdof", choices=MODELS,
                    help="nominal model: sdof (linear SDOF) or damper (linear FE damper)")
    ap.add_argument("--data", help="dataset folder (CSV + TOML pairs)")
    ap.add_argument("--check", action="store_true", help="with --data: print (and write to OUT/check.md) what the "
                    "diagnosis would read "
                    "(files, levels, channels and units, RMS in SI, noise floor, split, excited band, the nominal's "
                    "resonances) and stop before any fit")
    ap.add_argument("--config", help="TOML with a [diagnose] table")
    ap.add_argument("--nominal", help="TOML describing your system: [nominal] family, fixed and free parameters "
                                      "(default: the FMU's own; for the damper the reference damper)")
    ap.add_argument("--candidates", help="TOML declaring your own candidate effects (FMU parameters, bounds, start "
                                         "rules) and the FMU that holds them; docs: gap diagnosis")
    ap.add_argument("--out", default="results/diagnose")
    ap.add_argument("--workers", type=count, default=None)
    ap.add_argument("--fmus", default="fmus")
    ap.add_argument("--make-datasets", metavar="DIR", help="write the withheld-effect datasets of --model into DIR")
    ap.add_argument("--benchmark", action="store_true",
                    help="use the official Bouc-Wen benchmark signals (written as a dataset into OUT/data)")
    ap.add_argument("--cases", metavar="DIR", help="diagnose every dataset folder under DIR and write summary.md")
    ap.add_argument("--impedance", metavar="TEST.csv", help="diagnose a damper's impedance test (CSV + TOML "
                    "sidecar, kind = damper_impedance) at three or more clamp-velocity levels")
    ap.add_argument("--uncertainty", type=float, help="with --impedance: the test's relative measurement error "
                    "(RMS of |Z_meas/Z_true - 1|; default: `uncertainty` of the test's sidecar)")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2], help="noise seeds of the null cases")
    ap.add_argument("--excitation", choices=["multisine", "sweep", "stepped_sine", "noise", "impedance"],
                    help="with --make-datasets: steady multisine periods (the default), a sweep, stepped sine (a "
                    "damper's clamp gliding between its steps) or band-limited noise from rest, or (--model damper) an "
                    "impedance test; with --campaign: every case's excitation (default: drawn per case)")
    ap.add_argument("--record-s", type=float, help="with --make-datasets or --campaign: the length [s] of a sweep, "
                    "stepped-sine or noise record (default: 35 s; a campaign's 6 s)")
    ap.add_argument("--record", nargs="+", metavar="OUTPUT", help="with --make-datasets: the outputs recorded "
                    "(default: displacements; e.g. a, or acc_x1 acc_x2)")
    ap.add_argument("--campaign", type=count, metavar="N", help="validation campaign: draw N random cases of --model "
                    "(effects, pairs, nulls; strengths, loop shapes, excitation, sensors; a damper's geometry), "
                    "write and diagnose each, summarise (confusion matrix, detection limit, false alarms) in "
                    "OUT/summary.md; resumes")
    ap.add_argument("--campaign-seed", type=int, default=0, help="with --campaign: the draw's seed")
    ap.add_argument("--follow-up", action="store_true", help="with --campaign: each case whose report is not "
                    "decisive runs the test the report proposes on its truth and is diagnosed again; the summary "
                    "gives the verdicts before and after and the tests' length")
    ap.add_argument("--calibrate", action="store_true", help="with --campaign: its hit rates become the confidence "
                    "every later report of the same --model with the same settings (--config) states (stored in the "
                    "package: pyfit/gap/calibration.json, one calibration per family and set of settings)")
    ap.add_argument("--scheduler", help="with --campaign: a Dask scheduler address (default: a LocalCluster of "
                                        "--workers processes, 2 if not given)")
    ap.add_argument("--motion", default="xva", help="with --make-datasets --model damper: which of the clamp's "
                                                    "x, v, a are recorded (e.g. x)")


def run(args, ap) -> int:
    """Dispatch to the dataset writer, the case runner, the impedance or the measurement diagnosis."""
    from pyfit.gap import campaign, cases, datasets
    from pyfit.gap.dataset_check import check_dataset, check_text
    from pyfit.gap.diagnose import diagnose, load_config
    from pyfit.gap.impedance_gap import diagnose_impedance
    from pyfit.io import benchmark_data
    from pyfit.io.nominal import load_nominal
    from pyfit.io.schema import ConfigError

    try:
        if args.make_datasets:
            style = datasets.LabStyle(args.excitation or "multisine", tuple(args.record) if args.record else None,
                                      args.motion, args.record_s or datasets.LabStyle.record_s)
            base = load_nominal(args.nominal).fixed if args.nominal else None  # uncertain ones: FMU defaults
            for path in datasets.write_cases(args.make_datasets, args.model, args.seeds, style=style, base=base):
                print(path)
            return 0
        if args.campaign:
            campaign.run(args.campaign, args.out, args.fmus, args.campaign_seed, args.workers or 2, args.scheduler,
                         args.record_s or campaign.RECORD_S, calibrate=args.calibrate, model=args.model,
                         config=args.config, excitation=args.excitation, follow=args.follow_up)
            print((pathlib.Path(args.out) / "summary.md").read_text())
            return 0
        cfg = load_config(args.config) if args.config else None
        if args.cases:
            cases.run_cases(args.cases, args.out, cfg, args.model, args.fmus, args.workers, args.nominal)
            print((pathlib.Path(args.out) / "summary.md").read_text())
            return 0
        if args.impedance:
            report = diagnose_impedance(args.impedance, args.out, cfg, args.fmus, args.nominal, args.uncertainty,
                                        args.workers)
        else:
            if args.benchmark:
                args.data = benchmark_data.write_dataset(pathlib.Path(args.out) / "data")
            if not args.data:
                ap.error("--data is required (or --impedance, --benchmark, --make-datasets, --cases)")
            if args.check:
                text = check_text(check_dataset(args.model, args.data, args.nominal, cfg, args.fmus, args.candidates))
                print(text)
                pathlib.Path(args.out).mkdir(parents=True, exist_ok=True)
                (pathlib.Path(args.out) / "check.md").write_text(text + "\n")
                return 0
            report = diagnose(args.model, args.data, args.out, cfg, args.fmus, args.workers, nominal=args.nominal,
                              candidates=args.candidates)
    except (ConfigError, ValueError, OSError) as exc:  # OSError: a file not found, a scheduler not answering
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(json.dumps({"verdict": report.verdict.value, "chosen_effects": list(report.chosen)}, indent=1))
    print(f"report: {pathlib.Path(args.out) / 'report.md'}")
    return 0
