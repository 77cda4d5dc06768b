"""The four-bar family, shared by the four-bar types (crank_rocker_slider, drag_link_slider).

- ``geometry``: the output pin over a revolution, Grashof's conditions and class, the scale.
- ``construction``: the dead-centre construction, every design with the time ratio and the
  swing, one CasADi function compiled per thread.
- ``solver``: the exact reduced synthesis on that construction.
"""
