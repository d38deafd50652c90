"""Temporaries: every file citygen writes is first written beside its target as ``.<name>.citygen-<pid>-<random>``
(:func:`temp_prefix`) and renamed when whole. A later run removes those whose process is gone
(:func:`remove_stale_temporaries`), and never those of a writer still running. Without USD: output paths are checked
and stale temporaries removed before the stage writer is imported.
"""
from __future__ import annotations

import contextlib
import os
import re
import shutil
from pathlib import Path

#: A temporary's name; group 1 is the process id of its writer.
TEMPORARY = re.compile(r"^\..+\.citygen-(\d+)-")


def temp_prefix(name: str) -> str:
    """The prefix of a temporary for file or folder ``name`` written by this process (for ``tempfile``)."""
    return f".{name}.citygen-{os.getpid()}-"


def current_umask() -> int:
    """The process's file mode creation mask (read without changing it)."""
    umask = os.umask(0)
    os.umask(umask)
    return umask


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's live process
        return True
    return True


def remove_stale_temporaries(folder: Path) -> list[Path]:
    """Remove the temporaries in ``folder`` (files or folders named by :func:`temp_prefix`) whose process no
    longer runs; return what was removed. Nothing else is touched."""
    removed = []
    with contextlib.suppress(OSError):
        for entry in folder.iterdir():
            match = TEMPORARY.match(entry.name)
            if match and int(match[1]) != os.getpid() and not _alive(int(match[1])):
                if entry.is_dir() and not entry.is_symlink():
                    shutil.rmtree(entry, ignore_errors=True)
                else:
                    entry.unlink(missing_ok=True)
                removed.append(entry)
    return removed
