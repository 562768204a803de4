"""A running simulation: :class:`~.simulation.Simulation` (the frame loop), its inputs (controls, gusts), the
figures and blow-up checks read from each frame (:mod:`.diagnostics`) and checkpoints."""
