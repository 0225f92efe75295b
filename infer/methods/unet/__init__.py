"""methods/unet."""
