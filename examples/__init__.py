"""The bundled example session (``session/``), as package data.

Found through ``importlib.resources`` (``contactcal.infer.pipeline.examples.EXAMPLE_SESSION``).
``make_example.py`` is the developer script that rendered it (needs the ``synth`` extra); nothing
imports it.
"""
