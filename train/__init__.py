"""contactcal.train."""
