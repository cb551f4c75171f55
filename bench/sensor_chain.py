"""How the sensor chain of the withheld-effect generator sets a damper diagnosis's time, measured in one run.

The generator (pyfit.reference.synthetic) writes each output through the decimation FIR of scipy.signal.decimate
(order 20 q, Hamming: a passband gain of a few 0.1 %) and the clamp motion as the controller's exact signal, so
input and outputs disagree by that gain; and near a record's end the FIR runs into the zeros past it, so its
last half-length of samples (100 taps at q = 10: 10 samples) is off. This script writes one campaign case as the
campaign does (default: case 26 of `stockbridge diagnose --campaign 40 --campaign-seed 0 --model damper
--excitation stepped_sine --record-s 35`: cubic springs withheld, the clamp's displacement recorded), then takes
the truth's own held-out misfit (the FMU at the true parameters) on the files as written, with the clamp motion
passed through the FIR's gain, with the FIR's edge left out, and with both; and diagnoses the files as written
and with both (a chain whose input and outputs pass the same filters, cut from a continuous record).

    python bench/sensor_chain.py [--case 26] [--workers 2]
"""
import argparse
import json
import pathlib
import shutil
import tempfile
import time
import tomllib

import numpy as np
import scipy.signal

from pyfit.gap import campaign, datasets
from pyfit.gap.diagnose import DiagnoseConfig, diagnose, misfit_at
from pyfit.io.data import measurement_files
from pyfit.report.generated import BenchReport
from pyfit.runtime.examples import ensure_fmu

ROOT = pathlib.Path(__file__).resolve().parents[1]


def _fir(q: int) -> np.ndarray:
    """The FIR scipy.signal.decimate applies for a factor q (its documented default: order 20 q, Hamming)."""
    return scipy.signal.firwin(20 * q + 1, 1.0 / q, window="hamming")


def _copy(data: pathlib.Path, out: pathlib.Path, q: int, gain: bool, edge: bool) -> pathlib.Path:
    """The dataset `data` copied to `out`, its input columns passed through the FIR's magnitude (`gain`) and its
    last half-length of the FIR's samples dropped from every column (`edge`)."""
    out.mkdir(parents=True)
    fir = _fir(q)
    cut = (len(fir) // 2) // q
    shutil.copy(data / "truth.json", out / "truth.json")
    for csv in measurement_files(data):
        side = tomllib.loads(csv.with_suffix(".toml").read_text())
        header = csv.read_text().splitlines()[0]
        values = np.loadtxt(csv, delimiter=",", skiprows=1)
        names = header.split(",")
        if gain:
            fs = side["sample_rate_hz"]
            f = np.fft.rfftfreq(len(values), 1.0 / fs)
            h = np.abs(scipy.signal.freqz(fir, worN=f, fs=fs * q)[1])
            for name in side["inputs"]:
                k = names.index(name)
                values[:, k] = np.fft.irfft(np.fft.rfft(values[:, k]) * h, len(values))
        np.savetxt(out / csv.name, values[:-cut] if edge else values, delimiter=",", header=header, comments="",
                   fmt="%.17g")
        shutil.copy(csv.with_suffix(".toml"), out / csv.with_suffix(".toml").name)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--case", type=int, default=26)
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    fmu_dir = ROOT / "fmus"
    ensure_fmu("StockbridgeDamper", fmu_dir)
    q = datasets.OVERSAMPLE
    report = BenchReport("sensor_chain", ROOT)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        case = campaign.draw(40, 0, "damper", "stepped_sine")[args.case]
        t0 = time.perf_counter()
        case, data, described = campaign.write_case(case, tmp / "written", 35.0)
        written_s = time.perf_counter() - t0
        truth = json.loads((data / "truth.json").read_text())["params"]
        variants = {"as written": data}
        for name, gain, edge in (("input through the FIR's gain", True, False),
                                 ("the FIR's edge left out", False, True), ("both", True, True)):
            variants[name] = _copy(data, tmp / name.replace(" ", "_").replace("'", ""), q, gain, edge)
        misfits = {name: misfit_at("damper", d, truth, fmu_dir=fmu_dir, nominal=described).held_out
                   for name, d in variants.items()}
        runs = {}
        for name in ("as written", "both"):
            t0 = time.perf_counter()
            rep = diagnose("damper", variants[name], tmp / f"diagnosis_{len(runs)}", DiagnoseConfig(), fmu_dir,
                           workers=args.workers, progress=False, nominal=described)
            runs[name] = (time.perf_counter() - t0, rep)
    floor = runs["as written"][1].gap.noise_floor_scaled
    above = DiagnoseConfig().extend_factor * floor
    report.line(f"damper campaign case {args.case} (seed 0, stepped sines of 35 s; {case.withheld} withheld at "
                f"{', '.join(f'{v:.2f}' for v in (case.sizes or {}).values())} x the noise; clamp motion recorded: "
                f"{case.motion}; outputs {', '.join(case.outputs)}), its files written in {written_s:.0f} s; the "
                f"noise floor (scaled) {floor:.5f}, above which the selection extends a model: {above:.5f}")
    report.table("The truth's own held-out NRMSE (the FMU at the true parameters)", ["records", "NRMSE",
                 "over the noise floor"], [[n, f"{v:.5f}", f"{v / floor:.2f}"] for n, v in misfits.items()])
    rows = []
    for name, (wall, rep) in runs.items():
        stages = rep.stage_s
        rows.append([name, f"{wall:.0f}", f"{stages['refits with each effect']:.0f}",
                     f"{stages['combinations of effects']:.0f}", rep.sentence])
    report.table(f"Its diagnosis on {args.workers} workers", ["records", "wall [s]", "refits with each effect [s]",
                 "combinations of effects [s]", "verdict"], rows)


if __name__ == "__main__":
    main()
