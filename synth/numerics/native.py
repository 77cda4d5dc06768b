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
    if not path.exists() and not _build(source, path):
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


class Points:
    """A function of (x, p), x a point of ``dim`` numbers and p shared parameters, compiled and
    evaluated at many points through preallocated arrays (``bind``): up to ``small`` points in
    a buffer for their number, more in chunks of ``chunk`` (the last one padded) by the
    function mapped over a chunk and compiled as one loop (CasADi's own map of a compiled
    function calls it point by point, at about 1.6 times the cost). Each thread keeps its own
    (a CasADi function is never shared between threads)."""

    def __init__(self, fn: ca.Function, small: int = 16, chunk: int = 256) -> None:
        self.symbolic, self.fn = fn, native(fn)
        self.small, self.chunk = small, chunk
        self.dim, self.n_params, self.rows = fn.nnz_in(0), fn.nnz_in(1), fn.nnz_out(0)
        self.buffers: dict[int, list[Any]] = {}

    def compiled(self) -> list[ca.Function]:
        """The compiled functions: one point's, and the chunk's (built here if need be)."""
        self._buffer(self.chunk)
        return [self.fn, self.buffers[self.chunk][6]]

    def __call__(self, x: np.ndarray, params: Sequence[float]) -> np.ndarray:
        """The rows at each point of x (n, dim): shape (rows, n). ``params`` is copied into a
        buffer unless it is the sequence that buffer last took (kept, so never another at its
        address)."""
        n = len(x)
        if n <= self.small:
            return self._run(n, x, params).T.copy()  # the buffer is reused by the next call
        out = np.empty((self.rows, n))
        for k in range(0, n, self.chunk):
            part = x[k : k + self.chunk]
            if len(part) < self.chunk:  # padded with its first point
                part = np.concatenate([part, np.repeat(part[:1], self.chunk - len(part), 0)])
            out[:, k : k + self.chunk] = self._run(self.chunk, part, params)[: n - k].T
        return out

    def one(self, point: Sequence[float], params: Sequence[float]) -> list[float]:
        """The rows at one point, a list (the quickest way to a few numbers)."""
        return self._run(1, point, params)[0].tolist()  # type: ignore[no-any-return]

    def _run(
        self, width: int, x: np.ndarray | Sequence[float], params: Sequence[float]
    ) -> np.ndarray:
        b = self.buffers.get(width) or self._buffer(width)
        xs, ps, res, run = b[:4]
        xs[:] = x
        if params is not b[5]:
            ps[:] = params
            b[5] = params
        run()
        return cast(np.ndarray, res)

    def _buffer(self, width: int) -> list[Any]:
        """The arrays for ``width`` points, bound to the function mapped over them, and the
        parameters they last took (none yet)."""
        if width not in self.buffers:
            xs, ps = np.zeros((width, self.dim)), np.zeros(self.n_params)  # x: (dim, width)
            res = np.zeros((width, self.rows))
            if width == self.chunk:
                fn = native(self.symbolic.map(width, [False, True], [False]))
            else:
                fn = self.fn.map(width, [False, True], [False])
            run, buf = bind(fn, [xs, ps], res)
            self.buffers[width] = [xs, ps, res, run, buf, None, fn]
        return self.buffers[width]


def _build(source: str, path: Path) -> bool:
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
                subprocess.run([cast(str, _compiler()), *FLAGS, "-o", str(so), str(c)], check=True,
                               capture_output=True, timeout=BUILD_SECONDS)  # fmt: skip
                os.replace(so, path)  # whole or not at all, for other processes too
            return True
        except (OSError, subprocess.SubprocessError):
            _failed.add(path.name)
            return False


@functools.cache
def _compiler() -> str | None:
    return shutil.which(os.environ.get("CC", "cc"))
