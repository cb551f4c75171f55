"""The measured-input path into an FMU (pyfit.runtime.drive, FmuRunner's input rows): the shortcuts a fit's many
simulations take (inputs upsampled once, no interpolation on the communication grid) give the same values, to
the bit, as the general computation, and never a stale one."""
import numpy as np

from pyfit.runtime import drive
from pyfit.runtime.fmu import input_rows, interpolated_rows


def _noise(n, seed=0):
    return {"u": np.random.default_rng(seed).standard_normal(n), "v": np.random.default_rng(seed + 1).standard_normal(n)}


def test_inputs_on_the_communication_grid_give_the_interpolated_rows_to_the_bit():
    t = np.arange(7001) / 2000.0  # 2 kHz, as a 500 Hz record upsampled by 4
    table = np.vstack(list(_noise(len(t)).values()))
    fast, general = input_rows(table, t, t), interpolated_rows(table, t, t)
    assert all(np.array_equal(a, b) for a, b in zip(fast, general))
    # off the grid: interpolated (halfway between samples, the mean of the two, within the rounding of the
    # halfway times: an ulp of t, 4e-16 s, of a 5e-4 s segment whose ends differ by up to ~8)
    mid = t[:-1] + 0.25e-3
    u_mid, _ = input_rows(table, t, mid)
    assert np.allclose(u_mid, 0.5 * (table[:, :-1] + table[:, 1:]), rtol=0, atol=1e-11)


def test_remembered_upsampling_equals_a_fresh_one_and_an_input_changed_in_place_is_upsampled_anew():
    inputs = _noise(900, seed=3)
    remembered = {}
    for spp, lead in ((None, 0), (300, 1)):  # a cubic spline (from rest); a periodic record's band-limited period
        fresh, skip = drive.fine_inputs(inputs, 4, spp, lead)
        first, skip1 = drive.remembered_fine_inputs(inputs, 4, spp, lead)
        again, _ = drive.remembered_fine_inputs({k: v.copy() for k, v in inputs.items()}, 4, spp, lead)
        assert again is first and skip1 == skip  # equal values: the same result, not upsampled again
        assert all(np.array_equal(first[k], fresh[k]) for k in inputs)
        remembered[spp] = first
    inputs["u"][100] += 1.0  # changed in place: not the one remembered
    changed, _ = drive.remembered_fine_inputs(inputs, 4)
    assert changed is not remembered[None]
    assert np.array_equal(changed["u"], drive.fine_inputs(inputs, 4)[0]["u"])
    assert np.abs(changed["u"] - remembered[None]["u"]).max() > 0.5


def test_the_memory_forgets_the_least_recently_used_beyond_its_bytes():
    from pyfit.runtime.memo import BoundedMemo, digest

    memo = BoundedMemo(max_bytes=3000)
    for k in "abc":
        memo.put(k, k.upper(), 1000)
    assert memo.get("a") == "A"  # used: now the most recent
    memo.put("d", "D", 1000)  # 4000 bytes: the least recently used ("b") goes
    assert [memo.get(k) for k in "abcd"] == ["A", None, "C", "D"]
    memo.put("huge", "H", 3001)  # larger than the whole memory: not kept, nothing forgotten for it
    assert memo.get("huge") is None and memo.get("c") == "C"
    # keys: by value and exact bits (-0.0 and 0.0 run an FMU apart; an array's dtype and shape count)
    assert digest({"k": 1.0}, np.arange(3.0)) == digest({"k": 1.0}, np.arange(3.0))
    assert digest(0.0) != digest(-0.0) and digest(np.zeros(4)) != digest(np.zeros((2, 2)))


def test_a_run_made_before_is_returned_not_made_again_and_a_failed_one_is_made_again(runner, monkeypatch):
    from pyfit.runtime.fmu import FmuRunner

    sdof = runner("SDOFBoucWen")
    runs = []
    real = FmuRunner.simulate
    monkeypatch.setattr(FmuRunner, "simulate", lambda self, *a, **k: runs.append(1) or real(self, *a, **k))
    u = {"u": 20.0 * np.sin(2 * np.pi * 30.0 * np.arange(500) / 500.0)}
    params = {"exc_type": 0, "alpha": 0.0, "k3": 2.5e8}
    first = drive.drive(sdof, u, 500.0, ["y"], params)
    again = drive.drive(sdof, {"u": u["u"].copy()}, 500.0, ["y"], dict(reversed(list(params.items()))))
    assert len(runs) == 1 and np.array_equal(first["y"], again["y"])
    again["y"][:] = 0.0  # a copy: what the memory holds is unchanged
    assert np.array_equal(drive.drive(sdof, u, 500.0, ["y"], params)["y"], first["y"]) and len(runs) == 1
    other = drive.drive(sdof, u, 500.0, ["y"], {**params, "k3": 2.6e8})  # another parameter set: run
    assert len(runs) == 2 and not np.array_equal(other["y"], first["y"])
    # a softening spring past its escape deflection (sqrt(k / |k3|) = 3e-5 m; the static one is 2e-4 m)
    # diverges: a failure, made again each time (never remembered)
    bad = {**params, "k3": -1e14}
    assert not drive.drive(sdof, u, 500.0, ["y"], bad).ok and not drive.drive(sdof, u, 500.0, ["y"], bad).ok
    assert len(runs) == 4


def test_a_runner_named_by_a_relative_path_runs_after_the_working_directory_changes(fmu_dir, tmp_path, monkeypatch):
    """fmpy changes the working directory while it loads an FMU's library; a fit that simulates its records on
    several threads loads one runner per thread, so another thread's relative path must not depend on the working
    directory at that moment: a runner keeps the absolute path of the file it was given."""
    from pyfit.runtime.fmu import FmuRunner

    monkeypatch.chdir(fmu_dir.parent)
    sdof = FmuRunner(f"{fmu_dir.name}/SDOFBoucWen.fmu")
    monkeypatch.chdir(tmp_path)  # as fmpy's chdir in another thread does
    u = {"u": 20.0 * np.sin(2 * np.pi * 30.0 * np.arange(500) / 500.0)}
    res = drive.drive(sdof, u, 500.0, ["y"], {"exc_type": 0})
    assert res.ok and np.max(np.abs(res["y"])) > 1e-5  # 20 N at 30 Hz on the benchmark's 2 kg, 5e4 N/m oscillator
    sdof.close()
