"""Batch fitting: every config x repeat, in parallel, resumable, with a summary across repeats."""
from __future__ import annotations

import json
import pathlib
import traceback

import numpy as np

from pyfit.runtime.batch import map_tasks
from pyfit.io.fit_config import load_fit
from pyfit.fit.fitting import ensure_target, run_fit
from pyfit.runtime.examples import ensure_fmu
from pyfit.runtime.sweep import fmu_interface


def _parameters_of(fmu_dir):
    return lambda model: fmu_interface(ensure_fmu(model, fmu_dir)).parameters


def run_dir(out: pathlib.Path, config: pathlib.Path, seed: int) -> pathlib.Path:
    return out / config.stem / f"seed_{seed}"


def _task(task):
    """One fit in a worker: (config path, seed, fmu dir, out dir, GA stop value, nominal) -> result summary or
    the error."""
    config, seed, fmu_dir, out, stop_at, nominal = task
    try:
        cfg = load_fit(config, _parameters_of(fmu_dir), nominal)
        result = run_fit(cfg, fmu_dir, run_dir(out, config, seed), seed, stop_at)
        return {k: v for k, v in result.items() if k not in ("history", "config_text")}
    except Exception as exc:  # one failing fit does not stop the batch
        return {"config": str(config), "seed": seed, "error": f"{type(exc).__name__}: {exc}",
                "traceback": traceback.format_exc()}


def fit_batch(configs: list[pathlib.Path], repeats: int, out: pathlib.Path, fmu_dir: pathlib.Path,
              workers: int | None = None, scheduler=None, progress: bool = True, first_seed: int = 0,
              nominal=None) -> list[dict]:
    """Run every config x seed not finished yet (a result.json marks a finished run); write summary.md.
    nominal: a described system (pyfit.io.nominal.NominalModel) whose parameters every fit keeps fixed."""
    configs = [pathlib.Path(c) for c in configs]
    cfgs = [load_fit(c, _parameters_of(fmu_dir), nominal) for c in configs]  # validate all before running any
    for cfg in cfgs:
        ensure_target(cfg)  # made once here, not raced by the workers
    for cfg in cfgs:
        ensure_fmu(cfg.model, fmu_dir)
    # GA baselines run after the other methods: they stop once they reach the NNO median on the same objective
    results = []
    for phase in ("other", "ga"):
        tasks = []
        for c, cfg in zip(configs, cfgs):
            if (cfg.method == "ga") != (phase == "ga"):
                continue
            stop_at = nno_goal(results, cfg.problem_key()) if phase == "ga" else None
            for seed in range(first_seed, first_seed + repeats):
                f = run_dir(out, c, seed) / "result.json"
                if f.is_file():
                    r = json.loads(f.read_text())
                    results.append({k: v for k, v in r.items() if k not in ("history", "config_text")})
                else:
                    tasks.append((c, seed, fmu_dir, out, stop_at, nominal))
        results += map_tasks(_task, tasks, workers, scheduler, progress, "fits")
    out.mkdir(parents=True, exist_ok=True)
    (out / "summary.md").write_text(summary_markdown(results))
    return results


def describe_run(r: dict) -> str:
    """One line per fit: what it reached, and against a known truth the largest relative error."""
    name = f"{pathlib.Path(r['config']).stem} seed {r['seed']}"
    if "error" in r:
        return f"{name}: failed: {r['error']}"
    text = f"{name}: objective {r['objective']:.3g} after {r['true_evaluations']} evaluations, {r['wall_s']:.0f} s"
    if r.get("impedance_error"):
        text += (f"; impedance within {r['impedance_error']['magnitude_percent_max']:.2f} % in |Z| and "
                 f"{r['impedance_error']['phase_deg_max']:.2f}° in phase")
    if r.get("recovery"):
        worst = max(abs(v) for v in r["recovery"].values())
        text += ("; relative error against the truth " + ", ".join(f"{k} {100 * v:+.2f} %" for k, v in r["recovery"].items())
                 + f" (largest {100 * worst:.2f} %)")
    return text


def evaluations_to_reach(best_so_far: list[float], target: float, cap: int) -> int:
    """True evaluations until the best-so-far error first reaches target; cap if it never does."""
    hit = np.nonzero(np.asarray(best_so_far) <= target)[0]
    return int(hit[0]) + 1 if len(hit) else cap


def _nno_runs(results, problem):
    return [r for r in results if "error" not in r and r["method"] in ("nno", "nno+polish")
            and r.get("problem") == problem]


def nno_goal(results: list[dict], problem: str) -> float | None:
    """Median final objective of the NNO runs on this problem (FitConfig.problem_key; None if there are none)."""
    runs = _nno_runs(results, problem)
    return float(np.median([r["objective"] for r in runs])) if runs else None


