"""Every figure in the README and the docs comes from a file a command writes. A generated block in a page
(README.md or docs/**/*.md) is the verbatim content of one committed result file:

    <!-- generated from docs/results/quickstart.md -->
    (the file's content)
    <!-- end generated -->

`collect` copies each result a command has written under results/ to its committed place (RESULTS), with
the figures it links to; `render` rewrites every block of a text from its file; `stale` names the blocks
that differ from their files; `render_files` and `stale_files` do the same for every page.
"""
from __future__ import annotations

import os
import pathlib
import re
import shutil

BLOCK = re.compile(r"(<!-- generated from (?P<path>\S+) -->\n)(?P<body>.*?)(<!-- end generated -->)", re.S)

# committed file -> (what the command writes, the command)
RESULTS = {
    "docs/results/tests.md": ("results/tests.md", "python -m pytest"),
    "docs/results/quickstart.md": ("results/quickstart/summary.md",
                                   "stockbridge fit --repeats 2 --out results/quickstart"),
    "docs/results/tutorial_check.md": ("results/tutorial/check.md",
                                       "stockbridge examples lab_sweeps results/lab_sweeps && stockbridge diagnose "
                                       "--model sdof --data results/lab_sweeps --check --out results/tutorial"),
    "docs/results/tutorial_report.md": ("results/tutorial/report.md",
                                        "stockbridge diagnose --model sdof --data results/lab_sweeps --out "
                                        "results/tutorial"),
    "docs/results/diagnose_cases.md": ("results/diagnose_cases/summary.md",
                                       "stockbridge diagnose --make-datasets results/gap_cases && "
                                       "stockbridge diagnose --cases results/gap_cases --out "
                                       "results/diagnose_cases"),
    "docs/results/diagnose_cases_damper.md": ("results/diagnose_cases_damper/summary.md",
                                              "stockbridge diagnose --model damper --make-datasets "
                                              "results/gap_cases_damper --seeds 0 && stockbridge diagnose --model "
                                              "damper --cases results/gap_cases_damper --out "
                                              "results/diagnose_cases_damper"),
    "docs/results/diagnose_benchmark.md": ("results/diagnose_benchmark/report.md",
                                           "stockbridge diagnose --benchmark --config "
                                           "configs/diagnose_benchmark.toml --out results/diagnose_benchmark"),
    "docs/results/lab_example.md": ("results/lab_report/report.md",
                                    "stockbridge diagnose --make-datasets results/lab --excitation sweep "
                                    "--record a --seeds 0 && stockbridge diagnose --model sdof --data "
                                    "results/lab/sdof_hysteresis --out results/lab_report"),
    "docs/results/diagnose_lab.md": ("results/diagnose_lab/summary.md",
                                     "stockbridge diagnose --make-datasets results/lab_cases --excitation sweep "
                                     "--record a --seeds 0 && stockbridge diagnose --cases results/lab_cases "
                                     "--out results/diagnose_lab"),
    "docs/results/diagnose_lab_damper.md": ("results/diagnose_lab_damper/summary.md",
                                            "stockbridge diagnose --model damper --nominal "
                                            "configs/symmetric_damper.toml --make-datasets results/lab_cases_damper "
                                            "--excitation sweep --motion x --seeds 0 && stockbridge diagnose "
                                            "--model damper --nominal configs/symmetric_damper.toml --cases "
                                            "results/lab_cases_damper --out results/diagnose_lab_damper"),
    "docs/results/diagnose_lab_design.md": ("results/diagnose_lab_design/summary.md",
                                            "stockbridge diagnose --model damper --make-datasets "
                                            "results/lab_cases_design --excitation sweep --motion x --seeds 0 && "
                                            "stockbridge diagnose --model damper --cases results/lab_cases_design "
                                            "--out results/diagnose_lab_design"),
    "docs/results/diagnose_lab_design_acc.md": ("results/diagnose_lab_design_acc/summary.md",
                                                "stockbridge diagnose --model damper --make-datasets "
                                                "results/lab_cases_design_acc --excitation sweep --record acc_x1 "
                                                "acc_x2 --motion a --seeds 0 && stockbridge diagnose --model damper "
                                                "--cases results/lab_cases_design_acc --out "
                                                "results/diagnose_lab_design_acc"),
    "docs/results/diagnose_lab_design_step.md": ("results/diagnose_lab_design_step/summary.md",
                                                 "stockbridge diagnose --model damper --make-datasets "
                                                 "results/lab_cases_design_step --excitation stepped_sine --motion x "
                                                 "--seeds 0 && stockbridge diagnose --model damper --cases "
                                                 "results/lab_cases_design_step --out "
                                                 "results/diagnose_lab_design_step"),
    "docs/results/diagnose_impedance.md": ("results/diagnose_impedance/summary.md",
                                           "stockbridge diagnose --model damper --make-datasets "
                                           "results/impedance_cases --excitation impedance --seeds 0 && "
                                           "stockbridge diagnose --model damper --cases results/impedance_cases "
                                           "--out results/diagnose_impedance"),
    "docs/results/boucwen_benchmark.md": ("results/boucwen_benchmark/summary.md",
                                          "stockbridge fit configs/boucwen_benchmark.toml --repeats 2 "
                                          "--out results/boucwen_benchmark"),
    "docs/results/bench_batch_speedup.md": ("results/bench/batch_speedup.md", "python bench/batch_speedup.py"),
    "docs/results/bench_pool_start.md": ("results/bench/pool_start.md", "python bench/pool_start.py"),
    "docs/results/bench_escape_cost.md": ("results/bench/escape_cost.md", "python bench/escape_cost.py"),
    "docs/results/bench_sensor_chain.md": ("results/bench/sensor_chain.md", "python bench/sensor_chain.py"),
    "docs/results/bench_fmu_soak.md": ("results/bench/fmu_soak.md", "python bench/fmu_soak.py"),
    "docs/results/bench_eval_speed.md": ("results/bench/eval_speed.md", "python bench/eval_speed.py"),
    "docs/results/bench_diagnose_time.md": ("results/bench/diagnose_time.md", "python bench/diagnose_time.py"),
    "docs/results/bench_input_order.md": ("results/bench/input_order.md", "python bench/input_order.py"),
    "docs/results/bench_fit_time.md": ("results/bench/fit_time.md", "python bench/fit_time.py"),
    "docs/results/campaign.md": ("results/campaign/summary.md",
                                 "stockbridge diagnose --campaign 200 --campaign-seed 18 --calibrate "
                                 "--out results/campaign"),
    "docs/results/campaign_check.md": ("results/campaign_check/summary.md",
                                       "stockbridge diagnose --campaign 100 --campaign-seed 19 --out "
                                       "results/campaign_check"),
    "docs/results/campaign_threshold.md": ("results/campaign_threshold/summary.md",
                                           "stockbridge diagnose --campaign 200 --campaign-seed 18 --config "
                                           "configs/diagnose_nominal_threshold.toml --calibrate --out "
                                           "results/campaign_threshold"),
    "docs/results/campaign_damper.md": ("results/campaign_damper/summary.md",
                                        "stockbridge diagnose --campaign 100 --model damper --out "
                                        "results/campaign_damper"),
    "docs/results/campaign_damper_calibration.md": ("results/campaign_damper_calibration/summary.md",
                                                    "stockbridge diagnose --campaign 100 --campaign-seed 1 --model "
                                                    "damper --calibrate --out results/campaign_damper_calibration"),
    "docs/results/campaign_damper_step.md": ("results/campaign_damper_step/summary.md",
                                             "stockbridge diagnose --campaign 40 --model damper --excitation "
                                             "stepped_sine --record-s 35 --out results/campaign_damper_step"),
    "docs/results/bench_peers_fit.md": ("results/bench/peers_fit.md", "python bench/peers_fit.py"),
    "docs/results/bench_peers_diagnosis.md": ("results/bench/peers_diagnosis.md", "python bench/peers_diagnosis.py"),
    "docs/results/bench_peers_campaign.md": ("results/bench/peers_campaign.md",
                                             "stockbridge diagnose --campaign 100 --campaign-seed 19 --out "
                                             "results/campaign_check && python bench/peers_diagnosis.py "
                                             "--campaign results/campaign_check"),
    "docs/results/design_check.md": ("results/design_check/design_check.md",
                                     "stockbridge design-check configs/span_drake_300m.toml"),
    "docs/results/verify_balance.md": ("results/verify_balance/verify_balance.md", "stockbridge verify-balance"),
    "docs/results/bench_importer_tolerance.md": ("results/bench/importer_tolerance.md",
                                                 "python bench/importer_tolerance.py"),
}


