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
from pathlib import Path

import casadi as ca

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
    key = hashlib.sha256("\0".join((ca.__version__, *FLAGS, source)).encode()).hexdigest()
    path = cache() / f"{fn.name()}_{key[:20]}.so"
    if not path.exists() and not _build(source, path):
        return fn
    try:
        return ca.external(fn.name(), str(path))
    except RuntimeError:  # a library that does not load here (another machine's, truncated)
        return fn


def bind(fn: ca.Function, args: list, out) -> tuple:
    """``fn`` (mapped: each argument and result an array whose C order is the function's
    column-major layout) bound to preallocated arrays: calling the returned ``run`` reads
    ``args`` and writes ``out`` in place, with none of an ordinary call's conversions (~40 µs,
    more than a few points' evaluation). The returned buffer holds the bindings: keep it with
    ``run``."""
    buf, run = fn.buffer()
    for i, a in enumerate(args):
        buf.set_arg(i, memoryview(a))
    buf.set_res(0, memoryview(out))
    return run, buf


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
                subprocess.run([_compiler(), *FLAGS, "-o", str(so), str(c)], check=True,
                               capture_output=True, timeout=BUILD_SECONDS)  # fmt: skip
                os.replace(so, path)  # whole or not at all, for other processes too
            return True
        except (OSError, subprocess.SubprocessError):
            _failed.add(path.name)
            return False


@functools.cache
def _compiler() -> str | None:
    return shutil.which(os.environ.get("CC", "cc"))
