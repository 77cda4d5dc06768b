"""Certified global optima of a searched measure over a variant whose designs are a box of a
few free numbers u (``Mechanism.space``): branch-and-bound with rigorous lower bounds. The
measures, and their bounds over a box, are ``measures``' (``MEASURES``, by the objective's
terms). At each level, over the boxes alive:

- **feasibility**: the formulation's inequality rows (transmission, validity, the closed
  forms' domain) and the request's box on each parameter, enclosed over each box
  (``numerics.interval``'s centred form, compiled): a box that surely breaks one goes;
- **bound**: the measure's lower bound over each box, from its centre's measurement;
- **incumbent**: the least measured centre that meets every constraint (and first the
  least corner of the box: an optimum at a bound), if it is the least so far; with two or
  more free numbers also, on each face of the space that boxes the next step keeps touch,
  the centre of the one measuring least moved onto the face (an optimum a bound holds lies
  on a face, not at a corner: the centres alone near it only to first order in the boxes'
  width, and the gap would not close);
- a box whose bound is within ``CLOSE`` of the incumbent goes (its bound kept); the others
  are cut into parts (``SPLITS``, by the number of free numbers) across their widest side.

The search is done when no box is left: then every design of the variant measures at least
the least bound kept, and a bounded Brent search over where a better one may lie polishes the
incumbent (one free number) unless it is within ``POLISHED`` of that bound already. After
``LEVELS`` levels, or with more than ``LIVE`` boxes alive, it stops with the bound it reached
(a box not bounded yet: its parent's). Its work is the same on any machine: the deadline only
stops it, looked at before each ``CHUNK`` of boxes is measured and bounded (the answer then
says so, uncertified).
"""

from __future__ import annotations

import functools
import itertools
import math
import threading
import time
from dataclasses import dataclass, replace
from typing import Any

import casadi as ca
import numpy as np

from ..load import Load
from ..mechanisms import Mechanism
from ..mechanisms.kinetics import numbers
from ..mechanisms.reduced import Space
from ..numerics.compiled_interval import CompiledCentred
from ..numerics.native import Mapped
from ..results import Candidate
from ..targets import MAX_TRANSMISSION
from .formulation import formulation, relevant
from .measures import Acceleration, Speed
from .search import Spec, Targets, Variant, build_problem
from .stroke import Kinematics, design
from .torque import Model, Torque, unsupported

METHOD = "branch_and_bound"  # its candidates' method
# the objectives' terms (``Objective.terms``) searched here, and their measures
MEASURES: dict[str, Any] = {"acceleration": Acceleration, "speed": Speed}
TORQUE = "torque"  # the peak torque's terms, measured under the request's load (``torque``)
TOL = 1e-9  # the relative gap certified
# the relative gap the search closes: the incumbent nears the optimum as the bound does, so a
# tighter gap than the certificate's brings it to 1e-10 of the optimum's value (much closer,
# and the enclosures' rounding, ~1e-11 of the value, keeps ever more boxes about it alive)
CLOSE = 1e-10
EPS = float(np.finfo(float).eps)
POLISHED = 1e-12  # relative: an incumbent this close to the bound is not polished
GRADE, GRADES = 8, 8  # the box of an incumbent on a face: cut at x ± its width / 8, … / 8⁸
INSIDE = 1e-12  # how far inside the box its corners are measured again, of its width
SPLITS = {1: 8}  # the parts a box is cut into, by its dimension (fewer levels: each costs a
SPLIT = 4  # few calls; a box of two or more free numbers: this many)
FIRST = {1: 2}  # a box's cuts before the first level, by its free numbers (a wider box's bound
# proves nothing: the speed's window ends move too far over it)
LEVELS = 30  # levels at most (1-D: 8^-30 of the box)
LIVE = 4096  # boxes alive at most
CHUNK = 256  # the boxes measured and bounded between two looks at the deadline
_local = threading.local()


@dataclass(frozen=True)
class Certificate:
    """A search's answer: the best design it measured (stroke units; empty: none better than
    its cutoff), its measure, the least lower bound over every design of the variant, whether
    the search finished (not stopped by the deadline) and closed every box (``closed``: not
    stopped at ``LEVELS`` or ``LIVE``), and what it took."""

    design: dict[str, float]
    value: float
    bound: float
    complete: bool
    closed: bool
    levels: int
    boxes: int


