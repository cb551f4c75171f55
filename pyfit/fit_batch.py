"""Batch fitting: every config x repeat, in parallel, resumable, with a summary across repeats."""
from __future__ import annotations

import json
import pathlib
import traceback

import numpy as np

from .batch import map_tasks
from .fit_config import load_fit
from .fitting import ensure_target, run_fit
from .run_example import ensure_fmu
from .sweep import fmu_interface


def _parameters_of(fmu_dir):
    return lambda model: fmu_interface(ensure_fmu(model, fmu_dir)).parameters


def run_dir(out: pathlib.Path, config: pathlib.Path, seed: int) -> pathlib.Path:
    return out / config.stem / f"seed_{seed}"


def _task(task):
    """One fit in a worker: (config path, seed, fmu dir, out dir) -> result summary or the error."""
    config, seed, fmu_dir, out = task
    try:
        cfg = load_fit(config, _parameters_of(fmu_dir))
        result = run_fit(cfg, fmu_dir, run_dir(out, config, seed), seed)
        return {k: v for k, v in result.items() if k not in ("history", "config_text")}
    except Exception as exc:  # one failing fit does not stop the batch
        return {"config": str(config), "seed": seed, "error": f"{type(exc).__name__}: {exc}",
                "traceback": traceback.format_exc()}


def fit_batch(configs: list[pathlib.Path], repeats: int, out: pathlib.Path, fmu_dir: pathlib.Path,
              workers: int | None = None, scheduler=None, progress: bool = True, first_seed: int = 0) -> list[dict]:
    """Run every config x seed not finished yet (a result.json marks a finished run); write summary.md."""
    configs = [pathlib.Path(c) for c in configs]
    cfgs = [load_fit(c, _parameters_of(fmu_dir)) for c in configs]  # validate all before running any
    for cfg in cfgs:
        ensure_target(cfg)  # made once here, not raced by the workers
    for cfg in cfgs:
        ensure_fmu(cfg.model, fmu_dir)
    tasks, done = [], []
    for c in configs:
        for seed in range(first_seed, first_seed + repeats):
            f = run_dir(out, c, seed) / "result.json"
            if f.is_file():
                r = json.loads(f.read_text())
                done.append({k: v for k, v in r.items() if k not in ("history", "config_text")})
            else:
                tasks.append((c, seed, fmu_dir, out))
    new = map_tasks(_task, tasks, workers, scheduler, progress, "fits")
    results = done + new
    out.mkdir(parents=True, exist_ok=True)
    (out / "summary.md").write_text(summary_markdown(results))
    return results


def summary_markdown(results: list[dict]) -> str:
    """Median and spread across repeats, per config and method."""
    lines = ["# Fit summary", "", "| config | method | runs | objective median [min, max] | true evaluations median | "
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
    failed = [r for r in results if "error" in r]
    if failed:
        lines += ["", "Failed runs:"] + [f"- {pathlib.Path(r['config']).stem} seed {r['seed']}: {r['error']}"
                                         for r in failed]
    return "\n".join(lines) + "\n"
