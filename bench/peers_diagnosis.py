"""Naming the unmodelled effect: `stockbridge diagnose` side by side with the equation-error methods an engineer
would reach for instead (restoring-force surface, SINDy via pysindy, NARMAX via sysidentpy; pyfit.gap.peers),
on the same withheld-effect SDOF datasets (CasADi reference, lab sensor chain): each effect and a null case,
recorded as displacement or acceleration, under a random-odd multisine or a sweep. Prints top-1 accuracy,
false alarms on the null cases and wall time per case for each method. With --campaign, the same methods on
every case of a validation campaign already run (random effects and pairs, loop shapes, strengths, excitations,
sensors), beside the verdict the diagnosis gave there. The peers are an optional extra: pip install -e ".[peers]".

    python bench/peers_diagnosis.py           # 5 effects x 4 recordings = 20 cases, about 25 minutes on 2 cores
    python bench/peers_diagnosis.py --quick   # 5 effects, multisine, displacement: a few minutes
    stockbridge diagnose --campaign 100 --campaign-seed 19 --out results/campaign_check
    python bench/peers_diagnosis.py --campaign results/campaign_check   # its 100 cases: under a minute
"""
import argparse
import pathlib
import re
import tempfile
import time
import warnings

ROOT = pathlib.Path(__file__).resolve().parents[1]

from pyfit.gap import peers
from pyfit.gap.datasets import SDOF, LabStyle, write_dataset
from pyfit.gap.diagnose import diagnose
from pyfit.report.generated import BenchReport

EFFECTS = ("hysteresis", "cubic_stiffness", "coulomb_friction", "quadratic_damping", "none")
STYLES = {"multisine, y": LabStyle("multisine"), "multisine, a": LabStyle("multisine", outputs=("a",)),
          "sweep, y": LabStyle("sweep"), "sweep, a": LabStyle("sweep", outputs=("a",))}
DIAGNOSE = peers.DIAGNOSE


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="the multisine displacement recordings only")
    ap.add_argument("--campaign", metavar="FOLDER", help="the cases of a validation campaign run into FOLDER")
    ap.add_argument("--fmus", default=str(ROOT / "fmus"))
    args = ap.parse_args()
    warnings.filterwarnings("ignore")
    if args.campaign:
        return on_campaign(pathlib.Path(args.campaign))
    styles = {k: v for k, v in STYLES.items() if k == "multisine, y" or not args.quick}
    report = BenchReport("peers_diagnosis_quick" if args.quick else "peers_diagnosis", ROOT)
    verdicts = []  # (case, withheld, method, named, wall_s)
    with tempfile.TemporaryDirectory() as tmp:
        for label, style in styles.items():
            for effect in EFFECTS:
                case = f"{effect} ({label})"
                data = write_dataset(pathlib.Path(tmp) / f"{effect}_{label.replace(', ', '_')}", SDOF, effect,
                                     style=style)
                motions = peers.read_motions(data)
                for method, fn in peers.METHODS.items():
                    named = fn(motions)
                    verdicts.append((case, effect, method, named.effect, named.wall_s))
                t0 = time.perf_counter()
                rep = diagnose("sdof", data, pathlib.Path(tmp) / "out" / data.name, fmu_dir=args.fmus, workers=2,
                               progress=False)
                verdicts.append((case, effect, DIAGNOSE, rep.chosen_name, time.perf_counter() - t0))
                print(case, {m: n for c, _, m, n, _ in verdicts if c == case}, flush=True)
    methods = [DIAGNOSE, *peers.METHODS]
    rows = []
    for method in methods:
        mine = [v for v in verdicts if v[2] == method]
        effects = [v for v in mine if v[1] != "none"]
        nulls = [v for v in mine if v[1] == "none"]
        hits = sum(v[3] == v[1] for v in effects)
        alarms = sum(v[3] is not None for v in nulls)
        walls = sorted(v[4] for v in mine)
        rows.append([method, f"{hits}/{len(effects)} ({100 * hits / len(effects):.0f} %)",
                     f"{alarms}/{len(nulls)}", f"{walls[len(walls) // 2]:.2g}"])
    report.line(f"{len(verdicts) // len(methods)} SDOF cases ({', '.join(styles)}; withheld: "
                f"{', '.join(EFFECTS)}); command: python bench/peers_diagnosis.py{' --quick' if args.quick else ''}; "
                f"equation-error library: {', '.join(peers.LIBRARY)}; {peers.naming_rule()}")
    report.table("Top-1 accuracy, false alarms and wall time per case",
                 ["method", "withheld effect named (top-1)", "false alarms on null cases", "wall per case [s]"], rows)
    cases = list(dict.fromkeys(v[0] for v in verdicts))
    report.table("Per case: the effect each method names (— : none)", ["case", *methods],
                 [[c, *[next((v[3] or "—") for v in verdicts if v[0] == c and v[2] == m) for m in methods]]
                  for c in cases])


def on_campaign(folder: pathlib.Path):
    """The equation-error methods on a campaign's cases (pyfit.gap.peers.on_campaign), written as
    results/bench/peers_campaign.md."""
    if not any(folder.glob("case*/outcome.json")):
        raise SystemExit(f"{folder}: no campaign cases (case*/outcome.json); run stockbridge diagnose --campaign first")
    cases = peers.on_campaign(folder)
    if not cases:
        raise SystemExit(f"{folder}: no SDOF case whose diagnosis ran (the equation-error methods need an SDOF's "
                         "force and motion; a damper campaign has none)")
    report = BenchReport("peers_campaign", ROOT)
    summary = folder / "summary.md"
    made = re.search(r"^(.*?\)).*?command: (`[^`]+`)", summary.read_text(encoding="utf-8")) if summary.is_file() else None
    head = f"{made[1]} of {made[2]}" if made else f"{len(cases)} SDOF cases of the campaign in {folder}"
    report.line(f"{head}, the verdicts of `stockbridge diagnose` as that campaign stored them; command: "
                f"python bench/peers_diagnosis.py --campaign {folder}; equation-error library: "
                f"{', '.join(peers.LIBRARY)}; {peers.naming_rule()}")
    for title, header, rows in peers.campaign_tables(cases):
        report.table(title, header, rows)


if __name__ == "__main__":
    main()
