"""Design atlases: which type reaches which targets, computed exactly (``compute``), kept in
a folder a run resumes from (``store``), drawn (``charts``), run from the command line
(``python -m synth.atlas``)."""

from .charts import charts
from .compute import atlas, point, reach
from .values import Atlas, Inputs, Point

__all__ = ["Atlas", "Inputs", "Point", "atlas", "charts", "point", "reach"]
