"""The diagnosis's fits run in workers and stored as they finish (OUT/fits/<name>.json with the run's key), so
that an interrupted diagnosis resumes from them."""
from __future__ import annotations

import dataclasses
import functools
import json
import pathlib

import threadpoolctl

from pyfit.gap.attribute import Fit, run_fit
from pyfit.runtime.batch import map_tasks


def on_one_blas_thread(func):
    """`func` run with the BLAS libraries on one thread (threadpoolctl): a multi-threaded BLAS rounds by its thread
    count, and a multistart least squares amplifies a last-digit difference into another path, so the same files
    gave another verdict diagnosed alone than on a Dask worker (which starts with one BLAS thread). A diagnosis
    and each fit it runs in a worker process hold to it."""
    @functools.wraps(func)
    def run(*args, **kwargs):
        with threadpoolctl.threadpool_limits(limits=1, user_api="blas"):
            return func(*args, **kwargs)
    return run


@on_one_blas_thread
def fit_and_store(job) -> Fit:
    """Run one fit (in a worker) and store it at once, so an interrupted diagnosis keeps it. A job (task, path,
    key, *stages) may carry stages: fits run first, whose results the fit then also starts from (their evaluations
    and wall time are counted in the fit's)."""
    task, path, key, *stages = job
    staged = [run_fit(stage) for stage in stages]
    fit = run_fit(dataclasses.replace(task, alternatives=task.alternatives + tuple(
        {n: s.params[n] for n in task.start} for s in staged)))
    fit = dataclasses.replace(fit, evaluations=fit.evaluations + sum(s.evaluations for s in staged),
                              wall_s=fit.wall_s + sum(s.wall_s for s in staged))
    pathlib.Path(path).write_text(json.dumps({"key": key, "fit": fit.to_json()}, indent=1))
    return fit


def stored(path: pathlib.Path, key: str) -> Fit | None:
    """The fit stored at `path` by a run with this key, else None."""
    if path.is_file():
        d = json.loads(path.read_text())
        if d.get("key") == key:
            return Fit(**d["fit"])
    return None


def fits_of(jobs, key: str, alone: int, workers, progress: bool, desc: str) -> dict[str, Fit]:
    """The fits of `jobs` ((task, path, *stages): see fit_and_store) by their effect's name: each stored one read
    from its path, the others run (in workers: run_fits)."""
    done = {job[0].effect: stored(pathlib.Path(job[1]), key) for job in jobs}
    todo = [(task, str(path), key, *stages) for task, path, *stages in jobs if done[task.effect] is None]
    for fit in run_fits(todo, alone, workers, progress, desc):
        done[fit.effect] = fit
    return done


def run_fits(jobs, alone: int, workers, progress: bool, desc: str) -> list[Fit]:
    """fit_and_store of each job (task, path, key, *stages) in workers, each fit simulating its records on up to
    `alone` threads (the cores a fit running alone has): the fits that run while others end take up the cores
    those leave idle. A fit's result does not depend on its threads."""
    jobs = [(dataclasses.replace(task, threads=alone), path, key,
             *(dataclasses.replace(stage, threads=alone) for stage in stages)) for task, path, key, *stages in jobs]
    return map_tasks(fit_and_store, jobs, workers=workers, progress=progress, desc=desc)


def fit_once(task, path: pathlib.Path, key: str) -> Fit:
    """The fit stored at `path` by a run with this key, else `task` run here and stored there."""
    return stored(path, key) or fit_and_store((task, str(path), key))
