"""The README and the docs: every figure in a generated block is the content of a committed file a command
writes; the README is short, names only what a clone holds, and its two set-up commands are the documented
ones; its Python example runs."""
import os
import pathlib
import re
import shutil

from pyfit.report import generated

ROOT = pathlib.Path(__file__).resolve().parents[1]


def test_generated_blocks_equal_their_result_files():
    pages = {p: generated.blocks(p.read_text(encoding="utf-8")) for p in generated.pages(ROOT)}
    assert sum(len(b) for b in pages.values()) >= 10 and pages[ROOT / "README.md"]
    assert generated.stale_files(ROOT) == []


def test_a_changed_number_in_a_result_file_is_caught(tmp_path):
    text = (ROOT / "docs" / "validation" / "campaigns.md").read_text(encoding="utf-8")
    paths = [p for p, _ in generated.blocks(text)]
    for p in paths:
        (tmp_path / p).parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(ROOT / p, tmp_path / p)
    page_dir = tmp_path / "docs"
    assert generated.stale(text, tmp_path, page_dir) == []
    content = (tmp_path / paths[0]).read_text(encoding="utf-8")
    number = re.search(r"\d+\.\d+", content)
    changed = content[:number.start()] + str(float(number.group()) + 1.0) + content[number.end():]
    (tmp_path / paths[0]).write_text(changed, encoding="utf-8")
    assert generated.stale(text, tmp_path, page_dir) == [paths[0]]
    assert generated.stale(generated.render(text, tmp_path, page_dir), tmp_path, page_dir) == []


def test_a_block_in_a_subfolder_page_re_points_relative_links(tmp_path):
    (tmp_path / "docs" / "results").mkdir(parents=True)
    (tmp_path / "docs" / "results" / "r.md").write_text("![fig](r_fig.png) [page](../theory.md) [web](https://x.org/a)\n")
    text = "<!-- generated from docs/results/r.md -->\n<!-- end generated -->\n"
    assert "](results/r_fig.png) [page](theory.md) [web](https://x.org/a)" in generated.render(
        text, tmp_path, tmp_path / "docs")
    assert "](../results/r_fig.png) [page](../theory.md)" in generated.render(text, tmp_path, tmp_path / "docs" / "guide")
    assert "](docs/results/r_fig.png) [page](docs/theory.md)" in generated.render(text, tmp_path)


def test_readme_is_short_has_two_setup_commands_and_names_nothing_outside_the_clone():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 120
    setup = text.split("## Set-up", 1)[1].split("```bash", 1)[1].split("```", 1)[0]
    commands = [line for line in setup.splitlines() if line.strip() and not line.lstrip().startswith("#")]
    assert commands == ['pip install -e ".[test]" && stockbridge fit', "python -m pytest"]
    for page in generated.pages(ROOT):
        words = page.read_text(encoding="utf-8")
        assert "/".join(["..", "shared"]) not in words and "design §" not in words, page  # folders a clone lacks
        assert not re.search(r"(?<![\w/])design\.md", words), page  # the notes a clone does not hold
    for link in re.findall(r"\]\(([^)#\s]+)", text):  # every local link of the README exists in the clone
        assert link.startswith("http") or (ROOT / link).exists(), link


def test_the_readme_python_example_runs(fmu_dir, tmp_path, monkeypatch, capsys):
    code = (ROOT / "README.md").read_text(encoding="utf-8").split("```python\n", 1)[1].split("```", 1)[0]
    os.symlink(fmu_dir, tmp_path / "fmus")
    monkeypatch.chdir(tmp_path)
    exec(compile(code, "README.md", "exec"), {})
    power = float(re.search(r"mean power over the sweep: ([0-9.]+) W", capsys.readouterr().out)[1])
    assert power > 0  # a damper dissipates: F_clamp·v_clamp > 0 in the IEC 61897 sign convention


def test_every_documentation_page_is_at_most_400_lines_and_the_settings_table_is_the_declared_one():
    from pyfit.cli.docs_tables import SETTINGS
    from pyfit.gap.config import settings_table

    long = {str(p.relative_to(ROOT)): n for p in (ROOT / "docs").rglob("*.md")
            if (n := len(p.read_text(encoding="utf-8").splitlines())) > 400}
    assert not long, long
    assert (ROOT / SETTINGS).read_text(encoding="utf-8") == settings_table()
