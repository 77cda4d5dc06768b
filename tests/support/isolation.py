"""A check run in a fresh interpreter of its own, for one that registers a type: the registry
has no removal, so the type stays in that process and the rest of the suite never sees it."""

import multiprocessing
import traceback

import pytest


def _run(check, pipe) -> None:
    try:
        check()
    except BaseException:
        pipe.send(traceback.format_exc())
    else:
        pipe.send(None)


def in_a_process_of_its_own(check, timeout: float = 300.0) -> None:
    """Call ``check`` (a module-level function) in a spawned process; fail with its traceback
    if it fails there."""
    ctx = multiprocessing.get_context("spawn")
    receive, send = ctx.Pipe(duplex=False)
    p = ctx.Process(target=_run, args=(check, send))
    p.start()
    try:
        failure = receive.recv() if receive.poll(timeout) else f"no answer within {timeout} s"
    except EOFError:
        failure = "the process ended without an answer"
    p.join(10)
    if p.is_alive():
        p.kill()
        p.join()
    if failure is not None:
        pytest.fail(failure, pytrace=False)
