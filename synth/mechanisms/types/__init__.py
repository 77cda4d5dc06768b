"""The mechanism types, one module each: a module defines its type's maths in CasADi
operations and ends with ``register(Mechanism(...))``."""
