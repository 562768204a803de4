"""The CUDA path compiles, even on a machine without a GPU.

Warp ships NVRTC, so every kernel module can be compiled to PTX for a GPU architecture without a driver.
This catches CUDA-only compile errors (code that is valid C++ for the CPU but not device code) on every CI
run; running the compiled kernels still needs a GPU (README, "CUDA").
"""

import importlib

import pytest
import warp as wp

from warpsim.physics.kernels import MODULES, frame

KERNEL_MODULES = tuple(module.__name__ for module in (*MODULES, frame))  # the solvers' and the runner's


def _nvrtc_archs() -> set[int]:
    wp.init()
    runtime = getattr(getattr(getattr(wp, "_src", None), "context", None), "runtime", None)
    return set(getattr(runtime, "nvrtc_supported_archs", ()) or ())


@pytest.mark.parametrize("name", KERNEL_MODULES)
def test_kernel_module_compiles_to_ptx(name, tmp_path):
    archs = _nvrtc_archs()
    if not archs:
        pytest.skip("this Warp build has no NVRTC")
    arch = 90 if 90 in archs else max(archs)
    module = importlib.import_module(name)
    paths = wp.compile_aot_module(name, arch=arch, module_dir=tmp_path, use_ptx=True)
    assert paths and all(p.suffix == ".ptx" and p.stat().st_size > 0 for p in paths)
    ptx = "".join(p.read_text() for p in paths)
    kernels = [v.key for v in vars(module).values() if isinstance(v, wp.Kernel) and v.func.__module__ == name]
    assert kernels
    for key in kernels:
        assert f"{key}_" in ptx and "cuda_kernel_forward" in ptx, f"{key} missing from the PTX of {name}"
