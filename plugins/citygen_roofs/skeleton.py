"""Straight skeleton of a polygon with holes, by wavefront propagation (Felkel & Obdržálek 1998; Aichholzer et
al. 1995).

Every edge moves inward at unit speed; the wavefront's vertices move along the angle bisectors of their two
edges. Two kinds of event change its topology:

* an *edge event*: an edge of the wavefront shrinks to zero length, its two vertices merge;
* a *split event*: a reflex vertex reaches an opposite edge and splits that wavefront ring in two (or, when the
  edge belongs to another ring, e.g. a courtyard's, joins the two rings).

The next event is found by testing every vertex and edge of the current wavefront (``O(n^2)`` per event, in
numpy; a small wavefront in plain Python floats, the same operations): cheap for building footprints, and no
priority queue that could go stale after simultaneous events. A ring left with two vertices, or a thin ring with
no area left, ends in skeleton arcs (a ridge); a vertex between two antiparallel edges (a zero-width spike) is
folded back at once. Every arc the wavefront's vertices trace borders the faces of their two edges, so each input
edge's *face* is collected from those arcs.

Weighted (edges of speed 0 stand still): a ring none of whose edges moves (a region walled in by standing edges
that no moving edge reaches) ends as a *plateau* at the time its last moving edge vanished; a standing edge swept
to nothing between parallel edges of different speeds turns round into a new standing edge on its line (a wall
inside the roof), since no vertex can join two parallel edges that part. Faces are checked to lie in their edges'
planes.

API: :func:`straight_skeleton` returns a :class:`Skeleton` (nodes with their offset time, one face per input
edge) or raises :class:`SkeletonError` for input it cannot handle; callers fall back to something simpler.
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

import numpy as np
from shapely.geometry import Polygon
from shapely.geometry.polygon import orient

from citygen.roof import check_budget


#: Up to this many (reflex vertex, edge) pairs the next split event is found among all pairs; above, among the
#: pairs close enough to meet before a first guess of the next event (:meth:`_Wavefront._near_pairs`).
DENSE_PAIRS = 40_000
#: The nearest edges of each reflex vertex that make that first guess.
NEAR_EDGES = 8
#: Up to this many vertices the next event is found in plain Python (:meth:`_Wavefront.small_event`): a building's
#: wavefront is small, and numpy's overhead per call is most of its cost there.
SMALL_FRONT = 48
#: Up to this many (reflex vertex, edge) pairs a small wavefront's split events are found in plain Python too.
SMALL_PAIRS = 128


class SkeletonError(ValueError):
    """The skeleton could not be computed (degenerate input or numerical trouble)."""


@dataclass(frozen=True)
class Skeleton:
    """Nodes ``(k, 2)`` with ``times (k,)`` (distance swept by the wavefront; 0 on the outline), one face per
    input edge (node indices counter-clockwise, starting with the edge's start and end node) and the plateaus
    (counter-clockwise, all nodes at one time) that a weighted wavefront left unswept."""

    nodes: np.ndarray
    times: np.ndarray
    faces: tuple[tuple[int, ...], ...]
    flats: tuple[tuple[int, ...], ...] = ()
    walls: tuple[tuple[int, ...], ...] = ()  # vertical faces of standing edges born inside (see ``add_edge``)

    def face_polygon(self, k: int) -> np.ndarray:
        return self.nodes[list(self.faces[k])]


@dataclass(frozen=True)
class _Vertex:
    """A wavefront vertex: started at ``node`` (position ``p0`` at time ``t0``), moving with ``vel`` between
    edge ``e_in`` (behind it) and ``e_out`` (ahead)."""

    node: int
    p0: tuple[float, float]
    t0: float
    vel: tuple[float, float]
    e_in: int
    e_out: int
    spike: bool = False
    #: ``(*p0, t0, *vel, e_in, e_out)``: the vertex's row of :meth:`_Wavefront.front`
    row: tuple[float, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "row", (*self.p0, self.t0, *self.vel, self.e_in, self.e_out))

    def at(self, t: float) -> np.ndarray:
        return np.array([self.p0[0] + (t - self.t0) * self.vel[0], self.p0[1] + (t - self.t0) * self.vel[1]])


class _Wavefront:
    def __init__(self, rings: list[np.ndarray], weights: np.ndarray) -> None:
        starts = np.concatenate(rings)
        ends = np.concatenate([np.roll(r, -1, axis=0) for r in rings])
        d = ends - starts
        length = np.hypot(d[:, 0], d[:, 1])
        if np.any(length < 1e-9):
            raise SkeletonError("zero-length edge")
        self.scale = float(np.ptp(starts, axis=0).max()) or 1.0
        self.eps = 1e-9 * self.scale
        self.D = d / length[:, None]
        self.N = np.column_stack([-self.D[:, 1], self.D[:, 0]])  # inward: interior is left of every edge
        self.C = np.einsum("ij,ij->i", self.N, starts)
        self.W = weights
        self.nodes: list[tuple[float, float]] = [tuple(p) for p in starts]
        self.times: list[float] = [0.0] * len(starts)
        self.cells: dict[tuple[int, int], list[int]] = {}  # nodes after time 0 by cell of :meth:`node`'s tolerance
        self.arcs: list[set[tuple[int, int]]] = [set() for _ in starts]
        self.flats: list[tuple[int, ...]] = []
        self.edge_nodes = []
        self.rings: list[list[_Vertex]] = []
        self._front: tuple | None = None  # (key, value) of the last :meth:`front`
        self._lines: tuple | None = None  # D, N, C, W as lists of Python floats (:meth:`lines`)
        first = 0
        for r in rings:
            n = len(r)
            idx = list(range(first, first + n))
            self.edge_nodes += [(i, first + (i - first + 1) % n) for i in idx]
            self.rings.append([self.vertex(i, 0.0, idx[(k - 1) % n], i) for k, i in enumerate(idx)])
            first += n

    def velocity(self, a: int, b: int) -> tuple[float, float] | None:
        """Speed of the intersection of the offset lines of edges ``a`` and ``b``, each moving at its weight
        (None: antiparallel, or parallel at different speeds)."""
        na, nb, wa, wb = self.N[a], self.N[b], self.W[a], self.W[b]
        det = na[0] * nb[1] - na[1] * nb[0]
        if abs(det) < 1e-12:
            return (float(wa * na[0]), float(wa * na[1])) if na @ nb > 0 and wa == wb else None
        return ((wa * nb[1] - wb * na[1]) / det, (wb * na[0] - wa * nb[0]) / det)

    def vertex(self, node: int, t: float, e_in: int, e_out: int) -> _Vertex:
        vel = self.velocity(e_in, e_out)
        if vel is not None and math.hypot(*vel) > 1e6:
            vel = None
        return _Vertex(node, self.nodes[node], t, vel if vel is not None else (0.0, 0.0), e_in, e_out, vel is None)

    def antiparallel(self, v: _Vertex) -> bool:
        return v.spike

    def meet(self, v: _Vertex, u: _Vertex, t: float) -> tuple[float, float] | np.ndarray:
        """Where ``v`` and ``u`` meet at an edge event: where the offset lines of the collapsing edge and its
        neighbours cross at ``t`` (exact, so positions do not drift from event to event); the midpoint of the two
        vertices where those lines are nearly parallel."""
        points = []
        for a, b in ((v.e_in, v.e_out), (u.e_in, u.e_out)):
            det = self.N[a][0] * self.N[b][1] - self.N[a][1] * self.N[b][0]
            if abs(det) > 0.05:
                ca, cb = self.C[a] + self.W[a] * t, self.C[b] + self.W[b] * t
                points.append(((ca * self.N[b][1] - cb * self.N[a][1]) / det,
                               (self.N[a][0] * cb - self.N[b][0] * ca) / det))
        if not points:
            return (v.at(t) + u.at(t)) / 2
        x = y = 0.0  # their mean as numpy takes it: summed from +0.0 (a -0.0 comes out +0.0), then divided
        for px, py in points:
            x, y = x + px, y + py
        return x / len(points), y / len(points)

    def node(self, p: np.ndarray, t: float) -> int:
        """The node at ``p`` and time ``t`` (reusing one within tolerance: simultaneous events meet in one node; a
        standing vertex stays at one place over time, in distinct nodes)."""
        tol = 1e-7 * self.scale
        cx, cy = math.floor(p[0] / tol), math.floor(p[1] / tol)
        near = [k for dx in (-1, 0, 1) for dy in (-1, 0, 1) for k in self.cells.get((cx + dx, cy + dy), ())]
        for k in sorted(near, reverse=True):  # (the latest such node, as a scan from the end finds it)
            q = self.nodes[k]
            if abs(q[0] - p[0]) < tol and abs(q[1] - p[1]) < tol and abs(self.times[k] - t) < tol:
                return k
        self.nodes.append((float(p[0]), float(p[1])))
        self.times.append(float(t))
        if t > 0:  # (nodes of the outline are never reused)
            self.cells.setdefault((cx, cy), []).append(len(self.nodes) - 1)
        return len(self.nodes) - 1

    def end(self, v: _Vertex, node: int) -> None:
        """``v`` stops at ``node``: its arc borders the faces of both its edges."""
        if node != v.node:
            arc = (min(v.node, node), max(v.node, node))
            self.arcs[v.e_in].add(arc)
            self.arcs[v.e_out].add(arc)

    # -- events -------------------------------------------------------------------------------------------------

    def front(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The wavefront at ``t`` as arrays over its vertices, ring after ring: ``(pos, vel, nxt, e_in, e_out)``,
        ``nxt`` the index of each vertex's successor in its ring. Kept until the rings or ``t`` change: the clean-up
        after an event (:meth:`roomy`) and the search for the next one (:meth:`next_event`) share it."""
        verts = tuple(v for ring in self.rings for v in ring)
        key = (t, tuple(map(len, self.rings)), verts)
        if self._front is not None and self._front[0] == key:
            return self._front[1]
        rows = np.array([v.row for v in verts]).reshape(-1, 7)
        sizes = np.array(key[1])
        first = np.repeat(np.cumsum(sizes) - sizes, sizes)
        nxt = first + (np.arange(len(verts)) - first + 1) % np.repeat(sizes, sizes)
        vel = np.ascontiguousarray(rows[:, 3:5])
        pos = rows[:, 0:2] + (t - rows[:, 2])[:, None] * vel
        value = (pos, vel, nxt, rows[:, 5].astype(np.int64), rows[:, 6].astype(np.int64))
        self._front = (key, value)
        return value

    def where(self, k: int) -> tuple[int, int]:
        """Ring and place in it of the ``k``-th vertex of :meth:`front`."""
        for r, ring in enumerate(self.rings):
            if k < len(ring):
                return r, k
            k -= len(ring)
        raise IndexError(k)

    def lines(self) -> tuple[list, list, list, list]:
        """The edges' ``D``, ``N``, ``C`` and ``W`` as lists of Python floats."""
        if self._lines is None:
            self._lines = (self.D.tolist(), self.N.tolist(), self.C.tolist(), self.W.tolist())
        return self._lines

    def next_event(self, t: float) -> tuple[float, int, tuple] | None:
        """Earliest event at or after ``t``: ``(time, kind, where)`` with kind 0 (edge event, wins ties) or 1
        (split event); every vertex against every edge at once, in numpy (a small wavefront: :meth:`small_event`)."""
        if sum(map(len, self.rings)) <= SMALL_FRONT:
            return self.small_event(t)
        pos, vel, nxt, e_in, e_out = self.front(t)
        best = None
        d = self.D[e_out]
        length = np.einsum("ij,ij->i", d, pos[nxt] - pos)
        rate = np.einsum("ij,ij->i", d, vel[nxt] - vel)
        # an edge already of no length whose ends move together (the two vertices left where a spike folded onto
        # both its neighbours at once) is collapsing now: it would never shrink
        short = length < 1e-7 * self.scale
        if short.any():
            rate[short & (np.abs(rate) <= 1e-12)] = -1.0
        shrinking = np.flatnonzero(rate < -1e-12)
        if len(shrinking):
            te = t + np.maximum(length[shrinking], 0.0) / -rate[shrinking]
            k = int(np.argmin(te))
            best = (float(te[k]), 0, self.where(int(shrinking[k])))
        a, b = self.D[e_in], self.D[e_out]
        reflex = np.flatnonzero(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0] < -1e-9)
        if not len(reflex):
            return best
        context = (pos, vel, nxt, e_out, t)
        n = len(pos)
        if len(reflex) * n <= DENSE_PAIRS:
            split = self._split_event(np.repeat(reflex, n), np.tile(np.arange(n), len(reflex)), *context)
        else:
            split = self._split_event(*self._near_pairs(reflex, best, *context), *context)
        if split is not None and (best is None or split[0] < best[0]):
            best = split
        return best

    def small_event(self, t: float) -> tuple[float, int, tuple] | None:
        """:meth:`next_event` in plain Python floats, for a small wavefront: the same operations in the same order
        (a dot product of two rows in numpy is ``x0 * y0 + x1 * y1``), the same scan order and tie-breaking, so the
        same event to the last bit, at a fraction of the cost."""
        D, N, C, W = self.lines()
        verts = [v for ring in self.rings for v in ring]
        nxt: list[int] = []
        for ring in self.rings:
            first = len(nxt)
            nxt += range(first + 1, first + len(ring))
            nxt.append(first)
        pos = [(v.p0[0] + (t - v.t0) * v.vel[0], v.p0[1] + (t - v.t0) * v.vel[1]) for v in verts]
        best = None
        short = 1e-7 * self.scale
        for k, v in enumerate(verts):  # edge events: the earliest, the first of equal ones
            j = nxt[k]
            (dx, dy), p, q, u, w = D[v.e_out], pos[k], pos[j], v.vel, verts[j].vel
            length = dx * (q[0] - p[0]) + dy * (q[1] - p[1])
            rate = dx * (w[0] - u[0]) + dy * (w[1] - u[1])
            if length < short and abs(rate) <= 1e-12:
                rate = -1.0  # (see :meth:`next_event`)
            if rate < -1e-12:
                te = t + max(length, 0.0) / -rate
                if best is None or te < best[0]:
                    best = (te, k)
        reflex = [k for k, v in enumerate(verts)
                  if D[v.e_in][0] * D[v.e_out][1] - D[v.e_in][1] * D[v.e_out][0] < -1e-9]
        if len(reflex) * len(verts) > SMALL_PAIRS:  # split events: many pairs, in numpy
            front = self.front(t)
            n = len(verts)
            split = self._split_event(np.repeat(reflex, n), np.tile(np.arange(n), len(reflex)), *front[:3],
                                      front[4], t)
            if split is not None and (best is None or split[0] < best[0]):
                return split
            return None if best is None else (best[0], 0, self.where(best[1]))
        eps, split = self.eps, None
        edges = [(*N[v.e_out], C[v.e_out], W[v.e_out], W[v.e_out] * t) for v in verts]
        for k in reflex:  # split events: reflex vertex k against every edge j
            v = verts[k]
            (x0, y0), (vx, vy) = pos[k], v.vel
            for j, (nx, ny, c, w, wt) in enumerate(edges):
                rate = (vx * nx + vy * ny) - w
                if not rate < -1e-12:
                    continue
                dist = (x0 * nx + y0 * ny) - c - wt
                m = nxt[j]
                if not dist >= -eps or j == k or m == k:
                    continue
                x = verts[j]
                e = x.e_out
                dt = max(dist, 0.0) / -rate
                if (split is not None and dt >= split[0]) or (best is not None and t + dt >= best[0]):
                    continue  # (it can be neither the earliest split event, nor the first of equal ones, nor win)
                (fx, fy), (jx, jy), (jvx, jvy), (mx, my), (mvx, mvy) = D[e], pos[j], x.vel, pos[m], verts[m].vel
                px, py = jx + dt * jvx, jy + dt * jvy
                along = (x0 + dt * vx - px) * fx + (y0 + dt * vy - py) * fy
                span = (mx + dt * mvx - px) * fx + (my + dt * mvy - py) * fy
                if not (along >= -eps and along <= span + eps):
                    continue
                if dt <= eps and ((along <= eps and (vx - jvx) * fx + (vy - jvy) * fy < -1e-12)
                                  or (along >= span - eps and (vx - mvx) * fx + (vy - mvy) * fy > 1e-12)):
                    continue  # (see :meth:`_split_event`)
                if split is None or dt < split[0]:
                    split = (dt, k, j)
        if split is not None and (best is None or t + split[0] < best[0]):
            return t + split[0], 1, (*self.where(split[1]), *self.where(split[2]))
        return None if best is None else (best[0], 0, self.where(best[1]))

    def _split_event(self, pv: np.ndarray, pj: np.ndarray, pos: np.ndarray, vel: np.ndarray, nxt: np.ndarray,
                     e_out: np.ndarray, t: float) -> tuple[float, int, tuple] | None:
        """The earliest split event among the pairs (reflex vertex ``pv``, edge from vertex ``pj`` to its next); of
        simultaneous ones, that of the lowest vertex, then edge (the first of a dense scan)."""
        n_f, c_f, w_f = self.N[e_out[pj]], self.C[e_out[pj]], self.W[e_out[pj]]
        dist = np.einsum("ij,ij->i", pos[pv], n_f) - c_f - w_f * t
        rate = np.einsum("ij,ij->i", vel[pv], n_f) - w_f
        ok = np.flatnonzero((rate < -1e-12) & (dist >= -self.eps) & (pj != pv) & (nxt[pj] != pv))
        if not len(ok):  # candidate (reflex vertex, edge) pairs: does the vertex land inside the edge?
            return None
        dt = np.maximum(dist[ok], 0.0) / -rate[ok]
        v, jj = pv[ok], pj[ok]
        f = self.D[e_out[jj]]
        px = pos[jj] + dt[:, None] * vel[jj]
        along = np.einsum("ij,ij->i", pos[v] + dt[:, None] * vel[v] - px, f)
        span = np.einsum("ij,ij->i", pos[nxt[jj]] + dt[:, None] * vel[nxt[jj]] - px, f)
        # a vertex that already sits at an end of the edge (the two vertices a vertex event left) reaches the edge
        # only if it moves into it, not out past its end
        inside = (along >= -self.eps) & (along <= span + self.eps)
        now = dt <= self.eps
        if now.any():
            inside &= ~(now & (along <= self.eps) & (np.einsum("ij,ij->i", vel[v] - vel[jj], f) < -1e-12))
            inside &= ~(now & (along >= span - self.eps) & (np.einsum("ij,ij->i", vel[v] - vel[nxt[jj]], f) > 1e-12))
        inside = np.flatnonzero(inside)
        if not len(inside):
            return None
        first = inside[dt[inside] == dt[inside].min()]  # ties: the first pair of a dense scan
        k = first[np.lexsort((jj[first], v[first]))[0]]
        return t + float(dt[k]), 1, (*self.where(int(v[k])), *self.where(int(jj[k])))

    def _near_pairs(self, reflex: np.ndarray, edge: tuple[float, int, tuple] | None, pos: np.ndarray,
                    vel: np.ndarray, nxt: np.ndarray, e_out: np.ndarray, t: float
                    ) -> tuple[np.ndarray, np.ndarray]:
        """The (reflex vertex, edge) pairs that can meet before the next event, for a big wavefront: a first
        guess of that event (the earlier of the next edge event and the split events of each reflex vertex with
        its ``NEAR_EDGES`` nearest edges) bounds how far anything moves before it (``horizon``); a vertex can
        reach an edge by then only if its distance to the edge's midpoint is at most ``horizon`` times its speed
        plus ``horizon`` times the faster end's speed plus half the edge (k-d tree on the midpoints)."""
        from scipy.spatial import cKDTree  # (only big wavefronts need it: ~0.2 s of import a flat city skips)
        mid = (pos + pos[nxt]) / 2
        tree = cKDTree(mid)
        k = min(NEAR_EDGES, len(pos))
        _, near = tree.query(pos[reflex], k=k)
        guess = self._split_event(np.repeat(reflex, k), np.asarray(near).ravel(), pos, vel, nxt, e_out, t)
        times = [e[0] for e in (edge, guess) if e is not None]
        if not times:  # nothing to bound the search with: every pair
            return np.repeat(reflex, len(pos)), np.tile(np.arange(len(pos)), len(reflex))
        horizon = min(times) - t
        speed = np.hypot(vel[:, 0], vel[:, 1])
        reach = horizon * np.maximum(speed, speed[nxt]) + np.hypot(*(pos[nxt] - pos).T) / 2 + 4 * self.eps
        cut = min(float(reach.max()), 4 * float(np.median(reach)))  # edges reaching further: every reflex vertex
        far = np.flatnonzero(reach > cut)
        found = tree.query_ball_point(pos[reflex], horizon * speed[reflex] + cut)
        counts = np.fromiter(map(len, found), dtype=np.int64, count=len(found))
        pv = np.concatenate([np.repeat(reflex, len(far)), np.repeat(reflex, counts)]).astype(np.int64)
        near = np.fromiter(itertools.chain.from_iterable(found), dtype=np.int64, count=int(counts.sum()))
        pj = np.concatenate([np.tile(far, len(reflex)), near])
        return pv, pj  # (a pair may come twice: harmless)

    def edge_event(self, t: float, r: int, i: int) -> None:
        ring = self.rings[r]
        v, u = ring[i], ring[(i + 1) % len(ring)]
        node = self.node(self.meet(v, u, t), t)
        self.end(v, node)
        self.end(u, node)
        a, c, b = v.e_in, v.e_out, u.e_out
        if self.W[c] == 0 and self.W[a] != self.W[b] and self.N[a] @ self.N[b] > 1 - 1e-12:
            # a standing edge swept to nothing between parallel edges of different speeds: it does not vanish
            # but turns round, a standing edge on its own line that grows between them as they part
            flip = self.add_edge(c, node)
            new = [self.vertex(node, t, a, flip), self.vertex(node, t, flip, b)]
        else:
            # two pieces of one edge (parted by a split event) meeting again join into one: no vertex between them
            new = [self.vertex(node, t, a, b)] if a != b else []
        if (i + 1) % len(ring) == 0:
            self.rings[r] = new + ring[1:-1]
        else:
            self.rings[r] = ring[:i] + new + ring[i + 2:]
        self.settle(t)

    def add_edge(self, c: int, node: int) -> int:
        """A new standing edge (weight 0) on the line of edge ``c``, pointing the other way, born at ``node``."""
        return self.add_wall(node, -self.D[c])

    def add_wall(self, node: int, d: np.ndarray) -> int:
        """A new standing edge (weight 0) through ``node`` in direction ``d`` (the interior on its left)."""
        normal = np.array([-d[1], d[0]])
        self.D, self.N = np.vstack([self.D, d]), np.vstack([self.N, normal])
        self.C, self.W = np.append(self.C, normal @ np.asarray(self.nodes[node])), np.append(self.W, 0.0)
        self.arcs.append(set())
        self.edge_nodes.append((node, None))
        self._lines = None
        return len(self.W) - 1

    def split_event(self, t: float, r: int, i: int, s: int, j: int) -> None:
        ring, other = self.rings[r], self.rings[s]
        v, x = ring[i], other[j]
        node = self.node(v.at(t), t)
        self.end(v, node)
        at = np.asarray(self.nodes[node])
        hit = next((h for h in (x, other[(j + 1) % len(other)])
                    if np.abs(h.at(t) - at).max() < 1e-7 * self.scale), None)
        if hit is not None:
            self.vertex_event(t, r, i, s, other.index(hit), node)
            return
        w1 = self.vertex(node, t, x.e_out, v.e_out)
        w2 = self.vertex(node, t, v.e_in, x.e_out)
        after_v = ring[i + 1:] + ring[:i]  # next(v) ... prev(v)
        if r == s:
            k = after_v.index(x)
            first, second = [w1] + after_v[:k + 1], [w2] + after_v[k + 1:]
            self.rings[r:r + 1] = [first, second]
        else:
            after_x = other[j + 1:] + other[:j + 1]  # y ... x
            merged = [w1] + after_v + [w2] + after_x
            self.rings = [g for k, g in enumerate(self.rings) if k not in (r, s)] + [merged]
        self.settle(t)

    def vertex_event(self, t: float, r: int, i: int, s: int, h: int, node: int) -> None:
        """Reflex vertex ``rings[r][i]`` reaches an edge at its end vertex ``rings[s][h]``, which arrives there
        too (symmetric outlines): the two vertices meet, and each pairs its incoming edge with the other's outgoing
        one. Splitting the edge there instead left a piece of it with no length on the wrong side, which split and
        joined the rings again for ever."""
        ring, other = self.rings[r], self.rings[s]
        v, x = ring[i], other[h]
        self.end(x, node)
        a, b = self.vertex(node, t, x.e_in, v.e_out), self.vertex(node, t, v.e_in, x.e_out)
        after_v = ring[i + 1:] + ring[:i]  # next(v) ... prev(v)
        if r == s:
            k = after_v.index(x)
            self.rings[r:r + 1] = [[a] + after_v[:k], [b] + after_v[k + 1:]]
        else:
            merged = [a] + after_v + [b] + other[h + 1:] + other[:h]
            self.rings = [g for k, g in enumerate(self.rings) if k not in (r, s)] + [merged]
        self.settle(t)

    # -- clean-up after an event -----------------------------------------------------------------------------------

    def settle(self, t: float) -> None:
        """Fold spikes and finish rings that have collapsed (two vertices, or a strip with no area left) or stopped
        (no edge moves: a plateau)."""
        changed = True
        while changed:
            changed = False
            roomy = self.roomy(t)
            for r, ring in enumerate(self.rings):
                plateau = len(ring) > 2 and self.stopped(r, t)
                if len(ring) <= 2 or plateau or (not roomy[r] and self.collapsed(ring, t)):
                    nodes = self.finish(ring, t, snap=not plateau)
                    flat = [n for k, n in enumerate(nodes) if n != nodes[k - 1]]
                    inner = self.enclosed(r, t) if plateau else []
                    holes = [self.finish(self.rings[s], t, snap=False) for s in inner]  # standing courtyards
                    if plateau and len(flat) > 2 and self.area(ring, t) > 1e-9 * self.scale ** 2:
                        holes = [[n for k, n in enumerate(h) if n != h[k - 1]] for h in holes]
                        self.flats.append(tuple(_bridged(flat, [h for h in holes if len(h) > 2],
                                                         np.asarray(self.nodes))))
                    self.rings = [g for s, g in enumerate(self.rings) if s != r and s not in inner]
                    changed = True
                    break
                k = next((k for k, v in enumerate(ring) if self.antiparallel(v)), None)
                if k is not None:
                    self.rings[r] = self.step(ring, k, t) if self.parting(ring[k]) else self.fold(ring, k, t)
                    changed = True
                    break

    def stopped(self, r: int, t: float) -> bool:
        """Ring ``r`` encloses a region (counter-clockwise) none of whose edges moves, and no other ring inside it
        can still sweep into it: it is a plateau (with the rings inside, courtyards walled by standing edges, as its
        holes)."""
        ring = self.rings[r]
        if any(self.W[v.e_out] > 0 for v in ring):
            return False
        if _signed_area(self.positions(ring, t)) <= 0:
            return False  # a static courtyard: moving edges around it will reach it
        return not any(any(self.W[v.e_out] > 0 for v in self.rings[s]) for s in self.enclosed(r, t))

    def enclosed(self, r: int, t: float) -> list[int]:
        """The rings inside ring ``r``."""
        outline = self.positions(self.rings[r], t)
        return [s for s, other in enumerate(self.rings) if s != r and _contains(outline, other[0].at(t))]

    def roomy(self, t: float) -> np.ndarray:
        """Per ring, whether its area at ``t`` is clearly (twice) above what :meth:`collapsed` calls none: one
        vectorised shoelace over every ring, so only the few small rings get the exact test. A small wavefront
        whose rings all have clearly more area (``4e-9`` of the scale squared, in Python floats; the two sums of
        at most ``SMALL_FRONT`` cross products differ only by their order, by far less than the margin) or one or
        two vertices (no area: both sums are 0) skips it."""
        if 0 < sum(map(len, self.rings)) <= SMALL_FRONT and all(self.rings):
            clear = [len(ring) > 2 and abs(0.5 * _ring_cross(ring, t)) >= 4e-9 * self.scale ** 2
                     for ring in self.rings]
            if all(c or len(ring) <= 2 for c, ring in zip(clear, self.rings)):
                return np.array(clear, dtype=bool)
        sizes = np.array([len(ring) for ring in self.rings])
        if not len(sizes) or sizes.min() == 0:
            return np.zeros(len(sizes), dtype=bool)
        pos, _, nxt, _, _ = self.front(t)
        first = np.cumsum(sizes) - sizes
        start = np.repeat(first, sizes)
        rel = pos - pos[start]
        cross = rel[:, 0] * rel[nxt, 1] - rel[nxt, 0] * rel[:, 1]
        return np.abs(0.5 * np.add.reduceat(cross, first)) >= 2e-9 * self.scale ** 2

    def collapsed(self, ring: list[_Vertex], t: float) -> bool:
        """No area left and thin: a strip collapsing along its length. A ring small all round (area not tiny
        against its diameter squared) is no strip: its own edge events close it exactly."""
        area = self.area(ring, t)
        if area >= 1e-9 * self.scale ** 2:
            return False
        return area <= 1e-3 * float(np.ptp(self.positions(ring, t), axis=0).max()) ** 2

    def area(self, ring: list[_Vertex], t: float) -> float:
        return abs(_signed_area(self.positions(ring, t)))

    @staticmethod
    def positions(ring: list[_Vertex], t: float) -> np.ndarray:
        """Where the vertices of ``ring`` are at time ``t``, as rows."""
        return np.array([(v.p0[0] + (t - v.t0) * v.vel[0], v.p0[1] + (t - v.t0) * v.vel[1]) for v in ring])

    def parting(self, v: _Vertex) -> bool:
        """``v`` joins two edges on one line, facing the same way, that move at different speeds: from here they
        part (a free wall running on as a party wall)."""
        a, b = v.e_in, v.e_out
        return self.W[a] != self.W[b] and self.N[a] @ self.N[b] > 1 - 1e-12

    def step(self, ring: list[_Vertex], k: int, t: float) -> list[_Vertex]:
        """Where two edges on one line part (:meth:`parting`), a standing edge across the line joins them: a vertical
        wall inside the roof between the faster edge's slope and the roof above the slower one (no vertex can
        follow both edges)."""
        v = ring[k]
        a, b = v.e_in, v.e_out
        wall = self.add_wall(v.node, np.sign(self.W[b] - self.W[a]) * self.N[a])
        return ring[:k] + [self.vertex(v.node, t, a, wall), self.vertex(v.node, t, wall, b)] + ring[k + 1:]

    def fold(self, ring: list[_Vertex], k: int, t: float) -> list[_Vertex]:
        """Remove the tip ``ring[k]`` of a zero-width spike: it runs to its nearer neighbour, which then takes
        over the tip's far edge."""
        n = len(ring)
        w, p, q = ring[k], ring[(k - 1) % n], ring[(k + 1) % n]
        at = w.at(t)
        if np.hypot(*(p.at(t) - at)) <= np.hypot(*(q.at(t) - at)):
            node = self.node(p.at(t), t)
            self.end(w, node)
            self.end(p, node)
            merged, drop = self.vertex(node, t, p.e_in, w.e_out), (k - 1) % n
        else:
            node = self.node(q.at(t), t)
            self.end(w, node)
            self.end(q, node)
            merged, drop = self.vertex(node, t, w.e_in, q.e_out), (k + 1) % n
        out = []
        for m, v in enumerate(ring):
            if m == k:
                out.append(merged)
            elif m != drop:
                out.append(v)
        return out

    def finish(self, ring: list[_Vertex], t: float, snap: bool = True) -> list[int]:
        """A collapsed (or stopped) ring: its vertices stop where they are and each of its edges becomes a ridge
        (or plateau rim) arc of that edge's face, passing through every other node of the ring on it (so the faces
        on both sides of a ridge have the same nodes, without T-junctions). With ``snap`` (a collapsed ring),
        vertices within ``1e-4`` of the outline's size of an earlier one stop on it: rounding, not a ridge, set them
        apart; a plateau's vertices stand where they are (a millimetre jog of a party wall is no rounding). Returns
        the node each vertex stopped at."""
        at = self.positions(ring, t)
        for k in range(1, len(at) if snap else 0):
            near = np.flatnonzero(np.hypot(*(at[:k] - at[k]).T) < 1e-4 * self.scale)
            if len(near):
                at[k] = at[near[0]]
        nodes = [self.node(p, t) for p in at]
        for v, node in zip(ring, nodes):
            self.end(v, node)
        if len(ring) < 2:
            return nodes
        xy = np.array([self.nodes[n] for n in nodes])
        for k, v in enumerate(ring):
            a, b = nodes[k], nodes[(k + 1) % len(ring)]
            if a == b:
                continue
            pa, pb = np.asarray(self.nodes[a]), np.asarray(self.nodes[b])
            d = pb - pa
            inner = []
            if d @ d > 0:  # (two nodes of time 0 snapped onto one place, e.g. a sliver's corners, have no arc length)
                s = (xy - pa) @ d / (d @ d)
                off = np.abs((xy - pa) @ np.array([-d[1], d[0]])) / math.sqrt(d @ d)
                inner = sorted({(s[m], nodes[m]) for m in range(len(ring))
                                if 0 < s[m] < 1 and off[m] < 1e-7 * self.scale and nodes[m] not in (a, b)})
            chain = [a, *[n for _, n in inner], b]
            for p, q in zip(chain, chain[1:]):
                if p != q:
                    self.arcs[v.e_out].add((min(p, q), max(p, q)))
        return nodes

    # -- faces ---------------------------------------------------------------------------------------------------

    def check_planes(self, faces: tuple[tuple[int, ...], ...]) -> None:
        """Every node of edge ``e``'s face lies where the wavefront of ``e`` passes at the node's time (its
        weighted distance from the edge line is its time): the roof plane of ``e`` holds the face. A degenerate
        event the wavefront cannot resolve (e.g. adjacent parallel edges of different weights) breaks this."""
        xy, times = np.asarray(self.nodes), np.asarray(self.times)
        k = np.fromiter((n for face in faces for n in face), dtype=np.int64)
        e = np.repeat(np.arange(len(faces)), [len(face) for face in faces])
        off = np.abs(np.einsum("ij,ij->i", xy[k], self.N[e]) - self.C[e] - self.W[e] * times[k])
        if off.size and off.max() > 1e-3 * self.scale:
            raise SkeletonError(f"face of edge {e[off.argmax()]} leaves its plane by {off.max():.3g} "
                                "(a degenerate event of the weighted wavefront)")

    def with_holes(self, e: int, path: list[int]) -> list[int]:
        """``path`` (the outer boundary of edge ``e``'s face) with the loops of ``e``'s arcs it does not pass
        joined in as holes: where pieces of the edge's wavefront met again round a region that stands (a courtyard
        walled by party walls)."""
        if len(self.arcs[e]) - len(path) < 2:
            return path  # every arc but at most two is on the path (all but its first side): no loop left
        on_path = {(min(p, q), max(p, q)) for p, q in zip(path, path[1:] + path[:1])}
        nbrs: dict[int, list[int]] = {}
        for p, q in self.arcs[e] - on_path:
            nbrs.setdefault(p, []).append(q)
            nbrs.setdefault(q, []).append(p)
        if not nbrs or any(len(v) != 2 for v in nbrs.values()):
            return path  # nothing left, or no loops: left for the checks to reject
        loops: list[list[int]] = []
        for start in sorted(nbrs):
            if any(start in loop for loop in loops):
                continue
            loop, prev, cur = [start], None, start
            while True:
                cur, prev = next(n for n in nbrs[cur] if n != prev), cur
                if cur == start:
                    break
                loop.append(cur)
            loops.append(loop)
        return _bridged(path, loops, np.asarray(self.nodes))

    def face(self, e: int) -> tuple[int, ...]:
        """Walk the arcs of edge ``e``'s face from its end node back to its start, keeping the face on the left. An
        edge born during the propagation (:meth:`add_edge`) starts where it was born and ends where its front
        vertex stopped, the node of its arcs furthest along it."""
        a, b = self.edge_nodes[e]
        nbrs: dict[int, list[int]] = {}
        for p, q in self.arcs[e]:
            nbrs.setdefault(p, []).append(q)
            nbrs.setdefault(q, []).append(p)
        born = b is None
        if born:
            if not nbrs.get(a):
                return ()  # swept away in the instant it was born
            b = max(nbrs[a], key=lambda n: float(np.asarray(self.nodes[n]) @ self.D[e]))
        path, prev, cur = [a, b], a, b
        for _ in range(len(self.arcs[e]) + 1):
            options = [n for n in nbrs.get(cur, []) if n != prev and (n == a or n not in path)]
            if not options:
                break
            if len(options) > 1:
                here = np.asarray(self.nodes[cur])
                back = np.asarray(self.nodes[prev]) - here
                base = math.atan2(back[1], back[0])

                def turn(n: int) -> float:
                    d = np.asarray(self.nodes[n]) - here
                    return (base - math.atan2(d[1], d[0])) % (2 * math.pi)
                options.sort(key=turn)
            prev, cur = cur, options[0]
            if cur == a:
                if born:  # start with the side that advances furthest along the edge: the wall's foot
                    along = np.asarray([self.nodes[n] for n in path]) @ self.D[e]
                    k = int(np.argmax(np.roll(along, -1) - along))
                    path = path[k:] + path[:k]
                return tuple(self.with_holes(e, path))
            path.append(cur)
        raise SkeletonError(f"face of edge {e} does not close")