def mark(c: Candidate, bound: float, why: str | None = None) -> Candidate:
    """A verified candidate with its gap to ``bound``, a lower bound on every design of its
    type: certified where it is within ``TOL`` of it (its measure as the analysis verified
    it); else ``why`` it is not (default: how far above the bound it is)."""
    v = c.objective_value
    if not (v > 0 and math.isfinite(bound)):
        return replace(c, uncertified=why or "no finite bound on its type's designs")
    gap = max(0.0, (v - bound) / v)
    if gap <= TOL:
        return replace(c, certified=True, gap=float(gap))
    why = why or f"{gap:.2g} (relative) above the least any design of its type can reach"
    return replace(c, gap=float(gap), uncertified=why)


class Built:
    """What a search over one variant's space needs, built once per thread and structure: its
    kinematics (``stroke.Kinematics``), the constraint rows with the free parameters
    enclosed (``rows``) and at many points (``at``), the design's parameters at a point, and
    its crank torque (``torque``, built on first use; any space of the structure: the
    constants are inputs)."""

    def __init__(self, m: Mechanism, variant: frozenset[str], sp: Space):
        # every relevant parameter free: a request's fixed parts are the space's business
        self.form = form = formulation(m, variant, relevant(m, variant))
        self.name = name = "_".join((m.type, *sorted(variant), "certify"))
        self.mechanism, self.variant, self.space = m, variant, sp
        self.kin = Kinematics(m, variant, sp, name)
        u, k = ca.SX.sym("u", len(sp.lo)), ca.SX.sym("k", len(sp.constants))
        pv = ca.SX.sym("pv", form.nlp["p"].numel())
        p = design(m, variant, sp, u, k)
        x = ca.vertcat(*(p[q] for q in form.free))
        g = ca.Function("g", [form.nlp["x"], form.nlp["p"]], [form.nlp["g"]])(x, pv)
        self.inequality = form.lbg != form.ubg
        out = ca.vertcat(g[np.flatnonzero(self.inequality).tolist()], x)
        rows_fn = ca.Function(f"{name}_rows", [u, k, pv], [out], {"cse": True})
        self.rows = CompiledCentred(rows_fn, wrt=[0])
        self.at = Mapped(rows_fn, (False, True, True))  # at many points, each a row
        self.design = ca.Function("design", [u, k], [ca.vertcat(*(p[q] for q in m.names))])

    @functools.cached_property
    def torque(self) -> Model:
        """The crank torque in closed form (``torque.Model``), built on first use."""
        return Model(self.mechanism, self.variant, self.space, self.name)


def built(m: Mechanism, variant: frozenset[str], sp: Space) -> Built:
    cache: dict[Any, Built] = _local.__dict__.setdefault("built", {})
    key = (m.type, variant, len(sp.lo), len(sp.constants))  # a space's form (``Space``)
    if key not in cache:
        cache[key] = Built(m, variant, sp)
    return cache[key]


def prepared(m: Mechanism, variant: frozenset[str]) -> list[Built]:
    """What a search over the variant builds, for each form its spaces take (``Space``: with
    nothing fixed, and with each relevant part fixed, at the reduced solver's design), the
    peak torque's model with it where the type has a force model (a service's warm-up; the
    disk cache's libraries); none for a type without a space."""
    if m.space is None:
        return []
    names = relevant(m, variant)
    t = Targets(1.6 if m.quick_return else 1.0, 1.0, 0.0, MAX_TRANSMISSION, math.inf)
    free = build_problem(m, variant, names, {}, Spec(m.type), t)
    solved = m.reduced(free) if m.reduced is not None else None
    designs = solved.designs if solved is not None else []
    fixes = [{q: designs[0][q]} for q in names if designs and q in designs[0]]
    found: dict[int, Built] = {}
    for fixed in [{}, *fixes]:
        sp = m.space(build_problem(m, variant, names, fixed, Spec(m.type), t))
        if sp is not None:
            b = built(m, variant, sp)
            found[id(b)] = b
    if m.frame is not None:  # the peak torque's too
        for b in found.values():
            b.torque.libraries()
    return list(found.values())


