"""GET /v1/mechanisms and /v1/mechanisms/{type}: the registry, as data."""

from fastapi import APIRouter

from synth import mechanisms

from ..schemas import REFUSALS, MechanismInfo, NotFound

router = APIRouter(prefix="/v1/mechanisms", tags=["mechanisms"])


@router.get("", response_model=list[MechanismInfo])
async def list_mechanisms() -> list[MechanismInfo]:
    """Every mechanism type with its parameters, validity conditions and sources."""
    return [MechanismInfo.of(mechanisms.get(t)) for t in mechanisms.all_types()]


@router.get(
    "/{type}",
    response_model=MechanismInfo,
    responses={
        404: {"model": NotFound, "description": "unknown type; the known ones listed"},
        422: REFUSALS[422],
    },
)
async def get_mechanism(type: str) -> MechanismInfo:
    """One mechanism type; an unknown type is a 404 listing the known ones."""
    return MechanismInfo.of(mechanisms.get(type))
