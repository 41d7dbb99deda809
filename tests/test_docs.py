"""The user docs stay true: motion drawings match the shipped movesets, README commands exist."""
import os
import re
import subprocess
from pathlib import Path

import click
import pytest
from doccommands import bille_args, documents, expected_exit, lines_of, run_line, tracked_tops

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


DOC_COMMANDS = [(doc.name, line) for doc in documents() for line in lines_of(doc) if bille_args(line) is not None]


def _parse(args: list[str]) -> click.Context:
    """Parse ``bille ARGS`` as the command line would, down to the command that runs, without
    running it; returns that command's context (its parameters converted and checked)."""
    from bille.tools.cli import cli

    cmd, name, ctx = cli, "bille", None
    while isinstance(cmd, click.Group) and args and not args[0].startswith("-"):
        ctx = cmd.make_context(name, [], parent=ctx, resilient_parsing=True)
        name, cmd, args = cmd.resolve_command(ctx, args)
    return cmd.make_context(name, args, parent=ctx)


def test_docs_have_commands():
    pages = {doc for doc, _ in DOC_COMMANDS}
    assert "README.md" in pages and {"anytime.md", "exact.md", "planners.md", "sweeps.md"} <= pages
    assert len(DOC_COMMANDS) > 60


@pytest.mark.parametrize("doc, line", DOC_COMMANDS, ids=[f"{doc}:{line[:60]}" for doc, line in DOC_COMMANDS])
def test_docs_commands_parse(doc, line, monkeypatch):
    """Every ``bille`` line of the README's and the docs' bash blocks names a command and options
    that exist, with values of the right type, and methods and method options (``-O``, ``gap
    --methods``) that exist; a file it names need not exist yet (an earlier line makes it)."""
    from bille.solvers.options import check_options, gather_options
    from bille.tools.gap import parse_configs
    from bille.tools.solve_commands import _parse_options

    for path_type in {id(p.type): p.type for p in _all_params() if isinstance(p.type, click.Path)}.values():
        monkeypatch.setattr(path_type, "exists", False)
    try:
        ctx = _parse(bille_args(line))
    except click.exceptions.Exit as stop:  # --help, --version
        assert stop.exit_code == 0, line
        return
    except click.UsageError as exc:
        pytest.fail(f"{doc}: {line}: {exc.format_message()}")
    params = ctx.params
    if ctx.command.name == "solve" and params["extra"]:
        check_options(params["method"], gather_options(params["method"], _parse_options(params["extra"])))
    if ctx.command.name == "gap":
        parse_configs(params["methods"])


def test_doc_line_stopped_at_its_limit_exits_with_its_own_code(tmp_path):
    """A line that runs past its limit gets Ctrl-C and exits 130, as from a terminal (not the
    124 of ``timeout``); a line that ends by itself keeps its code."""
    assert run_line("sleep 20", tmp_path, dict(os.environ), tmp_path / "slow", 0.3) == 130
    assert run_line("echo hi; exit 3", tmp_path, dict(os.environ), tmp_path / "quick", 20) == 3
    assert (tmp_path / "quick.out").read_text() == "hi\n"


def test_doc_pages_see_the_repository_not_what_other_pages_wrote(tmp_path):
    """A page's folder links what git tracks (the shipped MovingAI maps under tools/), not what
    the README's lines wrote into the repository (gap.csv, sweep-small/)."""
    (tmp_path / "tools").mkdir()
    (tmp_path / "tools" / "room.map").write_text("..")
    (tmp_path / "README.md").write_text("x")
    subprocess.run(["git", "init", "-q"], cwd=tmp_path, check=True)
    subprocess.run(["git", "add", "tools", "README.md"], cwd=tmp_path, check=True)
    (tmp_path / "gap.csv").write_text("written by a README line")
    (tmp_path / "sweep-small").mkdir()
    assert tracked_tops(tmp_path) == ["README.md", "tools"]


def _all_params():
    from bille.tools.cli import cli

    stack = [cli]
    while stack:
        cmd = stack.pop()
        yield from cmd.params
        if isinstance(cmd, click.Group):  # the top group loads its commands when they are looked up
            ctx = click.Context(cmd)
            stack += [cmd.get_command(ctx, name) for name in cmd.list_commands(ctx)]


def test_doc_command_lines_are_read_whole(tmp_path):
    doc = tmp_path / "page.md"
    doc.write_text("text\n```bash\n# a comment\nbille solve lt-4 \\\n  -m cpsat   # why\n\nprintf 'oo' > g\n"
                   "cat > s.yaml <<'EOF'\nname: s   # kept\n\nEOF\nbille sweep s.yaml\n```\n"
                   "```\nbille not-a-command\n```\n")
    assert lines_of(doc) == ["bille solve lt-4    -m cpsat   # why", "printf 'oo' > g",
                             "cat > s.yaml <<'EOF'\nname: s   # kept\n\nEOF", "bille sweep s.yaml"]
    assert bille_args(lines_of(doc)[0]) == ["solve", "lt-4", "-m", "cpsat"]
    assert bille_args("python3.11 -m venv .venv && .venv/bin/bille gap") == ["gap"]
    assert bille_args("bille solve lt-4 --json > out.json  # stats") == ["solve", "lt-4", "--json"]
    assert bille_args("bille bench sweep --runs 1000 | tail -1") == ["bench", "sweep", "--runs", "1000"]
    assert bille_args(lines_of(doc)[2]) is None
    assert expected_exit("bille check c2 bad.yaml   # exit 1: the first violation") == 1
    assert expected_exit(lines_of(doc)[0]) == 0
    assert bille_args(lines_of(doc)[1]) is None
    with pytest.raises(click.UsageError):
        _parse(["solve", "lt-4", "--no-such-option"])
    with pytest.raises(click.UsageError):
        _parse(["sweep", "report"])
