"""Top-down pictures of the world, drawn as the browser viewer draws it.

Bodies at their real size and rotation in the viewer's colours (actuator
grey, blue block ``blockA``, red block ``blockB``, others green) on the
viewer's table (0.1 m grid, heavier every 0.5 m, the axes darkest), targets
as outlines in their block's colour. Plain numpy: an image is a boolean mask
per shape over the pixel centres, so there is nothing to install.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from ..learner import Shape

__all__ = ["Canvas", "Drawn", "colour_of"]

_BACKGROUND = (0xF7, 0xF7, 0xF2)
_GRID = ((0xEB, 0xEB, 0xE4), (0xD8, 0xD8, 0xD0), (0xB8, 0xB8, 0xB0))
_COLOURS = {
    "actuator": (0x44, 0x44, 0x44),
    "blockA": (0x1F, 0x5F, 0xD0),
    "blockB": (0xD0, 0x30, 0x2A),
}
_OTHER = (0x2A, 0x9D, 0x5C)


def colour_of(name: str) -> tuple[int, int, int]:
    """The viewer's colour of body ``name`` (RGB)."""
    return _COLOURS.get(name, _OTHER)


@dataclass(frozen=True)
class Drawn:
    """One thing to draw: body ``name``'s ``shape`` at ``(x, y)`` m with yaw ``theta`` rad."""

    name: str
    shape: Shape
    x: float
    y: float
    theta: float
    outline: bool = False
    """Only the outline (a target), not the filled body."""


class Canvas:
    """Square RGB images of the table from above, ``size`` pixels wide, ``half_width`` m from the centre to each edge."""

    def __init__(self, size: int = 480, half_width: float = 1.25) -> None:
        if size < 16:
            raise ValueError(f"an image needs at least 16 pixels a side, got {size}")
        self.size = size
        self.metres_per_pixel = 2.0 * half_width / size
        centres = (np.arange(size) + 0.5) * self.metres_per_pixel - half_width
        # Row 0 is the top of the picture: the largest y.
        self._x, self._y = np.meshgrid(centres, centres[::-1])
        self._table = self._draw_table()

    def _draw_table(self) -> npt.NDArray[np.uint8]:
        image = np.empty((self.size, self.size, 3), dtype=np.uint8)
        image[:] = _BACKGROUND
        half_pixel = self.metres_per_pixel / 2.0
        # Heavier lines last, so they win where lines cross.
        for weight, spacing in enumerate((0.1, 0.5, math.inf)):
            for axis in (self._x, self._y):
                if math.isinf(spacing):
                    on_line = np.abs(axis) <= half_pixel
                else:
                    offset = np.abs(axis - spacing * np.round(axis / spacing))
                    on_line = offset <= half_pixel
                image[on_line] = _GRID[weight]
        return image

    def _mask(
        self, shape: Shape, x: float, y: float, theta: float, grow: float
    ) -> npt.NDArray[np.bool_]:
        dx, dy = self._x - x, self._y - y
        # An upright cylinder seen from above is a disc, like a sphere.
        disc = shape.sphere_radius if shape.cylinder is None else shape.cylinder[0]
        if disc is not None:
            radius = disc + grow
            return np.asarray(dx * dx + dy * dy <= radius * radius)
        if shape.box_size is not None:
            cos, sin = math.cos(theta), math.sin(theta)
            along = cos * dx + sin * dy
            across = -sin * dx + cos * dy
            half_x = shape.box_size[0] / 2.0 + grow
            half_y = shape.box_size[1] / 2.0 + grow
            return np.asarray((np.abs(along) <= half_x) & (np.abs(across) <= half_y))
        # A shape the world did not describe: a dot, so that it is seen.
        return np.asarray(dx * dx + dy * dy <= (0.02 + grow) ** 2)

    def draw(self, things: Iterable[Drawn]) -> npt.NDArray[np.uint8]:
        """A fresh ``(size, size, 3)`` uint8 image with ``things`` drawn in order over the table."""
        image = self._table.copy()
        line = 1.5 * self.metres_per_pixel
        for thing in things:
            colour = colour_of(thing.name)
            if thing.outline:
                outer = self._mask(thing.shape, thing.x, thing.y, thing.theta, line / 2)
                inner = self._mask(
                    thing.shape, thing.x, thing.y, thing.theta, -line / 2
                )
                image[outer & ~inner] = colour
            else:
                image[self._mask(thing.shape, thing.x, thing.y, thing.theta, 0.0)] = (
                    colour
                )
        return image

    def pixel(self, x: float, y: float) -> tuple[int, int]:
        """The (row, column) of the pixel holding the point ``(x, y)`` m."""
        half_width = self.size * self.metres_per_pixel / 2.0
        column = int((x + half_width) / self.metres_per_pixel)
        row = self.size - 1 - int((y + half_width) / self.metres_per_pixel)
        return row, column
