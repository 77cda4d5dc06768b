"""Compiled functions found in the native cache by what defines them, before they are built.

``native.native`` finds a function's library by its generated code, so it needs the function
first: its expression graph, merged common subexpressions (tens of ms for the analysis's
unrolled root polish) and its code. Here the key is what defines the function: the functions
and numbers it is made of (serialized) and the code that makes them into it (its bytecode and
constants, as it runs, not its source file), with CasADi's version. On a hit only the library
loads (~1 ms): a service's start-up pays that instead of the build.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Callable, Sequence
from types import CodeType
from typing import Any, cast

import casadi as ca

from .native import FLAGS, build_library, cache


def compiled(
    name: str, parts: Sequence[ca.Function | int | float], build: Callable[..., ca.Function]
) -> ca.Function:
    """``build(name, *parts)`` (a function named ``name``, of CasADi maths and ``parts``
    alone) compiled, loaded from the native cache (built there first if need be), else the
    function itself (``native.native``'s rules)."""
    if os.environ.get("SYNTH_NATIVE", "1") == "0":
        return build(name, *parts)
    made = [p.serialize() if isinstance(p, ca.Function) else repr(p) for p in parts]
    text = (cast(Any, ca).__version__, *FLAGS, name, *made, _code(build.__code__))
    key = hashlib.sha256("\0".join(text).encode()).hexdigest()
    path = cache() / f"{name}_d{key[:20]}.so"
    if path.exists():
        try:
            return ca.external(name, str(path))
        except RuntimeError:  # a library that does not load here (another machine's, truncated)
            pass
    fn = build(name, *parts)
    gen = ca.CodeGenerator(f"{name}.c", {"with_header": False})
    gen.add(fn)
    if not build_library(gen.dump(), path):
        return fn
    try:
        return ca.external(name, str(path))
    except RuntimeError:
        return fn


def _code(code: CodeType) -> str:
    """What a function does, as text: its bytecode, the names it uses and its constants (a
    nested function's alike); not where it is written."""
    consts = [_code(c) if isinstance(c, CodeType) else repr(c) for c in code.co_consts]
    return repr((code.co_code, code.co_names, code.co_varnames, consts))
