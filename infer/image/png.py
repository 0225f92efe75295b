"""The PNG ``sBIT`` chunk (significant bits per sample), which Pillow and OpenCV do not expose.

A 16-bit PNG written by a 10- or 12-bit camera states its true depth in ``sBIT`` (PNG 1.2,
section 4.2.6.1). The chunk precedes ``PLTE`` and ``IDAT``, so only the file's first chunks are
walked.
"""

from __future__ import annotations

import struct

_SIGNATURE = b"\x89PNG\r\n\x1a\n"
#: Colour type → number of colour (non-alpha) entries at the start of ``sBIT``.
_COLOUR_ENTRIES = {0: 1, 2: 3, 3: 3, 4: 1, 6: 3}


def png_significant_bits(data: bytes) -> int | None:
    """Significant bits per colour sample from a PNG's ``sBIT`` chunk.

    Args:
        data: the PNG file's bytes.

    Returns:
        The largest significant-bit count over the colour channels (alpha is dropped on load),
        or None when the data is not a PNG, has no ``sBIT`` chunk before its image data, or the
        chunk is malformed (the decoder then reports any damage itself).
    """
    if not data.startswith(_SIGNATURE):
        return None
    pos, colour_type = len(_SIGNATURE), None
    while pos + 8 <= len(data):
        length, kind = struct.unpack(">I4s", data[pos : pos + 8])
        body = data[pos + 8 : pos + 8 + length]
        if kind == b"IHDR" and len(body) >= 10:
            colour_type = body[9]
        elif kind == b"sBIT":
            entries = _COLOUR_ENTRIES.get(colour_type or 0, 1)
            return max(body[:entries]) if len(body) >= entries else None
        elif kind in (b"PLTE", b"IDAT", b"IEND"):
            return None
        pos += 12 + length
    return None
