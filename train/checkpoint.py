"""Checkpoints (atomic ``torch.save``) and config dataclass ↔ JSON-able dict conversion."""

from __future__ import annotations

import dataclasses
import os
import typing
from pathlib import Path
from typing import Any, TypeVar

import torch

from contactcal.infer.files.atomic import atomic_path

C = TypeVar("C")


def config_to_dict(config: Any) -> dict[str, Any]:
    """A (nested) frozen dataclass as a JSON-able dict (tuples become lists)."""
    return dataclasses.asdict(config)


def config_from_dict(cls: type[C], data: dict[str, Any], where: str = "config") -> C:
    """Rebuild a (nested) dataclass from :func:`config_to_dict` output.

    Args:
        cls: dataclass type.
        data: field values; nested dataclasses as dicts, tuples as lists. Missing fields take
            their defaults (configs written by older versions still load).
        where: name used in error messages (e.g. the JSON file).

    Raises:
        ValueError: unknown field, or a value the dataclass rejects.
    """
    if not isinstance(data, dict):
        raise ValueError(
            f"{where}: expected an object for {cls.__name__}, got {type(data).__name__}"
        )
    hints = typing.get_type_hints(cls)
    names = {f.name for f in dataclasses.fields(cls)}  # type: ignore[arg-type]
    unknown = sorted(set(data) - names)
    if unknown:
        raise ValueError(f"{where}: unknown {cls.__name__} field(s) {', '.join(unknown)}")
    kwargs: dict[str, Any] = {}
    for name, value in data.items():
        hint = hints[name]
        if dataclasses.is_dataclass(hint):
            value = config_from_dict(hint, value, f"{where}.{name}")  # type: ignore[arg-type]
        elif typing.get_origin(hint) is tuple and isinstance(value, list):
            value = tuple(value)
        kwargs[name] = value
    try:
        return cls(**kwargs)
    except TypeError as exc:
        raise ValueError(f"{where}: {exc}") from exc


def rng_state() -> dict[str, Any]:
    """torch's global CPU (and CUDA) generator states (weight init; augmentation has its own)."""
    state: dict[str, Any] = {"torch": torch.get_rng_state()}
    if torch.cuda.is_available():
        state["cuda"] = torch.cuda.get_rng_state_all()
    return state


def set_rng_state(state: dict[str, Any]) -> None:
    """Restore what :func:`rng_state` returned."""
    torch.set_rng_state(state["torch"])
    if "cuda" in state and torch.cuda.is_available():
        torch.cuda.set_rng_state_all(state["cuda"])


def save_checkpoint(path: str | os.PathLike[str], payload: dict[str, Any]) -> None:
    """``torch.save`` atomically (a crash mid-write leaves the previous checkpoint intact)."""
    with atomic_path(path) as tmp:
        torch.save(payload, tmp)


def load_checkpoint(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Load a checkpoint written by :func:`save_checkpoint` (tensors to CPU, weights only).

    Raises:
        ValueError: missing or unreadable file.
    """
    p = Path(path)
    if not p.is_file():
        raise ValueError(f"{p}: no checkpoint (has this run completed an epoch?)")
    try:
        return torch.load(p, map_location="cpu", weights_only=True)
    except Exception as exc:  # corrupt/foreign file: report it as bad input
        raise ValueError(f"{p}: not a readable checkpoint ({exc})") from exc
