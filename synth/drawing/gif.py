"""A turn of the crank as an animated GIF (Pillow): the drawing's symbols in every frame, the
links, pins, names and the ram's block where the crank angle puts them, for documents,
slides and a workshop's screen (``synth.animate``, ``format="gif"`` of ``synth.export``)."""

from __future__ import annotations

import io
from collections.abc import Mapping

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from ..analysis.kinematics import joints
from ..errors import InvalidParameters
from . import FPS, FRAMES
from .model import Drawing, drawing, sketch, slot
from .svg import COLOURS

WIDTH = 640  # pixels
MOST_FRAMES = 360  # a frame a degree


def gif(d: Drawing, frames: int = FRAMES, fps: float = FPS, width: int = WIDTH) -> bytes:
    """A turn of the crank from ``d``'s angle, in ``frames`` equal steps at ``fps``: every
    frame in one box (the drawing does not jump), ``width`` pixels wide."""
    sk = sketch(d)
    angles = [d.crank_angle_deg + 360.0 * k / frames for k in range(frames)]
    at = joints(d.type, d.params, angles)
    moved = np.concatenate(list(at.values()))
    x0, y0, x1, y1 = sk.extent(d)
    x0, y0 = min(x0, moved[:, 0].min()), min(y0, moved[:, 1].min())
    x1, y1 = max(x1, moved[:, 0].max()), max(y1, moved[:, 1].max())
    pad = 0.05 * max(x1 - x0, y1 - y0)
    x0, y0, x1, y1 = x0 - pad, y0 - pad, x1 + pad, y1 + pad
    k = width / (x1 - x0)
    size = (width, max(1, round((y1 - y0) * k)))
    font = ImageFont.load_default(size=max(10, round(sk.text_height * k)))
    lw = max(1, round(sk.line_width * k))

    def px(p: tuple[float, float] | np.ndarray) -> tuple[float, float]:
        return float((p[0] - x0) * k), float((y1 - p[1]) * k)

    images = []
    for f in range(frames):
        pins = {n: (float(xy[f, 0]), float(xy[f, 1])) for n, xy in at.items()}
        shift = np.subtract(pins[d.ram], d.pins[d.ram])
        im = Image.new("RGB", size, "white")
        draw = ImageDraw.Draw(im)
        for xy in (d.paths or {}).values():
            draw.line([px(p) for p in xy], fill="#aaaaaa", width=1)
        for a, b in (*sk.guide, *sk.hatch):
            draw.line([px(a), px(b)], fill="#555555", width=1)
        for tri in sk.ground:
            draw.polygon([px(p) for p in tri], fill="#bbbbbb", outline="#333333")
        draw.polygon([px(np.add(p, shift)) for p in sk.block], fill="#dddddd", outline="#333333")
        draw.line([px(p) for p in sk.dimension], fill="#222222", width=1)
        draw.text(px(sk.label_at), sk.label, fill="#222222", font=font, anchor="ms")
        for a, b in (*(slot(pins, names) for names in d.slots), *d.yokes_at(pins)):
            draw.line([px(a), px(b)], fill="#cccccc", width=3 * lw)
        for i, link in enumerate(d.links):
            colour = COLOURS[i % len(COLOURS)]
            draw.line([px(pins[link.a]), px(pins[link.b])], fill=colour, width=2 * lw)
        r = max(2.0, sk.pin_radius * k)
        for n, p in pins.items():
            cx, cy = px(p)
            draw.ellipse((cx - r, cy - r, cx + r, cy + r), fill="white", outline="#222222")
            name_at = np.add(sk.names[n], np.subtract(p, d.pins[n]))
            draw.text(px(name_at), n, fill="#222222", font=font, anchor="ls")
        images.append(im.quantize(palette=_palette(), dither=Image.Dither.NONE))
    out = io.BytesIO()
    duration = round(1000 / fps)
    images[0].save(
        out, format="GIF", save_all=True, append_images=images[1:], duration=duration, loop=0
    )
    return out.getvalue()


def _palette() -> Image.Image:
    """The frames' colours: the links', and greys from black to white (the text's edges)."""
    colours = [tuple(int(c[i : i + 2], 16) for i in (1, 3, 5)) for c in COLOURS]
    greys = [(v, v, v) for v in range(0, 256, 17)]
    pal = Image.new("P", (1, 1))
    pal.putpalette([x for rgb in [*greys, *colours] for x in rgb])
    return pal


def animate(
    mechanism: str,
    params: Mapping[str, float],
    frames: int = FRAMES,
    fps: float = FPS,
    path: str | None = None,
) -> bytes:
    """A turn of the crank as an animated GIF (``frames`` equal steps from where the mechanism
    stands open, at ``fps``, the pins' paths in each); written to ``path`` too if given."""
    if not 1 <= frames <= MOST_FRAMES:
        msg = f"frames must be in [1, {MOST_FRAMES}], got {frames}"
        raise InvalidParameters(msg, ("frames",))
    if not 0 < fps <= 100:
        raise InvalidParameters(f"fps must be in (0, 100], got {fps}", ("fps",))
    doc = gif(drawing(mechanism, params, None, paths=True), frames, fps)
    if path is not None:
        with open(path, "wb") as f:
            f.write(doc)
    return doc
