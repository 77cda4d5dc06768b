"""The library's behaviour: the registry and its contract, validity checks, pins for drawings,
batched and compiled analysis, scale, the atlas, and a seventh type added from outside."""
