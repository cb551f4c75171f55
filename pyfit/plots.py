"""Matplotlib figures saved as PNG; every axis carries its quantity and unit."""
from __future__ import annotations

import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from . import signals  # noqa: E402


def _label(name: str, units: dict) -> str:
    return f"{name} [{units.get(name) or '-'}]"


def _save(fig, path: pathlib.Path) -> pathlib.Path:
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def time_histories(path, curves: list[tuple[str, np.ndarray, dict]], names: list[str], units: dict, title=""):
    """One panel per signal name; curves = [(legend, time, {name: samples})]."""
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
    fig, ax = plt.subplots(figsize=(8, 3.5))
    for legend, f in curves:
        ax.plot(t, f, lw=0.7, label=legend)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("instantaneous frequency [Hz]")
    ax.legend(fontsize=7)
    ax.set_title(title)
    return _save(fig, path)
