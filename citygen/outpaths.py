"""Output paths checked before a run generates anything, and small text files written atomically.

Missing folders on the way to an output are created (``-o out/new/city.usdc``, ``--png``, ``--report`` alike);
anything else that would stop the file from being written -- the path is a folder, a parent is a file, the folder
refuses new files (read-only, ``/proc``) -- is an :class:`ExportError` naming the path, raised up front.
"""
from __future__ import annotations

import os
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any, BinaryIO

from citygen.errors import ExportError
from citygen.temporaries import current_umask, temp_prefix


def check_writable(path: str | Path, what: str) -> None:
    """Raise :class:`ExportError` when a ``what`` (e.g. "stage", "report") cannot be written at ``path``: probes
    the nearest existing folder on its way by creating and removing a hidden file there."""
    path = Path(path)
    if _is(path, Path.is_dir):
        raise ExportError(f"cannot write the {what}: the path is a folder", where=str(path),
                          hint="give a file name")
    folder = path.parent
    while not _is(folder, Path.exists) and folder != folder.parent:
        folder = folder.parent
    if not _is(folder, Path.is_dir):
        raise ExportError(f"cannot write the {what}: {folder} is not a folder", where=str(path))
    try:
        fd, probe = tempfile.mkstemp(prefix=temp_prefix("probe"), dir=folder)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise ExportError(f"cannot write the {what}: {exc.strerror or exc} in {folder}", where=str(path),
                          hint="choose another output path or fix the folder's permissions") from None


def write_text(path: str | Path, text: str, what: str) -> None:
    """Write ``text`` to ``path`` through a temporary file in the same folder (created if missing), so a failed
    write keeps the previous file; an OSError becomes an :class:`ExportError` naming ``path``."""
    write_file(path, lambda f: f.write(text.encode("utf-8")), what)


def write_png(image: Any, path: str | Path, what: str = "PNG") -> None:
    """A PIL ``image`` saved as PNG at ``path`` the way :func:`write_text` writes text."""
    write_file(path, lambda f: image.save(f, format="PNG"), what)


def write_file(path: str | Path, write: Callable[[BinaryIO], object], what: str) -> None:
    """Call ``write`` on a temporary file in ``path``'s folder (created if missing), then rename it to ``path``
    with ordinary permissions; on an OSError (an :class:`ExportError` naming ``path``) the previous file stays."""
    path = Path(path)
    tmp: Path | None = None
    try:
        if _is(path, Path.is_dir):
            raise IsADirectoryError(21, "the path is a folder")
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, name = tempfile.mkstemp(prefix=temp_prefix(path.name), suffix=".tmp", dir=path.parent)
        tmp = Path(name)
        with os.fdopen(fd, "wb") as f:
            write(f)
        os.chmod(tmp, 0o666 & ~current_umask())  # mkstemp makes 0600; the result is an ordinary file
        os.replace(tmp, path)
        tmp = None
    except OSError as exc:
        raise ExportError(f"cannot write the {what}: {exc.strerror or exc}", where=str(path),
                          hint="check free disk space and permissions") from None
    finally:
        if tmp is not None:
            tmp.unlink(missing_ok=True)


def _is(path: Path, test) -> bool:
    """``test(path)``, False for a name the file system refuses (too long, not a folder on the way)."""
    try:
        return test(path)
    except OSError:
        return False
