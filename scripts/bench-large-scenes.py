#!/usr/bin/env python3
"""Loading large Mitsuba 3 scenes, trilux against Mitsuba 3: the cost of what a user's own
scene has many of, where a reader or a per-scene pass that is linear in the wrong thing shows.

Usage: scripts/bench-large-scenes.py [RENDER] [--repeats R] [--keep DIR]

Writes five scenes into a temporary folder (or DIR with --keep, reused when present):
  instances   10,000 `instance`s (moved and turned) of a shapegroup of a 20k-triangle PLY
  ply         one binary PLY of 2M triangles (a 1000 x 1000 height field)
  shapes      10,000 `cube`s, each with its own `ref` to one BSDF, and 5,000 emitting
              `rectangle`s
  obj         the same 2M triangles as an OBJ file
  plastics    500 `sphere`s, each with a `roughplastic` of its own roughness (Beckmann,
              Mitsuba's default): every one precomputes its coat's tables
For each, the median of R runs (default 3, interleaved) of trilux's scene load and Accel build
(`render -input SCENE --engine path -size 64 64 -num_antialias_samples 1 --stats`, the two
times of its first line, summed: Mitsuba's load builds its acceleration structure too) and of
Mitsuba 3's `mi.load_file` (llvm_ad_rgb, the variant its users render with; scalar_rgb where
that cannot load). Needs numpy and `pip install mitsuba`.
"""

import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

CAMERA = """<integrator type="path"><integer name="max_depth" value="3"/></integrator>
<sensor type="perspective"><float name="fov" value="60"/>
<transform name="to_world"><lookat origin="0,30,-60" target="0,0,0" up="0,1,0"/></transform>
<film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="64"/></film>
<sampler type="independent"><integer name="sample_count" value="1"/></sampler></sensor>
<emitter type="constant"><rgb name="radiance" value="1"/></emitter>
"""


def height_field(n):
    """An n x n grid of vertices over [-40, 40]^2 and its 2 (n - 1)^2 triangles."""
    xs, zs = np.meshgrid(np.linspace(-40, 40, n), np.linspace(-40, 40, n))
    ys = np.sin(xs * 0.3) * np.cos(zs * 0.2)
    v = np.stack([xs.ravel(), ys.ravel(), zs.ravel()], 1).astype("<f4")
    i = np.arange(n * n).reshape(n, n)
    a, b, c, d = i[:-1, :-1].ravel(), i[1:, :-1].ravel(), i[1:, 1:].ravel(), i[:-1, 1:].ravel()
    f = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)]).astype("<i4")
    return v, f


def write_ply(path, v, f):
    with open(path, "wb") as out:
        out.write((f"ply\nformat binary_little_endian 1.0\nelement vertex {len(v)}\n"
                   "property float x\nproperty float y\nproperty float z\n"
                   f"element face {len(f)}\nproperty list uchar int vertex_indices\nend_header\n").encode())
        out.write(v.tobytes())
        faces = np.zeros(len(f), dtype=[("n", "u1"), ("i", "<i4", 3)])
        faces["n"], faces["i"] = 3, f
        out.write(faces.tobytes())


def write_obj(path, v, f):
    with open(path, "w") as out:
        out.writelines(f"v {x:.5f} {y:.5f} {z:.5f}\n" for x, y, z in v)
        out.writelines(f"f {p + 1} {q + 1} {r + 1}\n" for p, q, r in f)


def scene(path, body):
    with open(path, "w") as out:
        out.write(f'<scene version="3.0.0">\n{CAMERA}{body}</scene>\n')