def pages(root: pathlib.Path) -> list[pathlib.Path]:
    """README.md and every Markdown page under docs/ (the result files themselves excluded)."""
    docs = sorted(p for p in (root / "docs").rglob("*.md") if "results" not in p.relative_to(root / "docs").parts)
    return [root / "README.md", *docs]


def render_files(root: pathlib.Path) -> list[pathlib.Path]:
    """Rewrite every page's generated blocks from their files; the pages changed."""
    changed = []
    for page in pages(root):
        text = page.read_text(encoding="utf-8")
        new = render(text, root, page.parent)
        if new != text:
            page.write_text(new, encoding="utf-8")
            changed.append(page)
    return changed


def stale_files(root: pathlib.Path) -> list[str]:
    """'page: result file' for every generated block that differs from its file."""
    return [f"{page.relative_to(root)}: {path}" for page in pages(root)
            for path in stale(page.read_text(encoding="utf-8"), root, page.parent)]


def blocks(text: str) -> list[tuple[str, str]]:
    """(file path, body) of every generated block, in order."""
    return [(m["path"], m["body"]) for m in BLOCK.finditer(text)]


LINK = re.compile(r"\]\((?!https?:|/|#)([^)\s]+)\)")


def _content(root: pathlib.Path, path: str, page_dir: pathlib.Path) -> str:
    """The file's text as it stands in a page in page_dir: its relative links re-pointed from the file's folder."""
    file = root / path
    if not file.is_file():
        raise FileNotFoundError(f"generated block: {path} not found (written by: "
                                f"{RESULTS.get(path, ('', 'its command'))[1]})")
    text = file.read_text(encoding="utf-8")
    text = LINK.sub(lambda m: "](" + pathlib.Path(os.path.relpath(file.parent / m[1], page_dir)).as_posix() + ")", text)
    return text if text.endswith("\n") else text + "\n"


