"""Where a PNG or JPEG file's image ends, found by walking its structure (pure Python).

OpenCV decodes a truncated PNG or JPEG partially without failing, so :mod:`.read` checks that the
file ends with its end marker. Some cameras append data after it (a Raspberry Pi camera's raw
Bayer trailer after the JPEG, a vendor block after a PNG's ``IEND``): there the end marker is not
at the end of the file, and these walks find it where the format puts it, so that such a file is
read and a truncated one still refused.
"""

from __future__ import annotations

#: JPEG markers without a length field: TEM, RST0-7, SOI (EOI ends the walk).
_STANDALONE = {0x01, *range(0xD0, 0xD8), 0xD8}
_EOI, _SOS = 0xD9, 0xDA


def _entropy_end(data: bytes, i: int) -> int:
    """Offset of the first marker after the entropy-coded data starting at ``i``, or len(data).

    In the entropy-coded data 0xFF is followed by a stuffed 0x00, a restart marker RST0-7 or
    fill bytes 0xFF; any other byte after 0xFF is the next marker.
    """
    n = len(data)
    while True:
        i = data.find(b"\xff", i)
        if i < 0 or i + 1 >= n:
            return n
        nxt = data[i + 1]
        if nxt == 0x00 or 0xD0 <= nxt <= 0xD7:
            i += 2
        elif nxt == 0xFF:
            i += 1
        else:
            return i


def jpeg_end(data: bytes) -> int | None:
    """Offset just past a JPEG's end-of-image marker (EOI), or None when the file ends before it.

    Walks the marker segments by their lengths from the start-of-image marker (an EXIF
    thumbnail's own EOI inside an APP1 segment is skipped with its segment) and scans each scan's
    entropy-coded data for the marker after it.

    Args:
        data: the file's bytes.

    Returns:
        The image's length in bytes (bytes after it are not part of the image), or None.
    """
    n = len(data)
    if not data.startswith(b"\xff\xd8"):
        return None
    i = 2
    while i + 1 < n:
        if data[i] != 0xFF:
            return None  # not a marker where one must be: a damaged file
        marker = data[i + 1]
        if marker == 0xFF:  # fill byte before a marker
            i += 1
        elif marker == _EOI:
            return i + 2
        elif marker in _STANDALONE:
            i += 2
        elif i + 4 > n:
            return None
        else:
            i += 2 + int.from_bytes(data[i + 2 : i + 4], "big")
            if marker == _SOS:
                i = _entropy_end(data, i)
    return None


def png_end(data: bytes) -> int | None:
    """Offset just past a PNG's ``IEND`` chunk, or None when the file ends before it.

    Walks the chunks by their lengths (4-byte length, 4-byte type, data, 4-byte CRC).

    Args:
        data: the file's bytes.

    Returns:
        The image's length in bytes, or None.
    """
    i, n = 8, len(data)
    while i + 12 <= n:
        length = int.from_bytes(data[i : i + 4], "big")
        end = i + 12 + length
        if data[i + 4 : i + 8] == b"IEND":
            return end if end <= n else None
        i = end
    return None
