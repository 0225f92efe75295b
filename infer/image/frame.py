"""A frame a caller gives a method as an array: the checks a file gets, then the canonical form.

:func:`~contactcal.infer.image.read.load_image` refuses a file too small or elongated to be a rig
frame, and 16-bit samples whose bit depth cannot be told. An array handed to a method's
``measure`` or ``set_reference`` gets the same refusals here (it used to give "no contact", or a
16-bit array of 12-bit data was read 16 times too dark), then :func:`to_gray_u8`'s conversion:
colour arrays are RGB(A) (convert OpenCV's BGR frames with ``to_gray_u8(frame, bgr=True)``).
"""

from __future__ import annotations

import numpy as np

from contactcal.infer.image.gray import ImageError, to_gray_u8

#: Largest maximum a 16-bit file without stated depth may have before it is ambiguous: 10-,
#: 12- and 14-bit data stored in the low bits never exceed 16383 (= 2**14 - 1), and a genuine
#: 16-bit rig frame (bright ring near saturation) does. Read such data as 16-bit and it comes
#: out 4 to 64 times too dark (areas off by +6 to +17 %, or no ring found).
LOW_BITS_MAX = 16383
#: Smallest width and height of a frame, px. The bundled tests' frames are 64×48, rig frames
#: thousands of px; below 16 px no ring or contact patch is resolvable, and a 3 px strip makes
#: the U-Net's ring fit ask for terabytes.
MIN_FRAME_SIDE_PX = 16
#: Largest long/short side ratio of a frame: sensors are 1:1 to 16:9 (1.8), panoramic ones
#: 21:9 (2.3); a more elongated image is a strip or a raw buffer read with the wrong width.
MAX_ASPECT_RATIO = 4.0


def check_frame_shape(name: str, height: int, width: int) -> None:
    """Reject images too small or too elongated to be a rig frame.

    Args:
        name: the file or array, for the message.
        height: its height, px (of the file, for a reduced decode).
        width: its width, px.

    Raises:
        ImageError: naming ``name``, its size and what is expected.
    """
    short, long = min(height, width), max(height, width)
    if short < MIN_FRAME_SIDE_PX or long > MAX_ASPECT_RATIO * short:
        raise ImageError(
            f"{name}: {width}×{height} px is not a rig frame; expected both sides >= "
            f"{MIN_FRAME_SIDE_PX} px and a long/short side ratio <= {MAX_ASPECT_RATIO:g}"
        )


def as_frame(image: np.ndarray, name: str = "frame") -> np.ndarray:
    """The ``(H, W) uint8`` frame of an array given to a method, checked as a file would be.

    Args:
        image: any array :func:`to_gray_u8` accepts (colour in RGB(A) order); a uint16 array
            must hold full-range 16-bit samples (its maximum above :data:`LOW_BITS_MAX`).
        name: how the message names it.

    Returns:
        ``(H, W) uint8`` contiguous array.

    Raises:
        ImageError: as :func:`to_gray_u8`; a uint16 array whose bit depth cannot be told; a
            frame too small or too elongated (:func:`check_frame_shape`).
    """
    if isinstance(image, np.ndarray) and image.dtype == np.uint16 and image.size:
        top = int(image.max())
        if top <= LOW_BITS_MAX:
            raise ImageError(
                f"{name}: uint16 samples with maximum {top} (<= {LOW_BITS_MAX}): 10- to 14-bit "
                "data or a dark 16-bit frame, which cannot be told apart; give it as uint8 "
                "(12-bit data: np.rint(a * 255 / 4095).astype(np.uint8)), or read the file with "
                "load_image(path, bit_depth=N)"
            )
    gray = to_gray_u8(image, name=name)
    check_frame_shape(name, *gray.shape)
    return gray
