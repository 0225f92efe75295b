"""The shipped U-Net (``contact_unet.onnx``) and its card, as package data.

Found through ``importlib.resources`` (``contactcal.infer.methods.unet.runner.DEFAULT_MODEL``), in
wheels and editable installs alike. No code.
"""
