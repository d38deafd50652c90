import pytest

from citygen.errors import ParseError
from citygen_layers.model import Alt, Rep, Seq, Sym
from citygen_layers.parser import parse

HEAD = "symbol A size=1 opaque\nsymbol B size=1\ncounter k\n"


def test_alternation_binds_tighter_than_concatenation():
    rs = parse(HEAD + "pattern P = A|B A\nlayer l x=P y=P\n")
    node = rs.patterns["P"].control
    assert isinstance(node, Seq) and isinstance(node.items[0], Alt) and node.items[1] == Sym("A")


def test_counting_reflection_and_substitution():
    rs = parse(HEAD + "pattern P = A (B A)^-k\npattern Q = c e c ; c := A B\nlayer l x=P y=Q\n")
    rep = rs.patterns["P"].control.items[1]
    assert isinstance(rep, Rep) and rep.count == "k" and rep.negate
    assert set(rs.patterns["Q"].substitutions) == {"c"}


@pytest.mark.parametrize("text, where, words", [
    ("frobnicate 1\n", ":4:1", "unknown statement"),
    ("pattern P = A (B\nlayer l x=P y=P\n", ":4:17", "expected ')'"),
    ("pattern P = A $\n", ":4:15", "unexpected character"),
    ("pattern P = A^q\nlayer l x=P y=P\n", ":4:15", "unknown counter"),
    ("pattern P = A Z\nlayer l x=P y=P\n", ":4:15", "no declaration"),
    ("pattern P = A\nlayer l x=P y=Nope\n", ":5:13", "unknown pattern"),
    ("pattern P = A ; z := B\n", ":4:17", "does not occur"),
    ("pattern P = A^k\npattern R = B^k\nlayer l x=P y=R\n", ":5:15", "both directions"),
    ("symbol C size=-1\n", ":4:10", "non-negative"),
    ("symbol C size=1 min=1.2\n", ":4:8", "min <= size <= max"),
    ("symbol C min=0.5 max=0.2\n", ":4:8", "min <= size <= max"),
    ("occlusion sometimes\n", ":4:1", "'occlusion cut'"),
    ("mirror always\n", ":4:1", "'mirror building'"),
    ("frobnicate\n", ":4:1", "occlusion or mirror"),
])
def test_errors_name_file_line_column(text, where, words):
    with pytest.raises(ParseError) as info:
        parse(HEAD + text, "stack.layers")
    assert f"stack.layers{where}" in str(info.value) and words in str(info.value)


def test_mirror_statement():
    text = "pattern P = A\nlayer l x=P y=P\n"
    assert not parse(HEAD + text).mirror and not parse(HEAD + "mirror none\n" + text).mirror
    assert parse(HEAD + "mirror building\n" + text).mirror


def test_symbol_size_range():
    rs = parse("symbol X size=0.25 min=0.15 max=0.4 label=ledge\nsymbol U max=2\npattern P = X U\n"
               "layer l x=P y=P\n")
    assert (rs.symbols["X"].least, rs.symbols["X"].size, rs.symbols["X"].most) == (0.15, 0.25, 0.4)
    assert (rs.symbols["U"].least, rs.symbols["U"].size, rs.symbols["U"].most) == (None, None, 2.0)
