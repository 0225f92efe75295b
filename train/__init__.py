"""contactcal.train: training and ONNX export of the contact segmenter (torch, kornia, onnx).

Modules: ``model`` (U-Net), ``augment`` (kornia), ``data`` (datasets → cached tensors),
``digest`` (dataset folders' digests; no torch), ``metrics`` (loss, validation with the
deployed decision), ``checkpoint``, ``report``
(CSV/plots), ``config`` (``TrainConfig``), ``loop`` (``train``), ``threshold`` (min-area tuning),
``export`` (``export_onnx``), ``run_folder`` (what ``--out`` may be; no torch), ``resume``
(what ``--resume`` continues), ``train_args`` (the options that build a ``TrainConfig``) and
``commands`` (CLI subcommands; imports no torch at import).
"""
