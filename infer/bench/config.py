"""What ``contactcal bench`` measures (one frozen settings object shared by its parts)."""

from __future__ import annotations

from dataclasses import dataclass, field

from contactcal.infer.bench.scoring import PRESSURE_BINS

#: ``results.json``'s ``reference`` when each session's zero-pressure frame is the reference.
SESSION_REFERENCE = "session zero-pressure frame"


@dataclass(frozen=True)
class BenchConfig:
    """What the benchmark measures."""

    repeats: int = 5  # timing runs per configuration; the median is reported
    timing_frames: int = 6  # frames timed per run (mid-range pressures, several fingers)
    full_size: tuple[int, int] = (2592, 1944)  # (width, height): rig resolution for speed, px
    threads: tuple[int, ...] = (1, 2)  # U-Net threads timed (onnxruntime and OpenCV)
    classical_scales: tuple[float, ...] = (1.0, 0.25)  # full and reduced-resolution baseline
    bins: tuple[tuple[float, float], ...] = field(default=PRESSURE_BINS)  # kPa, [lo, hi)
    robustness_frames: int = 0  # frames of the robustness suite (0: not run); each costs
    #   ~50 perturbed measurements per method, so more frames steady the medians but cost time
    seed: int = 0  # seed of the robustness suite's random perturbations (noise, angles)
    variants: tuple[tuple[str, str], ...] = ()  # further U-Net models (label, ONNX path),
    #   scored and timed beside the main one as method ``unet[label]`` (e.g. an INT8 variant)
    use_reference: bool = True  # False: every method measures without the session's
    #   zero-pressure frame (the U-Net then gets its no-reference placeholder)

    def __post_init__(self) -> None:
        if self.repeats < 1 or self.timing_frames < 1:
            raise ValueError("repeats and timing_frames must be >= 1")
        if len(self.full_size) != 2 or min(self.full_size) < 1:
            raise ValueError(f"full_size must be (width, height) >= 1, got {self.full_size}")
        if not self.threads or min(self.threads) < 1:
            raise ValueError(f"threads must be >= 1, got {self.threads}")
        if self.robustness_frames < 0:
            raise ValueError(f"robustness_frames must be >= 0, got {self.robustness_frames}")
