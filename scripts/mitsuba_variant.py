"""Mitsuba 3 as the scripts that measure it beside trilux load it: its users' variant,
llvm_ad_rgb (Dr.Jit's LLVM backend at the host's own vector width, through Debian's
libLLVM.so.19 unless DRJIT_LIBLLVM_PATH names another), or scalar_rgb where that cannot load.
"""

import glob
import os


def load_mitsuba():
    """Imports Mitsuba 3 and sets its variant; returns the module and the variant's name."""
    if not os.environ.get("DRJIT_LIBLLVM_PATH"):
        for candidate in glob.glob("/usr/lib/x86_64-linux-gnu/libLLVM.so.19*") + glob.glob("/usr/lib/llvm-19/lib/libLLVM.so*"):
            os.environ["DRJIT_LIBLLVM_PATH"] = candidate
            break
    import mitsuba as mi

    variant = "llvm_ad_rgb"
    try:
        mi.set_variant(variant)
    except Exception:
        variant = "scalar_rgb"
        mi.set_variant(variant)
    return mi, variant
