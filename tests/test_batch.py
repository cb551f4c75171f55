"""Batch runs: serial, process pool and Dask give identical results; failures stay local; no leaks."""
import os
import pathlib
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from pyfit.runtime.batch import RunSpec, run_batch, run_one
from pyfit.runtime.fmu import FmuRunner


def _sweep_specs(fmu):
    return [RunSpec(str(fmu), 1.0, 1e-3, ("y", "z"), {"exc_type": 1, "exc_f_start": f, "exc_amplitude": a},
                    label=f"{f}Hz_{a}N")
            for f in (5.0, 15.0, 30.0, 45.0) for a in (30.0, 60.0, 90.0, 120.0)]


def test_serial_pool_and_dask_give_identical_results(fmu_dir):
    from distributed import Client, LocalCluster

    specs = _sweep_specs(fmu_dir / "SDOFBoucWen.fmu")
    assert len(specs) == 16
    serial = run_batch(specs, workers=1, progress=False)
    pool = run_batch(specs, workers=2, progress=False)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        dask = run_batch(specs, scheduler=client, progress=False)
    for a, b, c in zip(serial, pool, dask):
        assert a.ok and b.ok and c.ok
        for o in ("y", "z"):
            np.testing.assert_array_equal(a[o], b[o])
            np.testing.assert_array_equal(a[o], c[o])
    # the runs differ from each other (a real sweep, not one result repeated)
    assert len({round(float(np.max(np.abs(r["y"]))), 12) for r in serial}) == 16


def test_one_failing_run_does_not_stop_the_batch(fmu_dir, tmp_path):
    good = _sweep_specs(fmu_dir / "SDOFBoucWen.fmu")[:3]
    bad_param = RunSpec(str(fmu_dir / "SDOFBoucWen.fmu"), 1.0, 1e-3, ("y",), {"no_such_parameter": 1.0})
    missing = RunSpec(str(tmp_path / "missing.fmu"), 1.0, 1e-3, ("y",))
    # a diverging run: a negative stiffness makes the mass run away like exp(316 t) until it overflows
    diverging = RunSpec(str(fmu_dir / "SDOFBoucWen.fmu"), 3.0, 1e-3, ("y",), {"k": -2e5, "alpha": 0.0})
    res = run_batch(good + [bad_param, missing, diverging], workers=2, progress=False)
    assert all(r.ok for r in res[:3])
    assert not res[3].ok and "no_such_parameter" in res[3].message and "valid parameters" in res[3].message
    assert not res[4].ok and "missing.fmu" in res[4].message
    assert not res[5].ok and "diverged" in res[5].message


