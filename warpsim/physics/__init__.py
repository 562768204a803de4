"""The physics: the model's arrays, the builder that fills them, the solvers and their Warp kernels, the terrain and
the typed settings. It reads no files and knows no TOML; it imports nothing else of warpsim."""
