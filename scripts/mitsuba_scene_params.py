#!/usr/bin/env python3
"""What Mitsuba 3's own loader makes of Mitsuba scenes, as plain JSON.

    scripts/mitsuba_scene_params.py SCENE.xml...

Prints a JSON list with one object per scene: the sensor (its to_world matrix, x_fov and
film size), every shape in Mitsuba's order (its class, face count when it is a mesh, its
world-space bounding box, its BSDF's plugin classes outermost first and the BSDF's plain
parameters from mi.traverse, its area emitter's), and every emitter that is not an area
light (its class and plain parameters). Values are lists of floats. Textures' data and
to_uv transforms are left out; a checkerboard's two values are plain and kept
(`reflectance.color0`). The wrappers' prefixes (`nested_bsdf.`, `brdf_0.`) and Mitsuba's
`.value` suffix are dropped, so a key names the parameter of the innermost BSDF.

The scenes are loaded in the scalar_rgb variant, which turns named IORs and spectra into
RGB as every RGB variant does, with optimize=False (otherwise Mitsuba merges identical
meshes into one shape) and parallel=False (so that shapes keep the file's order), each from
its own folder, as Mitsuba's render tests do.
"""

import json
import os
import re
import sys

import mitsuba as mi

mi.set_variant("scalar_rgb")

WRAPPER_PREFIX = re.compile(r"^(nested_bsdf\.|brdf_0\.)+")
# A wrapping BSDF names what it wraps on a line of its own in its description.
NESTED_CLASS = re.compile(r"^\s*(?:nested_bsdf|brdf\[0\]) = (\w+)\[", re.MULTILINE)


def plain(value):
    """A traversed value as a list of floats, or None when it is not a plain value."""
    if isinstance(value, (bool, int, float)):
        return [float(value)]
    if isinstance(value, (mi.Color3f, mi.Point3f, mi.Vector3f, mi.ScalarVector2u)):
        return [float(x) for x in value]
    if isinstance(value, mi.ScalarAffineTransform4f):
        return matrix(value)
    return None


def matrix(transform):
    m = transform.matrix
    return [[float(m[r][c]) for c in range(4)] for r in range(4)]


def parameters(obj):
    """obj's plain traversed parameters, wrapper prefixes and `.value` suffixes dropped."""
    out = {}
    for key, value in mi.traverse(obj).items():
        v = plain(value)
        if v is None or key.endswith("to_uv"):
            continue
        key = WRAPPER_PREFIX.sub("", key)
        key = key[: -len(".value")] if key.endswith(".value") else key
        out[key] = v
    return out


def bsdf_classes(bsdf):
    return [bsdf.class_name()] + NESTED_CLASS.findall(str(bsdf))


def bbox(b):
    return [[float(x) for x in b.min], [float(x) for x in b.max]]


def shape(s):
    emitter = s.emitter()
    return {
        "class": s.class_name(),
        "faces": int(s.face_count()) if s.is_mesh() else None,
        "bbox": bbox(s.bbox()),
        "bsdf": bsdf_classes(s.bsdf()),
        "bsdf_params": parameters(s.bsdf()),
        "area_emitter": parameters(emitter) if emitter is not None else None,
    }


def scene(path):
    here = os.getcwd()
    os.chdir(os.path.dirname(os.path.abspath(path)))
    try:
        s = mi.load_file(os.path.basename(path), parallel=False, optimize=False)
    finally:
        os.chdir(here)
    sensor = s.sensors()[0]
    film = sensor.film()
    return {
        "file": path,
        "bbox": bbox(s.bbox()),
        "sensor": {
            "class": sensor.class_name(),
            "to_world": matrix(sensor.world_transform()),
            "x_fov": float(mi.traverse(sensor)["x_fov"]),
            "film_size": [int(x) for x in film.size()],
        },
        "shapes": [shape(x) for x in s.shapes()],
        "emitters": [
            {"class": e.class_name(), "params": parameters(e)}
            for e in s.emitters()
            if not mi.has_flag(e.flags(), mi.EmitterFlags.Surface)
        ],
    }


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__.strip().splitlines()[2].strip())
    json.dump([scene(p) for p in sys.argv[1:]], sys.stdout, indent=1)
    print()