def _ring_cross(ring: list[_Vertex], t: float) -> float:
    """Twice the signed area of ``ring`` at ``t`` (shoelace about its first vertex), in Python floats."""
    p = [(v.p0[0] + (t - v.t0) * v.vel[0], v.p0[1] + (t - v.t0) * v.vel[1]) for v in ring]
    x0, y0 = p[0]
    rel = [(x - x0, y - y0) for x, y in p]
    return sum(a[0] * b[1] - b[0] * a[1] for a, b in zip(rel, rel[1:] + rel[:1]))


def _signed_area(p: np.ndarray) -> float:
    """Shoelace area about the first point (no cancellation far from the origin)."""
    x, y = p[:, 0] - p[0, 0], p[:, 1] - p[0, 1]
    return 0.5 * float(x[:-1] @ y[1:] - x[1:] @ y[:-1] + x[-1] * y[0] - x[0] * y[-1])


def _bridged(ring: list[int], holes: list[list[int]], xy: np.ndarray) -> list[int]:
    """``ring`` (node indices, counter-clockwise) with ``holes`` spliced in, each clockwise, at the shortest bridge
    from one of its nodes to the ring that crosses no side of the ring or the holes (walked both ways: one ring
    a triangulation takes as a polygon with holes). Holes it cannot bridge are left out (the area check fails)."""
    holes = [h if _signed_area(xy[h]) < 0 else h[::-1] for h in holes]
    sides = np.array([(p, q) for r in [ring, *holes] for p, q in zip(r, r[1:] + r[:1])])
    for hole in holes:
        gap = np.hypot(*(xy[ring][:, None, :] - xy[hole][None, :, :]).transpose(2, 0, 1))
        for flat in np.argsort(gap, axis=None):
            i, j = np.unravel_index(flat, gap.shape)
            if not _crosses(xy[ring[i]], xy[hole[j]], xy[sides[:, 0]], xy[sides[:, 1]]):
                ring = ring[:i + 1] + hole[j:] + hole[:j + 1] + ring[i:]
                break
    return ring


