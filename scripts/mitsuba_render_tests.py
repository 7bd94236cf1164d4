#!/usr/bin/env python3
"""Mitsuba 3's render-test scenes rendered by Mitsuba 3 and by trilux, side by side.

Usage: scripts/mitsuba_render_tests.py [RENDER] [--spp N] [--size S] [--repeats R] [--only TEXT[,TEXT...]]
                                      [--root DIR]

For each scene of ../shared/mitsuba-tests (both renderers reading the same XML), at equal
samples per pixel: the wall time of each (median of R runs, the two interleaved), the relMSE
of each against Mitsuba's reference image, time × relMSE, ours over Mitsuba's, our mean over
the reference's, and whether ours passes tests/shared_inputs.rs' rule (relMSE at most 1.5×
what Mitsuba's estimator has at the same samples, from the reference's variance, plus 2e-4;
mean within 2%). --root is the folder of scene groups (default ../shared/mitsuba-tests'
tests/scenes; a checkout of Mitsuba's test data has more). With --size S both render at S×S
(trilux's -size, Mitsuba's film overridden), where the scene's reference image no longer
applies: the reference is then Mitsuba's own render at --reference-spp samples (default 1024,
seed 1, where the timed renders take seed 0), kept in --reference-dir (default: a temporary
folder) for the next run; the rule column is then empty (the suite's variance is for its own
film), and the reference's own noise, about spp / reference-spp of Mitsuba's relMSE, is in
both relMSEs alike.

Mitsuba runs as its users run it: variant llvm_ad_rgb at the host's own vector width
(DRJIT_LIBLLVM_PATH is set to Debian's libLLVM.so.19 unless given), scalar_rgb where that
cannot load. RENDER is trilux's binary (default target/release/render).
"""

import argparse
import glob
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    parser = argparse.ArgumentParser()
    parser.add_argument("render", nargs="?", default=os.path.join(here, "..", "target", "release", "render"))
    parser.add_argument("--spp", type=int, default=256)
    parser.add_argument("--size", type=int, default=None)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--only", default="", help="only the scenes whose path contains one of the comma-separated TEXTs")
    parser.add_argument("--root", default=os.path.join(here, "..", "..", "shared", "mitsuba-tests", "tests", "scenes"))
    parser.add_argument("--reference-spp", type=int, default=1024)
    parser.add_argument("--reference-dir", default=None)
    args = parser.parse_args()

    from mitsuba_variant import load_mitsuba

    mi, variant = load_mitsuba()
    cpu = subprocess.run(["sh", "-c", "grep -m1 'model name' /proc/cpuinfo | cut -d: -f2"], capture_output=True, text=True).stdout.strip()
    width = "AVX-512 (16 lanes)" if "avx512f" in open("/proc/cpuinfo").read() else "AVX2 (8 lanes)"
    print(f"# host: {cpu}, {width}; Mitsuba {mi.__version__} {variant}; {args.spp} spp" + (f", {args.size}x{args.size}" if args.size else ", the scenes' own film"))

    wanted = args.only.split(",")
    scenes = [s for s in sorted(glob.glob(os.path.join(args.root, "*", "*.xml")))
              if os.path.basename(s).startswith(("test_", "scene_")) and any(w in s for w in wanted)]
    out = tempfile.mkdtemp()
    references = args.reference_dir or out
    os.makedirs(references, exist_ok=True)
    print(f"{'scene':44} {'ours s':>8} {'Mitsuba s':>9} {'time x':>7} {'ours relMSE':>11} {'Mitsuba':>9} {'t*relMSE x':>10} {'mean x':>7} rule")
    ratios, efficiency = [], []
    for scene in scenes:
        name = os.path.basename(scene)[:-4]
        folder = os.path.dirname(scene)
        ours_exr = os.path.join(out, name + ".exr")
        ours_cmd = [args.render, "-input", scene, "--engine", "path", "-num_antialias_samples", str(args.spp), "-o", ours_exr, "--quiet"]
        if args.size:
            ours_cmd += ["-size", str(args.size), str(args.size)]
        try:
            mi_scene = mi.load_file(scene)
        except Exception as e:
            print(f"{name:44} Mitsuba cannot load it: {str(e)[:60]}")
            continue
        sensor = mi_scene.sensors()[0]
        if args.size:
            # The scene's camera with a film of the size asked (its own is fixed in the XML).
            fov = mi.traverse(sensor)["x_fov"]
            fov = float(fov[0]) if hasattr(fov, "__len__") else float(fov)
            matrix = np.array(sensor.world_transform().matrix).reshape(4, 4).tolist()
            sensor = mi.load_dict({"type": "perspective", "to_world": mi.ScalarTransform4f(matrix), "fov": fov,
                                   "film": {"type": "hdrfilm", "width": args.size, "height": args.size,
                                            "rfilter": {"type": "box"}}})
        ours_times, theirs_times = [], []
        theirs_img = None
        ok = True
        for _ in range(args.repeats):
            start = time.perf_counter()
            done = subprocess.run(ours_cmd, capture_output=True, text=True)
            ours_times.append(time.perf_counter() - start)
            if done.returncode != 0:
                print(f"{name:44} trilux refuses it: {done.stderr.strip().splitlines()[-1][:70]}")
                ok = False
                break
            start = time.perf_counter()
            image = mi.render(mi_scene, sensor=sensor, spp=args.spp)
            theirs_img = np.array(image)[..., :3]
            theirs_times.append(time.perf_counter() - start)
        if not ok:
            continue
        ours_t, theirs_t = statistics.median(ours_times), statistics.median(theirs_times)
        stem = name.rsplit("_", 1)[0]
        if args.size:
            kept = os.path.join(references, f"{name}_{args.size}_{args.reference_spp}spp.exr")
            if not os.path.exists(kept):
                mi.Bitmap(mi.render(mi_scene, sensor=sensor, spp=args.reference_spp, seed=1)).write(kept)
            ref = np.array(mi.Bitmap(kept))[..., :3]
        else:
            ref = np.array(mi.Bitmap(os.path.join(folder, "refs", stem + "_ref_rgb.exr")))[..., :3]
        ours_img = np.array(mi.Bitmap(ours_exr))[..., :3]
        relmse = lambda a: float(np.mean((a - ref) ** 2 / (ref ** 2 + 1e-2)))
        ours_e, theirs_e = relmse(ours_img), relmse(theirs_img)
        mean = float(ours_img.sum() / ref.sum())
        rule = ""
        if not args.size:
            variance = np.array(mi.Bitmap(os.path.join(folder, "refs", stem + "_ref_rgb_var.exr")))[..., :3]
            estimator = float(np.mean(np.maximum(variance, 0) / args.spp / (ref ** 2 + 1e-2)))
            passes = ours_e <= 1.5 * estimator + 2e-4 and abs(mean - 1) <= 0.02
            rule = "pass" if passes else "FAIL"
        print(f"{name:44} {ours_t:8.3f} {theirs_t:9.3f} {ours_t / theirs_t:7.2f} {ours_e:11.2e} {theirs_e:9.2e} {ours_t * ours_e / (theirs_t * theirs_e):10.2f} {mean:7.3f} {rule}")
        ratios.append(ours_t / theirs_t)
        efficiency.append(ours_t * ours_e / (theirs_t * theirs_e))
    if ratios:
        print(f"# median time ratio, ours over Mitsuba's: {statistics.median(ratios):.2f}; "
              f"median time x relMSE ratio: {statistics.median(efficiency):.2f}; over {len(ratios)} scenes")


if __name__ == "__main__":
    sys.exit(main())
