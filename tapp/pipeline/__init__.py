"""The whole pipeline in one run: TAPP I -> TAPP III -> TAPP II (``tapp pipeline``).

:mod:`tapp.pipeline.spec` reads the pipeline file (the three parts, referenced or inlined, and
the step options); :mod:`tapp.pipeline.steps` runs TAPP III and TAPP II on tape files (for the
commands too: the programs themselves read no tape file); :mod:`tapp.pipeline.run` runs the
steps into one directory and offers the body of a tracking trade study for ITER
(:func:`tapp.pipeline.run.tracking_case`).
"""
