"""Run the diagnosis on every dataset folder under a root (the withheld-effect test cases) and summarise:
per case the verdict against the withheld effect (read from truth.json only for this summary), the
shrink, the band of largest misfit and the wall time. A folder holding a damper impedance test (sidecar
kind = "damper_impedance") is diagnosed on it (pyfit.gap.impedance_gap)."""
from __future__ import annotations

import json
import pathlib
import time

from pyfit.gap.diagnose import DiagnoseConfig, diagnose
from pyfit.gap.impedance_gap import diagnose_impedance
from pyfit.io.data import holds_measurements
from pyfit.io.schema import read_toml


def impedance_test_in(folder: pathlib.Path) -> pathlib.Path | None:
    """The CSV of a damper impedance test in the folder (its sidecar's kind is "damper_impedance"), if any."""
    for csv in sorted(folder.glob("*.csv")):
        side = csv.with_suffix(".toml")
        if side.is_file() and read_toml(side).get("kind") == "damper_impedance":
            return csv
    return None


def run_cases(root, out_dir, cfg: DiagnoseConfig | None = None, model: str = "sdof", fmu_dir="fmus",
              workers: int | None = None, nominal=None) -> list[dict]:
    """Diagnose every sub-folder of root holding a dataset (against the nominal model described, if any);
    OUT/<case>/report.*, OUT/summary.md."""
    rows = []
    for case in sorted(p for p in pathlib.Path(root).iterdir() if p.is_dir() and holds_measurements(p)):
        t0 = time.perf_counter()
        test = impedance_test_in(case)
        if test:
            rep = diagnose_impedance(test, pathlib.Path(out_dir) / case.name, cfg, fmu_dir, nominal, workers=workers)
        else:
            rep = diagnose(model, case, pathlib.Path(out_dir) / case.name, cfg, fmu_dir, workers, progress=False,
                           nominal=nominal)
        truth = json.loads((case / "truth.json").read_text())["effect"] if (case / "truth.json").is_file() else None
        expected = () if truth in (None, "none") else tuple(sorted(truth.split("+")))
        runner_up = rep.ranking[1] if len(rep.ranking) > 1 else None
        rows.append({"case": case.name, "withheld": truth, "verdict": rep.sentence,
                     "correct": tuple(sorted(rep.chosen)) == expected, "gap": rep.gap.overall,
                     "noise_floor": rep.gap.noise_floor, "worst_band_hz": list(rep.gap.worst_band_hz),
                     "shrink_pct": rep.best.shrink_pct if rep.chosen else None,
                     "runner_up": runner_up.effect if runner_up else None,
                     "runner_up_shrink_pct": runner_up.shrink_pct if runner_up else None,
                     "wall_s": time.perf_counter() - t0})
    write_summary(rows, out_dir)
    return rows


def write_summary(rows: list[dict], out_dir) -> pathlib.Path:
    """summary.md and summary.json of run_cases."""
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    (out / "summary.json").write_text(json.dumps(rows, indent=1))
    lines = ["| case | withheld | verdict | correct | held-out gap | noise floor | largest misfit [Hz] | shrink [%] "
             "| runner-up (shrink %) | wall [s] |", "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        ru = f"{r['runner_up']} ({r['runner_up_shrink_pct']:.1f})" if r["runner_up"] else "—"
        sh = f"{r['shrink_pct']:.1f}" if r["shrink_pct"] is not None else "—"
        lo, hi = r["worst_band_hz"]
        band = f"{lo:.1f}" if lo == hi else f"{lo:.1f}–{hi:.1f}"
        lines.append(f"| {r['case']} | {r['withheld']} | {r['verdict']} | {'yes' if r['correct'] else 'NO'} | "
                     f"{r['gap']:.4f} | {r['noise_floor']:.4f} | {band} | {sh} | {ru} | {r['wall_s']:.0f} |")
    n_ok = sum(r["correct"] for r in rows)
    lines += ["", f"{n_ok} of {len(rows)} cases correct."]
    md = out / "summary.md"
    md.write_text("\n".join(lines) + "\n")
    return md