def _crosses(p: np.ndarray, q: np.ndarray, a: np.ndarray, b: np.ndarray) -> bool:
    """Whether the segment ``p q`` properly crosses any segment ``a[k] b[k]`` (touching at an end does not)."""
    def side(u, v, w):
        return (v[..., 0] - u[..., 0]) * (w[..., 1] - u[..., 1]) - (v[..., 1] - u[..., 1]) * (w[..., 0] - u[..., 0])
    tol = 1e-12 * max(1.0, float(np.abs(p).max())) ** 2
    s1, s2 = side(p, q, a), side(p, q, b)
    s3, s4 = side(a, b, p), side(a, b, q)
    return bool(np.any((s1 * s2 < -tol) & (s3 * s4 < -tol)))


def _contains(ring: np.ndarray, point: np.ndarray) -> bool:
    """Whether ``point`` lies inside the polygon ``ring`` (even-odd rule)."""
    a, b = ring, np.roll(ring, -1, axis=0)
    crosses = (a[:, 1] > point[1]) != (b[:, 1] > point[1])
    with np.errstate(divide="ignore", invalid="ignore"):
        x = a[:, 0] + (point[1] - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    return bool(np.count_nonzero(crosses & (point[0] < x)) % 2)


def _rings(polygon: Polygon) -> list[np.ndarray]:
    polygon = orient(polygon, sign=1.0)
    rings = []
    for ring in (polygon.exterior, *polygon.interiors):
        pts = np.asarray(ring.coords)[:-1, :2].astype(float)
        keep = np.any(np.abs(pts - np.roll(pts, 1, axis=0)) > 1e-9, axis=1)
        pts = pts[keep]
        if len(pts) < 3:
            raise SkeletonError("ring with fewer than 3 vertices")
        rings.append(pts)
    return rings


def straight_skeleton(polygon: Polygon, max_events: int | None = None,
                      weights: np.ndarray | None = None) -> Skeleton:
    """The straight skeleton of a valid polygon (holes allowed); faces in input edge order, exterior ring first,
    then each hole (rings oriented exterior counter-clockwise, holes clockwise).

    ``weights`` (one per edge, default 1) is each edge's speed: a *weighted* straight skeleton (Eppstein & Erickson
    1999), where a node's time is still the wavefront's. An edge of weight 0 stays where it is: its face is the
    edge line itself (points along it, rising with time) -- a vertical gable in a roof. Where edges of weight 0
    wall in a region that no moving edge reaches, the skeleton ends there in a plateau (``Skeleton.flats``)."""
    if not polygon.is_valid or polygon.is_empty or polygon.area <= 0:
        raise SkeletonError("invalid or empty polygon")
    rings = _rings(polygon)
    n = sum(len(r) for r in rings)
    weights = np.ones(n) if weights is None else np.asarray(weights, dtype=float)
    if weights.shape != (n,) or np.any(weights < 0) or not np.any(weights > 0):
        raise SkeletonError(f"need {n} edge weights >= 0, not all 0")
    wf = _Wavefront(rings, weights)
    if any(v.spike for ring in wf.rings for v in ring):
        wf.settle(0.0)  # vertices between parallel edges of the input (spikes, collinear edges of different speeds)
    limit = max_events or 4 * n * n + 16
    t = 0.0
    for _ in range(limit):
        if not wf.rings:
            break
        check_budget()
        event = wf.next_event(t)
        if event is None:
            raise SkeletonError(f"wavefront stuck at time {t:.3f} with {sum(map(len, wf.rings))} vertices")
        t = max(t, event[0])
        if event[1] == 0:
            wf.edge_event(t, *event[2])
        else:
            wf.split_event(t, *event[2])
    else:
        raise SkeletonError(f"no convergence after {limit} events")
    faces = tuple(wf.face(e) for e in range(len(wf.W)))
    wf.check_planes(faces)
    return Skeleton(np.asarray(wf.nodes, dtype=float), np.asarray(wf.times, dtype=float), faces[:n], tuple(wf.flats),
                    tuple(f for f in faces[n:] if f))
