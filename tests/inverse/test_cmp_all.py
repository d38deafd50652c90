"""Every CMP base facade beside the checkout (``../shared/data/cmp_facade``, when present): the import is an exact
partition, and the grammars greedy and ADP extract re-derive every terminal rectangle and label of it (wu2014: a
grammar that describes its input exactly; tolerance 1e-6 of the facade size)."""
import pytest

from citygen.layout import check_partition
from citygen_inverse.cmp import import_cmp
from citygen_inverse.extract import extract_grammar

from ..conftest import SHARED_DATA
from .helpers import assert_reproduces

BASE = SHARED_DATA / "cmp_facade" / "base"
FACADES = sorted(BASE.glob("*.xml")) if BASE.is_dir() else []


@pytest.mark.skipif(not FACADES, reason="no CMP data beside the checkout (../shared/data/cmp_facade/base)")
@pytest.mark.parametrize("xml", FACADES or [None], ids=lambda p: p.stem if p else "none")
def test_every_cmp_facade_round_trips(xml):
    layout = import_cmp(xml)
    assert check_partition(layout) == []
    for method, iterations in (("greedy", 1), ("adp", 30)):
        assert_reproduces(extract_grammar(layout, method, iterations, seed=0).text, layout)
