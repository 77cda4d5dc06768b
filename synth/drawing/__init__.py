"""A design drawn, for every face that shows one: the playground's SVG, notebooks' figures
(``synth.draw``), the exports a CAD program reads (``synth.export``: SVG, DXF), a turn of the
crank (``synth.animate``: GIF) and the design report (``synth.report``).

The drawing itself is ``model``'s; each face renders it in its own module. This package's
own namespace holds only the names a caller chooses among, so that asking what they are (the
command line's choices, the API's schema) loads nothing else.
"""

FORMATS = ("svg", "dxf", "json", "gif")  # synth.export's
FRAMES, FPS = 36, 12.0  # synth.animate's turn: its frames and their rate (3 s)
