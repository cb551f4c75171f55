"""Every figure in the README's generated blocks is the content of a committed file a command writes."""
import pathlib
import re
import shutil

from pyfit.report import readme

ROOT = pathlib.Path(__file__).resolve().parents[1]


def test_readme_blocks_equal_their_result_files():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(readme.blocks(text)) >= 5
    assert readme.stale(text, ROOT) == []


def test_a_changed_number_in_a_result_file_is_caught(tmp_path):
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    path, _ = readme.blocks(text)[0]
    (tmp_path / path).parent.mkdir(parents=True)
    shutil.copyfile(ROOT / path, tmp_path / path)
    for p, _ in readme.blocks(text)[1:]:
        (tmp_path / p).parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(ROOT / p, tmp_path / p)
    assert readme.stale(text, tmp_path) == []
    content = (tmp_path / path).read_text(encoding="utf-8")
    number = re.search(r"\d+\.\d+", content)
    changed = content[:number.start()] + str(float(number.group()) + 1.0) + content[number.end():]
    (tmp_path / path).write_text(changed, encoding="utf-8")
    assert readme.stale(text, tmp_path) == [path]
    assert readme.stale(readme.render(text, tmp_path), tmp_path) == []


def test_readme_has_exactly_two_setup_commands():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    setup = text.split("## Set-up", 1)[1].split("```bash", 1)[1].split("```", 1)[0]
    commands = [line for line in setup.splitlines() if line.strip() and not line.lstrip().startswith("#")]
    assert commands == ["pip install -e . && python scripts/fit.py", "python -m pytest"]