def _rss_bytes():
    with open(f"/proc/{os.getpid()}/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def test_three_hundred_reset_runs_in_one_process_without_memory_growth(fmu_dir, measured):
    # short CI version of bench/fmu_soak.py (1000 runs)
    runner = FmuRunner(str(fmu_dir / "SDOFBoucWen.fmu"))
    rss = []
    for i in range(300):
        r = runner.simulate(0.05, 1e-3, ["y"], {"exc_type": 1, "exc_f_start": 10.0 + i % 7})
        assert r.ok
        if i == 99:
            rss.append(_rss_bytes())
    rss.append(_rss_bytes())
    runner.close()
    measured("300 reset runs of one FMU in one process: resident memory growth after run 100", rss[1] / rss[0] - 1,
             0.05)


def test_run_one_reuses_the_instance(fmu_dir, monkeypatch):
    from pyfit.runtime import batch
    from pyfit.runtime.fmu import FmuRunner

    made = []
    real = FmuRunner.instance
    monkeypatch.setattr(FmuRunner, "instance", lambda self: made.append(id(self._state.get("fmu"))) or real(self))
    monkeypatch.setattr(batch, "_RUNNERS", {})
    spec = _sweep_specs(fmu_dir / "SDOFBoucWen.fmu")[0]
    a, b = run_one(spec), run_one(spec)
    np.testing.assert_array_equal(a["y"], b["y"])
    # one runner in this process, and the second run found the instance the first one loaded
    assert len(batch._RUNNERS) == 1 and len(made) == 2 and made[0] == id(None) and made[1] != id(None)


_SLEEPING_BATCH = '''
import os, pathlib, sys, time
from pyfit.runtime.batch import map_tasks


def task(folder):
    pathlib.Path(folder, str(os.getpid())).write_text("")
    time.sleep(300)


if __name__ == "__main__":
    map_tasks(task, [sys.argv[1]] * 4, workers=2, progress=False)
'''


def _alive(pid: int) -> bool:
    """Running (a zombie, exited but not yet reaped, counts as gone; so does one that exits while its status is
    read, which the kernel reports as ProcessLookupError rather than FileNotFoundError)."""
    try:
        return pathlib.Path(f"/proc/{pid}/status").read_text().split("State:")[1].split()[0] != "Z"
    except (OSError, IndexError):
        return False


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGKILL], ids=["SIGTERM", "SIGKILL"])
def test_a_killed_batch_leaves_no_worker_processes(tmp_path, sig, measured):
    script, pids = tmp_path / "batch.py", tmp_path / "pids"
    script.write_text(_SLEEPING_BATCH)
    pids.mkdir()
    root = pathlib.Path(__file__).parents[1]
    proc = subprocess.Popen([sys.executable, str(script), str(pids)], cwd=root,
                            env={**os.environ, "PYTHONPATH": str(root)})
    deadline = time.monotonic() + 120
    while len(list(pids.iterdir())) < 2:  # both workers are inside a task
        assert time.monotonic() < deadline and proc.poll() is None, "the batch did not start its two workers"
        time.sleep(0.1)
    workers = [int(p.name) for p in pids.iterdir()]
    assert all(_alive(w) for w in workers)
    t0 = time.monotonic()
    proc.send_signal(sig)
    proc.wait(timeout=30)
    while any(_alive(w) for w in workers) and time.monotonic() - t0 < 20:
        time.sleep(0.05)
    measured(f"batch killed with {signal.Signals(sig).name} inside 300 s tasks: time until no worker runs [s]",
             time.monotonic() - t0, 5.0)
    assert not any(_alive(w) for w in workers)


def test_fmus_loaded_from_many_threads_leave_the_working_directory_alone(fmu_dir):
    """fmpy moves the process into the FMU's binaries folder while it loads the library; unguarded, two threads
    loading at once can leave the process in an extracted folder that close() deletes."""
    from concurrent.futures import ThreadPoolExecutor

    here = os.getcwd()

    def load_and_close(_):
        runner = FmuRunner(str(fmu_dir / "SDOFBoucWen.fmu"))
        runner.instance()
        runner.close()

    with ThreadPoolExecutor(8) as pool:
        list(pool.map(load_and_close, range(32)))
    assert os.getcwd() == here


def test_pool_workers_start_with_the_task_module_already_imported(tmp_path):
    """A local pool's workers fork from a server that imported the task's module once (map_tasks sets the
    forkserver's preload): a module that records the process it was imported in reports the server in every
    worker, neither the worker itself (each importing it again) nor the parent. Run in a fresh interpreter: a
    process's forkserver reads its preload list only when it starts."""
    (tmp_path / "where_imported.py").write_text(
        "import os\nIMPORTED_IN = os.getpid()\n\n\ndef where(_):\n    return IMPORTED_IN, os.getpid()\n")
    script = ("import os\nfrom where_imported import where\nfrom pyfit.runtime.batch import map_tasks\n"
              "print(os.getpid(), *(f'{a}:{b}' for a, b in map_tasks(where, range(4), workers=2, progress=False)))\n")
    # on the module search path of every process (the server imports by name from the path it starts with)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(tmp_path), os.environ.get("PYTHONPATH")]))}
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120, check=True,
                         env=env)
    parent, *runs = out.stdout.split()
    pairs = [tuple(r.split(":")) for r in runs]
    assert len(pairs) == 4
    servers = {imported for imported, _ in pairs}
    assert len(servers) == 1 and parent not in servers, (parent, pairs)
    assert all(imported != worker for imported, worker in pairs), pairs
