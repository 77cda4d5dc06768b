"""Small numerics every layer shares: compiled CasADi functions (``native``) and dense
Newton steps, bisection and the KKT step on a handful of unknowns (``dense``)."""