def render(text: str, root: pathlib.Path, page_dir: pathlib.Path | None = None) -> str:
    """The page's text with every generated block replaced by its file's current content."""
    page_dir = page_dir or root
    return BLOCK.sub(lambda m: m.group(1) + _content(root, m["path"], page_dir) + m.group(4), text)


def stale(text: str, root: pathlib.Path, page_dir: pathlib.Path | None = None) -> list[str]:
    """Paths of the blocks whose text differs from their file."""
    page_dir = page_dir or root
    return [path for path, body in blocks(text) if body != _content(root, path, page_dir)]


def collect(root: pathlib.Path) -> list[str]:
    """Copy every result a command has written (results/...) to its committed place; the paths copied."""
    copied = []
    for committed, (written, _) in RESULTS.items():
        src = root / written
        if src.is_file():
            dst = root / committed
            dst.parent.mkdir(parents=True, exist_ok=True)
            text = src.read_text(encoding="utf-8")
            for name in set(re.findall(r"\]\(([\w.-]+\.png)\)", text)):  # figures beside the result file
                if (src.parent / name).is_file():
                    shutil.copyfile(src.parent / name, dst.parent / f"{dst.stem}_{name}")
                    text = text.replace(f"]({name})", f"]({dst.stem}_{name})")
            dst.write_text(text, encoding="utf-8")
            copied.append(committed)
    return copied


def _measured(tests: str, check: str) -> str:
    """The measured figure of the test-table row whose check starts with `check`."""
    for line in tests.splitlines():
        if line.startswith(f"| {check}"):
            return line.split(" | ")[1]
    raise ValueError(f"docs/results/tests.md: no row for '{check}' (rerun python -m pytest)")


def _cases(root: pathlib.Path, name: str) -> str:
    """'N of M' from a diagnosis case summary."""
    m = re.search(r"(\d+ of \d+) cases correct", (root / "docs" / "results" / f"{name}.md").read_text(encoding="utf-8"))
    if not m:
        raise ValueError(f"docs/results/{name}.md: no 'N of M cases correct' line")
    return m[1]


def _peers_headline(res: pathlib.Path) -> str | None:
    """The diagnosis against the equation-error peers on a campaign's random cases, from bench_peers_campaign.md
    (None without it)."""
    path = res / "bench_peers_campaign.md"
    if not path.is_file():
        return None
    text = path.read_text(encoding="utf-8")
    cells = r"(\d+)/(\d+) \((\d+) %\)"
    rows = re.findall(rf"^\| ([^|]+?) \| {cells} \| [^|]+ \| [^|]+ \| {cells} \| (\d+)/(\d+) \|", text, re.M)
    ours = next((r for r in rows if r[0] == "stockbridge diagnose"), None)
    peers = [r for r in rows if r[0] != "stockbridge diagnose"]
    strong = re.search(r"weakest effect ≥ ([\d.]+) × the noise", text)
    if not ours or not peers or not strong:
        return None
    best = max(peers, key=lambda r: int(r[1]))
    return (f"- **Against the alternatives**: on a campaign's {ours[2]} random SDOF cases with one or two withheld "
            f"effects, `stockbridge diagnose` names exactly what was withheld in {ours[3]} % ({ours[6]} % of "
            f"the {ours[5]} whose weakest effect is at least {strong[1]} × the noise); the best equation-error "
            f"method, {best[0]}, in {best[3]} % ({best[6]} %); false alarms on {ours[8]} null cases: {ours[7]} and "
            f"{best[7]} ([validation](../validation/peers.md)).")


