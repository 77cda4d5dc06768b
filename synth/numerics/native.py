"""The analysis's CasADi functions compiled to machine code: CasADi generates their C code, the
system's C compiler builds it once per machine into a cache, and each thread loads its own
copy (a CasADi function is never shared between threads).

The compiled code does the same floating-point operations in the same order as CasADi's
virtual machine (contraction into fused multiply-adds is switched off), so its results are the
same to the bit; it is 2–5× faster. Without a C compiler, with ``SYNTH_NATIVE=0``, or where the
cache cannot be written, the virtual machine runs.
"""

from __future__ import annotations

import functools
import hashlib
import os
import shutil
import subprocess
import tempfile
import threading
from collections.abc import Sequence
from pathlib import Path
from typing import Any, cast

import casadi as ca
import numpy as np

FLAGS = ("-O2", "-ffp-contract=off", "-fPIC", "-shared")
BUILD_SECONDS = 120  # the most one compilation may take
_lock = threading.Lock()  # one build at a time in a process (files: atomic renames)
_failed: set[str] = set()  # libraries that could not be built here: not tried again
SMALL = 16  # up to this many points in one slot, padded to a power of two (``widths``)
WIDEST = 64  # the widest slot; between, powers of two (wider was no faster: 64–256 measured)
WIDTHS = tuple(1 << k for k in range(WIDEST.bit_length()))  # every slot's: 1, 2, 4 … WIDEST


def cache() -> Path:
    """Where the libraries are kept: ``SYNTH_CACHE``, else the user's cache folder."""
    if os.environ.get("SYNTH_CACHE"):
        return Path(os.environ["SYNTH_CACHE"])
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "synth"


def native(fn: ca.Function) -> ca.Function:
    """``fn`` compiled (from the cache, built there first if need be), else ``fn`` itself."""
    if os.environ.get("SYNTH_NATIVE", "1") == "0":
        return fn
    gen = ca.CodeGenerator(f"{fn.name()}.c", {"with_header": False})
    gen.add(fn)
    source = gen.dump()
    key = hashlib.sha256(
        "\0".join((cast(Any, ca).__version__, *FLAGS, source)).encode()
    ).hexdigest()
    path = cache() / f"{fn.name()}_{key[:20]}.so"
    if not path.exists() and not build_library(source, path):
        return fn
    try:
        return ca.external(fn.name(), str(path))
    except RuntimeError:  # a library that does not load here (another machine's, truncated)
        return fn


def bind(fn: ca.Function, args: list[np.ndarray], out: np.ndarray) -> tuple[Any, Any]:
    """``fn`` (mapped: each argument and result an array whose C order is the function's
    column-major layout) bound to preallocated arrays: calling the returned ``run`` reads
    ``args`` and writes ``out`` in place, with none of an ordinary call's conversions (~40 µs,
    more than a few points' evaluation). The returned buffer holds the bindings: keep it with
    ``run``."""
    buf, run = cast("tuple[Any, Any]", fn.buffer())
    for i, a in enumerate(args):
        buf.set_arg(i, memoryview(cast(Any, a)))
    buf.set_res(0, memoryview(cast(Any, out)))
    return run, buf


class Slot:
    """One number of points' arrays, bound to the function mapped over them: fill ``args``,
    ``run()``, read ``out`` (shape (points, rows), column-major (rows, points); the next run
    overwrites it). ``last``: what a caller last copied into a shared argument (kept, so never
    another object at its address)."""

    def __init__(self, mapped: ca.Function, fn: ca.Function, width: int, shared: Sequence[bool]):
        self.fn = mapped
        # a shared argument (n,), another (points, n)
        self.args = [
            np.zeros(fn.nnz_in(i) if one else (width, fn.nnz_in(i))) for i, one in enumerate(shared)
        ]
        self.out = np.zeros((width, fn.nnz_out(0)))
        self.run, self._bindings = bind(mapped, self.args, self.out)
        self.last: Any = None


