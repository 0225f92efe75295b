"""contactcal.train: training and ONNX export of the contact segmenter (torch, kornia, onnx).

Modules: ``model`` (U-Net), ``augment`` (kornia), ``data`` (datasets → cached tensors),
``digest`` (dataset folders' digests; no torch), ``metrics`` (loss, validation with the
deployed decision), ``checkpoint``, ``report``
(CSV/plots), ``config`` (``TrainConfig``), ``loop`` (``train``), ``threshold`` (min-area tuning),
``export`` (``export_onnx``) and ``commands`` (CLI subcommands; imports no torch at import).
"""
