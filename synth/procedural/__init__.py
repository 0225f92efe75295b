"""A cheap procedural 2D generator of rig frames for cross-checks only (never for training).

Written independently of the Mitsuba renderer (it imports none of ``contactcal.synth``'s
fingerprint, mechanics, camera or render code): its own ring, contact, ridge and camera models,
deliberately different in appearance, so that a method tuned to one renderer shows it.
"""
