"""plot_trinary: a trinary map's cells drawn in the right place with the right shade."""

from __future__ import annotations

import matplotlib as mpl
import numpy as np
from matplotlib.colors import to_hex

from sonarcarve.plotting import TRINARY_COLORS, new_axes, plot_trinary

mpl.use("Agg")


def test_cells_get_their_shade_and_place() -> None:
    cells = np.array([[0, 100, -1], [-1, 0, 100]], dtype=np.int8)  # row 0 at the bottom
    ax = new_axes()
    (image,) = plot_trinary(cells, (1.0, 2.0, 1.3, 2.2), ax)
    # matplotlib's extent is (left, right, bottom, top); the map's is (xmin, ymin, xmax, ymax).
    assert tuple(image.get_extent()) == (1.0, 1.3, 2.0, 2.2)
    assert image.origin == "lower"
    rgba = image.to_rgba(image.get_array())
    colour = {0: TRINARY_COLORS[0], -1: TRINARY_COLORS[1], 100: TRINARY_COLORS[2]}
    for (i, j), value in np.ndenumerate(cells):
        assert to_hex(rgba[i, j]) == colour[int(value)]
    assert TRINARY_COLORS[0] == "#ffffff"  # free white, occupied black, as map_server images
    assert TRINARY_COLORS[2] == "#000000"
