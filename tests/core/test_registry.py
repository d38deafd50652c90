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


class NotAList:
    @hookimpl
    def citygen_ruleset_kinds(self):
        return GridKind()


class NoneInList:
    @hookimpl
    def citygen_roof_builders(self):
        return [None]


class WithoutId:
    @hookimpl
    def citygen_footprint_importers(self):
        return [object()]


class Exits:
    @hookimpl
    def citygen_commands(self):
        raise SystemExit(3)


class HalfAKind(GridKind):
    id = "half"
    suffixes = (".half",)
    generate = None


class HalfKind:
    @hookimpl
    def citygen_ruleset_kinds(self):
        return [HalfAKind()]


MALFORMED = [(NotAList(), "NotAList", "citygen_ruleset_kinds returned GridKind, not a list"),
             (NoneInList(), "NoneInList", "citygen_roof_builders returned item 0 (NoneType) without a string 'id'"),
             (WithoutId(), "WithoutId", "citygen_footprint_importers returned item 0 (object) without a string 'id'"),
             (Exits(), "Exits", "citygen_commands failed: SystemExit: 3"),
             (HalfKind(), "HalfKind", "citygen_ruleset_kinds returned 'half' without method(s) generate of a "
                                      "RulesetKind")]


@pytest.mark.parametrize(("plugin", "name", "problem"), MALFORMED)
def test_a_malformed_hook_result_is_a_broken_plugin_not_a_broken_cli(plugin, name, problem, monkeypatch, capsys):
    """Was: a hook returning a non-list, ``[None]`` or an object without ``id`` broke every command, even
    ``citygen plugins``."""
    import citygen.registry
    registry = load_registry(extra_plugins=[FakePlugin(), plugin])
    assert (name, problem + ("" if "failed" in problem else "; nothing of it is registered")) in registry.broken
    assert "testgrid" in registry.ruleset_kinds and "split" in registry.ruleset_kinds
    monkeypatch.setattr(citygen.registry, "_DEFAULT", registry)
    assert main(["plugins"]) == 0
    assert f"broken plugin {name}: {problem}" in capsys.readouterr().out
    assert main(["facade", "rulesets/house.grammar", "--size", "10", "6"]) == 0
    err = capsys.readouterr().err
    assert err.startswith(f"citygen: warning: broken plugin {name} not loaded: {problem}")


class ClaimsGrammar(GridKind):
    id = "impostor"
    suffixes = (".grammar", ".testgrid2")


class Impostor:
    @hookimpl
    def citygen_ruleset_kinds(self):
        return [ClaimsGrammar()]


def test_a_plugin_claiming_a_shipped_suffix_does_not_take_it_over(tmp_path, monkeypatch, capsys):
    """Was: a second kind claiming ``.grammar`` silently took every grammar (every building skipped, exit 0).
    The shipped kind keeps it; the claim is a warning naming both; the other suffixes of the kind work."""
    import citygen.registry
    registry = load_registry(extra_plugins=[Impostor()])
    assert registry.kind_for_path(tmp_path / "a.grammar").id == "split"
    assert registry.kind_for_path(tmp_path / "a.testgrid2").id == "impostor"
    assert registry.warnings == ["ruleset kind 'impostor' (plugin Impostor) also claims .grammar, which stays with "
                                 "ruleset kind 'split' (plugin split); set kind = \"impostor\" in a scene to use it"]
    monkeypatch.setattr(citygen.registry, "_DEFAULT", registry)
    assert main(["facade", "rulesets/house.grammar", "--size", "10", "6"]) == 0
    out, err = capsys.readouterr()
    assert out.startswith("house.grammar [split]") and "also claims .grammar" in err


def test_between_third_party_plugins_the_first_by_name_keeps_a_suffix(tmp_path):
    class ClaimsToo(ClaimsGrammar):
        id = "second"

    class Second:
        @hookimpl
        def citygen_ruleset_kinds(self):
            return [ClaimsToo()]

    registry = load_registry(extra_plugins=[Second(), Impostor()], entry_points=False)
    assert registry.kind_for_path(tmp_path / "a.grammar").id == "impostor"
    assert len(registry.warnings) == 2 and all("'second' (plugin Second)" in w for w in registry.warnings)
