"""GET /v1/atlas: the design atlas the service ships (``make atlas``; ``synth.atlas``)."""

import functools
import json
from pathlib import Path

from fastapi import APIRouter

from ..schemas import AtlasInfo

router = APIRouter(prefix="/v1/atlas", tags=["atlas"])
SHIPPED = Path(__file__).resolve().parent.parent / "atlas.json"


@functools.cache
def shipped() -> AtlasInfo:
    return AtlasInfo.model_validate(json.loads(SHIPPED.read_text()))


@router.get("", response_model=AtlasInfo)
async def get_atlas() -> AtlasInfo:
    """Per quick-return type, the best minimum transmission angle any design reaches at each
    time ratio of a grid (everything free within the default bounds; each a verified
    synthesis, certified where an exact solver found it), and the time-ratio range each type
    reaches at each of a few bounds, its ends bisected: which type can meet which target,
    before any link length. The inputs that reproduce it come with it."""
    return shipped()
