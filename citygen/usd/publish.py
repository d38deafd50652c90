"""Publishing a stage's files so that no moment, crash or ``kill -9`` leaves a root composing the wrong tiles, and
no temporary file outlives the next run.

Every file is written as a temporary beside its target and renamed (:mod:`citygen.temporaries`).

*Tile layers* are published under content names, ``<stem>_tiles/Tile_<i>_<j>.<digest>.usdc`` (:func:`publish_tile`):
a new run's tiles never overwrite a tile the current root lists (equal names mean equal bytes), so the old root
stays whole until the new root replaces it in one rename; only then are the tiles no root lists any more removed
(:func:`remove_unlisted_tiles`). Same scene and seed, same tile bytes, same names: the root is byte-identical.
"""
from __future__ import annotations

import contextlib
import hashlib
import os
import re
import tempfile
from collections.abc import Collection
from pathlib import Path

from pxr import Sdf, Tf

from citygen.errors import ExportError
from citygen.temporaries import TEMPORARY, current_umask, remove_stale_temporaries, temp_prefix

#: Modification time given to the files packed into a .usdz (its zip records them): 2000-01-01, so the same city
#: packs to the same bytes.
PACKED_MTIME = 946684800
#: Hex digits of the content digest in a published tile's name.
DIGEST_DIGITS = 12


def publish_tile(staged: Path, tiles_dir: Path) -> str:
    """Move the finished tile layer ``staged`` (``Tile_i_j.usdc``) into ``tiles_dir`` as ``Tile_i_j.<digest>.usdc``;
    return that name. A tile of the same name there already has the same bytes: it stays, ``staged`` goes."""
    digest = hashlib.blake2b(digest_size=DIGEST_DIGITS // 2)
    with open(staged, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    name = f"{staged.stem}.{digest.hexdigest()}{staged.suffix}"
    target = tiles_dir / name
    if target.is_file():
        staged.unlink()
    else:
        os.replace(staged, target)
    return name


def remove_unlisted_tiles(tiles_dir: Path, listed: Collection[str], since: float) -> None:
    """After the root was replaced: remove the files in ``tiles_dir`` it does not list that are older than
    ``since`` (the run's start; a concurrent run's newer tiles stay for its root), and stale temporaries."""
    remove_stale_temporaries(tiles_dir)
    with contextlib.suppress(OSError):
        for entry in tiles_dir.iterdir():
            if entry.name in listed or TEMPORARY.match(entry.name) or not entry.is_file():
                continue
            with contextlib.suppress(OSError):
                if entry.stat().st_mtime < since:
                    entry.unlink()


def export_layer(layer: Sdf.Layer, target: Path) -> None:
    """``layer.Export`` whose failures (False, a ``Tf.ErrorException`` such as a full disk, an OSError) are one
    :class:`ExportError` naming the file and USD's first reason."""
    try:
        if layer.Export(str(target)):
            return
        reason = ""
    except Tf.ErrorException as exc:
        reason = _usd_reason(exc)
    except OSError as exc:
        reason = exc.strerror or str(exc)
    raise ExportError(f"USD export failed{': ' + reason if reason else ''}", where=str(target),
                      hint="check free disk space and permissions")


def _usd_reason(exc: Tf.ErrorException) -> str:
    """The commentary of the first error inside a ``Tf.ErrorException`` (its text lists every error, with C++
    function names and source lines)."""
    text = "\n".join(str(a) for a in exc.args) or str(exc)
    match = re.search(r" : '([^\n]*)'", text)
    return match[1] if match else text.strip().splitlines()[0] if text.strip() else ""


def write_layer(layer: Sdf.Layer, path: Path) -> int:
    """Export ``layer`` to ``path`` through a temporary file in the same folder; return the file size. A
    ``.usdz``'s root layer is named after it (``city.usdz`` holds ``city.usdc``). On any failure (an
    :class:`ExportError`) the file at ``path`` is unchanged and the temporary one removed."""
    suffix = path.suffix.lower()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp_name = tempfile.mkstemp(prefix=temp_prefix(path.stem), suffix=suffix, dir=path.parent)
    except OSError as exc:
        raise ExportError(f"cannot write the stage: {exc.strerror or exc}", where=str(path),
                          hint="check free disk space and permissions") from None
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        if suffix == ".usdz":
            from pxr import UsdUtils  # (with UsdShade and UsdGeom: only a .usdz needs them)
            inner = tmp.with_suffix(".usdc")
            export_layer(layer, inner)
            os.utime(inner, (PACKED_MTIME, PACKED_MTIME))
            try:
                if not UsdUtils.CreateNewUsdzPackage(Sdf.AssetPath(str(inner)), str(tmp), f"{path.stem}.usdc"):
                    raise ExportError("usdz packaging failed", where=str(path))
            finally:
                inner.unlink(missing_ok=True)
        else:
            export_layer(layer, tmp)
        os.chmod(tmp, 0o666 & ~current_umask())  # mkstemp makes 0600; a stage is an ordinary file
        os.replace(tmp, path)
    except OSError as exc:
        raise ExportError(f"cannot write the stage: {exc.strerror or exc}", where=str(path),
                          hint="check free disk space and permissions") from None
    except ExportError as exc:  # named by the stage's path, not the temporary file's
        raise ExportError(exc.message, where=str(path), hint=exc.hint) from None
    finally:
        tmp.unlink(missing_ok=True)
    return path.stat().st_size
