"""The four-bar family, shared by the four-bar types (crank_rocker_slider, drag_link_slider).

- ``geometry``: the output pin over a revolution, Grashof's conditions and class, the scale.
- ``construction``: the dead-centre construction, every design with the time ratio and the
  swing, one CasADi function compiled per thread.
- ``search``: a grid, then Newton from its best points, on that construction.
- ``solver``: the exact reduced synthesis: the best transmission, the smallest design, a
  front continued point by point.
"""
