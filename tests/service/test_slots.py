"""The engine's solver slots (``api.engine.Slots``): earliest start-by first, a refusal at the
start-by time, and no slot lost to a waiter that gave up or was cancelled."""

from __future__ import annotations

import asyncio
import time

import pytest

from api.config import Settings
from api.engine import Busy, Engine, Slots
from synth.synthesis.driver import SynthesisRequest

pytestmark = pytest.mark.serial  # timing-sensitive: alone, not beside other tests (make test)


def run(coro):
    return asyncio.run(coro)


def test_a_freed_slot_goes_to_the_earliest_start_by_not_the_first_to_come():
    async def scenario() -> list[str]:
        slots, order = Slots(1), []
        now = time.monotonic()
        holder = await _take(slots, now, now + 10)

        async def waiter(name: str, start_by: float) -> None:
            async with slots.held(now, start_by):
                order.append(name)
                await asyncio.sleep(0.01)

        # arriving in this order, by start-by: long, short, middle
        tasks = [
            asyncio.create_task(waiter(n, now + s))
            for n, s in (("long", 9.0), ("short", 5.0), ("middle", 7.0))
        ]
        await asyncio.sleep(0.05)
        holder.set()
        await asyncio.gather(*tasks)
        return order

    assert run(scenario()) == ["short", "middle", "long"]


def test_ties_are_first_come_first_served():
    async def scenario() -> list[int]:
        slots, order = Slots(1), []
        now = time.monotonic()
        holder = await _take(slots, now, now + 10)

        async def waiter(k: int) -> None:
            async with slots.held(now, now + 5):
                order.append(k)

        tasks = []
        for k in range(5):
            tasks.append(asyncio.create_task(waiter(k)))
            await asyncio.sleep(0)  # each queued before the next
        await asyncio.sleep(0.02)
        holder.set()
        await asyncio.gather(*tasks)
        return order

    assert run(scenario()) == [0, 1, 2, 3, 4]


def test_a_waiter_is_refused_at_its_start_by_time_and_its_place_is_not_kept():
    async def scenario():
        slots = Slots(1)
        now = time.monotonic()
        holder = await _take(slots, now, now + 10)
        with pytest.raises(Busy) as refused:
            async with slots.held(now - 0.2, now + 0.05):  # arrived 0.2 s ago
                pass
        waited = time.monotonic() - now
        holder.set()
        await asyncio.sleep(0.01)
        return refused.value, waited, slots.free, len(slots.waiting)

    busy, waited, free, waiting = run(scenario())
    assert waited >= 0.05  # not before its start-by time
    assert "since the request arrived" in str(busy) and busy.retry_after_s >= 1
    assert (free, waiting) == (1, 0)  # the holder's slot came back: nobody else wanted it


def test_a_cancelled_waiter_passes_on_the_slot_it_was_handed():
    """Handed a slot and cancelled before it ran (a client gone): the next waiter gets it."""

    async def scenario():
        slots = Slots(1)
        now = time.monotonic()
        holder = await _take(slots, now, now + 10)
        first = asyncio.create_task(_enter(slots, now, now + 5))
        second = asyncio.create_task(_enter(slots, now, now + 6))
        await asyncio.sleep(0.01)
        holder.set()  # the slot goes to `first`...
        await asyncio.sleep(0)
        first.cancel()  # ...which is cancelled before it resumes
        with pytest.raises(asyncio.CancelledError):
            await first
        got = await asyncio.wait_for(second, 1.0)
        await asyncio.sleep(0.01)
        return got, slots.free

    got, free = run(scenario())
    assert got == "in" and free == 1


def test_a_free_slot_is_taken_at_once_and_the_count_holds_under_churn():
    async def scenario():
        slots = Slots(2)
        now = time.monotonic()
        results = await asyncio.gather(
            *(_enter(slots, now, now + (0.02 if k % 3 else 5.0), hold=0.005) for k in range(60)),
            return_exceptions=True,
        )
        return results, slots.free, len([w for w in slots.waiting if not w[2].done()])

    results, free, live = run(scenario())
    assert free == 2 and live == 0
    assert all(r == "in" or isinstance(r, Busy) for r in results)
    assert all(r == "in" for k, r in enumerate(results) if k % 3 == 0)  # the patient ones


def test_a_request_that_waited_past_its_start_by_before_the_engine_is_refused():
    """A short synthesis that has waited behind others in the loop, before it reached the
    engine, for longer than a slot's waiter may (half its budget) gets ``Busy``, as that waiter
    would; within it, it runs."""
    engine = Engine(Settings(executor="thread", workers=1))
    request = {"time_ratio": 1.5, "stroke": 1.0, "time_budget_ms": 1000.0}
    try:
        now = time.monotonic()
        late = engine.run("synthesize", SynthesisRequest(**request), now - 0.6)
        with pytest.raises(Busy):
            run(late)
        assert run(engine.run("synthesize", SynthesisRequest(**request), now - 0.4)).candidates
    finally:
        engine.close()


async def _take(slots: Slots, arrival: float, start_by: float) -> asyncio.Event:
    """Hold one slot until the returned event is set."""
    release, taken = asyncio.Event(), asyncio.Event()

    async def hold() -> None:
        async with slots.held(arrival, start_by):
            taken.set()
            await release.wait()

    asyncio.get_running_loop().create_task(hold())
    await taken.wait()
    return release


async def _enter(slots: Slots, arrival: float, start_by: float, hold: float = 0.0) -> str:
    async with slots.held(arrival, start_by):
        await asyncio.sleep(hold)
        return "in"
