"""Our caustic scene (scenes/glass_sphere_caustic.obj) set up in Mitsuba 3, for side-by-side
figures, and a render of it:

    python3 scripts/mitsuba_caustic.py SPP OUT.exr [RES] [SEED]
    python3 scripts/mitsuba_caustic.py reference BATCHES SPP OUT.exr [RES]

The first prints the wall time of the render (a first render at the same sample count is not
timed, so that Dr.Jit's kernel compilation is not counted). The second writes the mean of
BATCHES renders of SPP samples with different seeds: a converged reference (16 × 2,048 for
the 32k-spp references of BENCHMARKS.md). Our conventions, as
../shared/peers/mitsuba_cornell.py sets them for the Cornell box:
  * geometry copied from the scene file; each quad 'f a b c d' becomes triangles (a,b,c),
    (a,c,d), whose winding gives the geometric normal n = (b-a)x(c-a);
  * the light (material 0) is a one-sided area emitter of radiance 60 along its normal (down),
    black otherwise;
  * the glass sphere (ior 1.5, `transmitted 0.95`): a smooth dielectric whose reflection and
    refraction are both scaled by 0.95, as our engines scale both branches;
  * our camera: position (0, 4.5, 7), looking at (0, 0.6, 0), up (0, 1, 0), a full field of
    view of 0.7 rad across the image; box filter;
  * a black background: render ours with `background_color 0 0 0` appended (our default, white,
    is seen by camera rays and through glass but lights nothing, which Mitsuba has no emitter
    for).
Checked: 128×128, Mitsuba 256 spp against our path tracer 256 spp, image means
0.1006/0.0893/0.0857 against 0.1005/0.0892/0.0856, and within 1% in each band of rows.
Needs `pip install mitsuba`; the default variant llvm_ad_rgb needs Debian's libllvm19 and
DRJIT_LIBLLVM_PATH (MITSUBA_VARIANT=scalar_rgb runs without them, slowly).
"""
import math
import os
import sys
import tempfile
import time

import mitsuba as mi

VERTS = [(-0.25, 4, -0.25), (0.25, 4, -0.25), (0.25, 4, 0.25), (-0.25, 4, 0.25),
         (-4, 0, -4), (-4, 0, 4), (4, 0, 4), (4, 0, -4),
         (-4, 0, -4), (4, 0, -4), (4, 4, -4), (-4, 4, -4)]
LIGHT, FLOOR, WALL = (1, 2, 3, 4), (5, 6, 7, 8), (9, 10, 11, 12)
SPHERE = ((0.0, 1.2, 0.0), 0.8)
LE = 60.0


def quad_obj(quad):
    """An OBJ file of one quad as two triangles; returns its path."""
    fd, path = tempfile.mkstemp(suffix=".obj")
    with os.fdopen(fd, "w") as f:
        for v in (VERTS[i - 1] for i in quad):
            f.write("v %g %g %g\n" % v)
        f.write("f 1 2 3\nf 1 3 4\n")
    return path


def diffuse(rgb):
    return {"type": "diffuse", "reflectance": {"type": "rgb", "value": rgb}}


def scene(res=256, max_depth=64, rr_depth=5):
    return {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": max_depth, "rr_depth": rr_depth},
        "sensor": {
            "type": "perspective",
            "fov": math.degrees(0.7), "fov_axis": "larger",
            "to_world": mi.ScalarTransform4f().look_at(
                origin=[0, 4.5, 7], target=[0, 0.6, 0], up=[0, 1, 0]),
            "film": {"type": "hdrfilm", "width": res, "height": res,
                     "pixel_format": "rgb", "rfilter": {"type": "box"}},
        },
        "light": {"type": "obj", "filename": quad_obj(LIGHT), "face_normals": True,
                  "bsdf": diffuse([0, 0, 0]),
                  "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [LE] * 3}}},
        "floor": {"type": "obj", "filename": quad_obj(FLOOR), "face_normals": True,
                  "bsdf": diffuse([0.75, 0.75, 0.75])},
        "wall": {"type": "obj", "filename": quad_obj(WALL), "face_normals": True,
                 "bsdf": diffuse([0.6, 0.3, 0.2])},
        "glass": {"type": "sphere", "center": list(SPHERE[0]), "radius": SPHERE[1],
                  "bsdf": {"type": "dielectric", "int_ior": 1.5, "ext_ior": 1.0,
                           "specular_reflectance": 0.95, "specular_transmittance": 0.95}},
    }


def reference(batches, spp, out, res):
    import numpy as np
    loaded = mi.load_dict(scene(res=res))
    total = None
    for b in range(batches):
        image = np.array(mi.render(loaded, spp=spp, seed=1000 + b))
        total = image if total is None else total + image
    mi.Bitmap(total / batches).write(out)


if __name__ == "__main__":
    mi.set_variant(os.environ.get("MITSUBA_VARIANT", "llvm_ad_rgb"))
    if sys.argv[1] == "reference":
        reference(int(sys.argv[2]), int(sys.argv[3]), sys.argv[4],
                  int(sys.argv[5]) if len(sys.argv) > 5 else 256)
        sys.exit(0)
    spp, out = int(sys.argv[1]), sys.argv[2]
    res = int(sys.argv[3]) if len(sys.argv) > 3 else 256
    seed = int(sys.argv[4]) if len(sys.argv) > 4 else 0
    loaded = mi.load_dict(scene(res=res))
    mi.Bitmap(mi.render(loaded, spp=spp, seed=seed + 7919))  # the untimed first render
    start = time.perf_counter()
    bitmap = mi.Bitmap(mi.render(loaded, spp=spp, seed=seed))
    elapsed = time.perf_counter() - start
    bitmap.write(out)
    print(f"{elapsed:.4f}")
