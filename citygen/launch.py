"""The ``citygen`` console script. A command registered in the ``citygen.early`` entry-point group (``name =
"module:function"``, called with the command's arguments) starts here, before the plugins load: a server that
must answer at once (``citygen studio``) loads them behind its first page. Every other command runs through
:func:`citygen.cli.main`, which loads the plugins first."""
from __future__ import annotations

import importlib.metadata
import sys


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv and not argv[0].startswith("-"):
        for entry in importlib.metadata.entry_points(group="citygen.early"):
            if entry.name == argv[0]:
                return int(entry.load()(argv[1:]) or 0)
    from citygen.cli import main as run
    return run(argv)


if __name__ == "__main__":
    sys.exit(main())
