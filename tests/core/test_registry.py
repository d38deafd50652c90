import pytest

from citygen.cli import main
from citygen.errors import PluginError
from citygen.hookspecs import hookimpl
from citygen.registry import load_registry
from tests.core.fakes import FakePlugin, GridKind


class Broken:
    @hookimpl
    def citygen_ruleset_kinds(self):
        raise RuntimeError("boom")


class Duplicate:
    @hookimpl
    def citygen_ruleset_kinds(self):
        return [GridKind()]


def test_broken_plugin_is_reported_not_fatal():
    registry = load_registry(extra_plugins=[FakePlugin(), Broken()], entry_points=False)
    assert "testgrid" in registry.ruleset_kinds
    assert any("boom" in problem for _, problem in registry.broken)


def test_duplicate_ids_name_both_plugins():
    with pytest.raises(PluginError, match="duplicate ruleset kind id 'testgrid'") as info:
        load_registry(extra_plugins=[FakePlugin(), Duplicate()], entry_points=False)
    assert "also registered by" in str(info.value)


def test_lookup_errors_list_what_is_known(tmp_path):
    registry = load_registry(extra_plugins=[FakePlugin()], entry_points=False)
    with pytest.raises(PluginError, match=r"known ruleset suffixes: \.testgrid"):
        registry.kind_for_path(tmp_path / "x.unknown")
    with pytest.raises(PluginError, match="localjson"):
        registry.importer_for(tmp_path / "x.shp")
    assert registry.importer_for(tmp_path / "a.local.json").id == "localjson"


def test_plugins_command_lists_first_party_kinds(capsys):
    assert main(["plugins"]) == 0
    out = capsys.readouterr().out
    for kind in ("split", "relayout", "geojson", "cityjson", "flat", "grammar"):
        assert kind in out
