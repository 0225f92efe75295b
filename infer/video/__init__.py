"""Video or camera input: steady pressure steps of a recording → a calibration session."""
