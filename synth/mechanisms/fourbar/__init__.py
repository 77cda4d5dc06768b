"""The four-bar family, shared by the four-bar types (crank_rocker_slider, drag_link_slider).

- ``geometry``: the output pin over a revolution, Grashof's conditions and class, the scale.
- ``construction``: the dead-centre construction, every design with the time ratio and the
  swing, one CasADi function compiled per thread.
- ``search``: a grid, then Newton from its best points, on that construction.
- ``levels``: a problem's bounds and fixed links as level sets of the construction, and the
  lines of constant swing (range edges, a rod's kinks).
- ``strata`` and ``active``: every stratum of the feasible set searched from a grid, with
  Newton's method as an active-set method: the certified optimum where fixed links set the
  scale (or where the free scale's search was not exact).
- ``limited``: the best transmission where a rod from the swinging arm decides it.
- ``solver``: the exact reduced synthesis: the best transmission, the smallest design, a
  front continued point by point.
"""