def search(
    m: Mechanism,
    v: Variant,
    terms: str | None,
    targets: tuple[float, float],
    deadline: float,
    load: Load | None = None,
    metres: float = 1.0,
    cutoff: float = math.inf,
) -> Certificate | str:
    """The certified least of the ``terms``' peak over the variant ``v`` (``targets``: the
    time ratio and cos of the transmission bound; the peak torque's under ``load``, the
    space's lengths ``metres`` each), or why this search cannot take it (no space, a measure
    its bounds do not close in good time, a load ``torque`` does not bound). A design known
    to measure ``cutoff`` (another variant's) starts it as the incumbent: boxes bounded above
    it go at once, and where none of the variant's designs is better the certificate has no
    design, and its bound says so."""
    # the box of the problem as searched: its transmission bound the search's own
    problem = replace(v.problem, cos_bound=targets[1])
    sp = m.space(problem) if m.space is not None else None
    if sp is None or terms is None:
        return f"{m.type}'s designs are no box of free numbers that the certified search covers"
    if sp.measures is not None and terms not in sp.measures:
        free = int(np.count_nonzero(np.subtract(sp.hi, sp.lo)))
        return (
            f"over {m.type}'s {free} free numbers the certified search's bounds on this measure "
            "are too loose to close in good time"
        )
    b = built(m, v.parts, sp)
    if terms in MEASURES:
        measure, spaces = MEASURES[terms], [sp]
    elif terms == TORQUE and load is not None and m.frame is not None:
        why = unsupported(load, sp)
        if why is not None:
            return f"the certified bound on the peak torque does not hold with {why}"
        measure = Torque(b.torque, load, numbers(load, metres))
        spaces = [sp] if sp.mirror is None else [sp, replace(sp, constants=sp.mirror)]
    else:
        return f"the certified search does not bound {m.type}'s {terms}"
    found = [_search(b, s, measure, v, targets, deadline, cutoff) for s in spaces]
    best = min(found, key=lambda c: c.value)
    return replace(
        best,
        bound=min(c.bound for c in found),
        complete=all(c.complete for c in found),
        closed=all(c.closed for c in found),
        levels=sum(c.levels for c in found),
        boxes=sum(c.boxes for c in found),
    )


