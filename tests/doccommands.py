"""The commands of the README and docs/: every line of their ```bash blocks, in order.

``tests/test_docs.py`` checks that each ``bille`` line parses (the command, its options and the
methods and method options it names exist). Run as a script, this module runs them as a new user
would, from a fresh clone with bille installed in ``.venv``::

    python tests/doccommands.py OUT [--only README.md --only anytime.md] [--timeout 900]

The README's lines run in the repository (they write into ``docs/``), each page of docs/ in a
folder of its own under OUT that links to the repository's files (``tools/bench/movingai/...``),
so that a page never leans on files another page made. Each line
runs under ``nice`` with the ``bille`` of the interpreter running this script first on PATH, its
output in ``OUT/logs``; at its time limit it gets SIGINT, as a terminal's Ctrl-C (exit 130), and
SIGKILL 30 s later. A table of every line, its exit code, the code its comment expects (``# exit
1: ...``; 0 where it says none) and its seconds is printed at the end.
"""
from __future__ import annotations

import argparse
import itertools
import os
import re
import shlex
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def documents(root: Path = ROOT) -> list[Path]:
    """The README, then the pages of docs/ by name."""
    return [root / "README.md", *sorted((root / "docs").glob("*.md"))]


def lines_of(doc: Path) -> list[str]:
    """The commands of the document's ```bash blocks, in order: continuation lines joined, a
    here-document kept with its command (``cat > f.yaml <<'EOF'`` ... ``EOF``), blank lines and
    lines that are only a comment left out."""
    out = []
    for block in re.findall(r"^```bash\n(.*?)^```", doc.read_text(), re.S | re.M):
        lines = iter(block.replace("\\\n", " ").splitlines())
        for line in lines:
            if not line.strip() or line.lstrip().startswith("#"):
                continue
            here = re.search(r"<<-?\s*['\"]?(\w+)['\"]?", line)
            if here:
                body = []
                for more in lines:
                    body.append(more)
                    if more.strip() == here.group(1):
                        break
                line = "\n".join([line, *body])
            out.append(line.strip())
    return out


def bille_args(line: str) -> list[str] | None:
    """The arguments after ``bille`` (or ``.venv/bin/bille``) in the last command of a ``&&``
    chain, up to a redirection or pipe, or None for a line that runs no bille command."""
    lex = shlex.shlex(line.split("\n")[0], posix=True, punctuation_chars=True)
    lex.whitespace_split = True
    words = list(lex)
    while "&&" in words:
        words = words[words.index("&&") + 1:]
    command = list(itertools.takewhile(lambda w: not set(w) <= set("|&;<>"), words))
    if command and command[0] in ("bille", ".venv/bin/bille"):
        return command[1:]
    return None


def expected_exit(line: str) -> int:
    """The exit code a line's comment announces (``bille check ... # exit 1: ...``), else 0."""
    found = re.search(r"#.*\bexit (\d+)", line.split("\n")[0])
    return int(found.group(1)) if found else 0


def run(out: Path, only: list[str], timeout: float) -> list[tuple[str, str, int, float]]:
    """Run every line of the documents (or of those named in ``only``); see the module docstring."""
    env = dict(os.environ, PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}")
    logs = out / "logs"
    logs.mkdir(parents=True, exist_ok=True)
    rows = []
    for doc in documents():
        if only and doc.name not in only:
            continue
        cwd = ROOT if doc.name == "README.md" else _folder(out / doc.stem)
        for k, line in enumerate(lines_of(doc), 1):
            if doc.name == "README.md" and k <= 2:  # the install and the test suite: run by hand
                continue
            export = re.fullmatch(r"export (\w+)=(\S+)(\s+#.*)?", line)
            if export:
                env[export.group(1)] = export.group(2)
                rows.append((doc.name, line, 0, 0.0))
                continue
            start = time.monotonic()
            code = run_line(line, cwd, env, logs / f"{doc.stem}-{k:02d}", timeout)
            rows.append((doc.name, line, code, time.monotonic() - start))
            print(f"{doc.name}\t{code}\t{expected_exit(line)}\t{rows[-1][3]:.1f}\t{line}", flush=True)
    return rows


def run_line(line: str, cwd: Path, env: dict, log: Path, timeout: float) -> int:
    """Run one line under ``nice`` in ``cwd``, its output in ``log``.out and .err; at ``timeout``
    seconds its process group gets SIGINT, as from a terminal's Ctrl-C, and SIGKILL 30 s later.
    Returns the line's own exit code (130 for a command that ended on the Ctrl-C)."""
    command = ["timeout", "--preserve-status", "-s", "INT", "-k", "30", str(timeout), "nice", "bash", "-c", line]
    with open(f"{log}.out", "w") as stdout, open(f"{log}.err", "w") as stderr:
        return subprocess.call(command, cwd=cwd, env=env, stdin=subprocess.DEVNULL, stdout=stdout, stderr=stderr)


def _folder(path: Path) -> Path:
    """An empty working folder for one page, with links to the repository's own top-level files
    (those git tracks: not what the README's lines wrote there)."""
    path.mkdir(parents=True, exist_ok=True)
    for name in tracked_tops(ROOT):
        if not (path / name).exists():
            (path / name).symlink_to(ROOT / name)
    return path


def tracked_tops(root: Path) -> list[str]:
    """The top-level names of the files git tracks in ``root``, hidden ones left out."""
    listed = subprocess.run(["git", "ls-files"], cwd=root, capture_output=True, text=True, check=True).stdout
    return sorted({line.split("/")[0] for line in listed.splitlines() if not line.startswith(".")})


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("out", type=Path, help="folder for the pages' working folders and the logs")
    parser.add_argument("--only", action="append", default=[], help="a document's file name (repeatable)")
    parser.add_argument("--timeout", type=float, default=900.0, help="seconds per line before Ctrl-C")
    args = parser.parse_args()
    rows = run(args.out.resolve(), args.only, args.timeout)
    print("\n| document | command | exit | expected | seconds |\n|---|---|---|---|---|")
    for doc, line, code, seconds in rows:
        print(f"| {doc} | `{line.split('  #')[0].strip()}` | {code} | {expected_exit(line)} | {seconds:.1f} |")


if __name__ == "__main__":
    main()
