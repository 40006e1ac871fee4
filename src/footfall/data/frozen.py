"""Finishing a frozen record: the checked, normalised values of its fields are set once, at the
end of ``__post_init__``, and its arrays become read-only, so a stored record cannot drift.
"""

from __future__ import annotations

from typing import Any

import numpy as np


def set_fields(record: Any, **values: Any) -> None:
    """Set fields of a frozen dataclass ``record``; every NumPy array among them is made read-only."""
    for name, value in values.items():
        if isinstance(value, np.ndarray):
            value.setflags(write=False)
        object.__setattr__(record, name, value)
