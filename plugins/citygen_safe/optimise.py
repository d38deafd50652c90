"""Spatial optimisation (dang2014 §5, Eq. 1): new leaf widths by a quadratic program.

``minimise ||W (x - x*)||^2  s.t.  x > 0, C_h x = 0, C_a x = d_a, C_s x = 0`` plus the target width and any
floor lines, with ``W`` the inverse leaf area normalised by the facade area (capped at 10). ``x`` holds one
width per *variable node* after the variable reduction of Fig. 9. Heights are the same problem on the
transposed facade. Width and left edge of a node are linear in ``x``: ``w = alpha' x`` and ``l = beta' x``,
kept as sparse rows (index -> coefficient) and assembled into sparse matrices for the solve.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import daqp
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from citygen_safe.bounds import MIN_SIZE, collapse, node_minimum, share
from citygen_safe.grids import FacadeGrid
from citygen_safe.leaves import EPS, Facade, Leaf
from citygen_safe.memory import Memory
from citygen_safe.tree import GROUP, X, Node

WEIGHT_CAP = 10.0
SAME_SIZE_TOL = 0.01  #: grid elements of one label whose widths agree within this fraction have the same size
ACTIVE_SET_ROUNDS = 12  #: KKT solves before the DAQP fallback
#: variables up to which the dense DAQP fallback runs: its time grows with their cube (2,000: ~3 s), and it is
#: not counted in the work budget, so one face of a 400 m tower must not hold up its city
DENSE_LIMIT = 2000
DAQP_EQUALITY = 5  #: DAQP constraint sense ACTIVE | IMMUTABLE
KKT_REG = 1e-9
ANCHORS = np.array([0.0, 0.5, 1.0])  #: anchor points of a column: left, centre, right (epsilon)
REFINEMENTS = 4  #: iterative refinement steps of the regularised KKT solve


@dataclass(frozen=True)
class SpatialResult:
    """Outcome of one sizing QP: the resized ``facade`` (valid only when ``success``), ``objective`` E(x),
    the number of variables and the constraint groups that had to be dropped to stay feasible."""

    facade: Facade
    success: bool
    objective: float
    variables: int
    dropped: tuple[str, ...] = ()
    message: str = ""


@dataclass(frozen=True)
class Lines:
    """Positions ``at`` that the left edges of tree nodes ``nodes`` must take (floor lines in the height problem)."""

    nodes: tuple[Node, ...]
    at: tuple[float, ...]


Vec = dict[int, float]  #: a sparse row over the reduced variables (index -> coefficient)


def _comb(*terms: tuple[float, Vec]) -> Vec:
    """The linear combination of sparse rows ``sum(c * v)``."""
    out: Vec = {}
    get = out.get
    for c, vec in terms:
        if c == 1.0:  # (the common term; 1.0 * a is a)
            for k, a in vec.items():
                out[k] = get(k, 0.0) + a
        else:
            for k, a in vec.items():
                out[k] = get(k, 0.0) + c * a
    return out


class _System:
    """alpha and beta vectors of the tree's nodes over the reduced variables (sparse rows)."""

    def __init__(self, root: Node, constrained: set[int]) -> None:
        self.alpha: dict[int, Vec] = {}
        self.beta: dict[int, Vec] = {}
        self.var_nodes: list[Node] = []
        self.hierarchy: list[Vec] = []
        reduced: dict[int, bool] = {}
        self._reduced(root, constrained, reduced)
        self._assign(root, reduced)
        self._beta(root, {})

    def _reduced(self, node: Node, constrained: set[int], memo: dict[int, bool]) -> bool:
        """Fill ``memo`` (node -> collapses to one variable); returns whether the subtree holds a constrained
        node."""
        below = False
        for child in node.children:
            below = self._reduced(child, constrained, memo) or below
        memo[id(node)] = (node.is_leaf or not below
                          or (node.split != X and all(memo[id(c)] for c in node.children)))
        return below or id(node) in constrained

    def _assign(self, node: Node, reduced: dict[int, bool]) -> dict[int, float]:
        if reduced[id(node)]:
            vec = {len(self.var_nodes): 1.0}
            self.var_nodes.append(node)
            self._share(node, vec)
            return vec
        vecs = [self._assign(c, reduced) for c in node.children]
        if node.split == X:
            vec = _comb(*((1.0, v) for v in vecs))
        else:
            vec = vecs[0]
            for a, b in zip(vecs, vecs[1:]):
                self.hierarchy.append(_comb((1.0, a), (-1.0, b)))
        self.alpha[id(node)] = vec
        return vec

    def _share(self, node: Node, vec: dict[int, float]) -> None:
        """Nodes below a variable node through transverse splits have its width."""
        self.alpha[id(node)] = vec
        if node.split not in (X, GROUP):
            for c in node.children:
                self._share(c, vec)

    def _beta(self, node: Node, beta: Vec) -> None:
        self.beta[id(node)] = beta
        offset = beta
        for c in node.children:
            if id(c) not in self.alpha:
                continue
            self._beta(c, offset)
            if node.split == X:
                offset = _comb((1.0, offset), (1.0, self.alpha[id(c)]))


