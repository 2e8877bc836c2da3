"""The array types of the library, in one place.

Arrays follow numpy's struct-of-arrays habit: one array per field, batch axis first. These
aliases name the element type only; docstrings give the shapes.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

__all__ = ["BoolArray", "FloatArray", "Int8Array", "IntArray", "JsonDict", "SlotArray"]

#: Metres, radians or seconds, float64.
FloatArray = npt.NDArray[np.float64]
#: Indices, counts and reading ids, int64.
IntArray = npt.NDArray[np.int64]
#: Small codes (point sources, arc fates), int8.
Int8Array = npt.NDArray[np.int8]
#: Masks.
BoolArray = npt.NDArray[np.bool_]
#: Rows of the history's storage (see :class:`~sonarcarve.history.SonarHistory`).
SlotArray = npt.NDArray[np.int64]
#: A JSON-ready mapping (results, summaries).
JsonDict = dict[str, Any]