class Mapped:
    """``fn`` compiled and evaluated at many points in one call: ``mapped(*args)``, the
    arguments ``shared`` by every point given once. The points go through a ``Slot`` per
    width, of a few fixed widths only (``widths``): what a thread keeps is bounded whatever
    numbers of points its callers ask for (a slot holds ~2 × its outputs per point). At the
    ``looped`` widths the map itself is compiled, as one loop (CasADi's map of a compiled
    function calls it point by point, at about 1.6 times the cost; a library per width, so
    only for a few). Each thread keeps its own (a CasADi function is never shared between
    threads)."""

    def __init__(
        self,
        fn: ca.Function,
        shared: Sequence[bool],
        looped: Sequence[int] = (),
        compiled: ca.Function | None = None,
    ) -> None:
        self.symbolic, self.fn = fn, compiled or native(fn)  # ``compiled``: fn, already built
        self.shared, self.looped = list(shared), tuple(looped)
        self.own = self.shared.index(False)  # an argument with a row per point
        self.rows = self.fn.nnz_out(0)
        self.slots: dict[int, Slot] = {}

    def __getitem__(self, width: int) -> Slot:
        slot = self.slots.get(width)
        if slot is None:
            source = self.symbolic if width in self.looped else self.fn
            mapped = source.map(width, self.shared, [False])
            if width in self.looped:
                mapped = native(mapped)
            slot = self.slots[width] = Slot(mapped, self.fn, width, self.shared)
        return slot

    def __call__(self, *args: np.ndarray) -> np.ndarray:
        """The function at n points: a shared argument's numbers (k,), any other's (n, k), a
        row a point; shape (rows, n). Every point's numbers are its own call's, to the bit."""
        n = len(args[self.own])
        if 0 < n <= SMALL:  # one slot: the common few points, with the least overhead
            slot = self._filled(1 << (n - 1).bit_length(), args, 0, n)
            slot.run()
            return slot.out[:n].T.copy()
        out = np.empty((self.rows, n))
        k = 0
        for w in widths(n):
            m = min(w, n - k)
            slot = self._filled(w, args, k, m)
            slot.run()
            out[:, k : k + m] = slot.out[:m].T
            k += m
        return out

    def _filled(self, width: int, args: Sequence[np.ndarray], k: int, m: int) -> Slot:
        """The slot of ``width`` holding points k … k + m − 1 of ``args`` (the rest padding:
        copies of point k) and the shared arguments."""
        slot = self[width]
        for a, into, one in zip(args, slot.args, self.shared, strict=True):
            if one:
                into[:] = a
            else:
                into[:m], into[m:] = a[k : k + m], a[k]
        return slot

    def compiled(self) -> list[ca.Function]:
        """The compiled functions: one point's, and each looped map (built here if need be)."""
        return [self.fn, *(self[w].fn for w in self.looped)]


def widths(n: int) -> list[int]:
    """n points as the widths of the slots that take them: ``WIDEST`` at a time, then powers
    of two, the last ``SMALL`` or fewer in one slot of the next power of two (padded: a few
    points are what a Newton step asks for, in one call; the fewest widths, so the fewest
    slots a thread keeps)."""
    out = []
    while n > SMALL:
        out.append(min(WIDEST, 1 << (n.bit_length() - 1)))
        n -= out[-1]
    return [*out, 1 << (n - 1).bit_length()] if n else out


class Points:
    """A function of (x, p), x a point of a few numbers and p shared parameters, at many
    points (``Mapped``): up to ``small`` points in a slot for their number, more in chunks of
    ``chunk`` through the looped map."""

    def __init__(self, fn: ca.Function, small: int = SMALL, chunk: int = 256) -> None:
        self.mapped = Mapped(fn, (False, True), looped=(chunk,))
        self.fn, self.small, self.chunk, self.rows = self.mapped.fn, small, chunk, fn.nnz_out(0)

    def __call__(self, columns: Sequence[np.ndarray], params: Sequence[float]) -> np.ndarray:
        """The rows at n points given by their coordinates (``columns``: ``dim`` arrays of n):
        shape (rows, n)."""
        n = len(columns[0])
        if n <= self.small:
            slot = self._fill(n, params)
            for j, c in enumerate(columns):
                slot.args[0][:, j] = c
            slot.run()
            return slot.out.T.copy()  # the slot is reused by the next call
        out = np.empty((self.rows, n))
        slot = self._fill(self.chunk, params)
        xs = slot.args[0]
        for k in range(0, n, self.chunk):
            m = min(self.chunk, n - k)
            for j, c in enumerate(columns):
                xs[:m, j] = c[k : k + m]
            xs[m:] = xs[0]  # a short last chunk padded with its first point
            slot.run()
            out[:, k : k + m] = slot.out[:m].T
        return out

    def one(self, point: Sequence[float], params: Sequence[float]) -> list[float]:
        """The rows at one point, a list (the quickest way to a few numbers)."""
        slot = self._fill(1, params)
        slot.args[0][0] = point
        slot.run()
        return slot.out[0].tolist()  # type: ignore[no-any-return]

    def _fill(self, width: int, params: Sequence[float]) -> Slot:
        """The slot for ``width`` points, holding ``params`` (copied unless it is the sequence
        the slot last took)."""
        slot = self.mapped[width]
        if params is not slot.last:
            slot.args[1][:] = params
            slot.last = params
        return slot


def build_library(source: str, path: Path) -> bool:
    """C ``source`` built into the library at ``path`` (whole or not at all), unless it is
    there; whether it is now."""
    with _lock:
        if path.exists():
            return True
        if path.name in _failed or _compiler() is None:
            return False
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            with tempfile.TemporaryDirectory(dir=path.parent) as tmp:
                c, so = Path(tmp) / "f.c", Path(tmp) / "f.so"
                c.write_text(source)
                subprocess.run(
                    [cast(str, _compiler()), *FLAGS, "-o", str(so), str(c)],
                    check=True,
                    capture_output=True,
                    timeout=BUILD_SECONDS,
                )
                os.replace(so, path)  # whole or not at all, for other processes too
            return True
        except (OSError, subprocess.SubprocessError):
            _failed.add(path.name)
            return False


@functools.cache
def _compiler() -> str | None:
    return shutil.which(os.environ.get("CC", "cc"))