def _search(
    b: Built,
    sp: Space,
    meas: Any,
    v: Variant,
    targets: tuple[float, float],
    deadline: float,
    cutoff: float,
) -> Certificate:
    """The branch-and-bound over one space (the module's docstring), ``cutoff`` the
    incumbent's measure at its start: its best design (empty: none better found) and the
    least bound over its designs (∞: it has none)."""
    measure, lower_bound = meas.measure, meas.lower
    k = np.array(sp.constants)
    pv = np.array(targets, dtype=float)
    # the request's bounds on its free parameters (its fixed ones are the space's own)
    box = [v.problem.bounds.get(q, (-math.inf, math.inf)) for q in b.form.free]
    lb = np.concatenate([b.form.lbg[b.inequality], [x[0] for x in box]])
    ub = np.concatenate([b.form.ubg[b.inequality], [x[1] for x in box]])
    lo, hi = np.array([sp.lo]), np.array([sp.hi])
    width, parts = hi[0] - lo[0], SPLITS.get(len(sp.lo), SPLIT)
    top, best = cutoff, None
    least, levels, boxes, stopped = math.inf, 0, 0, False
    near = lo[0], hi[0]

    def probe(points: np.ndarray, value: np.ndarray) -> None:
        """The incumbent: the point of least measured ``value`` that is a design, if it is the
        best so far."""
        nonlocal top, best
        g = b.at(points, k, pv).T
        value = np.where(np.all((g >= lb) & (g <= ub), axis=1), value, math.inf)  # designs
        j = int(np.argmin(value))
        if value[j] < top:
            top, best = value[j], points[j]

    # an optimum at a bound: the corners, and the corners moved inside by 1e-12 of the box
    # (a face where a constraint holds with equality is a design to rounding only)
    corners = np.array(list(itertools.product(*zip(sp.lo, sp.hi, strict=True))))
    inside = corners + INSIDE * (np.array(sp.lo) + np.array(sp.hi) - 2 * corners)
    corners = np.unique(np.vstack([corners, inside]), axis=0)  # a point box's are one
    probe(corners, measure(b.kin, corners, k)[0])
    for _ in range(FIRST.get(int(np.count_nonzero(width)), 0)):  # too wide to bound: cut first
        lo, hi = _split(lo, hi, width, parts)
    parent = np.full(len(lo), -math.inf)  # each box's parent's bound, which holds for it too
    while len(lo) and levels < LEVELS and len(lo) <= LIVE:
        if time.monotonic() >= deadline:
            stopped = True
            break
        levels, boxes = levels + 1, boxes + len(lo)
        e = b.rows([lo, k, pv], [hi, k, pv])
        possible = ~np.any((e.hi[0] < lb) | (e.lo[0] > ub), axis=1)
        lo, hi, parent = lo[possible], hi[possible], parent[possible]
        if not len(lo):
            break
        centres = 0.5 * (lo + hi)
        value, lower = np.full(len(lo), math.inf), parent.copy()
        for c in range(0, len(lo), CHUNK):  # the deadline looked at between chunks
            if c and time.monotonic() >= deadline:
                stopped = True
                break
            at = slice(c, c + CHUNK)
            value[at], info = measure(b.kin, centres[at], k)
            lower[at] = lower_bound(b.kin, lo[at], hi[at], info, k)
        probe(centres, value)
        if stopped:  # mid-level: each box's bound so far counts
            least = min([least, *lower])
            lo = lo[:0]
            break
        keep = lower < top * (1 - CLOSE)
        faces = _faces(lo[keep], hi[keep], centres[keep], value[keep], sp)  # on the faces
        if len(faces):
            probe(faces, measure(b.kin, faces, k)[0])
            keep = lower < top * (1 - CLOSE)
        least = min([least, *lower[~keep]])
        point = np.all(lo == hi, axis=1)  # a box that is a point: its bound is all there is
        least = min([least, *lower[keep & point]])
        keep &= ~point
        if (lower <= top).any():  # where a design as good as the incumbent may be
            near = lo[lower <= top].min(axis=0), hi[lower <= top].max(axis=0)
        lo, hi, parent = _cut(lo[keep], hi[keep], lower[keep], width, parts, _on_face(best, sp))
    closed = not (stopped or len(lo))
    if len(lo):  # stopped with boxes alive: their parents' bounds count (no work past it)
        least = min([least, *parent])
    if best is None:
        return Certificate({}, math.inf, least, not stopped, closed, levels, boxes)
    if np.count_nonzero(width) == 1 and not stopped and top - least > POLISHED * top:
        top, best = _polish(b, measure, k, pv, (lb, ub), near, top, best)
    design = dict(
        zip(b.mechanism.names, np.asarray(b.design(best, k)).ravel().tolist(), strict=True)
    )
    return Certificate(design, top, min(least, top), not stopped, closed, levels, boxes)


def _polish(
    b: Built,
    measure: Any,
    k: np.ndarray,
    pv: np.ndarray,
    limits: tuple[np.ndarray, np.ndarray],
    near: tuple[np.ndarray, np.ndarray],
    top: float,
    best: np.ndarray,
) -> tuple[float, np.ndarray]:
    """The incumbent moved to the least of the measure over ``near`` (one free number: the
    others' sides are points), where every design as good lies: Brent's bounded minimiser to
    the last few ulps of u, a point that is no design counting as twice the incumbent's
    measure."""
    from scipy.optimize import minimize_scalar

    j = int(np.argmax(near[1] - near[0]))

    def point(x: float) -> np.ndarray:
        u = np.array(near[0], dtype=float)
        u[j] = x
        return u

    def at(x: float) -> float:
        u = point(x)
        g = b.at(u[None], k, pv)[:, 0]
        if not np.all((g >= limits[0]) & (g <= limits[1])):
            return 2 * top
        return float(measure(b.kin, u[None], k)[0][0])

    lo, hi = float(near[0][j]), float(near[1][j])
    xatol = 4 * EPS * max(abs(lo), abs(hi))
    res = minimize_scalar(at, bounds=(lo, hi), method="bounded", options={"xatol": xatol})
    value = at(float(res.x))
    return (value, point(float(res.x))) if value < top else (top, best)


