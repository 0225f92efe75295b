"""JPEG frame size from the file header: the frame's SOF segment is read, no pixel is decoded.

Only the header's first segments are parsed and no image library is imported (importing one
cost ~10 ms of a ``measure`` run's start-up, where the U-Net reads every file's header to
choose its reduced decode).
"""

from __future__ import annotations

import io
import os
from pathlib import Path
from typing import BinaryIO

from contactcal.infer.files.regular import open_input
from contactcal.infer.image.gray import ImageError

#: Start-of-frame markers (baseline, extended, progressive, lossless; Huffman and arithmetic).
SOF_MARKERS = frozenset(range(0xC0, 0xD0)) - {0xC4, 0xC8, 0xCC}
#: Markers without a length field (TEM, RST0-7); SOI is read before the loop.
STANDALONE = frozenset({0x01, *range(0xD0, 0xD8)})
#: Other formats named in the error message, by their first bytes.
SIGNATURES = {b"\x89PNG": "PNG", b"II*\x00": "TIFF", b"MM\x00*": "TIFF", b"BM": "BMP"}


def _read(f: BinaryIO, n: int) -> bytes:
    """Exactly ``n`` bytes of ``f``; EOFError when the file ends first (truncated header)."""
    data = f.read(n)
    if len(data) != n:
        raise EOFError
    return data


def _frame_size(f: BinaryIO) -> tuple[int, int] | None:
    """``(height, width)`` from the first SOF segment after SOI; None at SOS or EOI before it.

    Raises:
        EOFError: the file ends inside the header.
        ValueError: bytes that are not the marker structure of a JPEG header.
    """
    while True:
        if _read(f, 1) != b"\xff":
            raise ValueError("no marker where one was expected")
        marker = _read(f, 1)[0]
        while marker == 0xFF:  # fill bytes
            marker = _read(f, 1)[0]
        if marker == 0x00:  # a stuffed data byte: only valid inside entropy-coded data
            raise ValueError("data bytes where a marker was expected")
        if marker in STANDALONE:
            continue
        if marker in (0xD9, 0xDA):  # EOI, SOS: no frame header before the data
            return None
        length = int.from_bytes(_read(f, 2), "big")
        if length < 2 or (marker in SOF_MARKERS and length < 8):
            raise ValueError(f"segment FF {marker:02X} of length {length}")
        if marker in SOF_MARKERS:
            seg = _read(f, 5)  # precision, height, width
            return int.from_bytes(seg[1:3], "big"), int.from_bytes(seg[3:5], "big")
        f.seek(length - 2, os.SEEK_CUR)


def jpeg_size(path: str | os.PathLike[str], data: bytes | None = None) -> tuple[int, int]:
    """The frame size of a JPEG file, read from its header (the pixels are not decoded).

    The size is the frame header's, as stored: an EXIF orientation is not applied (nor does
    :func:`~contactcal.infer.image.read.load_image` apply it, at any decode reduction).

    Args:
        path: the JPEG file.
        data: its content, already read (None: read the header from ``path``).

    Returns:
        ``(height, width)`` in pixels.

    Raises:
        ImageError: missing or unreadable file, a folder, not a JPEG, or a JPEG without a
            usable frame header (truncated, or a height left to a DNL segment).
    """
    p = Path(path)
    try:
        f = open_input(p, "a JPEG file", ImageError) if data is None else io.BytesIO(data)
        with f:
            start = f.read(4)
            if not start.startswith(b"\xff\xd8"):
                got = next((n for s, n in SIGNATURES.items() if start.startswith(s)), None)
                what = f"got {got}" if got else "no JPEG start-of-image marker (FF D8)"
                raise ImageError(f"{p}: expected a JPEG file, {what}")
            f.seek(2)
            size = _frame_size(f)
    except ImageError:
        raise
    except FileNotFoundError as exc:
        raise ImageError(f"{p}: no such file") from exc
    except (EOFError, ValueError) as exc:
        why = str(exc) or "truncated"
        raise ImageError(f"{p}: not a readable JPEG (header: {why})") from exc
    except OSError as exc:
        raise ImageError(f"{p}: not a readable JPEG ({exc.strerror or exc})") from exc
    if size is None:
        raise ImageError(f"{p}: not a readable JPEG (no frame header before the image data)")
    if size[1] == 0:
        raise ImageError(f"{p}: not a readable JPEG (width 0 in its frame header)")
    if size[0] == 0:
        raise ImageError(
            f"{p}: height 0 in its frame header (left to a DNL segment, which contactcal does "
            "not read); save the frame again (e.g. with OpenCV), which writes the height there"
        )
    return size
