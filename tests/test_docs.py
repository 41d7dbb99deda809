"""The user docs stay true: motion drawings match the shipped movesets, README commands exist."""
import re
from pathlib import Path

import pytest

from bille.instances import load_moveset
from bille.tools.render import motion_diagram

ROOT = Path(__file__).parent.parent
RULES = (ROOT / "docs" / "rules.md").read_text()


@pytest.mark.parametrize("action", load_moveset("S7").names)
def test_rules_doc_draws_each_motion_from_the_data(action):
    drawing = "\n".join(motion_diagram(load_moveset("S7"), action))
    assert f"#### `{action}`" in RULES
    assert drawing in RULES, f"docs/rules.md has an outdated drawing of {action}"


def test_rules_doc_table_matches_the_moveset_files():
    s7 = load_moveset("S7")
    for act in s7.actions:
        row = re.search(rf"^\| `{act.name}` \| \(([-\d]+),([-\d]+)\) \| \(([-\d]+),([-\d]+)\) \|", RULES, re.M)
        assert row, act.name
        front, back = tuple(map(int, row.groups()[:2])), tuple(map(int, row.groups()[2:]))
        assert (front, back) == (act.front, act.back)


def test_readme_starts_with_the_two_commands():
    readme = (ROOT / "README.md").read_text()
    block = re.search(r"```bash\n(.*?)```", readme, re.S).group(1).strip().splitlines()
    assert len(block) == 2
    assert "pip install -e '.[test]'" in block[0] and block[0].endswith(".venv/bin/bille gap")
    assert block[1] == ".venv/bin/python -m pytest"
    ci = (ROOT / ".ci" / "run").read_text()
    assert "pip install --quiet -e '.[test]'" in ci and ".venv/bin/python -m pytest" in ci


def test_readme_and_docs_pictures_exist():
    for doc in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
        for target in re.findall(r"!\[[^\]]*\]\(([^)]+)\)", doc.read_text()):
            picture = (doc.parent / target)
            assert picture.is_file() and picture.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", f"{doc.name}: {target}"


def test_readme_commands_exist():
    from bille.tools.cli import cli

    readme = (ROOT / "README.md").read_text()
    blocks = "\n".join(re.findall(r"```bash\n(.*?)```", readme, re.S))
    commands = [c for c in re.findall(r"^bille ([a-z-]+)", blocks, re.M) if not c.startswith("-")]
    assert len(commands) > 10
    for command in commands:
        assert command in cli.commands, command
