"""Run many FMU simulations: serially, on a local process pool, or on a Dask cluster.

A RunSpec holds only paths, settings and arrays, so it pickles; each worker process keeps one
FmuRunner per FMU (instantiated once, reset between runs). A run that fails returns
SimulationResult(ok=False) with the reason; the other runs of the batch go on.
"""
from __future__ import annotations

import concurrent.futures as cf
import multiprocessing
import os
import signal
import sys
import threading
import time
import pathlib
from dataclasses import dataclass, field

import numpy as np

from pyfit.runtime.fmu import FmuRunner, SimulationResult

_RUNNERS: dict[tuple[str, str], FmuRunner] = {}  # per process


@dataclass(frozen=True)
class RunSpec:
    """One simulation of one FMU (times in s, parameters by FMU variable name)."""

    fmu: str
    stop_time: float
    output_interval: float
    outputs: tuple[str, ...]
    params: dict = field(default_factory=dict)
    interface: str = "CoSimulation"
    tolerance: float = 1e-8
    inputs: dict | None = None  # name -> samples at input_time
    input_time: np.ndarray | None = None
    label: str = ""

    def __hash__(self):
        return hash((self.fmu, self.label, self.stop_time))


def run_one(spec: RunSpec) -> SimulationResult:
    """Run one spec in this process (reusing this process's FmuRunner for the FMU); never raises."""
    key = (str(spec.fmu), spec.interface)
    try:
        if key not in _RUNNERS:
            if not pathlib.Path(spec.fmu).is_file():
                raise FileNotFoundError(f"{spec.fmu}: FMU file not found")
            _RUNNERS[key] = FmuRunner(str(spec.fmu), spec.interface)
        return _RUNNERS[key].simulate(spec.stop_time, spec.output_interval, list(spec.outputs), spec.params,
                                      spec.inputs, spec.input_time, spec.tolerance)
    except Exception as exc:  # a bad spec fails this run only
        return SimulationResult(np.array([]), {}, ok=False, message=f"{type(exc).__name__}: {exc}")


def _progress(total, enabled, desc):
    from tqdm import tqdm

    return tqdm(total=total, disable=not enabled, desc=desc, unit="run")


def _connect(address: str):
    """A Dask client of the scheduler at `address`; ConnectionError naming it when none answers."""
    from distributed import Client

    try:
        return Client(address)
    except (OSError, ValueError) as exc:  # nothing listening, a timeout, or an address Dask cannot parse
        raise ConnectionError(f"no Dask scheduler answered at {address} ({exc}): start one (`dask scheduler`, "
                              f"then `dask worker {address}` on each machine), or give no scheduler address to run "
                              "on this machine's cores") from exc


def map_tasks(fn, items: list, workers: int | None = None, scheduler=None, progress: bool = True,
              desc: str = "tasks") -> list:
    """fn(item) for every item, results in order: serially (workers=1), on a local process pool
    (workers=None: one per core), or on a Dask cluster (scheduler address or distributed.Client).
    fn must be picklable (a module-level function) and should not raise."""
    items = list(items)
    results: list = [None] * len(items)
    bar = _progress(len(items), progress and len(items) > 1, desc)
    try:
        if scheduler is not None:
            from distributed import Client, as_completed

            client = scheduler if isinstance(scheduler, Client) else _connect(scheduler)
            futures = {client.submit(fn, it, pure=False): i for i, it in enumerate(items)}
            for fut in as_completed(futures):
                results[futures[fut]] = fut.result()
                bar.update()
            if client is not scheduler:
                client.close()
        elif workers == 1 or len(items) == 1:
            for i, it in enumerate(items):
                results[i] = fn(it)
                bar.update()
        else:
            # forkserver: workers fork from a clean server process, never from this one, whose threads
            # (torch, BLAS) could be holding locks at the moment of a fork
            method = "forkserver" if sys.platform.startswith("linux") else "spawn"
            ctx = multiprocessing.get_context(method)
            module = getattr(fn, "__module__", None)  # None for some callables (a numpy ufunc)
            if method == "forkserver" and module not in (None, "__main__"):
                # the server imports fn's module once (numpy, scipy, fmpy with it): the workers it forks have it
                # instead of importing it each (bench/pool_start.py). Only the server's first start reads the list.
                ctx.set_forkserver_preload([module])
            pool = cf.ProcessPoolExecutor(max_workers=workers or os.cpu_count() or 1, mp_context=ctx,
                                          initializer=_watch_parent, initargs=(os.getpid(),))
            previous = signal.signal(signal.SIGTERM, _interrupt) \
                if threading.current_thread() is threading.main_thread() else None
            try:
                futures = {pool.submit(fn, it): i for i, it in enumerate(items)}
                for fut in cf.as_completed(futures):
                    results[futures[fut]] = fut.result()
                    bar.update()
            except BaseException:  # interrupted or killed: stop the workers now, not after their tasks
                for proc in list((pool._processes or {}).values()):
                    proc.terminate()
                pool.shutdown(wait=False, cancel_futures=True)
                raise
            finally:
                pool.shutdown(wait=True)
                if previous is not None:
                    signal.signal(signal.SIGTERM, previous)
    finally:
        bar.close()
    return results


def _interrupt(signum, frame):
    """SIGTERM in the parent of a pool: unwind like Ctrl-C, so the workers are stopped."""
    raise KeyboardInterrupt(f"signal {signum}")


def _watch_parent(parent_pid: int, every_s: float = 1.0) -> None:
    """Pool worker initialiser: exit when the parent process is gone (killed with SIGKILL, which no handler
    sees), so a killed run leaves no worker processes behind."""
    def watch():
        while True:
            time.sleep(every_s)
            try:
                os.kill(parent_pid, 0)
            except ProcessLookupError:
                os._exit(1)

    threading.Thread(target=watch, daemon=True).start()


def run_batch(specs: list[RunSpec], workers: int | None = None, scheduler=None, progress: bool = True,
              desc: str = "simulations") -> list[SimulationResult]:
    """Simulate every spec (see map_tasks for workers and scheduler); results in the order of specs."""
    return map_tasks(run_one, specs, workers, scheduler, progress, desc)
