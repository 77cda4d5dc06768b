"""A design over a crank revolution: its compiled model (``model``), the stationary points of
its slider and transmission (``roots``), how it meets motion objectives (``quality``), the
analysis itself (``kinematics``), a candidate's a-posteriori check (``verify``) and a
parameter sweep (``sweep``). Nothing here uses a type's closed forms."""
