"""The deployment spec of an exported U-Net, built strictly from the model's metadata.

``contactcal export`` writes the metadata (``metadata_props``, all strings); deployment reads it
here and nowhere else. Every key is known: a missing or unknown key is an error naming the key
(like timm's ``resolve_data_config``), so a model exported by another version cannot be run with
a silently different preprocessing.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from contactcal.infer.errors import option_error
from contactcal.infer.files.regular import parse_input_json
from contactcal.infer.methods.unet.config import PreprocessConfig


class ModelError(ValueError):
    """A model file that cannot be used; the message names the file."""


def by_model_option(
    option: str, value: object, path: str | os.PathLike[str], exc: ModelError
) -> ValueError:
    """``exc``, a refusal of the model file ``path``, led by the option that gave it, the path
    named once, by the value as typed: ``--model m.onnx: no such model file``,
    ``--variant int8=m.onnx: ...`` (:func:`~contactcal.infer.errors.option_error`)."""
    return option_error(option, value, ModelError(str(exc).removeprefix(f"{path}: ")))


#: Metadata keys that define the pre- and post-processing (all required).
SPEC_KEYS = ("channels", "preprocess", "threshold", "min_contact_area_px", "output", "interval")
#: Metadata keys that define the post-processing and may be absent, with the value a model
#: exported before the key existed was deployed with.
OPTIONAL_SPEC_KEYS = {"region": "largest", "min_change": "0.0"}
#: How the kept region becomes the contact region (metadata ``region``): ``"largest"``, the
#: largest connected region above the threshold as it is; ``"convex"``, its convex hull (a finger
#: pulp pressed on the membrane touches it in a convex region, and the rig paper's reference areas
#: are ellipses; the hull restores edge lobes the network left out, at the price of the pixels
#: it adds across a ragged outline).
REGIONS = ("largest", "convex")
#: The key under which ``interval`` (in its JSON object) and ``min_change`` (as
#: ``{"value": min_change, "data": …}``) may record the datasets a restating tool calibrated them
#: on (:mod:`contactcal.train.calibration_data`). Provenance: accepted, recorded, not interpreted
#: (the spec does not carry it); an entry without it (export's, the shipped model's) reads the same.
CALIBRATION_DATA_KEY = "data"
#: Metadata keys that describe the model's provenance (all required; recorded, not interpreted).
PROVENANCE_KEYS = (
    "data_digest",
    "contactcal_version",
    "created",
    "train_config",
    "best_epoch",
    "val_metrics",
)


@dataclass(frozen=True)
class IntervalSpec:
    """The stated interval of a frame's area, calibrated on validation data (metadata ``interval``).

    The interval is built from the kept region's boundary band
    (:func:`contactcal.infer.methods.unet.postprocess.area_interval`): the region measured at a
    stricter (``threshold_high``) and a looser (``threshold_low``) probability threshold, plus half
    a network pixel across its boundary, each side widened by ``widen``. ``widen`` is chosen by
    ``contactcal export`` (:mod:`contactcal.train.interval`) so that the interval covers the true
    area in ``level`` of the calibration frames.
    """

    level: float  # stated coverage, e.g. 0.9
    threshold_low: float  # probability; the looser threshold (< the decision threshold)
    threshold_high: float  # probability; the stricter threshold (> the decision threshold)
    widen: float  # >= 0; factor on the band's half-widths (calibrated)
    frames: int  # calibration frames the factor was chosen on (provenance)

    def __post_init__(self) -> None:
        if not 0.0 < self.level < 1.0:
            raise ValueError(f"interval level must be in (0, 1), got {self.level}")
        if not 0.0 < self.threshold_low < self.threshold_high < 1.0:
            raise ValueError(
                "interval thresholds must satisfy 0 < threshold_low < threshold_high < 1, got "
                f"{self.threshold_low}, {self.threshold_high}"
            )
        if not (math.isfinite(self.widen) and self.widen >= 0.0):
            raise ValueError(f"interval widen must be finite and >= 0, got {self.widen}")
        if isinstance(self.frames, bool) or not isinstance(self.frames, int) or self.frames < 1:
            raise ValueError(f"interval frames must be an integer >= 1, got {self.frames!r}")


@dataclass(frozen=True)
class ModelSpec:
    """What the model's metadata says about its input and output."""

    channels: int  # frame [+ the session's zero-pressure frame] [+ ridge energy, when
    #   preprocess.ridge_work_px > 0]
    preprocess: PreprocessConfig  # crop, input size and normalisation used in training
    threshold: float  # probability above which a network pixel is contact
    min_contact_area_px: float  # network pixels; smaller predicted regions are "no contact"
    #: None only before calibration (training's validation); every exported model states one.
    interval: IntervalSpec | None = None
    region: str = "largest"  # one of REGIONS; "convex" fills the kept region's convex hull
    #: Network input units (the crop over its bright percentile, normalised), >= 0: a kept region
    #: whose mean |frame − reference| channel difference is below it is "no contact" (a speck on
    #: the window, a pre-contact glare: things the zero-pressure frame already shows). 0: no gate.
    #: Higher rejects more such regions and risks the faint first contact of a hard session;
    #: calibrated on validation renders by ``python -m contactcal.train.change_gate``. Applies
    #: only when the session has a reference frame.
    min_change: float = 0.0

    @property
    def uses_reference(self) -> bool:
        """True when one input channel is the session's zero-pressure frame."""
        return self.channels - (self.preprocess.ridge_work_px > 0) == 2

    def __post_init__(self) -> None:
        ridge = self.preprocess.ridge_work_px > 0
        if self.channels - ridge not in (1, 2):
            raise ValueError(
                f"channels must be {1 + ridge} or {2 + ridge} (frame[, reference]"
                f"{', ridge energy' if ridge else ''}), got {self.channels}"
            )
        if not 0.0 < self.threshold < 1.0:
            raise ValueError(f"threshold must be in (0, 1), got {self.threshold}")
        if not (math.isfinite(self.min_contact_area_px) and self.min_contact_area_px >= 0.0):
            raise ValueError(
                f"min_contact_area_px must be finite and >= 0, got {self.min_contact_area_px}"
            )
        if self.region not in REGIONS:
            raise ValueError(f"region must be one of {', '.join(REGIONS)}, got {self.region!r}")
        if not (math.isfinite(self.min_change) and self.min_change >= 0.0):
            raise ValueError(f"min_change must be finite and >= 0, got {self.min_change}")
        if self.min_change > 0.0 and not self.uses_reference:
            raise ValueError(
                f"min_change {self.min_change} needs a reference channel, and the model has none"
            )
        iv = self.interval
        if iv is not None and not iv.threshold_low < self.threshold < iv.threshold_high:
            raise ValueError(
                f"interval thresholds ({iv.threshold_low}, {iv.threshold_high}) must enclose the "
                f"threshold {self.threshold}"
            )

    def to_metadata(self) -> dict[str, str]:
        """The :data:`SPEC_KEYS` and :data:`OPTIONAL_SPEC_KEYS` part of the metadata (what
        ``contactcal export`` writes; the optional keys with their values).

        Raises:
            ValueError: the interval is not calibrated yet (``interval`` is None).
        """
        if self.interval is None:
            raise ValueError("the spec has no calibrated interval; calibrate it before export")
        return {
            "channels": str(self.channels),
            "preprocess": json.dumps(dataclasses.asdict(self.preprocess)),
            "threshold": repr(self.threshold),
            "min_contact_area_px": repr(self.min_contact_area_px),
            "output": "logits",
            "interval": json.dumps(dataclasses.asdict(self.interval)),
            "region": self.region,
            "min_change": repr(self.min_change),
        }


