"""Image input: any PNG/JPEG/TIFF/BMP file or array → one canonical form.

The canonical form is a ``(H, W) uint8`` grayscale image, the form the published OpenCV routine
works on (its ROI threshold of 150 is an 8-bit grey level). Colour is converted with OpenCV's
ITU-R BT.601 luma (``cv2.cvtColor(..., COLOR_BGR2GRAY)``), alpha is dropped, float arrays are
taken as ``[0, 1]`` intensities (values outside are an error).

Bit depth is never guessed silently (:mod:`~contactcal.infer.image.bit_depth`: 16-bit samples
holding N-bit data are scaled to 8 bits, N stated by the PNG ``sBIT`` chunk or ``--bit-depth``).
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from contactcal.infer.files.digest import sha256_bytes
from contactcal.infer.files.regular import folder_message, read_input_bytes
from contactcal.infer.image.bit_depth import MAX_BIT_DEPTH, scale_depth
from contactcal.infer.image.complete import jpeg_end, png_end
from contactcal.infer.image.decode import decode_strict
from contactcal.infer.image.frame import check_frame_shape
from contactcal.infer.image.gray import ImageError, reduce_area, to_gray_u8
from contactcal.infer.image.jpeg import jpeg_size

#: File suffixes accepted by :func:`load_image` (lower case).
SUPPORTED_SUFFIXES = (".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp")


#: File signatures (first bytes) of the formats read, by name and suffixes.
_SIGNATURES: tuple[tuple[str, tuple[bytes, ...], tuple[str, ...]], ...] = (
    ("PNG", (b"\x89PNG\r\n\x1a\n",), (".png",)),
    ("JPEG", (b"\xff\xd8\xff",), (".jpg", ".jpeg")),
    ("TIFF", (b"II*\x00", b"MM\x00*"), (".tif", ".tiff")),
    ("BMP", (b"BM",), (".bmp",)),
)
_SIGNATURES_BY_NAME = {name: suffixes[0] for name, _, suffixes in _SIGNATURES}


def _check_content(path: Path, data: bytes, fix: str | None = None) -> None:
    """Reject a file whose content is not the format its suffix names (the suffix decides how it
    is decoded and checked: a JPEG named .png would be called a truncated PNG); ``fix``: the
    advice when it is another image format (default: rename it to that format's suffix)."""
    suffix = path.suffix.lower()
    found = next((name for name, sigs, _ in _SIGNATURES if data.startswith(sigs)), None)
    named = next(name for name, _, suffixes in _SIGNATURES if suffix in suffixes)
    if found == named:
        return
    what = f"a {found} image" if found else "not an image of a supported type"
    if fix is None or not found:
        fix = f"rename it to {_SIGNATURES_BY_NAME[found]}" if found else "export the frame again"
    raise ImageError(f"{path}: not a {named} file (its content is {what}); {fix}")


def _check_complete(path: Path, data: bytes) -> None:
    """Reject truncated PNG/JPEG files, which OpenCV may decode partially without failing.

    The end marker is looked for at the end of the file first (one comparison); only a file
    without it there is walked (:mod:`.complete`), so that data a camera appends after the image
    (a Raspberry Pi's raw trailer) is not taken for a truncation.
    """
    suffix = path.suffix.lower()
    if suffix == ".png":
        if not data.rstrip(b"\x00").endswith(b"IEND\xaeB`\x82") and png_end(data) is None:
            raise ImageError(f"{path}: truncated PNG (no IEND chunk); re-export the file")
    elif suffix in (".jpg", ".jpeg"):
        if b"\xff\xd9" not in data[-64:] and jpeg_end(data) is None:
            raise ImageError(f"{path}: truncated JPEG (no end-of-image marker); re-export the file")


def read_file_bytes(path: str | os.PathLike[str], other_format_fix: str | None = None) -> bytes:
    """Read an image file's bytes with clear errors for missing, unreadable or empty files.

    Args:
        path: image file.
        other_format_fix: the advice when its content is another image format than its suffix
            names (None: rename it to that format's suffix, right for a frame; a mask must be
            re-saved as PNG instead).

    Returns:
        The file content.

    Raises:
        ImageError: missing, not a file, unreadable, empty, unsupported suffix, or truncated.
    """
    p = Path(path)
    if p.is_dir():
        raise ImageError(f"{folder_message(p, 'an image file')}; give the frames' file names")
    if p.suffix.lower() not in SUPPORTED_SUFFIXES:
        raise ImageError(
            f"{p}: unsupported image type {p.suffix!r}; expected one of "
            f"{', '.join(SUPPORTED_SUFFIXES)}"
        )
    if not p.exists():
        raise ImageError(f"{p}: no such file")
    try:
        data = read_input_bytes(p, "an image file", ImageError)
    except OSError as exc:
        raise ImageError(f"{p}: cannot read ({exc.strerror})") from exc
    if not data:
        raise ImageError(f"{p}: empty file (0 bytes)")
    _check_content(p, data, other_format_fix)
    _check_complete(p, data)
    return data


def load_image(
    path: str | os.PathLike[str], reduce: int = 1, bit_depth: int | None = None
) -> np.ndarray:
    """Load an image file into the canonical ``(H, W) uint8`` grayscale form.

    Args:
        path: PNG, JPEG, TIFF or BMP file; 8- or 16-bit integer or float; gray, RGB or RGBA.
        reduce: 1, 2, 4 or 8. For JPEG, decode at 1/reduce resolution directly (libjpeg's
            DCT scaling: several times cheaper); other formats are decoded fully and
            area-resized. The result is about ``(H/reduce, W/reduce)``.
        bit_depth: significant bits of 16-bit integer samples (1-16), e.g. 12 for a 12-bit
            camera's 16-bit PNG holding 0-4095; None → from the PNG ``sBIT`` chunk, else the
            rule of :mod:`~contactcal.infer.image.bit_depth`. Ignored for float files; an error
            for 8-bit ones.

    Returns:
        ``(H, W) uint8`` grayscale image.

    Raises:
        ImageError: the file is missing, unreadable, empty, truncated, corrupt, not an image,
            not frame-shaped, or of an unknown or contradictory bit depth.
    """
    return ImageFile.read(path).decode(reduce, bit_depth)


@dataclass(frozen=True)
class ImageFile:
    """An image file's content, read once: its decodes and its digest all come from these bytes,
    so that a record's sha256 is that of the content measured (the file read again may have
    been replaced in between)."""

    path: Path
    data: bytes = field(repr=False)
    _sha256: str | None = field(default=None, init=False, repr=False, compare=False)  # memo

    @classmethod
    def read(cls, path: str | os.PathLike[str]) -> ImageFile:
        """Read a frame file (:func:`read_file_bytes`; raises ImageError as it does)."""
        p = Path(path)
        return cls(p, read_file_bytes(p))

    def sha256(self) -> str:
        """The content's sha256, lower-case hex (hashed on the first call, ~1 ms per MB)."""
        if self._sha256 is None:
            object.__setattr__(self, "_sha256", sha256_bytes(self.data))  # frozen: a memo only
        return self._sha256

    def decode(self, reduce: int = 1, bit_depth: int | None = None) -> np.ndarray:
        """The content in the canonical form, as :func:`load_image` documents it."""
        if reduce not in (1, 2, 4, 8):
            raise ValueError(f"reduce must be 1, 2, 4 or 8, got {reduce}")
        if bit_depth is not None and not 1 <= bit_depth <= MAX_BIT_DEPTH:
            raise ValueError(
                f"bit depth must be 1-{MAX_BIT_DEPTH} bits per sample, got {bit_depth}"
            )
        p, data = self.path, self.data
        buf = np.frombuffer(data, dtype=np.uint8)
        jpeg = p.suffix.lower() in (".jpg", ".jpeg")
        if jpeg:
            # IMREAD_UNCHANGED ignores an EXIF orientation; the reduced flags would apply it, so
            # a tagged frame would turn at 1/k and not at full size: they ignore it too.
            flag = {
                2: cv2.IMREAD_REDUCED_GRAYSCALE_2 | cv2.IMREAD_IGNORE_ORIENTATION,
                4: cv2.IMREAD_REDUCED_GRAYSCALE_4 | cv2.IMREAD_IGNORE_ORIENTATION,
                8: cv2.IMREAD_REDUCED_GRAYSCALE_8 | cv2.IMREAD_IGNORE_ORIENTATION,
            }.get(reduce, cv2.IMREAD_UNCHANGED)
        else:
            flag = cv2.IMREAD_UNCHANGED
        img = decode_strict(buf, flag, str(p))
        if img is None or img.size == 0:
            raise ImageError(f"{p}: not a decodable image (corrupt or unsupported content)")
        k = reduce if jpeg else 1  # the JPEG was decoded at 1/k
        check_frame_shape(str(p), img.shape[0] * k, img.shape[1] * k)
        img = scale_depth(p, img, data, bit_depth)
        gray = to_gray_u8(img, name=str(p), bgr=True)
        return gray if jpeg else reduce_area(gray, reduce)


#: An image file to read: its path (read when needed), or its content read already.
ImageSource = str | os.PathLike[str] | ImageFile


def read_contents(files: Iterable[Path]) -> dict[Path, ImageFile]:
    """The content of each of ``files``, each file read once (:meth:`ImageFile.read`; a file
    listed twice is read once), for a run whose steps must all use the same content.

    Raises:
        ImageError: as :func:`read_file_bytes`.
    """
    return {p: ImageFile.read(p) for p in dict.fromkeys(files)}


def sources_of(files: Sequence[Path], contents: dict[Path, ImageFile] | None) -> list[ImageSource]:
    """``files`` as a run measures them: with ``contents`` (the frames a run holds to use their
    content for more than one step) their contents, each file not in ``contents`` yet read into
    it now (:func:`read_contents`: every later step takes the content read), or with None the
    paths (each file read when it is measured, none held).

    Raises:
        ImageError: a file read here unreadable (as :func:`read_file_bytes`).
    """
    if contents is None:
        return list(files)
    contents.update(read_contents(p for p in files if p not in contents))
    return [contents[p] for p in files]


def source_content(source: ImageSource) -> ImageFile:
    """The content of ``source``: as given, or its file read now (:meth:`ImageFile.read`)."""
    return source if isinstance(source, ImageFile) else ImageFile.read(source)


def source_path(source: ImageSource) -> Path:
    """The file of ``source``."""
    return source.path if isinstance(source, ImageFile) else Path(source)


def source_jpeg_size(source: ImageSource) -> tuple[int, int]:
    """``(height, width)`` from a JPEG's header (:func:`~contactcal.infer.image.jpeg.jpeg_size`):
    of the content read already, else of the file (only its header read)."""
    if isinstance(source, ImageFile):
        return jpeg_size(source.path, source.data)
    return jpeg_size(source)


def source_size(source: ImageSource, bit_depth: int | None = None) -> tuple[int, int]:
    """``(width, height)`` of ``source`` as its decode reads it: a JPEG's from its header (of
    the content read already, else of the file: only the header read; no pixel decoded),
    another format's (or a JPEG whose header does not state it) decoded.

    Raises:
        ImageError: as :meth:`ImageFile.decode`.
    """
    if source_path(source).suffix.lower() in (".jpg", ".jpeg"):
        try:
            h, w = source_jpeg_size(source)
            return w, h
        except ImageError:
            pass  # a height left to a DNL segment, or a bad file: decoded (or refused) below
    h, w = source_content(source).decode(bit_depth=bit_depth).shape
    return w, h
