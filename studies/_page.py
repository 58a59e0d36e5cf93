"""The one writer of the studies' results pages (docs/results/*.md).

Every study writes its page through ``write``: the page's text, which names the command that
wrote it, then, when the page reads a folder of runs, the line saying that the command makes
that folder and that the repository does not keep it (.gitignore lists the run folders). A
page is thus regenerated, never edited by hand, and its figures are the ones the tests of
tests/docs.rs compare the README and docs with.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Iterable, Optional, Sequence, Union

REPO = Path(__file__).resolve().parent.parent


def runs_note(runs: Union[str, Path]) -> str:
    """The line that says where a page's runs are: made by its command, not kept in git."""
    shown = os.path.relpath(Path(runs).resolve(), REPO) if Path(runs).is_absolute() else str(runs)
    return (f"The runs this page reads (`{shown.rstrip('/')}/`) are made by the command that "
            "wrote it; the repository does not keep them.")


def table(header: Sequence[str], rows: Iterable[Sequence[object]]) -> list[str]:
    """A markdown table: the header, its rule, one line per row (cells as ``str`` gives them)."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return lines


def write(path: Union[str, Path], text: Union[str, Sequence[str]],
          runs: Optional[Union[str, Path]] = None) -> Path:
    """Writes the page ``path`` (its folder made if missing): ``text`` (a string or its lines),
    then, with ``runs``, ``runs_note(runs)``; the file ends with one newline."""
    body = text if isinstance(text, str) else "\n".join(text)
    body = body.rstrip("\n")
    if runs is not None:
        body += "\n\n" + runs_note(runs)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(body + "\n")
    return path