def nno_vs_ga_markdown(results: list[dict]) -> list[str]:
    """For every problem (FitConfig.problem_key) with both NNO (or NNO + polish) and GA runs: the evaluations
    each GA run needed to reach the median final objective of NNO at its budget (a run that never reaches it
    counts as its budget)."""
    ok = [r for r in results if "error" not in r and "problem" in r]
    lines = []
    for problem in sorted({r["problem"] for r in ok}):
        nno_runs = _nno_runs(ok, problem)
        ga_runs = [r for r in ok if r["problem"] == problem and r["method"] == "ga"]
        if not nno_runs or not ga_runs:
            continue
        goal = nno_goal(ok, problem)
        names = sorted({pathlib.Path(r["config"]).stem for r in nno_runs + ga_runs})
        n_nno = float(np.median([r["true_evaluations"] for r in nno_runs]))
        counts = [evaluations_to_reach(r["global_best_so_far"], goal, len(r["global_best_so_far"])) for r in ga_runs]
        n_ga = float(np.median(counts))
        lines += ["", f"NNO vs GA ({' vs '.join(names)}, same problem): target = NNO median final objective "
                      f"{goal:.4g}", "",
                  "| NNO evaluations (median) | GA evaluations to reach the target, per seed | GA median | NNO / GA |",
                  "|---|---|---|---|",
                  f"| {n_nno:g} | {', '.join(str(c) for c in counts)} | {n_ga:g} | {n_nno / n_ga:.3f} |"]
    return lines


def summary_markdown(results: list[dict]) -> str:
    """Median and spread across repeats, per config and method."""
    lines = ["| config | method | runs | objective median [min, max] | true evaluations median | "
             "wall time median [s] | band error % (median) | recovery (median relative error) |",
             "|---|---|---|---|---|---|---|---|"]
    groups: dict = {}
    for r in results:
        groups.setdefault((pathlib.Path(r["config"]).stem, r.get("method", "?")), []).append(r)
    for (name, method), rs in sorted(groups.items()):
        ok = [r for r in rs if "error" not in r]
        if not ok:
            lines.append(f"| {name} | {method} | 0 of {len(rs)} | failed: {rs[0]['error'][:80]} | | | | |")
            continue
        obj = np.array([r["objective"] for r in ok])
        ev = np.median([r["true_evaluations"] for r in ok])
        wall = np.median([r["wall_s"] for r in ok])
        band = {k: np.median([r["band_error_percent"][k] for r in ok]) for k in ok[0].get("band_error_percent", {})}
        rec = {k: np.median([abs(r["recovery"][k]) for r in ok]) for k in ok[0].get("recovery", {})}
        lines.append(f"| {name} | {method} | {len(ok)} of {len(rs)} | {np.median(obj):.3g} [{obj.min():.3g}, "
                     f"{obj.max():.3g}] | {ev:g} | {wall:.1f} | "
                     + ", ".join(f"{k}: {v:.2f}" for k, v in band.items()) + " | "
                     + ", ".join(f"{k}: {100 * v:.2f} %" for k, v in rec.items()) + " |")
    recovered = sorted((r for r in results if "error" not in r and r.get("recovery")),
                       key=lambda r: (pathlib.Path(r["config"]).stem, r["seed"]))
    if recovered:
        lines += ["", "Per run, relative error against the truth of the synthetic target:", "",
                  "| config | seed | objective | true evaluations | wall time [s] | relative error |", "|---|---|---|---|---|---|"]
        lines += [f"| {pathlib.Path(r['config']).stem} | {r['seed']} | {r['objective']:.3g} | {r['true_evaluations']} | "
                  f"{r['wall_s']:.1f} | " + ", ".join(f"{k}: {100 * v:+.3f} %" for k, v in r["recovery"].items()) + " |"
                  for r in recovered]
    lines += nno_vs_ga_markdown(results)
    bench = [r for r in results if r.get("benchmark_rms_db")]
    if bench:
        lines += ["", "Bouc-Wen benchmark, RMS error on the official validation signals [dB re 1 m]:", "",
                  "| config | seed | multisine | sinesweep |", "|---|---|---|---|"]
        lines += [f"| {pathlib.Path(r['config']).stem} | {r['seed']} | {r['benchmark_rms_db']['multisine']:.1f} | "
                  f"{r['benchmark_rms_db']['sinesweep']:.1f} |" for r in sorted(bench, key=lambda r: r["seed"])]
    failed = [r for r in results if "error" in r]
    if failed:
        lines += ["", "Failed runs:"] + [f"- {pathlib.Path(r['config']).stem} seed {r['seed']}: {r['error']}"
                                         for r in failed]
    return "\n".join(lines) + "\n"
