"""Every structure a request can ask the library to build, counted, and built ahead of it.

A structure is what a request's work builds once and then keeps (per thread: CasADi functions
are never shared between threads):

- the compiled analysis (``analysis.model.compiled``): per type, structural variant and kind,
  with its sensitivities and root polish, and the loads' equations and torque where the type
  has a frame (``analysis.forces.compiled``); native libraries in the disk cache
  (``numerics.native``), loaded per thread;
- IPOPT's solvers (``solve.built``): per type, variant, free set (the variant's parameters a
  request leaves free: it may fix any of the others) and objective (the two the search
  solves, the two diagnostics);
- the motion search's formulation and its compiled constraints (``formulation.formulation``,
  ``screen``): per type, variant and free set;
- the certified search's enclosures (``certify``): per type with a space, variant and form
  of its spaces (nothing fixed, one part fixed), the peak torque's with them; a four-bar's
  coordinates on its construction (``chart``), per variant.

``compile_all`` puts every native library in the disk cache (an image's build step, ``make``'s
install step; ``python -m synth.synthesis.warm``). ``warm`` builds in the calling thread the
compiled analysis of every type and variant (~25 ms each, hundreds of ms at a request's first
use) and what a searched objective's request with nothing fixed builds (``searched``: the
motion search's structures for each variant's full free set: one per type and variant, ~40 ms
and ~1 MB in all), so a service does it before it reports ready (~1 s a thread): a first
searched request then builds only slots of a few widths (~1–10 ms). Such a request builds no
solver: every variant it leaves open is answered exactly by its type's reduced solver. The
solvers, and the motion search's structures for other free sets (parts fixed), are built at
first use: ~5 ms each, a request's deadline looked at around each, where all of them would take
~7 s a thread, and from a disk cache 2.5 s and 180 MB (docs/benchmarks.md, "Start-up").
"""

from __future__ import annotations

import importlib
import itertools
import os
from collections.abc import Collection, Iterable, Iterator
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from multiprocessing import get_context

from ..analysis import forces, model
from ..mechanisms import Mechanism, all_types, get, rod
from ..mechanisms.fourbar.construction import construction
from ..numerics.native import WIDTHS, cache
from . import certify, chart, screen
from .formulation import DIAGNOSTICS, SOLVED, formulation, kept_by, relevant

OBJECTIVES = (*SOLVED, *DIAGNOSTICS)  # those a request's search and diagnosis solve by IPOPT
# what the motion search and the sweep import on first use (~0.3 s)
IMPORTS = ("scipy.linalg", "scipy.optimize")


@dataclass(frozen=True)
class Structure:
    """One variant of a type with the parameters a request leaves free (the rest fixed)."""

    type: str
    variant: frozenset[str]
    free: tuple[str, ...]


def structures() -> Iterator[Structure]:
    """Every (type, variant, free set) a request can reach: a nonempty subset of the variant's
    parameters (``formulation.relevant``), in their order. Each has a solver per objective
    (``OBJECTIVES``) and a motion search's formulation."""
    for mtype in all_types():
        m = get(mtype)
        for variant in variants(m):
            names = relevant(m, variant)
            for k in range(1, len(names) + 1):
                for free in itertools.combinations(names, k):
                    yield Structure(mtype, variant, free)


def counts() -> dict[str, int]:
    """How many structures of each kind there are (every registered type's)."""
    types = [get(t) for t in all_types()]
    analyses = sum(len(variants(m)) * (len(model.KINDS) + (m.frame is not None)) for m in types)
    free = sum(1 for _ in structures())
    return {"analyses": analyses, "solvers": free * len(OBJECTIVES), "motion_searches": free}


def warm(kinds: Collection[str] = model.KINDS, searches: bool = True) -> None:
    """Build in this thread the compiled analysis of every type and variant (``kinds`` of it;
    with every kind, the loads' too), the four-bar construction and the connecting rod; with
    ``searches``, import what the searches import on first use and build what a searched
    request with nothing fixed reaches (``searched``)."""
    if searches:
        for name in IMPORTS:
            importlib.import_module(name)
    for m in (get(t) for t in all_types()):
        for variant in variants(m):
            if set(model.KINDS) <= set(kinds):
                model.compiled(m, variant)
                forces.compiled(m, variant)
            else:
                for kind in kinds:
                    model.model(m, variant, kind)
            if searches:
                searched(m, variant)
    construction()
    rod.compiled()


def searched(m: Mechanism, variant: frozenset[str]) -> None:
    """Build in this thread the motion search's formulation of a variant with every parameter
    free (a request that fixes none: the searched objectives' default), its compiled
    constraints and their slots of every width (``native.WIDTHS``). Besides these such a request
    uses the analysis (``warm``'s) and no IPOPT solver: the exact solvers answer every variant
    it leaves open."""
    free = relevant(m, variant)
    if m.facts is None or not free:  # no motion search (``motion.motion``), or nothing to vary
        return
    form = formulation(m, variant, free)
    constraints = screen.compiled_constraints(form, kept_by(m, variant, free))
    for w in WIDTHS:
        constraints[w]
    certify.prepared(m, variant)
    if chart.applies(m, variant, free):  # a four-bar's construction
        for scale in (False, True):
            chart.function(m, variant, free, scale)


def variants(m: Mechanism) -> list[frozenset[str]]:
    """Every structural variant of a type: each set of its optional parts left out."""
    optional = [q.name for q in m.parameters if q.zero_means]
    return [
        frozenset(parts)
        for k in range(len(optional) + 1)
        for parts in itertools.combinations(optional, k)
    ]


def compile_all(part: int = 0, parts: int = 1) -> int:
    """Every native library a request can load, built into the disk cache: the analysis's
    (every type's, variant's and kind's, the loads', the reduced solvers' construction and
    rod) and every structure's motion-search constraints. Of ``parts`` processes building at
    once, the first builds the analysis's and the others share the constraints; one builds
    all. Raises where a library cannot be built; the number of the constraints' built."""
    fns = []
    if part == 0:
        fns += [
            fn
            for m in map(get, all_types())
            for v in variants(m)
            for fn in (*model.compiled(m, v), *forces.compiled(m, v))
        ]
        c = construction()  # its points, its chunks' loop and its local model
        fns += [*c.points.mapped.compiled(), c.local.fn, rod.compiled().fn]
    share: Iterable[Structure] = structures()
    if parts > 1:
        share = itertools.islice(share, part - 1, None, parts - 1) if part else ()
    n = 0
    for s in share:
        fns.append(screen.compiled_constraints(formulation(get(s.type), s.variant, s.free), s).fn)
        n += 1
    for fn in fns:
        if fn.class_name() != "External":
            raise RuntimeError(f"{fn.name()}: no C compiler or cache (synth.numerics.native)")
    if part == 0:  # the certified search's enclosures (synth.numerics.compiled_interval)
        for m in map(get, all_types()):
            for v in variants(m):
                for b in certify.prepared(m, v):
                    torque = b.torque.libraries() if m.frame is not None else []
                    if None in (*b.kin.libraries(), b.rows.library, *torque):
                        raise RuntimeError(f"{m.type}: the certified search's enclosures not built")
    return n


def main(processes: int | None = None) -> None:
    """``compile_all`` in as many processes as the cores (``processes``: at least 2), each
    its share."""
    n = max(processes or len(os.sched_getaffinity(0)), 2)
    with ProcessPoolExecutor(n, mp_context=get_context("spawn")) as pool:
        built = sum(pool.map(compile_all, range(n), [n] * n))
    print(f"the analysis's libraries and {built} of the motion search's in {cache()}")


if __name__ == "__main__":
    main()
