"""Strict decoding: a file whose decoder warns is an error, never a silently damaged image.

OpenCV's libjpeg decodes a damaged entropy-coded segment (a file cut short and given a new
end-of-image marker, flipped bytes) without failing: it fills the rest with grey, and its only
sign is a warning such as ``Corrupt JPEG data: premature end of data segment`` printed on the
process's standard error; libtiff and libpng report damage the same way. :func:`decode_strict`
captures that output around the decode and turns it into an :class:`ImageError` (one line,
quoting the decoder). Pillow is no alternative: it decodes such JPEGs silently too.
"""

from __future__ import annotations

import os
import re
import sys
import tempfile
import threading

import cv2
import numpy as np

from contactcal.infer.image.gray import ImageError

#: Standard error (file descriptor 2) is process-wide: one capturing decode at a time.
_STDERR_LOCK = threading.Lock()


#: Decoder messages about colour/metadata chunks, not pixels (e.g. libpng's "iCCP: known
#: incorrect sRGB profile", common in files from some editors): passed on as warnings.
METADATA_WARNING = re.compile(
    r"libpng warning: (iCCP|sRGB|cHRM|gAMA|iTXt|tEXt|zTXt|pHYs|tIME|bKGD)"
)


def decode_strict(buf: np.ndarray, flag: int, name: str) -> np.ndarray | None:
    """``cv2.imdecode(buf, flag)`` with anything the decoder says turned into an error.

    Standard error is redirected to a temporary file for the decode only (a few tens of µs;
    a full 2592×1944 decode takes tens of ms) and restored, also when it was closed.

    Args:
        buf: the file's bytes as a ``(N,) uint8`` array.
        flag: an OpenCV ``IMREAD_*`` flag (full or reduced decode).
        name: the file, for the message.

    Returns:
        What ``cv2.imdecode`` returns (None when it cannot decode at all).

    Raises:
        ImageError: the decoder refused the file (e.g. a header larger than OpenCV allows), or
            warned or complained about the data (corrupt); a warning about
            colour metadata only (:data:`METADATA_WARNING`) is printed on stderr instead.
    """
    with _STDERR_LOCK, tempfile.TemporaryFile() as sink:
        if sys.stderr is not None:
            sys.stderr.flush()
        try:
            saved: int | None = os.dup(2)
        except OSError:  # standard error is closed
            saved = None
        os.dup2(sink.fileno(), 2)
        try:
            img = cv2.imdecode(buf, flag)
        except cv2.error as exc:  # e.g. a header declaring a frame wider than OpenCV allows
            refused = str(exc).strip().splitlines()[-1]
            raise ImageError(
                f"{name}: the decoder refused the file ({refused}); expected an image of a "
                "plausible size: copy or export it again from the camera"
            ) from exc
        finally:
            if saved is None:
                os.close(2)
            else:
                os.dup2(saved, 2)
                os.close(saved)
        sink.seek(0)
        said = [ln for ln in sink.read(4096).decode("utf-8", "replace").splitlines() if ln.strip()]
    damage = [ln for ln in said if not METADATA_WARNING.search(ln)]
    if damage:
        raise ImageError(
            f"{name}: corrupt image data (the decoder said: {' / '.join(damage)}); "
            "the file is damaged: copy or export it again from the camera"
        )
    for ln in said:  # pixels intact: said, not hidden, and not an error
        print(
            f"contactcal: warning: {name}: {ln.strip()} (colour metadata ignored)", file=sys.stderr
        )
    return img
