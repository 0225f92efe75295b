"""A session's preparation as deployment fixes it: the shrink of its frames and its reference.

Torch-free, so that the INT8 calibration (``contactcal quantize``, which needs only onnx and
onnxruntime) prepares frames exactly as the training cache and deployment do.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from contactcal.infer.bench.dataset import IndexRow, sessions_of
from contactcal.infer.image.gray import reduce_area
from contactcal.infer.image.read import load_image
from contactcal.infer.methods.unet.config import PreprocessConfig
from contactcal.infer.methods.unet.prepare import SessionReference
from contactcal.infer.methods.unet.shrink import shrunk_reference


@dataclass(frozen=True)
class SessionInput:
    """A session's preparation, fixed by its lowest-pressure frame, as deployment fixes it."""

    reference: SessionReference  # of the shrunk reference frame
    shrink: int  # every frame is shrunk by this factor first (deployed_shrink; 1, 2, 4 or 8)
    rows: tuple[IndexRow, ...]  # the session's index rows, lowest pressure first

    def frame(self, path: str | os.PathLike[str]) -> np.ndarray:
        """``path`` decoded and shrunk: the ``(H / k, W / k) uint8`` frame deployment prepares."""
        return reduce_area(load_image(path), self.shrink)


def session_inputs(rows: Sequence[IndexRow], config: PreprocessConfig) -> dict[str, SessionInput]:
    """Each session's :class:`SessionInput`: the shrink deployment would choose for its
    lowest-pressure frame and that frame, shrunk, as reference, by deployment's own
    :func:`~contactcal.infer.methods.unet.shrink.shrunk_reference`. A 1296×972 render is thus
    prepared at 324×243, as a 2592×1944 rig frame decoded at 1/8 is."""
    out = {}
    for key, frames in sessions_of(rows).items():
        reference, k = shrunk_reference(load_image(frames[0].frame), config)
        out[key] = SessionInput(reference, k, tuple(frames))
    return out
