"""Small numerics every layer shares: compiled CasADi functions (``native``) and dense
Newton steps, bisection and the KKT step on a handful of unknowns (``dense``)."""

# the relative slack of a comparison with a limit: a value built on the limit in floating point
# is on it, not past it
ROUNDING = 1e-12
