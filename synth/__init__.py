"""contactcal.synth."""
