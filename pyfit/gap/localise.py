"""Where a model misfits: NRMSE of the outputs overall and split by frequency band, amplitude level,
channel, harmonic line class (odd/even detection lines of an odd multisine) and hysteresis-loop region;
the noise floor estimated from the data itself. Plain numpy on measured and simulated signals.

All split metrics are contributions: their squares add up to the squared NRMSE of the record, so they
say where the residual's energy lies.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.signal

from pyfit.gap.simulate import Record

LOOP_REGIONS = ("centre, loading", "centre, unloading", "tips, loading", "tips, unloading")


def nrmse(sim: dict, rec: Record) -> float:
    """sqrt(mean over channels of RMS(y_sim - y)^2 / RMS(y)^2)."""
    return float(np.sqrt(np.mean([np.mean((sim[k] - y) ** 2) / np.mean(y**2) for k, y in rec.outputs.items()])))


@dataclass(frozen=True)
class ConfinedMisfit:
    """A model's held-out misfit confined to a few windows of time: the share of its squared NRMSE they hold,
    their length and the held-out records' [s], the windows (file, start [s], end [s]; adjacent ones joined) and the
    model's held-out NRMSE over the samples outside them."""

    share: float
    seconds: float
    total_seconds: float
    windows: tuple
    nrmse_rest: float