def _matrix(rows: Sequence[Vec], n: int) -> sp.csr_matrix:
    """Sparse rows as a CSR matrix (n columns)."""
    data = [a for r in rows for a in r.values()]
    cols = [k for r in rows for k in r]
    indptr = np.concatenate([[0], np.cumsum([len(r) for r in rows], dtype=np.int64)])
    return sp.csr_matrix((np.asarray(data, dtype=float), np.asarray(cols, dtype=np.int64), indptr),
                         shape=(len(rows), n))


def _anchor_eps(facade: Facade, column: Sequence[int]) -> float:
    """epsilon of the anchor point set (left 0, centre 0.5, right 1) of least x variance in a column."""
    lefts = np.array([facade.leaves[i].x for i in column])
    widths = np.array([facade.leaves[i].w for i in column])
    spread = np.var(lefts + ANCHORS[:, None] * widths, axis=1)  # (one call for the three: rows reduce as 1-D)
    return min(zip(ANCHORS.tolist(), spread.tolist()), key=lambda a: (a[1], abs(a[0] - 0.5)))[0]


def _same_size_pairs(facade: Facade, grids: Sequence[FacadeGrid]) -> list[tuple[int, int]]:
    pairs = []
    for grid in grids:
        by_label: dict[str | None, list[int]] = {}
        for i in grid.elements:
            by_label.setdefault(facade.leaves[i].label, []).append(i)
        for members in by_label.values():
            members.sort(key=lambda i: facade.leaves[i].w)
            for a, b in zip(members, members[1:]):
                wa, wb = facade.leaves[a].w, facade.leaves[b].w
                if wb - wa <= SAME_SIZE_TOL * wb:
                    pairs.append((a, b))
    return pairs


def optimise_widths(facade: Facade, root: Node, grids: Sequence[FacadeGrid], target: float,
                    lines: Lines | None = None, corners: tuple[float, float] = (0.0, 0.0),
                    corner_labels: frozenset[str] = frozenset(), alignment: bool = True,
                    symmetry: bool = True, minimum: np.ndarray | None = None, collapse_below: float = 0.0,
                    centred: Sequence[int] = ()) -> SpatialResult:
    """Solve Eq. 1 for the widths of ``facade`` (tree ``root``) at width ``target``.

    ``minimum``: each leaf's least width (default 1 mm; :func:`citygen_safe.bounds.minimum_extents`), bounding
    the variable nodes by their subtrees' least widths; slabs of walls thinner than ``collapse_below`` are then
    removed (:func:`citygen_safe.bounds.collapse`). ``centred``: leaves whose centre is pinned to the facade's
    middle (a centred door; with ``symmetry``), the first constraint group dropped when infeasible."""
    centred = tuple(centred)
    key = None if lines is not None else (id(facade), id(root), tuple(grids), corners, corner_labels, alignment,
                                          symmetry, None if minimum is None else minimum.tobytes(), centred)
    problem = PROBLEMS.lookup(key) if key is not None else None
    if problem is None or problem.facade is not facade or problem.root is not root:
        problem = _prepare(facade, root, grids, lines, corners, corner_labels, alignment, symmetry, minimum, centred)
        if key is not None:
            PROBLEMS.remember(key, problem, len(facade.leaves))
    n = len(problem.var_nodes)
    rhs_of = {**problem.rhs, "size": [target, *(lines.at if lines is not None else ())],
              "centring": [0.5 * target] * problem.centred}
    h = np.asarray(problem.h + [-corners[0], target - corners[1]] * problem.cornered, dtype=float)
    dropped: list[str] = []
    for drop in ((), ("centring",), ("centring", "symmetry"), ("centring", "symmetry", "alignment")):
        rows = [r for k, rs in problem.rows.items() if k not in drop for r in rs]
        rhs = [v for k in problem.rows if k not in drop for v in rhs_of[k]]
        x = _solve(problem.weight, problem.x_star, _matrix(rows, n), np.asarray(rhs, dtype=float), problem.G, h)
        if x is not None:
            objective = float(np.sum((problem.weight * (x - problem.x_star)) ** 2))
            placed = _place(facade, root, problem.var_nodes, x, target, problem.least)
            if collapse_below > 0:
                placed = collapse(placed, root, collapse_below)
            return SpatialResult(placed, True, objective, n, tuple(drop))
        dropped = list(drop) or ["(inconsistent)"]
    return SpatialResult(facade, False, float("inf"), n, tuple(dropped), "no feasible sizing")


