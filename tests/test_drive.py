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