def _fields(
    key: str, text: str, cls: type, legacy: Mapping[str, Any] | None = None, recorded: bool = False
) -> dict[str, Any]:
    """The JSON object of metadata ``key``, with exactly the fields of dataclass ``cls``; the
    ``legacy`` fields (those a model may predate) filled in with their values where absent; with
    ``recorded``, its :data:`CALIBRATION_DATA_KEY` record (if any) accepted and left out."""
    values = parse_input_json(text)
    if not isinstance(values, dict):
        raise ValueError(f"{key}: expected a JSON object")
    values = {**(legacy or {}), **values}
    if recorded:
        values.pop(CALIBRATION_DATA_KEY, None)
    names = {f.name for f in dataclasses.fields(cls)}
    unknown, missing = sorted(set(values) - names), sorted(names - set(values))
    if unknown or missing:
        raise ValueError(f"{key}: unknown key(s) {unknown}, missing key(s) {missing}")
    return values


#: Preprocessing fields a model exported before they existed lacks, with the value it was
#: deployed with (its metadata's ``preprocess`` may omit exactly these).
LEGACY_PREPROCESS: dict[str, Any] = {"norm_floor_percentile": 0.0}


def _preprocess(text: str) -> PreprocessConfig:
    return PreprocessConfig(**_fields("preprocess", text, PreprocessConfig, LEGACY_PREPROCESS))


