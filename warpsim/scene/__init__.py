"""Scenes: TOML descriptors read and checked (:mod:`.descriptor`), ``--set``/``--vary`` values, control schedules,
the model built from a descriptor (:mod:`.build`) and the scene files shipped with the package (``files/``)."""