@dataclass(frozen=True)
class _Problem:
    """The part of Eq. 1 that does not depend on the target width, for one facade and tree: the variable nodes,
    each constraint group's rows (``rhs``: right-hand sides of the groups without the target in them), the
    weights, the nodes' least widths, the bound rows ``G`` with the right-hand sides ``h`` of the variables' bounds
    and how many ``cornered`` (two rows each) and ``centred`` leaves add rows whose sides use the target."""

    facade: Facade
    root: Node
    var_nodes: tuple[Node, ...]
    rows: dict[str, list[Vec]]
    rhs: dict[str, list[float]]
    x_star: np.ndarray
    weight: np.ndarray
    least: dict[int, float]
    G: sp.csr_matrix
    h: list[float]
    cornered: int
    centred: int


#: prepared problems by facade and tree (identity: the remembered jumps and merges give the same objects again;
#: each entry holds both, so their ids stay theirs), grids and switches; the same states are sized at other
#: targets by other faces of a city and by the studio's keystrokes
PROBLEMS: Memory[_Problem] = Memory(25_000)  #: (capacity in leaves)


def _prepare(facade: Facade, root: Node, grids: Sequence[FacadeGrid], lines: Lines | None,
             corners: tuple[float, float], corner_labels: frozenset[str], alignment: bool, symmetry: bool,
             minimum: np.ndarray | None, centred: tuple[int, ...]) -> _Problem:
    leaf_node = {n.leaves[0]: n for n in root.walk() if n.split is None}
    columns = [[i for i in grid.column(c) if i is not None and i in leaf_node]
               for grid in grids for c in range(len(grid.columns))] if alignment else []
    pairs = [(a, b) for a, b in _same_size_pairs(facade, grids) if a in leaf_node and b in leaf_node] if symmetry \
        else []
    cornered = [i for i, f in enumerate(facade.leaves) if f.label in corner_labels and i in leaf_node] \
        if any(corners) else []
    constrained = {id(leaf_node[i]) for col in columns for i in col} | {id(leaf_node[i]) for p in pairs for i in p}
    centred = [i for i in centred if i in leaf_node] if symmetry else []
    constrained |= {id(leaf_node[i]) for i in (*cornered, *centred)}
    constrained |= {id(node) for node in (lines.nodes if lines else ())}
    sys_ = _System(root, constrained)
    n = len(sys_.var_nodes)
    alpha = lambda i: sys_.alpha[id(leaf_node[i])]  # noqa: E731
    beta = lambda i: sys_.beta[id(leaf_node[i])]  # noqa: E731
    rows: dict[str, list[Vec]] = {"hierarchy": sys_.hierarchy}
    rhs: dict[str, list[float]] = {"hierarchy": [0.0] * len(sys_.hierarchy)}
    rows["size"] = [sys_.alpha[id(root)]] + [sys_.beta[id(node)] for node in (lines.nodes if lines else ())]
    rows_a, rhs_a = [], []
    for col in (c for c in columns if len(c) > 1):
        eps = _anchor_eps(facade, col)
        for a, b in zip(col, col[1:]):
            fa, fb = facade.leaves[a], facade.leaves[b]
            rows_a.append(_comb((1.0, beta(a)), (eps, alpha(a)), (-1.0, beta(b)), (-eps, alpha(b))))
            rhs_a.append((fa.x + eps * fa.w) - (fb.x + eps * fb.w))
    rows["alignment"], rhs["alignment"] = rows_a, rhs_a
    rows["symmetry"], rhs["symmetry"] = [_comb((1.0, alpha(a)), (-1.0, alpha(b))) for a, b in pairs], [0.0] * len(pairs)
    rows["centring"] = [_comb((1.0, beta(i)), (0.5, alpha(i))) for i in centred]
    x_star = np.array([v.w for v in sys_.var_nodes])
    area = np.array([v.w * v.h for v in sys_.var_nodes])
    weight = np.minimum(facade.width * facade.height / np.maximum(area, EPS), WEIGHT_CAP)
    mins = minimum if minimum is not None else np.full(len(facade.leaves), MIN_SIZE)
    least = node_minimum(root, facade, mins)
    G_rows: list[Vec] = [{k: -1.0} for k in range(n)]
    h_rows = [-max(MIN_SIZE, least[id(v)]) for v in sys_.var_nodes]
    for i in cornered:
        G_rows += [_comb((-1.0, beta(i))), _comb((1.0, beta(i)), (1.0, alpha(i)))]
    return _Problem(facade, root, tuple(sys_.var_nodes), rows, rhs, x_star, weight, least, _matrix(G_rows, n), h_rows,
                    len(cornered), len(centred))


