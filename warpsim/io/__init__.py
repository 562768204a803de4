"""Outputs: animated USD stages (:mod:`warpsim.io.usd`) and streaming HDF5 recordings (:mod:`warpsim.io.hdf5`)."""
