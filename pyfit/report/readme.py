"""The README's figures come from files that commands write. A generated block in README.md is the verbatim
content of one committed result file:

    <!-- generated from docs/results/quickstart.md -->
    (the file's content)
    <!-- end generated -->

`collect` copies each result a command has written under results/ to its committed place (RESULTS), with
the figures it links to;
`render` rewrites every block from its file; `stale` names the blocks that differ from their files.
"""
from __future__ import annotations

import pathlib
import re
import shutil

BLOCK = re.compile(r"(<!-- generated from (?P<path>\S+) -->\n)(?P<body>.*?)(<!-- end generated -->)", re.S)

# committed file -> (what the command writes, the command)
RESULTS = {
    "docs/results/tests.md": ("results/tests.md", "python -m pytest"),
    "docs/results/quickstart.md": ("results/quickstart/summary.md",
                                   "python scripts/fit.py --repeats 2 --out results/quickstart"),
    "docs/results/diagnose_cases.md": ("results/diagnose_cases/summary.md",
                                       "python scripts/diagnose.py --make-datasets results/gap_cases && "
                                       "python scripts/diagnose.py --cases results/gap_cases --out "
                                       "results/diagnose_cases"),
    "docs/results/diagnose_cases_damper.md": ("results/diagnose_cases_damper/summary.md",
                                              "python scripts/diagnose.py --model damper --make-datasets "
                                              "results/gap_cases_damper --seeds 0 && python scripts/diagnose.py "
                                              "--model damper --cases results/gap_cases_damper --out "
                                              "results/diagnose_cases_damper"),
    "docs/results/diagnose_benchmark.md": ("results/diagnose_benchmark/report.md",
                                           "python scripts/diagnose.py --benchmark --config "
                                           "configs/diagnose_benchmark.toml --out results/diagnose_benchmark"),
    "docs/results/lab_example.md": ("results/lab_report/report.md",
                                    "python scripts/diagnose.py --make-datasets results/lab --excitation sweep "
                                    "--record a --seeds 0 && python scripts/diagnose.py --model sdof --data "
                                    "results/lab/sdof_hysteresis --out results/lab_report"),
    "docs/results/diagnose_lab.md": ("results/diagnose_lab/summary.md",
                                     "python scripts/diagnose.py --make-datasets results/lab_cases --excitation sweep "
                                     "--record a --seeds 0 && python scripts/diagnose.py --cases results/lab_cases "
                                     "--out results/diagnose_lab"),
    "docs/results/diagnose_lab_damper.md": ("results/diagnose_lab_damper/summary.md",
                                            "python scripts/diagnose.py --model damper --nominal "
                                            "configs/symmetric_damper.toml --make-datasets results/lab_cases_damper "
                                            "--excitation sweep --motion x --seeds 0 && python scripts/diagnose.py "
                                            "--model damper --nominal configs/symmetric_damper.toml --cases "
                                            "results/lab_cases_damper --out results/diagnose_lab_damper"),
    "docs/results/diagnose_lab_design.md": ("results/diagnose_lab_design/summary.md",
                                            "python scripts/diagnose.py --model damper --make-datasets "
                                            "results/lab_cases_design --excitation sweep --motion x --seeds 0 && "
                                            "python scripts/diagnose.py --model damper --cases results/lab_cases_design "
                                            "--out results/diagnose_lab_design"),
    "docs/results/diagnose_lab_design_acc.md": ("results/diagnose_lab_design_acc/summary.md",
                                                "python scripts/diagnose.py --model damper --make-datasets "
                                                "results/lab_cases_design_acc --excitation sweep --record acc_x1 "
                                                "acc_x2 --motion a --seeds 0 && python scripts/diagnose.py --model "
                                                "damper --cases results/lab_cases_design_acc --out "
                                                "results/diagnose_lab_design_acc"),
    "docs/results/diagnose_impedance.md": ("results/diagnose_impedance/summary.md",
                                           "python scripts/diagnose.py --model damper --make-datasets "
                                           "results/impedance_cases --excitation impedance --seeds 0 && "
                                           "python scripts/diagnose.py --model damper --cases results/impedance_cases "
                                           "--out results/diagnose_impedance"),
    "docs/results/boucwen_benchmark.md": ("results/boucwen_benchmark/summary.md",
                                          "python scripts/fit.py configs/boucwen_benchmark.toml --repeats 2 "
                                          "--out results/boucwen_benchmark"),
    "docs/results/bench_batch_speedup.md": ("results/bench/batch_speedup.md", "python bench/batch_speedup.py"),
    "docs/results/bench_fmu_soak.md": ("results/bench/fmu_soak.md", "python bench/fmu_soak.py"),
    "docs/results/bench_eval_speed.md": ("results/bench/eval_speed.md", "python bench/eval_speed.py"),
    "docs/results/bench_diagnose_time.md": ("results/bench/diagnose_time.md", "python bench/diagnose_time.py"),
    "docs/results/bench_fit_time.md": ("results/bench/fit_time.md", "python bench/fit_time.py"),
    "docs/results/design_check.md": ("results/design_check/design_check.md",
                                     "python scripts/design_check.py configs/span_drake_300m.toml"),
    "docs/results/verify_balance.md": ("results/verify_balance/verify_balance.md", "python scripts/verify_balance.py"),
    "docs/results/bench_importer_tolerance.md": ("results/bench/importer_tolerance.md",
                                                 "python bench/importer_tolerance.py"),
}


def blocks(text: str) -> list[tuple[str, str]]:
    """(file path, body) of every generated block, in order."""
    return [(m["path"], m["body"]) for m in BLOCK.finditer(text)]


def _content(root: pathlib.Path, path: str) -> str:
    file = root / path
    if not file.is_file():
        raise FileNotFoundError(f"README block: {path} not found (written by: "
                                f"{RESULTS.get(path, ('', 'its command'))[1]})")
    text = file.read_text(encoding="utf-8")
    return text if text.endswith("\n") else text + "\n"


def render(text: str, root: pathlib.Path) -> str:
    """The README text with every generated block replaced by its file's current content."""
    return BLOCK.sub(lambda m: m.group(1) + _content(root, m["path"]) + m.group(4), text)


def stale(text: str, root: pathlib.Path) -> list[str]:
    """Paths of the blocks whose text differs from their file."""
    return [path for path, body in blocks(text) if body != _content(root, path)]


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
                    text = text.replace(f"]({name})", f"]({dst.parent.relative_to(root).as_posix()}/{dst.stem}_{name})")
            dst.write_text(text, encoding="utf-8")
            copied.append(committed)
    return copied


class BenchReport:
    """What a bench/ script prints, also written to results/bench/<name>.md (one line per figure)."""

    def __init__(self, name: str, root: pathlib.Path | None = None):
        self.path = (root or pathlib.Path.cwd()) / "results" / "bench" / f"{name}.md"
        self.lines: list[str] = []

    def line(self, text: str) -> None:
        """Print one result line and keep it for the file."""
        print(text, flush=True)
        self.lines.append(text)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.path.write_text("".join(f"- {t}\n" for t in self.lines), encoding="utf-8")
