"""Matplotlib figures saved as PNG; every axis carries its quantity and unit."""
from __future__ import annotations

import pathlib

import numpy as np

from pyfit.analysis import signals


def _pyplot():
    """matplotlib.pyplot with the file-only Agg backend, imported on the first figure."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _label(name: str, units: dict) -> str:
    return f"{name} [{units.get(name) or '-'}]"


def _save(fig, path: pathlib.Path) -> pathlib.Path:
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    _pyplot().close(fig)
    return path


def time_histories(path, curves: list[tuple[str, np.ndarray, dict]], names: list[str], units: dict, title=""):
    """One panel per signal name; curves = [(legend, time, {name: samples})]."""
    plt = _pyplot()
    fig, axes = plt.subplots(len(names), 1, sharex=True, figsize=(9, 1.8 * len(names) + 1), squeeze=False)
    for ax, n in zip(axes[:, 0], names):
        for legend, t, values in curves:
            ax.plot(t, values[n], lw=0.6, label=legend)
        ax.set_ylabel(_label(n, units))
    axes[-1, 0].set_xlabel("time [s]")
    if len(curves) > 1:
        axes[0, 0].legend(fontsize=7, loc="upper left")
    fig.suptitle(title)
    return _save(fig, path)


def loops(path, panels: list[tuple[str, list[tuple[str, np.ndarray, np.ndarray]]]], x_name, f_name, units, title=""):
    """Hysteresis loops (force against displacement); panels = [(panel title, [(legend, x, f)])]."""
    plt = _pyplot()
    n = len(panels)
    cols = min(n, 5)
    rows = int(np.ceil(n / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(max(5.5, 3.2 * cols), 3.2 * rows + 0.4), squeeze=False)
    for ax, (ptitle, curves) in zip(axes.flat, panels):
        for legend, x, f in curves:
            ax.plot(x, f, lw=0.9, label=legend)
        ax.set_title(ptitle, fontsize=9)
        ax.ticklabel_format(style="sci", scilimits=(-2, 3))
        ax.set_xlabel(_label(x_name, units))
        ax.set_ylabel(_label(f_name, units))
        if len(curves) > 1:
            ax.legend(fontsize=7)
    for ax in list(axes.flat)[n:]:
        ax.set_visible(False)
    fig.suptitle(title)
    return _save(fig, path)


def psd_overlay(path, curves: list[tuple[str, np.ndarray, float]], name: str, units: dict, title="",
                segment_s: float | None = None, f_max: float | None = None):
    """Welch PSDs (Hann, 50 % overlap) of several signals on one log axis; curves = [(legend, samples, fs)]."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(8, 4))
    for legend, y, fs in curves:
        f, p = signals.welch_psd(y, fs, segment_s)
        sel = f <= (f_max or f[-1])
        ax.semilogy(f[sel], p[sel], lw=0.8, label=legend)
    u = units.get(name) or "-"
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel(f"PSD of {name} [{u}²/Hz]")
    if len(curves) > 1:
        ax.legend(fontsize=7)
    ax.set_title(title)
    return _save(fig, path)


def spectrogram(path, y, fs, name, units, title="", f_max=None, segment_s=1.0):
    """Spectrogram in dB re 1 unit²/Hz."""
    plt = _pyplot()
    f, t, s = signals.spectrogram(y, fs, segment_s)
    sel = f <= (f_max or f[-1])
    fig, ax = plt.subplots(figsize=(8, 4))
    mesh = ax.pcolormesh(t, f[sel], 10 * np.log10(s[sel] + 1e-300), shading="auto")
    fig.colorbar(mesh, ax=ax, label=f"PSD of {name} [dB re 1 {units.get(name) or '-'}²/Hz]")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("frequency [Hz]")
    ax.set_title(title)
    return _save(fig, path)


def instantaneous_frequency(path, t, curves: list[tuple[str, np.ndarray]], title=""):
    """Instantaneous frequency [Hz] against time; curves = [(legend, frequency samples)]."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(8, 3.5))
    for legend, f in curves:
        ax.plot(t, f, lw=0.7, label=legend)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("instantaneous frequency [Hz]")
    ax.legend(fontsize=7)
    ax.set_title(title)
    return _save(fig, path)


def semilogy_curves(path, curves: list[tuple[str, np.ndarray, np.ndarray, str]], xlabel: str, ylabel: str,
                    title: str = "", ylim=None, log: bool = True) -> pathlib.Path:
    """Curves [(legend, x, y, matplotlib style)] on one axis (log y by default)."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 3.6))
    for legend, x, y, style in curves:
        (ax.semilogy if log else ax.plot)(x, y, style, ms=3, lw=1.2, label=legend)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if ylim is not None:
        ax.set_ylim(*ylim)
    if any(c[0] for c in curves):
        ax.legend(fontsize=8)
    ax.set_title(title, fontsize=9)
    return _save(fig, path)


