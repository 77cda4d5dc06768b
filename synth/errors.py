"""Domain errors: misuse and designs that cannot run. The API places them in the request and
answers a 422 (api.routers.common, api.main).

Every error carries ``loc`` (the argument it concerns, as a Python caller names it: a parameter,
or a path such as ``("mechanisms", 0, "bounds", "crank")``) and a message that states the
condition with its numbers, so a caller can fix the input without reading the code.
"""

from __future__ import annotations

from typing import Any


class SynthError(ValueError):
    """Base of every error this library raises on purpose."""

    def __init__(
        self, msg: str, loc: tuple[str | int, ...] = (), kind: str = "value_error"
    ) -> None:
        super().__init__(msg)
        self.msg = msg
        self.loc = tuple(loc)
        self.kind = kind

    def __reduce__(self) -> tuple[Any, ...]:  # survive pickling (a process pool sends errors back)
        return (_restore, (type(self), self.__dict__))


def _restore(cls: type[SynthError], state: dict[str, Any]) -> SynthError:
    err = cls.__new__(cls)
    Exception.__init__(err, state["msg"])
    err.__dict__.update(state)
    return err


class UnknownMechanism(SynthError):
    """A mechanism type that is not in the registry."""

    def __init__(self, name: str, known: tuple[str, ...]) -> None:
        super().__init__(
            f"unknown mechanism type {name!r}; known types: {', '.join(known)}",
            ("type",),
            "unknown_mechanism",
        )
        self.known = known


class InvalidParameters(SynthError):
    """Parameter names or values that are malformed (unknown, missing, non-finite, non-positive)."""

    def __init__(self, msg: str, loc: tuple[str | int, ...]) -> None:
        super().__init__(msg, loc, "invalid_parameters")


class InvalidDesign(SynthError):
    """A well-formed design that cannot run: it cannot assemble, or the crank cannot turn fully.

    ``loc`` lists every parameter the failed condition involves."""

    def __init__(self, msg: str, loc: tuple[str, ...], condition: str) -> None:
        super().__init__(msg, loc, "invalid_design")
        self.condition = condition


class Unreachable(Exception):
    """Raised by a type's ``reduced`` solver when the targets and fixed parts admit no design."""

    def __init__(self, code: str, reason: str) -> None:
        super().__init__(reason)
        self.code, self.reason = code, reason
