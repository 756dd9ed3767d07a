"""Type aliases shared by the whole library."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

# A float64 array of any shape: every public function's return type, every kernel's argument.
Array = NDArray[np.float64]
# A boolean array: masks such as ``is_gimbal_lock``'s answer.
BoolArray = NDArray[np.bool_]