def impedance_curves(out_dir, test, models: dict, title: str) -> list[pathlib.Path]:
    """impedance_abs.png and impedance_phase.png in out_dir: a damper test (pyfit.io.impedance.ImpedanceTest,
    dots) and model impedances {legend: Z [N·s/m] of the test's shape} at every clamp-velocity level."""
    out_dir = pathlib.Path(out_dir)
    v = 2 * np.pi * test.frequencies[:, None] * test.amplitudes
    styles = ["-", "--", ":", "-."]
    curves_abs, curves_phase = [], []
    for j in range(test.amplitudes.shape[1]):
        level = f"{np.median(v[:, j]) * 1e3:.3g} mm/s"
        colour = f"C{j % 10}"  # one colour per level, one line style per model
        measured = test.impedance[:, j]
        curves_abs.append((f"measured {level}", test.frequencies, np.abs(measured), colour + "o"))
        curves_phase.append((f"measured {level}", test.frequencies, np.degrees(np.angle(measured)), colour + "o"))
        for (legend, z), style in zip(models.items(), styles):
            curves_abs.append((f"{legend} {level}", test.frequencies, np.abs(z[:, j]), colour + style))
            curves_phase.append((f"{legend} {level}", test.frequencies, np.degrees(np.angle(z[:, j])), colour + style))
    return [semilogy_curves(out_dir / "impedance_abs.png", curves_abs, "frequency [Hz]", "|Z| [N·s/m]",
                            f"{title}: clamp impedance"),
            semilogy_curves(out_dir / "impedance_phase.png", curves_phase, "frequency [Hz]", "phase of Z [deg]",
                            f"{title}: clamp impedance phase", log=False)]


def heat_map(path, values: np.ndarray, columns: list[str], rows: list[str], row_label: str,
             title: str) -> pathlib.Path:
    """A matrix (rows x columns) as colours with a colour bar."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(1.6 + 1.1 * len(columns), 3.8))
    im = ax.imshow(values, aspect="auto", origin="lower", cmap="viridis")
    ax.set_xticks(range(len(columns)), columns, fontsize=7, rotation=20)
    ax.set_yticks(range(len(rows)), rows, fontsize=7)
    ax.set_ylabel(row_label)
    ax.set_title(title, fontsize=8)
    fig.colorbar(im, ax=ax)
    return _save(fig, path)


def error_signals(path, panels: list[tuple[str, np.ndarray, np.ndarray]], ylabel: str) -> pathlib.Path:
    """One panel per (title, time [s], error) signal."""
    plt = _pyplot()
    fig, axes = plt.subplots(len(panels), 1, figsize=(7, 2.5 * len(panels)), squeeze=False)
    for ax, (title, t, e) in zip(axes[:, 0], panels):
        ax.plot(t, e, lw=0.5)
        ax.set_xlabel("time [s]")
        ax.set_ylabel(ylabel)
        ax.set_title(title, fontsize=9)
    return _save(fig, path)


def convergence(path, history: list[dict], ann: list[dict], title: str) -> pathlib.Path:
    """True (FMU) error per evaluation, the best so far, and the surrogate's prediction at its optimum."""
    plt = _pyplot()
    ev = [h["evaluations"] for h in history]
    err = [h["true_error"] for h in history]
    fig, ax = plt.subplots(figsize=(7, 3.5))
    ax.semilogy(ev, err, ".", ms=4, label="true (FMU) error")
    ax.semilogy(ev, np.minimum.accumulate(err), "-", label="best so far")
    if ann:
        space = " (log-ratio search space)" if ann[0].get("searched_error") is not None else ""
        ax.semilogy([h["evaluations"] for h in ann], [max(h["ann_error"], 1e-300) for h in ann], "x", ms=4,
                    label="ANN-predicted error at the GA optimum" + space)
        if space:
            ax.semilogy([h["evaluations"] for h in ann], [h["searched_error"] for h in ann], "+", ms=5,
                        label="true error at the GA optimum" + space)
    ax.set_xlabel("true evaluations [-]")
    ax.set_ylabel("objective sum(r²) [-]")
    ax.legend(fontsize=8)
    ax.set_title(title)
    return _save(fig, path)


def psd_in_bands(path, curves: list[tuple[str, np.ndarray]], fs: float, segment_s: float, band: tuple[float, float],
                 name: str, units: dict, title: str) -> pathlib.Path:
    """Welch PSDs of [(legend, samples)] shown over [lo, hi] Hz."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 3.5))
    for label, y in curves:
        f, p = signals.welch_psd(y, fs, segment_s)
        sel = (f >= band[0]) & (f <= band[1])
        ax.semilogy(f[sel], p[sel], label=label)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel(f"PSD of {name} [{units.get(name) or '-'}²/Hz]")
    ax.legend(fontsize=8)
    ax.set_title(title)
    return _save(fig, path)
