"""Renders the course Cornell box with the diffuse sphere in Mitsuba 3 and prints the wall time.

    python3 scripts/mitsuba_time.py SPP OUT.exr [RES] [SEED]   (MITSUBA_SAMPLER=ldsampler: another sampler)

MITSUBA_VECTOR_WIDTH=8 (or 4) has Dr.Jit compile its kernels for AVX2 with that many lanes
instead of for the host (16 lanes on an AVX-512 host), through Dr.Jit's C function
`jit_llvm_set_target`: how much of Mitsuba's speed is its vector width.

The scene is ../shared/peers/mitsuba_cornell.py's (our conventions: one-sided emitter, box
filter, camera through the front face). One render at the same sample count comes first and is
not timed, so that the time is the render's own and not Dr.Jit's kernel compilation (its
kernels are also cached on disk across runs). Used by scripts/vs-mitsuba.sh.
"""
import os
import sys
import time

here = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(here, "..", "..", "shared", "peers"))
import mitsuba as mi  # noqa: E402

mi.set_variant(os.environ.get("MITSUBA_VARIANT", "llvm_ad_rgb"))


def set_vector_width(width):
    """Dr.Jit's LLVM kernels for AVX2 (x86-64-v3) with `width` lanes. Dr.Jit's Python
    module does not expose its target, so the C++ function is called by its mangled name."""
    import ctypes
    import drjit

    core = ctypes.CDLL(os.path.join(os.path.dirname(drjit.__file__), "libdrjit-core.so"))
    set_target = core._Z19jit_llvm_set_targetPKcS0_j  # jit_llvm_set_target(cpu, features, width)
    set_target.argtypes = [ctypes.c_char_p, ctypes.c_char_p, ctypes.c_uint32]
    features = b"+avx2,+avx,+fma,+f16c,+bmi,+bmi2,+popcnt,+sse4.2,+sse4.1"
    set_target(b"x86-64-v3", features, width)


if os.environ.get("MITSUBA_VECTOR_WIDTH"):
    # Dr.Jit needs FMA and gathers: widths below AVX2's are still AVX2 code, on fewer lanes.
    set_vector_width(int(os.environ["MITSUBA_VECTOR_WIDTH"]))
import mitsuba_cornell  # noqa: E402

spp, out = int(sys.argv[1]), sys.argv[2]
res = int(sys.argv[3]) if len(sys.argv) > 3 else 256
seed = int(sys.argv[4]) if len(sys.argv) > 4 else 0
setup = mitsuba_cornell.cornell(True, res=res)
# MITSUBA_SAMPLER: another of Mitsuba's samplers in place of the peer's `independent`.
# The count as rendered, which such samplers want at load (a square power of two for
# `ldsampler`, which warns on stdout otherwise); `mi.render(spp=...)` sets it anyway.
setup["sensor"]["sampler"]["type"] = os.environ.get("MITSUBA_SAMPLER", "independent")
setup["sensor"]["sampler"]["sample_count"] = spp
scene = mi.load_dict(setup)
mi.Bitmap(mi.render(scene, spp=spp, seed=seed + 7919))  # the untimed first render
start = time.perf_counter()
image = mi.render(scene, spp=spp, seed=seed)
# Evaluating the image into a bitmap is part of the render: Dr.Jit is lazy.
bitmap = mi.Bitmap(image)
elapsed = time.perf_counter() - start
bitmap.write(out)
print(f"{elapsed:.4f}")
