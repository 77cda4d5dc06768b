"""Error replies' entries: always valid JSON, of a bounded size, whatever the request held.

JSON bodies may hold ``NaN``, ``Infinity``, ``1e309`` (an infinite float) and ``\\ud800`` (a
string no UTF-8 encoder takes). The models refuse them, naming the field; a 422 that echoed
such input back would fail to encode (a 500), so every value an error carries is made safe here.
"""

from __future__ import annotations

import itertools
import json
import math
from collections.abc import Callable, Collection, Sequence
from typing import Any

# an error reply is small whatever the request held (tests/service/test_hostile.py: ≤ 16 KB)
MAX_ECHO_CHARS = 200  # an error echoes its input only when its JSON is this short
MAX_TEXT_CHARS = 300  # a longer message or value is cut in the middle (``clip``)
MAX_NAME_CHARS = 100  # so is a longer name in a loc
MAX_ITEMS, MAX_DEPTH = 10, 3  # of a list or dict an error carries (its loc, ctx or input)
MAX_ERRORS, MAX_DETAIL_CHARS = 24, 12_000  # a reply lists at most these many, this large


def safe(x: Any, depth: int = 0) -> Any:
    """``x`` as JSON can carry it, in bounded size whatever it is: a non-finite float as its
    name ("nan", "inf"), a string with U+FFFD for its lone surrogates and cut (``clip``) past
    ``MAX_TEXT_CHARS``, a huge integer as such a string, at most ``MAX_ITEMS`` items of a list
    or dict and ``MAX_DEPTH`` levels of them (no recursion deeper than that, however deep the
    input), anything else unknown as its str()."""
    if isinstance(x, bool) or x is None:
        return x
    if isinstance(x, int):
        return x if abs(x) < 10**15 else clip(str(x))
    if isinstance(x, float):
        return x if math.isfinite(x) else repr(x)
    if isinstance(x, str):
        return clip(x)
    if isinstance(x, dict | list | tuple):
        if depth >= MAX_DEPTH:
            return "…"
        items = itertools.islice(x.items() if isinstance(x, dict) else x, MAX_ITEMS)
        more = [f"… {len(x) - MAX_ITEMS} more"] if len(x) > MAX_ITEMS else []
        if isinstance(x, dict):
            kept = {safe(str(k)): safe(v, depth + 1) for k, v in items}
            return kept | ({"…": more[0]} if more else {})
        return [safe(v, depth + 1) for v in items] + more
    return safe(str(x))


def clip(s: str, limit: int = MAX_TEXT_CHARS) -> str:
    """``s`` with U+FFFD for its lone surrogates; past ``limit``, its head and tail around a
    note of how much was cut (a message's end often says what is allowed)."""
    if _surrogates(s):
        s = s.encode("utf-16", "surrogatepass").decode("utf-16", "replace")
    if len(s) <= limit:
        return s
    head, tail = limit * 2 // 3, limit // 3
    return f"{s[:head]}…[{len(s) - head - tail} characters cut]…{s[-tail:]}"


def _surrogates(s: str) -> bool:
    try:
        s.encode("utf-8")
    except UnicodeEncodeError:
        return True
    return False


def error_item(loc: Sequence[Any], msg: str, kind: str, **more: Any) -> dict[str, Any]:
    """One entry of an error's detail, safe to encode and bounded (``safe``, ``clip``); what
    ``more`` adds (an ``input``, a ``ctx``) is kept only when short."""
    where = [k if isinstance(k, int) else clip(str(k), MAX_NAME_CHARS) for k in loc]
    if len(where) > MAX_ITEMS:
        where = [*where[: MAX_ITEMS - 1], "…"]
    item = {"loc": where, "msg": safe(msg), "type": safe(kind)}
    for k, v in more.items():  # input, ctx: only when short
        shown = safe(v)
        if _size(shown) <= MAX_ECHO_CHARS:
            item[k] = shown
    return item


def capped(items: Collection[Any], item: Callable[[Any], dict[str, Any]]) -> list[dict[str, Any]]:
    """An error reply's detail: ``item`` of each of ``items``, at most ``MAX_ERRORS`` of them
    and ``MAX_DETAIL_CHARS`` in all, then one that says how many more there were."""
    kept: list[dict[str, Any]] = []
    size = 0
    for x in items:
        entry = item(x)
        size += _size(entry)
        if len(kept) == MAX_ERRORS or size > MAX_DETAIL_CHARS:
            break
        kept.append(entry)
    if len(kept) < len(items):
        more = len(items) - len(kept)
        kept.append(
            error_item(
                [],
                f"{more} more errors not listed (a reply lists at most {MAX_ERRORS})",
                "too_many_errors",
            )
        )
    return kept


def _size(x: Any) -> int:
    return len(json.dumps(x, ensure_ascii=False))


# pydantic's bound errors: the context key holding the bound, and its sign
BOUNDS = {
    "greater_than_equal": ("ge", "≥"),
    "greater_than": ("gt", ">"),
    "less_than_equal": ("le", "≤"),
    "less_than": ("lt", "<"),
}
NUMBERS = {
    "float_type",
    "float_parsing",
    "int_type",
    "int_parsing",
    "finite_number",
    "int_from_float",
}


def worded(e: dict[str, Any]) -> str:
    """A schema's refusal worded as the library words its own: the field, the rule with its
    numbers, and what was given ("stroke must be ≥ 1e-09, got -250"), not pydantic's
    "Input should be greater than or equal to 0.000000001"."""
    loc, kind, ctx = e.get("loc", ()), e.get("type", ""), e.get("ctx") or {}
    names = [str(k) for k in loc if isinstance(k, str) and k != "body"]
    field = names[-1] if names else "the body"
    if loc and isinstance(loc[-1], int):  # an item of a list
        field += f"[{loc[-1]}]"
    got = f", got {e['input']!r}" if "input" in e and _size(safe(e["input"])) <= 60 else ""
    if kind in BOUNDS and BOUNDS[kind][0] in ctx:
        key, sign = BOUNDS[kind]
        return f"{field} must be {sign} {ctx[key]:g}{got}"
    if kind == "missing":
        return f"{field} is required"
    if kind == "extra_forbidden":
        return f"{field}: no such field here"
    if kind == "literal_error" and "expected" in ctx:
        return f"{field} must be {ctx['expected']}{got}"
    if kind in NUMBERS:
        return f"{field} must be a finite number{got}"
    msg = str(e.get("msg", ""))
    return f"{field}: {msg[:1].lower()}{msg[1:]}"
