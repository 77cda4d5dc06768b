"""The library against values computed independently of it: the sources' reference cases, a
brute-force simulation, closed forms in 50-digit arithmetic, a global search, the generic
path as the referee of the reduced solvers, and property tests at the edges of every type."""