def confined_misfit(sims: dict, held: list[Record], window_s: float = 1.0, share: float = 0.8,
                    most_time: float = 0.2) -> ConfinedMisfit | None:
    """Whether a model's held-out misfit (its simulations `sims`, record name -> outputs) lies for at least `share`
    of its squared NRMSE in windows of window_s seconds that together last at most `most_time` of the held-out
    records: the fewest such windows, largest first, and the NRMSE over the rest; None when it is spread wider (or
    a simulation failed)."""
    if any(sims.get(rec.name) is None for rec in held):
        return None
    windows = []  # (contribution to the squared held-out NRMSE, record, first sample, end sample)
    for rec in held:
        sim, n, per = sims[rec.name], rec.n, max(1, int(round(window_s * rec.fs)))
        ends = list(range(per, n - per // 2, per)) + [n]  # a short last window joins the one before it
        for start, end in zip([0] + ends[:-1], ends):
            part = np.mean([np.sum((sim[k][start:end] - y[start:end]) ** 2) / (n * np.mean(y ** 2))
                            for k, y in rec.outputs.items()]) / len(held)
            windows.append((part, rec, start, end))
    whole = sum(w[0] for w in windows)
    if whole <= 0:
        return None
    kept, held_share = [], 0.0
    for w in sorted(windows, key=lambda w: -w[0]):
        kept.append(w)
        held_share += w[0] / whole
        if held_share >= share:
            break
    seconds, total = sum((e - s) / r.fs for _, r, s, e in kept), sum(r.n / r.fs for r in held)
    if seconds > most_time * total:
        return None
    rest = []
    for rec in held:
        mask = np.ones(rec.n, bool)
        for _, r, start, end in kept:
            if r is rec:
                mask[start:end] = False
        if mask.any():
            rest.append(np.mean([np.mean((sims[rec.name][k][mask] - y[mask]) ** 2) / np.mean(y[mask] ** 2)
                                 for k, y in rec.outputs.items()]))
    if not rest:  # every held-out sample lies in the windows (records far shorter than others)
        return None
    shown = []  # adjacent windows of a record joined
    for name, start, end in sorted((r.name, (r.first + s) / r.fs, (r.first + e) / r.fs) for _, r, s, e in kept):
        if shown and shown[-1][0] == name and abs(shown[-1][2] - start) < 1e-9:
            shown[-1] = (name, shown[-1][1], end)
        else:
            shown.append((name, start, end))
    return ConfinedMisfit(float(held_share), float(seconds), float(total), tuple(shown),
                          float(np.sqrt(np.mean(rest))))


def _period_spectra(x: np.ndarray, spp: int) -> np.ndarray:
    """DFT of every period (rows), or of the whole record when not periodic (spp = 0)."""
    if spp:
        return np.fft.rfft(x.reshape(-1, spp), axis=1)
    return np.fft.rfft(x)[None, :]


def _resolution_variance(y: np.ndarray) -> float:
    """Variance of the rounding a file writer leaves: q^2/12 for the smallest step q between the record's
    distinct values (a floor under any noise estimate; never zero for a non-constant record)."""
    steps = np.diff(np.unique(y))
    q = float(steps.min()) if steps.size else 0.0
    return max(q * q / 12.0, 1e-16 * float(np.mean(y**2)))


def _noise_variance(rec: Record, y: np.ndarray) -> tuple[float, str]:
    """Noise variance of one output channel and how it was estimated:
    - 'period scatter': two or more periods of a periodic record: the variance between periods;
    - 'pre-excitation': the record starts at rest for at least 0.2 s (rest_samples);
    - 'unexcited lines': a single period of a periodic record: the DFT lines the input does not excite (an
      upper bound: distortion lands there too);
    - 'quiet band': white noise level from the output PSD between 2x the highest excited frequency and
      0.4 fs (median over the bins, so that harmonic lines there do not count), or from 1.25x when the band
      from 2x holds fewer than 8 bins (a record sampled at less than 5x its top frequency);
    - 'local polynomial': otherwise the local polynomial method (Pintelon & Schoukens) on the record's DFT:
      around every line the output is fitted as a smooth FRF times the input plus a smooth transient term
      (polynomials of degree 2 over 13 neighbouring lines); the residual power is the noise (an upper
      bound: nonlinear distortion of a random input is noise-like and counts too)."""
    u = rec.compared(next(iter(rec.inputs)))
    spp = rec.samples_per_period
    if spp and rec.n // spp >= 2:
        return float(np.mean(np.var(y[:rec.n // spp * spp].reshape(-1, spp), axis=0, ddof=1))), "period scatter"
    rest = rest_samples(u, rec.fs)
    if rest >= 0.2 * rec.fs:
        return float(np.var(y[:rest])), "pre-excitation"
    if spp:
        U, Y = np.fft.rfft(u), np.fft.rfft(y)
        quiet = np.abs(U) ** 2 < 1e-8 * np.max(np.abs(U) ** 2)
        quiet[0] = False
        if quiet.any():
            return float(np.mean(np.abs(Y[quiet]) ** 2) / len(y)), "unexcited lines"
    seg = min(rec.n / rec.fs, max(1.0, rec.n / rec.fs / 8))
    f, puu = scipy.signal.welch(u, rec.fs, nperseg=int(seg * rec.fs))
    on = np.flatnonzero(puu > 1e-3 * puu[1:].max())
    f_hi = f[on[-1]] if on.size else 0.0
    _, pyy = scipy.signal.welch(y, rec.fs, nperseg=int(seg * rec.fs))
    quiet = (f >= 2 * f_hi) & (f <= 0.4 * rec.fs)
    if quiet.sum() < 8:
        quiet = (f >= 1.25 * f_hi) & (f <= 0.4 * rec.fs)
    if quiet.sum() >= 8:
        return float(np.median(pyy[quiet]) * rec.fs / 2), "quiet band"
    return local_polynomial_noise(u, y), "local polynomial"


def rest_samples(u: np.ndarray, fs: float, window_s: float = 0.05, factor: float = 2.0) -> int:
    """Samples [count] before the excitation starts. The input is split into windows of window_s [s] (at least
    16 samples); the excitation starts in the first window whose RMS about the mean of all the windows before it
    (the sensor's zero as known so far) exceeds `factor` x theirs, or at the first sample above 1 % of the peak
    (about the first window's mean) if that comes earlier; the window before that start is left out too (a
    ramp still within the input's noise already moves the output). An input that ramps up from its first
    sample (a sweep's or a noise record's fade-in) leaves none; an input at rest (zero or its sensor's noise)
    until the shaker starts leaves that lead-in, where the output is sensor noise alone. With factor 2, the
    input's white noise alone seldom ends a rest early (tests/test_noise_floor.py measures how seldom)."""
    w = max(16, int(round(window_s * fs)))
    n = len(u) // w
    if n < 2:
        return 0
    x = u - np.mean(u[:w])
    win = x[:n * w].reshape(n, w)
    k = np.arange(1, n)  # each window after the first, against the k windows before it
    zero = np.cumsum(win.sum(axis=1))[:-1] / (k * w)  # their mean: the sensor's zero as known so far
    square = np.cumsum((win**2).sum(axis=1))[:-1] / (k * w)
    before = np.sqrt(np.maximum(square - zero**2, 0.0) * k * w / (k * w - 1))  # their RMS about it (unbiased)
    dev = np.sqrt(np.mean((win[1:] - zero[:, None]) ** 2, axis=1))  # the window's about it
    rising = np.flatnonzero(dev > factor * before)
    start = rising[0] if rising.size else n  # the window before the one the excitation starts in
    large = np.flatnonzero(np.abs(x) > 0.01 * np.max(np.abs(x)))
    return int(min(start * w, large[0] if large.size else len(u)))


def local_polynomial_noise(u: np.ndarray, y: np.ndarray, degree: int = 2, half_width: int = 6) -> float:
    """Noise variance of y (its unit squared) from one non-periodic record: at every DFT line k, Y(k+r) =
    G(r) U(k+r) + T(r) + V(k+r) over r = -half_width..half_width, with G and T polynomials of `degree` in r
    (the FRF and the leakage/transient term, both smooth); the least-squares residual, divided by its
    degrees of freedom, estimates E|V(k)|^2. Summed over the lines it gives the time-domain variance
    (Parseval). Unlike a coherence, this is free of the leakage bias of a lightly damped resonance."""
    U, Y = np.fft.rfft(u), np.fft.rfft(y)
    r = np.arange(-half_width, half_width + 1)
    powers = r[:, None] ** np.arange(degree + 1)[None, :]  # (lines, degree + 1)
    centres = np.arange(half_width, len(Y) - half_width)
    idx = centres[:, None] + r[None, :]
    A = np.concatenate([U[idx][:, :, None] * powers[None], np.broadcast_to(powers, idx.shape + powers.shape[1:])],
                       axis=2).astype(complex)
    b = Y[idx][:, :, None]
    coef = np.linalg.pinv(A) @ b
    resid = b - A @ coef
    dof = len(r) - A.shape[2]
    var_k = np.sum(np.abs(resid[:, :, 0]) ** 2, axis=1) / dof  # E|V(k)|^2 at the centre lines
    n = len(y)
    # Parseval for the one-sided DFT: var = (|V_0|^2 + 2 sum_k |V_k|^2) / n^2; lines at the edges take the
    # mean level of their neighbours
    return float(2 * np.mean(var_k) * len(Y) / n**2)


UPPER_BOUNDS = ("unexcited lines", "quiet band", "local polynomial")  # methods that count distortion as noise too


def channel_noise(records: list[Record]) -> dict[str, dict[str, tuple[float, str]]]:
    """Each record's noise variance per output channel and its method (_noise_variance), by record name."""
    return {r.name: {k: _noise_variance(r, y) for k, y in r.outputs.items()} for r in records}


def noise_estimates(records: list[Record], level_scaled: bool = False,
                    per: dict | None = None) -> dict[str, tuple[float, str]]:
    """Each record's noise floor as an NRMSE (over its output channels) and the method used (see
    _noise_variance); never below the writer's rounding, so never zero.

    Where a method is an upper bound that also counts nonlinear distortion (UPPER_BOUNDS), a channel's noise
    variance is the smallest that method gives over the dataset's records: sensor noise does not grow with
    the excitation level, distortion does, so the lowest level bounds the noise of all (method marked
    'lowest level').

    level_scaled: the estimate for sensor noise that may instead grow in proportion to the level (a data
    acquisition whose input range is set per level): the larger of that bound and the lowest level's noise
    relative to its own power, times the record's power (each at most the record's own estimate).
    per: channel_noise(records) when already computed."""
    per = per or channel_noise(records)
    lowest, lowest_relative = {}, {}
    for r in records:
        for k, (var, method) in per[r.name].items():
            if method in UPPER_BOUNDS:
                lowest[k] = min(lowest.get(k, np.inf), var)
                lowest_relative[k] = min(lowest_relative.get(k, np.inf), var / np.mean(r.outputs[k] ** 2))
    out = {}
    for r in records:
        ratios, methods = [], []
        for k, y in r.outputs.items():
            var, method = per[r.name][k]
            if method in UPPER_BOUNDS and len(records) > 1:
                var, method = lowest[k], f"{method}, lowest level"
                if level_scaled:
                    var = max(var, lowest_relative[k] * np.mean(y**2))
            ratios.append(max(var, _resolution_variance(y)) / np.mean(y**2))
            methods.append(method)
        out[r.name] = (float(np.sqrt(np.mean(ratios))), methods[0])
    return out


UNSETTLED_NRMSE = 0.05  # a response that differs between periods by this share of its RMS ...
UNSETTLED_FACTOR = 3.0  # ... and by this many times the noise floor of a lower level is no steady state


def unsettled(records: list[Record]) -> dict[str, tuple[float, float]]:
    """Periodic records whose response does not repeat from one period to the next: their period scatter (an
    NRMSE) exceeds UNSETTLED_NRMSE and UNSETTLED_FACTOR x the noise floor of a record at a lower level. Sensor
    noise relative to the response does not grow with the level (a fixed noise falls relative to it, a range
    set per level keeps it), so such scatter is the response itself: chaotic, subharmonic or still settling,
    which no simulation follows sample by sample. Name -> (its scatter, the lowest floor of a lower level)."""
    per = channel_noise(records)
    floors = noise_estimates(records, per=per)
    out = {}
    for r in records:
        lower = [floors[q.name][0] for q in records if q.level_value < r.level_value]
        scatter = floors[r.name][0]
        if all(m == "period scatter" for _, m in per[r.name].values()) and lower and \
                scatter > max(UNSETTLED_NRMSE, UNSETTLED_FACTOR * min(lower)):
            out[r.name] = (scatter, min(lower))
    return out


def by_band(sim: dict, rec: Record, bands: list[tuple[float, float]]) -> list[float]:
    """Contribution of each band [Hz] to the NRMSE: sqrt(residual power in band / total output power)."""
    res = []
    for k, y in rec.outputs.items():
        E, Y = np.fft.rfft(sim[k] - y), np.fft.rfft(y)
        f = np.fft.rfftfreq(len(y), 1.0 / rec.fs)
        total = np.sum(np.abs(Y) ** 2)
        res.append([np.sum(np.abs(E[(f >= lo) & (f < hi)]) ** 2) / total for lo, hi in bands])
    return [float(v) for v in np.sqrt(np.mean(res, axis=0))]


def line_classes(rec: Record) -> dict[str, np.ndarray] | None:
    """For a periodic record: masks over the DFT lines of one period: excited, odd and even detection
    lines inside the excited band, and lines above it (harmonics). None when not periodic."""
    spp = rec.samples_per_period
    if not spp:
        return None
    U = np.abs(np.mean(_period_spectra(next(iter(rec.inputs.values())), spp), axis=0))
    excited = U > 1e-3 * U.max()
    idx = np.flatnonzero(excited)
    k = np.arange(len(U))
    inside = (k > idx[0]) & (k < idx[-1]) & ~excited
    return {"excited": excited, "odd_detection": inside & (k % 2 == 1), "even_detection": inside & (k % 2 == 0),
            "above_band": k > idx[-1]}


def by_harmonic(sim: dict, rec: Record) -> dict | None:
    """Residual contribution to the NRMSE on each line class (period-averaged spectra, so the periodic
    misfit stays and noise averages down), with the noise floor of that class. None when not periodic."""
    classes = line_classes(rec)
    if classes is None:
        return None
    spp = rec.samples_per_period
    periods = rec.n // spp
    out = {name: {"misfit": 0.0, "noise": 0.0} for name in classes}
    for k, y in rec.outputs.items():
        E = np.mean(_period_spectra(sim[k] - y, spp), axis=0)
        Yp = _period_spectra(y, spp)
        total = np.sum(np.abs(np.mean(Yp, axis=0)) ** 2)
        noise_line = np.var(Yp, axis=0, ddof=1) / periods if periods >= 2 else np.zeros(Yp.shape[1])
        for name, mask in classes.items():
            out[name]["misfit"] += float(np.sum(np.abs(E[mask]) ** 2) / total) / len(rec.outputs)
            out[name]["noise"] += float(np.sum(noise_line[mask]) / total) / len(rec.outputs)
    return {name: {key: float(np.sqrt(v)) for key, v in d.items()} for name, d in out.items()}


def by_loop_region(sim: dict, rec: Record) -> dict[str, float]:
    """Contribution to the NRMSE of four regions of the measured displacement-velocity loop: centre or
    tips (|y| below or above half its peak), loading (moving away from 0) or unloading."""
    out = {r: 0.0 for r in LOOP_REGIONS}
    for k, y in rec.outputs.items():
        v = np.gradient(y) * rec.fs
        tips = np.abs(y) >= 0.5 * np.max(np.abs(y))
        loading = y * v > 0
        total = np.sum(y**2)
        e2 = (sim[k] - y) ** 2
        for name, mask in zip(LOOP_REGIONS, (~tips & loading, ~tips & ~loading, tips & loading, tips & ~loading)):
            out[name] += float(np.sum(e2[mask]) / total) / len(rec.outputs)
    return {r: float(np.sqrt(v)) for r, v in out.items()}


EXCITED_ENERGY = 0.998  # share of the input's spectral energy the excited range holds (non-periodic records)


def excited_band(rec: Record) -> tuple[float, float]:
    """Lowest and highest frequency [Hz] one record's input excites: the DFT lines above 1e-3 of the peak, and
    for a record that is not periodic (a sweep or noise, whose start and end leak energy to every line) the
    band that holds EXCITED_ENERGY of the input's energy."""
    u = rec.compared(next(iter(rec.inputs)))
    U = np.abs(np.fft.rfft(u))
    f = np.fft.rfftfreq(len(u), 1.0 / rec.fs)
    on = (U > 1e-3 * U.max()) & (f > 0)
    if not rec.periodic:
        cum = np.cumsum(np.where(f > 0, U**2, 0.0))
        tail = (1.0 - EXCITED_ENERGY) / 2 * cum[-1]
        on &= (cum >= tail) & (cum <= cum[-1] - tail)
    exc = f[on]
    return float(exc.min()), float(exc.max())


def excited_range(records: list[Record]) -> tuple[float, float]:
    """Lowest and highest frequency [Hz] the records' inputs excite (excited_band of each)."""
    bands = [excited_band(rec) for rec in records]
    return min(b[0] for b in bands), max(b[1] for b in bands)


BAND_SPAN = 32.0  # the default bands span at most this factor (five octaves) below their top


def default_bands(records: list[Record], n: int = 8) -> list[tuple[float, float]]:
    """n log-spaced bands over the lines the inputs excite (from 0.8x the lowest to 1.2x the highest), at most
    BAND_SPAN wide: a sweep from 0 Hz excites down to a fraction of a hertz but spends a fraction of a second
    there, and bands spread over those decades would leave the response in one band and the others empty."""
    lo, hi = excited_range(records)
    top = min(1.2 * hi, records[0].fs / 2)
    edges = np.geomspace(max(0.8 * lo, top / BAND_SPAN), top, n + 1)
    return [(float(a), float(b)) for a, b in zip(edges[:-1], edges[1:])]
