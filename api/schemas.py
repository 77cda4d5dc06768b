"""Pydantic models of the REST contract, generated from the registry where they describe types."""

from __future__ import annotations

from pydantic import BaseModel, Field

from synth.mechanisms import Mechanism


class Health(BaseModel):
    status: str = "ok"
    version: str


class ParameterInfo(BaseModel):
    name: str
    symbol: str = Field(description="the textbook symbol")
    description: str
    required: bool
    default: float | None = Field(None, description="constant default, if any")
    default_rule: str | None = Field(None, description="a default derived from the others")
    signed: bool = Field(False, description="may be zero or negative")
    zero_means: str | None = Field(None, description="0 is allowed and selects this variant")


class MechanismInfo(BaseModel):
    type: str
    title: str
    description: str
    parameters: list[ParameterInfo]
    validity: list[str] = Field(description="the validity conditions, in words")
    quick_return: bool
    seeds: list[str] = Field(description="the source documents (shared/seeds)")

    @classmethod
    def of(cls, m: Mechanism) -> MechanismInfo:
        return cls(
            type=m.type,
            title=m.title,
            description=m.description,
            parameters=[
                ParameterInfo(
                    name=q.name,
                    symbol=q.symbol,
                    description=q.description,
                    required=q.required,
                    default=q.default,
                    default_rule=q.default_rule,
                    signed=q.signed,
                    zero_means=q.zero_means,
                )
                for q in m.parameters
            ],
            validity=[c.text for c in m.conditions],
            quick_return=m.quick_return,
            seeds=list(m.seeds),
        )
