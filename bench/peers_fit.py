"""The same FMU fit by NNO + polish and by the tools an engineer would pick instead (CMA-ES, scipy's
differential evolution, multi-start least squares, the direct GA, estim8, ModestPy), on three problems: the
Bouc-Wen benchmark (configs/boucwen_benchmark.toml), the SDOF wide study (configs/sdof_nno_wide_log.toml) and
the damper joint study (configs/damper_joint.toml). Same target, bounds and objective (where the tool takes
one), NNO's budget of FMU evaluations and its wall time for every peer (whichever ends first), 5 seeds; what each tool's answer recovers (every
parameter within 1 %), after how many evaluations and seconds, and at NNO's evaluations and wall time.
The peers are an optional extra: pip install -e ".[peers]".

    python bench/peers_fit.py            # 3 problems x 5 seeds on 2 cores (the wall time is in its output)
    python bench/peers_fit.py --quick    # the SDOF wide and damper studies, 1 seed, a few minutes
"""
import argparse
import dataclasses
import json
import pathlib
import sys
import warnings
import time
from concurrent.futures import ProcessPoolExecutor, as_completed

ROOT = pathlib.Path(__file__).resolve().parents[1]

from pyfit.fit import peers
from pyfit.fit.fitting import ensure_target
from pyfit.io.fit_config import load_fit
from pyfit.report.generated import BenchReport

PROBLEMS = ("boucwen_benchmark", "sdof_nno_wide_log", "damper_joint")
QUICK = ("sdof_nno_wide_log", "damper_joint")


def _one(job):
    problem, seed, fmus = job
    warnings.filterwarnings("ignore")
    import torch
    torch.set_num_threads(1)
    return peers.compare(load_fit(ROOT / "configs" / f"{problem}.toml"), pathlib.Path(fmus), seed, problem)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="two problems, one seed")
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--fmus", default=str(ROOT / "fmus"))
    args = ap.parse_args()
    problems, seeds = (QUICK, 1) if args.quick else (PROBLEMS, args.seeds)
    for problem in problems:  # the synthetic targets, once, before the workers start
        ensure_target(load_fit(ROOT / "configs" / f"{problem}.toml"))
    report = BenchReport("peers_fit_quick" if args.quick else "peers_fit", ROOT)
    jobs = [(p, s, args.fmus) for p in problems for s in range(seeds)]
    t0, runs = time.perf_counter(), []
    with ProcessPoolExecutor(args.workers) as pool:
        for done in as_completed([pool.submit(_one, job) for job in jobs]):
            runs += done.result()
            print(f"{runs[-1].problem} seed {runs[-1].seed} done ({time.perf_counter() - t0:.0f} s)", flush=True)
    command = "python bench/peers_fit.py" + (" --quick" if args.quick else "") + \
        (f" --seeds {args.seeds}" if not args.quick and args.seeds != 5 else "")
    report.line(f"{len(problems)} problems x {seeds} seeds; command: {command}; {args.workers} worker processes, wall "
                f"{(time.perf_counter() - t0) / 60:.0f} min; Python {sys.version.split()[0]}")
    (report.path.with_suffix(".json")).write_text(json.dumps([dataclasses.asdict(r) for r in runs], indent=1))
    for problem in problems:
        header, rows = peers.table([r for r in runs if r.problem == problem])
        report.table(f"{problem} (configs/{problem}.toml)", header, rows)


if __name__ == "__main__":
    main()