def _interval(text: str) -> IntervalSpec:
    values = _fields("interval", text, IntervalSpec, recorded=True)
    floats = sorted(set(values) - {"frames"})
    bad = [
        k for k in floats if isinstance(values[k], bool) or not isinstance(values[k], int | float)
    ]
    if bad:
        raise ValueError(f"interval: key(s) {bad} must be numbers")
    return IntervalSpec(**{**values, **{k: float(values[k]) for k in floats}})


def _recorded_value(text: str) -> float:
    """The number of ``{"value": number, "data": …}`` (an entry with its calibration record,
    :data:`CALIBRATION_DATA_KEY`); NaN for any other text."""
    try:
        entry = parse_input_json(text)
    except json.JSONDecodeError:
        return math.nan
    if not isinstance(entry, dict) or set(entry) != {"value", CALIBRATION_DATA_KEY}:
        return math.nan
    value = entry["value"]
    number = isinstance(value, int | float) and not isinstance(value, bool)
    return float(value) if number else math.nan


def _min_change(text: str, path: str | Path) -> float:
    """Metadata ``min_change`` as a number >= 0 (written as a number, or with its calibration
    record as ``{"value": number, "data": …}``), or an error naming the file and the fix."""
    try:
        value = float(text)
    except ValueError:
        value = _recorded_value(text)
    if not (math.isfinite(value) and value >= 0.0):
        raise ModelError(
            f"{path}: invalid model metadata: min_change must be a finite number >= 0 (or "
            f'{{"value": that number, "{CALIBRATION_DATA_KEY}": …}}), got {text!r}; restate it '
            "with `python -m contactcal.train.change_gate MODEL …`"
        )
    return value


def read_spec(meta: Mapping[str, str], path: str | Path) -> ModelSpec:
    """Build the deployment spec from a model's metadata; every key must be known.

    Args:
        meta: the ONNX model's ``metadata_props`` (key → string).
        path: the model file, for messages.

    Returns:
        The spec. A model without an optional key (exported before it existed) gets the value it
        was deployed with (:data:`OPTIONAL_SPEC_KEYS`): ``region`` ``"largest"``, ``min_change``
        0 (no gate). The calibration record that ``interval`` and ``min_change`` may carry
        (:data:`CALIBRATION_DATA_KEY`) is accepted and not part of the spec.

    Raises:
        ModelError: a missing, unknown or invalid key; the message names it and the file.
    """
    known = (*SPEC_KEYS, *OPTIONAL_SPEC_KEYS, *PROVENANCE_KEYS)
    missing = [k for k in (*SPEC_KEYS, *PROVENANCE_KEYS) if k not in meta]
    unknown = sorted(k for k in meta if k not in known)
    fix = "re-export the model with this version's `contactcal export`"
    if missing:
        raise ModelError(f"{path}: model metadata lacks key(s) {', '.join(missing)}; {fix}")
    if unknown:
        raise ModelError(f"{path}: unknown model metadata key(s) {', '.join(unknown)}; {fix}")
    region = meta.get("region", OPTIONAL_SPEC_KEYS["region"])
    if region not in REGIONS:
        raise ModelError(
            f"{path}: invalid model metadata: region must be one of {', '.join(REGIONS)}, got "
            f"{region!r}; restate it with `python -m contactcal.train.interval MODEL --region …`"
        )
    min_change = _min_change(meta.get("min_change", OPTIONAL_SPEC_KEYS["min_change"]), path)
    if meta["output"] != "logits":
        raise ModelError(f"{path}: metadata 'output' must be 'logits', got {meta['output']!r}")
    try:
        spec = ModelSpec(
            channels=int(meta["channels"]),
            preprocess=_preprocess(meta["preprocess"]),
            threshold=float(meta["threshold"]),
            min_contact_area_px=float(meta["min_contact_area_px"]),
            interval=_interval(meta["interval"]),
            region=region,
        )
    except (ValueError, TypeError) as exc:
        raise ModelError(f"{path}: invalid model metadata: {exc}; {fix}") from exc
    if min_change > 0.0 and not spec.uses_reference:
        raise ModelError(
            f"{path}: invalid model metadata: min_change {min_change} needs a reference channel "
            "and the model has none; remove the min_change key (a change gate compares the "
            "frame with the session's zero-pressure frame)"
        )
    return dataclasses.replace(spec, min_change=min_change)