def _solve(weight: np.ndarray, x_star: np.ndarray, A: sp.spmatrix, b: np.ndarray, G: sp.spmatrix,
           h: np.ndarray) -> np.ndarray | None:
    """Eq. 1 with equality rows ``A x = b`` and inequality rows ``G x <= h`` (sparse); None when infeasible.

    Active-set loop on the sparse KKT system, which tolerates redundant equality rows (so no rank test): violated
    inequality rows join the active set, active rows whose multiplier has the wrong sign leave it. When the loop
    does not settle (adding every violated row at once can over-constrain), DAQP's dual active set, which also
    copes with dependent rows, solves the dense problem -- up to ``DENSE_LIMIT`` variables; beyond, None."""
    P = 2 * weight**2
    q = -P * x_star
    A, G = sp.csr_matrix(A), sp.csr_matrix(G)
    scale = 1.0 + float(np.max(np.abs(np.concatenate([b, h])), initial=0.0))
    active: list[int] = []
    for _ in range(ACTIVE_SET_ROUNDS):
        solved = _kkt(P, q, sp.vstack([A, G[active]], format="csr"), np.concatenate([b, h[active]]), scale)
        if solved is None:
            if not active:
                return None  # the equality rows alone are inconsistent
            break
        x, y = solved
        mu = y[len(b):]
        if active and mu.min() < -1e-9 * scale:
            active.pop(int(np.argmin(mu)))
            continue
        slack = G @ x - h
        violated = [int(i) for i in np.flatnonzero(slack > 1e-9 * scale) if int(i) not in active]
        if not violated:
            return x
        active += violated
    return _dual_active_set(P, q, A, b, G, h) if P.size <= DENSE_LIMIT else None


def _dual_active_set(P: np.ndarray, q: np.ndarray, A: sp.spmatrix, b: np.ndarray, G: sp.spmatrix,
                     h: np.ndarray) -> np.ndarray | None:
    """DAQP on ``A x = b, G x <= h`` (``P`` diagonal, rows made dense); None unless it reports an optimum."""
    rows = np.ascontiguousarray(sp.vstack([A, G]).toarray())
    upper = np.concatenate([b, h])
    lower = np.concatenate([b, np.full(h.size, -1e30)])
    sense = np.zeros(upper.size, dtype=np.int32)
    sense[:b.size] = DAQP_EQUALITY
    x, _, flag, _ = daqp.solve(np.diag(P), q, rows, upper, lower, sense)
    return np.asarray(x) if flag == 1 and np.all(np.isfinite(x)) else None


