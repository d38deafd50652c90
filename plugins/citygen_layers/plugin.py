"""The ``layers`` ruleset kind: registers the layer-stack generator with citygen. The solver (and SciPy and the QP
solvers it needs) is imported on first use, so loading the plugin costs a city that uses no layer stack nothing."""
from __future__ import annotations

from pathlib import Path

from citygen.hookspecs import hookimpl
from citygen.layout import FacadeLayout
from citygen.registry import RulesetKind
from citygen.request import FacadeRequest
from citygen_layers.model import Ruleset
from citygen_layers.parser import load, parse


class LayersKind(RulesetKind):
    id = "layers"
    suffixes = (".layers",)
    description = "layer stacks of horizontal x vertical patterns, aligned and sized automatically (ilcik2015)"

    def render_png(self, layout, path, floor_lines=()):
        """Layers back to front with the alignment columns of the solve."""
        from citygen_layers.preview import render
        render(layout, path)

    def load(self, path: Path) -> Ruleset:
        return load(path)

    def loads(self, text: str, path: Path) -> Ruleset:
        return parse(text, str(path))

    def generate(self, ruleset: Ruleset, request: FacadeRequest) -> FacadeLayout:
        from citygen_layers.facade import generate
        return generate(ruleset, request)

    def explain(self, ruleset: Ruleset, request: FacadeRequest) -> str:
        from citygen_layers.explain import explain_text
        from citygen_layers.facade import solve_request, swapped_corners, takes_mirror_image
        if takes_mirror_image(ruleset, request):
            sx, sy = solve_request(ruleset, swapped_corners(request))
            return explain_text(ruleset, sx, sy) + ("\nmirror building: this building takes the mirror image "
                                                    "(the x words above read from the right end)")
        sx, sy = solve_request(ruleset, request)
        return explain_text(ruleset, sx, sy)


@hookimpl
def citygen_ruleset_kinds() -> list[RulesetKind]:
    return [LayersKind()]
