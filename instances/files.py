"""Writing files so that a failed write leaves nothing behind: through a temporary file in the
same folder, renamed into place."""
from __future__ import annotations

from pathlib import Path


def write_atomic(path: str | Path, text: str, error: type[Exception]) -> None:
    """Write ``text`` to ``path`` through a temporary file in the same folder, then rename."""
    write_with(path, lambda tmp: tmp.write_text(text, encoding="utf-8"), error)


def write_with(path: str | Path, write, error: type[Exception]) -> None:
    """Call ``write(tmp)`` on a temporary path in the folder of ``path``, then rename it to
    ``path``: a failure (an :class:`OSError` becomes ``error``) leaves no file behind."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp")
    try:
        write(tmp)
        tmp.replace(path)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise error(f"{path}: cannot write ({exc.strerror})") from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