def _faces(
    lo: np.ndarray, hi: np.ndarray, centres: np.ndarray, value: np.ndarray, sp: Space
) -> np.ndarray:
    """On each face of a space of two or more free numbers that boxes touch, the centre of
    the one whose centre measures least, moved onto the face (``INSIDE`` of the space's width
    within it)."""
    s_lo, s_hi = np.array(sp.lo), np.array(sp.hi)
    width = s_hi - s_lo
    free = np.flatnonzero(width > 0)
    if len(free) < 2:  # one free number: its faces are the corners, measured first
        return centres[:0]
    found = []
    for d in free:
        for side, edge, at in ((lo, s_lo, 1.0), (hi, s_hi, -1.0)):
            on = np.flatnonzero(side[:, d] == edge[d])
            if len(on):
                x = centres[on[np.argmin(value[on])]].copy()
                x[d] = edge[d] + at * INSIDE * width[d]
                found.append(x)
    return np.array(found).reshape(-1, len(width))


def _on_face(x: np.ndarray | None, sp: Space) -> np.ndarray | None:
    """The incumbent x where it is on a face of a space of one free number (an optimum a bound
    holds: the corners' probe finds it to 1e-12 of the box), else None."""
    width = np.array(sp.hi) - np.array(sp.lo)
    if x is None or np.count_nonzero(width) != 1:
        return None
    j = int(np.argmax(width > 0))
    return x if min(x[j] - sp.lo[j], sp.hi[j] - x[j]) <= 2 * INSIDE * width[j] else None


def _cut(
    lo: np.ndarray,
    hi: np.ndarray,
    bound: np.ndarray,
    width: np.ndarray,
    parts: int,
    x: np.ndarray | None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every box cut in ``parts`` (``_split``), but the one holding the point x (None: none),
    whose one free side j is cut at x ± its width / ``GRADE``^k, k = 1 … ``GRADES``: parts
    that shrink geometrically towards x. Each part with its box's ``bound``."""
    inside = np.zeros(len(lo), dtype=bool) if x is None else np.all((lo <= x) & (x <= hi), axis=1)
    held = np.flatnonzero(inside)[:1]
    rest = np.ones(len(lo), dtype=bool)
    rest[held] = False
    los, his = _split(lo[rest], hi[rest], width, parts)
    bounds = np.tile(bound[rest], parts)  # part j of box i: row j n + i (``_split``)
    if x is None or not len(held):
        return los, his, bounds
    i, j = int(held[0]), int(np.argmax(width > 0))
    steps = (hi[i, j] - lo[i, j]) * float(GRADE) ** -np.arange(1, GRADES + 1)
    cuts = np.concatenate([[lo[i, j], hi[i, j], x[j]], x[j] - steps, x[j] + steps])
    cuts = np.unique(cuts[(cuts >= lo[i, j]) & (cuts <= hi[i, j])])
    graded_lo, graded_hi = (np.tile(e[i], (len(cuts) - 1, 1)) for e in (lo, hi))
    graded_lo[:, j], graded_hi[:, j] = cuts[:-1], cuts[1:]
    bounds = np.concatenate([bounds, np.full(len(cuts) - 1, bound[i])])
    return np.vstack([los, graded_lo]), np.vstack([his, graded_hi]), bounds


def _split(
    lo: np.ndarray, hi: np.ndarray, width: np.ndarray, parts: int
) -> tuple[np.ndarray, np.ndarray]:
    """Each box cut into ``parts`` equal parts across its widest side (relative to the first
    box's; a side the first box does not span is never cut)."""
    if not len(lo):
        return lo, hi
    side = np.argmax((hi - lo) / np.where(width > 0, width, math.inf), axis=1)
    ix = np.arange(len(lo))
    cuts = lo[ix, side] + (hi[ix, side] - lo[ix, side]) * np.arange(parts + 1)[:, None] / parts
    cuts[-1] = hi[ix, side]
    los, his = np.tile(lo, (parts, 1)), np.tile(hi, (parts, 1))  # part j of box i: row j n + i
    at = (np.arange(parts * len(lo)), np.tile(side, parts))
    los[at], his[at] = cuts[:-1].ravel(), cuts[1:].ravel()
    return los, his
