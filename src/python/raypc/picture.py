"""The rendered picture, a NumPy array; a notebook shows it as a PNG where Pillow is installed, which
is imported only then because the package needs nothing beyond NumPy to import."""
from __future__ import annotations

from typing import Optional

import numpy as np


class Picture(np.ndarray):
    """A rendered picture: (height, width, 4) uint8 RGBA, row-major from the top left; a notebook
    shows it as an image."""

    def __repr__(self) -> str:
        if self.ndim == 3:
            return f"raypc.Picture({self.shape[1]} x {self.shape[0]} pixels, RGBA)"
        return super().__repr__()

    def _repr_png_(self) -> Optional[bytes]:
        if self.ndim != 3 or self.shape[2] != 4:
            return None
        try:
            from PIL import Image
        except ImportError:
            return None
        import io

        out = io.BytesIO()
        Image.fromarray(np.asarray(self), "RGBA").save(out, format="PNG")
        return out.getvalue()
