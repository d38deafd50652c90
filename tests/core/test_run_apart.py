"""The city planned in a forked child process (issue 24, memory at scale): what the child allocates never enters the
main process; its result comes back, its failure lets the caller raise the error itself."""
from __future__ import annotations

import multiprocessing
import os
import sys

import pytest

from citygen.errors import CitygenError
from citygen.lifeline import apart, run_apart
from citygen.pipeline import generate_city
from citygen.scene import load_scene

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="forks only on Linux")


def _pid_and_list() -> tuple[int, list[int]]:
    return os.getpid(), list(range(5))


def _fails() -> None:
    raise ValueError("bad footprint file")


def test_the_result_is_computed_in_another_process_and_sent_back():
    pid, values = run_apart(_pid_and_list)
    assert pid != os.getpid() and values == [0, 1, 2, 3, 4]


def test_a_failing_child_answers_none_so_the_caller_raises_its_error():
    assert run_apart(_fails) is None


def _sleeps() -> int:
    import time
    time.sleep(60)
    return os.getpid()


def test_the_caller_goes_on_while_the_child_computes_and_an_error_of_its_own_kills_the_child():
    with apart(_pid_and_list) as result:
        assert result()[1] == [0, 1, 2, 3, 4]
    with pytest.raises(KeyError), apart(_sleeps) as result:
        children = {child.pid for child in multiprocessing.active_children()}
        raise KeyError("a ruleset that does not load")
    assert children and not children & {child.pid for child in multiprocessing.active_children()}


def test_a_scene_whose_footprints_fail_to_import_raises_in_the_main_process(small_scene, test_registry):
    """The child's error is not lost: the main process plans the city itself and raises it, with its usual text."""
    (small_scene.parent / "bad.geojson").write_text("{not json")
    small_scene.write_text(small_scene.read_text().replace('path = "city.local.json"', 'path = "bad.geojson"'))
    with pytest.raises(CitygenError, match="bad.geojson"):
        generate_city(load_scene(small_scene), registry=test_registry)


def test_the_report_counts_the_planning_child_s_cpu(small_scene, test_registry):
    report = generate_city(load_scene(small_scene), registry=test_registry)
    assert report.cpu["import"] > 0 and report.cpu["masses"] > 0
    assert report.cpu["total"] >= report.cpu["import"] + report.cpu["masses"]