def _kkt(P: np.ndarray, q: np.ndarray, A: sp.spmatrix, b: np.ndarray, scale: float
         ) -> tuple[np.ndarray, np.ndarray] | None:
    """``x`` and multipliers ``y`` of ``min 1/2 x'Px + q'x s.t. A x = b`` (``P`` diagonal) from the sparse KKT
    system with a small dual regularisation, refined against the exact system (so redundant rows are harmless
    and the rows hold to rounding); None when the rows are inconsistent."""
    n = P.size
    As = sp.csr_matrix(A)
    AsT = As.T
    K = kkt_matrix(P, As)
    try:
        lu = spla.splu(K)
    except RuntimeError:
        return None
    rhs = np.concatenate([-q, b])
    sol = lu.solve(rhs)
    for _ in range(REFINEMENTS):
        x, y = sol[:n], sol[n:]
        residual = rhs - np.concatenate([P * x + AsT @ y, As @ x])
        if np.max(np.abs(residual)) <= 1e-12 * scale:
            break
        sol = sol + lu.solve(residual)
    x = sol[:n]
    if not np.all(np.isfinite(sol)) or np.max(np.abs(As @ x - b), initial=0.0) > 1e-7 * scale:
        return None
    return x, sol[n:]


def kkt_matrix(P: np.ndarray, A: sp.csr_matrix) -> sp.csc_matrix:
    """The regularised KKT matrix ``[[diag(P) + r, A'], [A, -r I]]`` (r = ``KKT_REG``) in canonical CSC form
    (``A``'s explicit zeros kept), its arrays written directly: column ``j < n`` holds the diagonal then ``A``'s
    column ``j``, column ``n + i`` holds ``A``'s row ``i`` then ``-r`` (``sp.bmat`` built and converted each block:
    it cost as much as the factorisation at the QP's sizes)."""
    n, m = P.size, A.shape[0]
    rows, cols = A.sorted_indices(), A.tocsc()
    counts = np.concatenate([np.diff(cols.indptr) + 1, np.diff(rows.indptr) + 1])
    indptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int32)
    fixed = np.concatenate([indptr[:n], indptr[n + 1:] - 1])  # the diagonal entries' places
    rest = np.ones(indptr[-1], dtype=bool)
    rest[fixed] = False
    indices = np.empty(indptr[-1], dtype=np.int32)
    indices[fixed] = np.arange(n + m)
    indices[rest] = np.concatenate([n + cols.indices, rows.indices])
    data = np.empty(indptr[-1])
    data[fixed] = np.concatenate([P + KKT_REG, np.full(m, -KKT_REG)])
    data[rest] = np.concatenate([cols.data, rows.data])
    return sp.csc_matrix((data, indices, indptr), shape=(n + m, n + m))


def _place(facade: Facade, root: Node, var_nodes: Sequence[Node], x: np.ndarray, target: float,
           least: dict[int, float]) -> Facade:
    """Leaf x and w from the solution: variable nodes get their width; collapsed subtrees share the change (each
    child kept at its least width ``least``)."""
    var_width = {id(v): float(x[k]) for k, v in enumerate(var_nodes)}
    lefts: dict[int, tuple[float, float]] = {}

    known = dict(var_width)  # widths of nodes worked out so far (place asks again at every level below)

    def width(node: Node) -> float:
        if id(node) not in known:
            ws = [width(c) for c in node.children]
            known[id(node)] = sum(ws) if node.split == X else ws[0]
        return known[id(node)]

    def place(node: Node, left: float, w: float, collapsed: bool = False) -> None:
        collapsed = collapsed or id(node) in var_width
        if node.split is None:
            lefts[node.leaves[0]] = (left, w)
        elif node.split == GROUP:
            scale = w / node.w if node.w > EPS else 0.0
            for i in node.leaves:
                f = facade.leaves[i]
                lefts[i] = (left + (f.x - node.x) * scale, f.w * scale)
        elif node.split == X:
            if collapsed:
                widths = share([c.w for c in node.children], [least[id(c)] for c in node.children], w)
            else:
                widths = [width(c) for c in node.children]
            for c, cw in zip(node.children, widths):
                place(c, left, cw, collapsed)
                left += cw
        else:
            for c in node.children:
                place(c, left, w, collapsed)

    place(root, 0.0, target)
    leaves = tuple(Leaf.fast(lefts[i][0], f.y, lefts[i][1], f.h, f.region, f.origin)
                   for i, f in enumerate(facade.leaves))
    return replace(facade, width=target, leaves=leaves)