def write_scenes(folder):
    rng = np.random.default_rng(1)
    v, f = height_field(101)
    write_ply(os.path.join(folder, "small.ply"), v * np.float32(0.02), f)
    instances = ['<shape type="shapegroup" id="g"><shape type="ply">'
                 '<string name="filename" value="small.ply"/><bsdf type="diffuse"/></shape></shape>']
    for k in range(10_000):
        x, z = rng.uniform(-40, 40, 2)
        instances.append(f'<shape type="instance"><ref id="g"/><transform name="to_world">'
                         f'<rotate y="1" angle="{rng.uniform(0, 360):.2f}"/>'
                         f'<translate x="{x:.3f}" z="{z:.3f}"/></transform></shape>')
    scene(os.path.join(folder, "instances.xml"), "\n".join(instances) + "\n")

    v, f = height_field(1000)
    write_ply(os.path.join(folder, "terrain.ply"), v, f)
    write_obj(os.path.join(folder, "terrain.obj"), v, f)
    for kind in ("ply", "obj"):
        scene(os.path.join(folder, f"{kind}.xml"),
              f'<shape type="{kind}"><string name="filename" value="terrain.{kind}"/><bsdf type="diffuse"/></shape>\n')

    shapes = ['<bsdf type="diffuse" id="w"><rgb name="reflectance" value="0.6"/></bsdf>']
    for x, z in rng.uniform(-40, 40, (10_000, 2)):
        shapes.append(f'<shape type="cube"><ref id="w"/><transform name="to_world"><scale value="0.4"/>'
                      f'<translate x="{x:.3f}" y="0.4" z="{z:.3f}"/></transform></shape>')
    for x, z in rng.uniform(-40, 40, (5_000, 2)):
        shapes.append(f'<shape type="rectangle"><transform name="to_world"><scale value="0.2"/>'
                      f'<rotate x="1" angle="90"/><translate x="{x:.3f}" y="3" z="{z:.3f}"/></transform>'
                      '<emitter type="area"><rgb name="radiance" value="5"/></emitter></shape>')
    scene(os.path.join(folder, "shapes.xml"), "\n".join(shapes) + "\n")

    plastics = []
    for k in range(500):
        x, z = k % 25 - 12, k // 25 - 10
        plastics.append(f'<shape type="sphere"><point name="center" x="{2 * x}" y="1" z="{2 * z}"/>'
                        f'<bsdf type="roughplastic"><float name="alpha" value="{0.05 + 0.3 * k / 500:.4f}"/>'
                        '</bsdf></shape>')
    scene(os.path.join(folder, "plastics.xml"), "\n".join(plastics) + "\n")


def ours(render, path):
    done = subprocess.run([render, "-input", path, "--engine", "path", "-size", "64", "64",
                           "-num_antialias_samples", "1", "-o", path + ".exr", "--stats"],
                          capture_output=True, text=True)
    found = re.search(r"scene load ([0-9.]+) s, accel build \([a-z]+\) ([0-9.]+) s", done.stderr)
    if done.returncode != 0 or not found:
        sys.exit(f"{path}: trilux failed: {done.stderr.strip()[-300:]}")
    return float(found.group(1)) + float(found.group(2))


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    parser = argparse.ArgumentParser()
    parser.add_argument("render", nargs="?", default=os.path.join(here, "..", "target", "release", "render"))
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--keep", default=None)
    args = parser.parse_args()
    from mitsuba_variant import load_mitsuba

    mi, variant = load_mitsuba()

    folder = args.keep or tempfile.mkdtemp()
    os.makedirs(folder, exist_ok=True)
    if not os.path.exists(os.path.join(folder, "plastics.xml")):
        write_scenes(folder)
    print(f"# Mitsuba {mi.__version__} {variant}; medians of {args.repeats}")
    print("| scene | trilux load + build (s) | Mitsuba load_file (s) | trilux / Mitsuba |")
    print("|---|---|---|---|")
    for name in ("instances", "ply", "obj", "shapes", "plastics"):
        path = os.path.join(folder, f"{name}.xml")
        mine, theirs = [], []
        for _ in range(args.repeats):
            mine.append(ours(args.render, path))
            start = time.perf_counter()
            mi.load_file(path)
            theirs.append(time.perf_counter() - start)
        a, b = statistics.median(mine), statistics.median(theirs)
        print(f"| {name} | {a:.3f} | {b:.3f} | {a / b:.2f} |")


if __name__ == "__main__":
    main()
