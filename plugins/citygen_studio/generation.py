"""Generating a studio session's whole scene in a background thread, its progress readable while it runs."""
from __future__ import annotations

import os
import threading
from pathlib import Path
from typing import Any

from citygen.errors import CitygenError
from citygen.pipeline import generate_city
from citygen.registry import Registry
from citygen.scene import Scene
from citygen_studio.confinement import error_data

#: Output formats the studio's generate writes (into ``OUTPUT_FOLDER`` under the scene's folder).
OUTPUT_SUFFIXES = (".usdc", ".usda", ".usdz", ".glb")
OUTPUT_FOLDER = "studio-out"


class Generation:
    """One run of the whole scene in a background thread, its progress readable while it runs; ``edited`` names the
    rulesets it reads as unsaved edits (``registry`` reads them so)."""

    def __init__(self, scene: Scene, registry: Registry, out: Path, jobs: int, edited: tuple[str, ...] = ()) -> None:
        self.out, self.done, self.total, self.edited = out, 0, 0, edited
        self.report: dict[str, Any] | None = None
        self.error: dict[str, Any] | None = None
        self.thread = threading.Thread(target=self._run, args=(scene, registry, jobs), daemon=True)
        self.thread.start()

    def _progress(self, done: int, total: int) -> None:
        self.done, self.total = done, total

    def _run(self, scene: Scene, registry: Registry, jobs: int) -> None:
        try:
            report = generate_city(scene, out=self.out, jobs=jobs, registry=registry, progress=self._progress)
            self.report = {**report.to_dict(), "summary": report.summary()}
        except CitygenError as exc:
            self.error = error_data(exc)
        except Exception as exc:  # a library bug ends this run, not the studio
            self.error = {"message": f"internal error {type(exc).__name__}: {exc}"}

    def state(self, root: Path) -> dict[str, Any]:
        running = self.thread.is_alive()
        return {"running": running, "done": self.done, "total": self.total, "error": self.error,
                "report": None if running else self.report, "output": os.path.relpath(self.out, root),
                "edited": list(self.edited)}