def _campaign_headline(res: pathlib.Path, name: str = "campaign.md", label: str = "Validation campaign",
                       cases: str = "SDOF cases", drawn: str = "random loop shapes, excitations, sensors",
                       page: str = "campaigns.md", first: bool = True) -> str | None:
    """A validation campaign's accuracy, from its summary `name` (None without it): the SDOF campaign's by default;
    `cases`, `drawn` and `page` say what it drew and which validation page shows it; `first`: the line that
    says which misses the data cannot decide (a later line refers to it)."""
    path = res / name
    if not path.is_file():
        return None
    text = path.read_text(encoding="utf-8")
    m = re.search(r"Top-1 accuracy on the (\d+) cases with a withheld effect: (\d+) %; false alarms on the (\d+) "
                  r"null cases: (\d+)", text)
    if not m:
        return None
    decided = re.search(r"Top-1 accuracy on the (\d+) cases detected and decided by the data: (\d+) %", text)
    sizes = re.search(r"each withheld effect at ([\d.]+–[\d.]+) × the sensor noise", text)
    return (f"- **{label}**: on {m[1]} random {cases} with one or two withheld effects ("
            + (f"each at {sizes[1]} × the sensor noise; " if sizes else "")
            + f"{drawn}) the diagnosis names exactly what was withheld in "
            f"{m[2]} %"
            + (f", and in {decided[2]} % of the {decided[1]} left when the misses the data cannot decide are set "
               "aside" + (" (a gap within the noise, the named model fitting the held-out files at least as well as "
                          "the truth, or the truth itself removing too little of the gap to be named)" if first else
                          "") if decided else "")
            + f"; false alarms: {m[4]} of {m[3]} null cases ([validation](../validation/{page})).")


def headlines(root: pathlib.Path) -> pathlib.Path:
    """docs/results/headlines.md: the README's headline results, each taken from the committed result file that
    holds it (links relative to docs/results/)."""
    res = root / "docs" / "results"
    tests = (res / "tests.md").read_text(encoding="utf-8")
    speed = re.search(r"SDOF.*?ratio ([0-9.]+)", (res / "bench_eval_speed.md").read_text(encoding="utf-8"))
    run = re.search(r"(\d+) tests passed in (\d+) s on (\d+) cores", tests)
    lines = [
        f"- **Bouc-Wen benchmark**: the SDOF FMU reproduces the official validation outputs to "
        f"{_measured(tests, 'SDOF FMU on the official benchmark multisine')} dB (multisine) and "
        f"{_measured(tests, 'SDOF FMU on the official benchmark sine sweep')} dB (sweep); identified from its own "
        f"estimation data it reaches {_measured(tests, 'Bouc-Wen benchmark identification')} dB on the official "
        "multisine ([validation](../validation/tests.md)).",
        f"- **Gap diagnosis**: the withheld effect (or \"no significant gap\") is named in "
        f"{_cases(root, 'diagnose_lab')} lab-style SDOF sweeps recorded by an accelerometer, a skew between the "
        "channels included ([cases](../validation/cases.md)).",
        _campaign_headline(res),
        _campaign_headline(res, "campaign_damper.md", "Damper campaign", "catalogue dampers",
                           "masses, arms, offsets, messenger stiffness and damping, loop shapes, excitations and "
                           "sensors drawn; the geometry described to the diagnosis", "damper-campaigns.md", first=False),
        _peers_headline(res),
        f"- **Damper physics**: the damper FMU's clamp power matches a harmonic solution of independently "
        f"assembled 6-DOF matrices to a relative error of "
        f"{_measured(tests, 'damper FMU mean clamp power')} ([validation](../validation/tests.md)).",
        f"- **Speed**: an SDOF evaluation through the FMU costs {speed[1]}× a bare C loop of the same integrator "
        "([validation](../validation/crosscheck-and-speed.md#speed))." if speed else None,
        f"- **Tests**: {run[1]} pass in {run[2]} s on {run[3]} cores, each model against an independent "
        "computation ([validation](../validation/tests.md))." if run else None,
    ]
    out = res / "headlines.md"
    out.write_text("\n".join(line for line in lines if line) + "\n", encoding="utf-8")
    return out


class BenchReport:
    """What a bench/ script prints, also written to results/bench/<name>.md (one line per figure, or tables)."""

    def __init__(self, name: str, root: pathlib.Path | None = None):
        self.path = (root or pathlib.Path.cwd()) / "results" / "bench" / f"{name}.md"
        self.blocks: list[str] = []

    def _keep(self, text: str) -> None:
        print(text, flush=True)
        self.blocks.append(text)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.path.write_text("".join(self.blocks), encoding="utf-8")

    def line(self, text: str) -> None:
        """Print one result line and keep it for the file."""
        self._keep(f"- {text}\n")

    def table(self, title: str, header: list[str], rows: list[list]) -> None:
        """Print a Markdown table under a bold title and keep it for the file."""
        lines = [f"\n**{title}**\n", "", "| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
        lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
        self._keep("\n".join(lines) + "\n")
