"""From an edited facade back to a FacadeLayout whose region tree is the facade's decomposition tree."""
from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from citygen.layout import FacadeLayout, Region
from citygen_safe.leaves import Facade, leaf_region, upright
from citygen_safe.tree import GROUP, Node, X, decompose

_SYMBOL = {X: "SplitX", "y": "SplitY", GROUP: "Group"}


def to_layout(facade: Facade, meta: Mapping[str, Any] | None = None) -> FacadeLayout:
    """The layout of an (upright or transposed) facade, its region tree recovered by :func:`decompose`."""
    facade = upright(facade)
    regions = [leaf_region(f) for f in facade.leaves]
    root = _region(decompose(facade), regions)
    if root.children == () and root.label is not None:
        root = Region(0.0, 0.0, facade.width, facade.height, "Facade", None, children=(root,))
    else:
        root = Region(0.0, 0.0, facade.width, facade.height, "Facade", None, children=root.children)
    return FacadeLayout(facade.width, facade.height, root, meta=dict(meta or {}))


def _region(node: Node, regions: list[Region]) -> Region:
    if node.split is None:
        return regions[node.leaves[0]]
    children = (tuple(regions[i] for i in node.leaves) if node.split == GROUP
                else tuple(_region(c, regions) for c in node.children))
    return Region(node.x, node.y, node.w, node.h, _SYMBOL[node.split], None, children=children)
