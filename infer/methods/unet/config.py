"""The U-Net's preprocessing configuration: ring search, crop, resize and normalisation."""

from __future__ import annotations

from dataclasses import dataclass

NO_REFERENCE_MODES = ("self", "blank")


@dataclass(frozen=True)
class PreprocessConfig:
    """Crop, resize and normalisation of a frame into the network input."""

    input_size: int = 256  # px, network input side; finer ridges vs ~quadratic time
    crop_factor: float = 2.2  # × outer-ring radius = crop side; 2.0 is the ring's diameter,
    #   the margin keeps the whole ring (context + scale cue) in view; larger wastes resolution
    norm_percentile: float = 99.5  # %, brightness reference P; lower is less sparkle-sensitive
    #   but saturates larger bright areas (big contacts)
    norm_floor_percentile: float = 0.0  # %, dark level F subtracted first: u = (g - F)/(P - F);
    #   0 = none (F = 0, every model before it existed). A floor makes the input invariant to a
    #   camera's black level and contrast setting, but moves every frame whose surround is not
    #   black; a higher percentile is steadier against noise and tracks a brighter surround
    norm_mean: float = 0.25  # fixed offset after dividing by P (typical mean of u); no effect
    #   on the optimum, only on conditioning
    norm_std: float = 0.25  # fixed scale after dividing by P (typical spread of u); idem
    ring_threshold_fraction: float = 0.5  # of the ring search's bright percentile; lower merges
    #   the ring with the background glow, higher breaks a dim ring into pieces
    ring_percentile: float = 99.5  # %, bright level the ring threshold is relative to
    ring_min_contrast: float = 2.0  # bright percentile / median needed to accept a ring;
    #   lower accepts noise as a ring, higher rejects dim rigs
    ring_min_radius_fraction: float = 0.2  # of min(H, W); smaller circles are not the ring
    ring_max_residual_fraction: float = 0.08  # RMS circle-fit residual / radius; higher accepts
    #   ellipses and blobs, lower rejects slightly broken rings
    ring_work_px: int = 512  # px, longest side the ring search works at; smaller is faster, coarser
    fallback_radius_fraction: float = 0.45  # of min(H, W), ring radius assumed when none is found
    ridge_work_px: int = 0  # px, side the ridge-energy channel is measured at (``ridge.py``);
    #   0 = no ridge channel; larger resolves finer ridges but needs a finer JPEG decode
    ridge_sigma_fine_px: float = 0.6  # px at ridge_work_px, DoG inner σ; with the coarse σ it
    #   passes ridge periods of ~3-7 px (0.35-0.55 mm at 288 px across 2.2 ring radii)
    ridge_sigma_coarse_px: float = 1.3  # px at ridge_work_px, DoG outer σ (see fine)
    ridge_smooth_px: float = 2.0  # px at ridge_work_px, σ of the energy smoothing; larger is
    #   steadier but blurs the contact edge
    ridge_norm: float = 0.02  # RMS ridge amplitude / bright level mapped to 1 (typical contact)
    no_reference: str = "self"  # a 2-channel model's reference channel without a reference frame:
    #   "self" = the frame itself (models trained without reference dropout), "blank" = a
    #   constant black plane, the placeholder a model trained with reference dropout has seen

    def __post_init__(self) -> None:
        if self.no_reference not in NO_REFERENCE_MODES:
            raise ValueError(
                f"no_reference must be one of {NO_REFERENCE_MODES}, got {self.no_reference!r}"
            )
        if self.ridge_work_px < 0 or (0 < self.ridge_work_px < self.input_size):
            raise ValueError(
                f"ridge_work_px must be 0 (off) or >= input_size ({self.input_size}), "
                f"got {self.ridge_work_px}"
            )
        ridge = (self.ridge_sigma_fine_px, self.ridge_sigma_coarse_px, self.ridge_smooth_px)
        if not (0.0 < ridge[0] < ridge[1] and ridge[2] > 0.0 and self.ridge_norm > 0.0):
            raise ValueError(
                "ridge band must satisfy 0 < ridge_sigma_fine_px < ridge_sigma_coarse_px, "
                f"ridge_smooth_px > 0 and ridge_norm > 0, got {ridge}, {self.ridge_norm}"
            )
        if self.input_size < 8:
            raise ValueError(f"input_size must be >= 8 px, got {self.input_size}")
        if not self.crop_factor > 0.0:
            raise ValueError(f"crop_factor must be > 0, got {self.crop_factor}")
        for name in ("norm_percentile", "ring_percentile"):
            if not 0.0 < getattr(self, name) <= 100.0:
                raise ValueError(f"{name} must be in (0, 100], got {getattr(self, name)}")
        if not 0.0 <= self.norm_floor_percentile < self.norm_percentile:
            raise ValueError(
                "norm_floor_percentile must be in [0, norm_percentile "
                f"({self.norm_percentile})), got {self.norm_floor_percentile}"
            )
        if not self.norm_std > 0.0:
            raise ValueError(f"norm_std must be > 0, got {self.norm_std}")
        if not 0.0 < self.ring_threshold_fraction < 1.0:
            raise ValueError(
                f"ring_threshold_fraction not in (0, 1): {self.ring_threshold_fraction}"
            )
