"""thinburn: physically based burning of thin shells (Liu et al. 2009, and beyond)."""
from __future__ import annotations

from ._threads import get_threads, has_openmp, set_threads

__all__ = ["get_threads", "has_openmp", "set_threads"]
__version__ = "0.1.0"
