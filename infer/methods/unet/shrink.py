"""How much deployment shrinks a frame before preparing it (one decision for every caller).

The U-Net resizes a crop around the window ring to its input size, so a frame may first be
shrunk by an integer factor k (the JPEG's reduced DCT decode, or area averaging of a decoded
frame) as long as the crop keeps at least the input size. Deployment
(:class:`~contactcal.infer.methods.unet.method.UnetMethod`), training's cache, the interval
calibration and the INT8 calibration all call :func:`deployed_shrink`, so a 1296×972 render
reaches the network exactly as a 2592×1944 rig frame decoded at 1/8 does (at k = 4).
"""

from __future__ import annotations

import numpy as np

from contactcal.infer.image.gray import reduce_area
from contactcal.infer.methods.unet.config import PreprocessConfig
from contactcal.infer.methods.unet.crop import crop_box
from contactcal.infer.methods.unet.prepare import SessionReference, session_reference
from contactcal.infer.methods.unet.ring import locate_ring

#: JPEG decode reductions (and shrink factors of decoded frames) tried, cheapest first.
REDUCTIONS = (8, 4, 2)


def fitting_reduction(side: float, shape: tuple[int, ...], config: PreprocessConfig) -> int:
    """The largest of :data:`REDUCTIONS` that keeps the ring crop at least the network's input
    size and divides both sides of the frame exactly (so areas scale back by exactly k²); 1
    when none does.

    The ridge channel's work side (288 px) may be larger than the reduced crop (~235 px for a
    2592×1944 frame at k = 8): it is then interpolated up. Measured through this chain
    (``docs/synth.md``, "Resolution chain"), a 1296×972 render shrunk by 4 gives the network the
    ridge contrast and ridge channel of a 2592×1944 JPEG decoded at 1/8 within ~10 %.

    Args:
        side: ring crop side in pixels of the frame (``CropBox.side``; 0 when no ring).
        shape: the frame's ``(H, W)``.
        config: the model's preprocessing (``input_size``).
    """
    h, w = int(shape[0]), int(shape[1])
    fits = (k for k in REDUCTIONS if side / k >= config.input_size and h % k == 0 and w % k == 0)
    return next(fits, 1)


def deployed_shrink(gray: np.ndarray, config: PreprocessConfig) -> int:
    """The factor by which deployment shrinks a full-size frame like ``gray``:
    :func:`fitting_reduction` for the crop of its ring (the fallback ring's crop when none is
    found: what ``prepare`` then uses too). Only the ring search runs at full size.

    Args:
        gray: ``(H, W) uint8`` full-size frame (normally the session's reference).
        config: the model's preprocessing.

    Returns:
        k in {1, 2, 4, 8}.
    """
    box = crop_box(locate_ring(gray, config), gray.shape, config)
    return fitting_reduction(box.side, gray.shape, config)


def shrunk_reference(gray: np.ndarray, config: PreprocessConfig) -> tuple[SessionReference, int]:
    """A session's reference as deployment prepares it: ``gray`` shrunk by
    :func:`deployed_shrink`, then :func:`~contactcal.infer.methods.unet.prepare.session_reference`.

    Args:
        gray: ``(H, W) uint8`` full-size zero-pressure frame of the session.
        config: the model's preprocessing.

    Returns:
        The reference (of the shrunk frame) and the shrink factor k, by which every frame of the
        session is shrunk too.
    """
    k = deployed_shrink(gray, config)
    return session_reference(reduce_area(gray, k), config), k
