"""Output problems (issue 23 #3 and the rule for missing folders): found before generating where they can be, one
``citygen: error:`` line (exit 2) when a write fails, the previous file kept, nothing left behind."""
from __future__ import annotations

import errno
import os
import resource
import signal

import pytest

import citygen.pipeline as pipeline
from citygen.cli import main
from citygen.errors import ExportError
from citygen.scene import load_scene
from tests.core.cli_scene import citygen_process, write_scene


def _no_generation(monkeypatch):
    def refuse(*args, **kw):
        raise AssertionError("footprints were imported: the output was not checked first")
    monkeypatch.setattr(pipeline, "import_footprints", refuse)


def _one_error_line(err: str, *needles: str) -> None:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("citygen: error: "), err
    for needle in needles:
        assert needle in lines[0]


def test_a_stage_under_proc_is_refused_before_generating(tmp_path, monkeypatch, capsys):
    """Was: the whole city generated, then a traceback from the writer."""
    scene = write_scene(tmp_path)
    _no_generation(monkeypatch)
    assert main(["generate", str(scene), "-q", "-o", "/proc/citygen-test/city.usdc"]) == 2
    _one_error_line(capsys.readouterr().err, "/proc/citygen-test/city.usdc: cannot write the stage")


def test_a_stage_whose_folder_is_a_file_or_a_folder_itself_is_refused(tmp_path, monkeypatch):
    (tmp_path / "file").write_text("x")
    (tmp_path / "dir.usdc").mkdir()
    scene = load_scene(write_scene(tmp_path))
    _no_generation(monkeypatch)
    with pytest.raises(ExportError, match="is not a folder"):
        pipeline.generate_city(scene, out=tmp_path / "file" / "city.usdc")
    with pytest.raises(ExportError, match="the path is a folder"):
        pipeline.generate_city(scene, out=tmp_path / "dir.usdc")
    with pytest.raises(ExportError, match="unsupported output extension '.obj'"):
        pipeline.generate_city(scene, out=tmp_path / "city.obj")


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only folders")
def test_a_read_only_output_folder_is_refused_before_generating(tmp_path, monkeypatch):
    folder = tmp_path / "ro"
    folder.mkdir(mode=0o555)
    _no_generation(monkeypatch)
    with pytest.raises(ExportError, match="cannot write the stage: Permission denied"):
        pipeline.generate_city(load_scene(write_scene(tmp_path)), out=folder / "city.usdc")


def test_a_report_path_that_is_a_folder_is_refused_before_generating(tmp_path, monkeypatch, capsys):
    scene = write_scene(tmp_path)
    (tmp_path / "report.json").mkdir()
    _no_generation(monkeypatch)
    assert main(["generate", str(scene), "-q", "--report", str(tmp_path / "report.json")]) == 2
    _one_error_line(capsys.readouterr().err, "report.json: cannot write the report: the path is a folder")
    assert not (tmp_path / "out").exists()


def _limit_file_size():
    """In the child: files may not grow past 64 kB, as on a full disk (EFBIG instead of ENOSPC)."""
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (64_000, 64_000))


def test_a_full_disk_is_one_line_and_keeps_the_previous_stage(tmp_path):
    """Was: a ``pxr.Tf.ErrorException`` traceback with an empty message after the whole run."""
    scene = write_scene(tmp_path, buildings=30)
    assert main(["generate", str(scene), "-q"]) == 0
    stage = tmp_path / "out" / "city.usdc"
    before = stage.read_bytes()
    assert len(before) > 64_000
    proc = citygen_process("generate", str(scene), "-q", "--seed", "7", preexec=_limit_file_size)
    out, err = proc.communicate(timeout=300)
    assert proc.returncode == 2
    _one_error_line(err, f"{stage}: USD export failed: Error occurred writing file: File too large")
    assert stage.read_bytes() == before
    assert sorted(p.name for p in stage.parent.iterdir()) == ["city.usdc"]  # no temporary left


def test_a_failing_report_write_is_one_line_and_keeps_the_previous_report(tmp_path, monkeypatch, capsys):
    scene = write_scene(tmp_path)
    report = tmp_path / "report.json"
    report.write_text("previous\n")

    replace = os.replace

    def full_for_the_report(src, dst):
        if str(dst) == str(report):
            raise OSError(errno.ENOSPC, "No space left on device")
        replace(src, dst)

    monkeypatch.setattr(os, "replace", full_for_the_report)
    assert main(["generate", str(scene), "-q", "--report", str(report)]) == 2
    _one_error_line(capsys.readouterr().err,
                    "report.json: cannot write the report: No space left on device")
    assert report.read_text() == "previous\n"
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == []


def test_png_previews_create_missing_folders_as_stages_do(tmp_path, capsys):
    """One rule for outputs: missing folders are created (was: ``--png`` into a new folder was a traceback)."""
    png = tmp_path / "new" / "deeper" / "house.png"
    assert main(["facade", "rulesets/house.grammar", "--size", "10", "6", "--png", str(png)]) == 0
    assert png.read_bytes().startswith(b"\x89PNG")
    capsys.readouterr()
    assert main(["facade", "rulesets/house.grammar", "--size", "10", "6", "--png", "/proc/citygen/x.png"]) == 2
    _one_error_line(capsys.readouterr().err, "/proc/citygen/x.png: cannot write the PNG")


def test_extracted_grammars_are_ordinary_files(tmp_path):
    """Was: ``grammar extract -o`` wrote mode 0600 (a mkstemp file renamed into place)."""
    from tests.inverse.test_cli import XML
    layout = tmp_path / "b.json"
    grammar = tmp_path / "b.grammar"
    umask = os.umask(0o022)
    try:
        assert main(["layout", "import-cmp", str(XML), "--width", "14", "-o", str(layout)]) == 0
        assert main(["grammar", "extract", str(layout), "--method", "greedy", "-o", str(grammar)]) == 0
    finally:
        os.umask(umask)
    assert layout.stat().st_mode & 0o777 == 0o644 and grammar.stat().st_mode & 0o777 == 0o644
