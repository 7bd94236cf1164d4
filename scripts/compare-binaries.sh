#!/usr/bin/env bash
# Renders the docs gallery's (docs/gallery/) and the course's command lines with two `render` binaries and
# compares the outputs byte for byte: the check that a refactoring changed no image.
#
#   scripts/compare-binaries.sh OLD_RENDER NEW_RENDER [SCENE_DIR]
#
# SCENE_DIR (default: scenes/) holds the scene files the lines name. Each line renders at the
# gallery's size (200×200; the L-shaped room 300×150) with both binaries into a temporary
# folder; a line whose outputs differ, or that fails with one binary only, is reported and the
# script exits 1. Ray-tree outputs (PNG and OBJ) are compared too.
set -euo pipefail
old=$(realpath "$1")
new=$(realpath "$2")
scenes=$(realpath "${3:-$(dirname "$0")/../scenes}")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

S="-size 200 200"
lines=(
  # The course's ray-tracing lines (gallery rt01–rt11).
  "rt01|$S -input reflective_spheres.obj"
  "rt02|$S -input reflective_spheres.obj -num_bounces 1"
  "rt03|$S -input reflective_spheres.obj -num_bounces 3 -num_shadow_samples 1"
  "rt04|$S -input textured_plane_reflective_sphere.obj -num_bounces 1 -num_shadow_samples 1"
  "rt05|$S -input textured_plane_reflective_sphere.obj -num_bounces 1 -num_shadow_samples 4"
  "rt06|$S -input textured_plane_reflective_sphere.obj -num_bounces 1 -num_shadow_samples 9 -num_antialias_samples 9"
  "rt07|$S -input cornell_box_diffuse_sphere.obj -ambient_light 0.0 0.0 0.0"
  "rt08|$S -input cornell_box_diffuse_sphere.obj -ambient_light 0.0 0.0 0.0 -num_shadow_samples 1"
  "rt09|$S -input cornell_box_diffuse_sphere.obj -ambient_light 0.2 0.2 0.2 -num_shadow_samples 1"
  "rt10|$S -input cornell_box_diffuse_sphere.obj -ambient_light 0.2 0.2 0.2 -num_shadow_samples 10"
  "rt11|$S -input cornell_box_diffuse_sphere.obj -ambient_light 0.2 0.2 0.2 -num_shadow_samples 100"
  "rtdof|$S -input reflective_spheres.obj -num_shadow_samples 4 -num_antialias_samples 16 --aperture 0.05"
  "rttree|$S -input reflective_spheres.obj -num_bounces 3 -num_shadow_samples 1 --ray-tree 100 100"
  "raycast|$S -input textured_plane_reflective_sphere.obj --engine raycast"
  "path|$S -input cornell_box_diffuse_sphere.obj --engine path -num_antialias_samples 16"
  "pathglass|$S -input glass_sphere_caustic.obj --engine path -num_antialias_samples 16"
  # The course's radiosity lines and the radiosity gallery (rad01–rad11).
  "radc1|$S -input cornell_box.obj"
  "radc2|$S -input cornell_box_diffuse_sphere.obj -sphere_rasterization 16 12"
  "radc3|$S -input cornell_box_diffuse_sphere.obj -sphere_rasterization 16 12 -num_shadow_samples 1"
  "rad01|$S -input cornell_box.obj --engine radiosity --subdivide 3 -interpolate"
  "radring|$S -input reflective_ring.obj --engine radiosity -num_shadow_samples 1 -num_form_factor_samples 4 --subdivide 1 -interpolate"
  "rad02|-size 300 150 -input l.obj -num_shadow_samples 1 --subdivide 3 -interpolate"
  "rad03|-size 300 150 -input l.obj -num_shadow_samples 1 --subdivide 2 --wireframe"
  "rad04|$S -input cornell_box_diffuse_sphere.obj -sphere_rasterization 16 12 -num_shadow_samples 1 --subdivide 2 -interpolate"
  "rad05|$S -input cornell_box.obj --subdivide 2 --visualize form-factors --ff-source 40 --wireframe"
  "rad06|$S -input cornell_box.obj --subdivide 2 --visualize materials --wireframe"
  "rad07|$S -input cornell_box.obj --subdivide 2 --visualize lights"
  "rad08|$S -input cornell_box.obj --subdivide 2 --visualize undistributed --radiosity-iterations 16"
  "rad09|$S -input cornell_box.obj --subdivide 2 --visualize absorbed"
  "rad10|-size 300 150 -input l.obj --adaptive-subdivide 0.05 --wireframe"
  "rad11|$S -input cornell_box_diffuse_sphere.obj -num_shadow_samples 16 --indirect radiosity --subdivide 2 -interpolate"
  # The course's photon lines and the photon gallery (ph01–ph09).
  "ph01|$S -input reflective_ring.obj -num_photons_to_shoot 10000 -num_bounces 2 -num_shadow_samples 10"
  "ph02|$S -input reflective_ring.obj -num_photons_to_shoot 500000 -num_bounces 2 -num_shadow_samples 10 -num_antialias_samples 4"
  "ph03|$S -input cornell_box_diffuse_sphere.obj -num_photons_to_shoot 500000 -num_shadow_samples 500 -num_photons_to_collect 500"
  "ph04|$S -input cornell_box_reflective_sphere.obj -num_photons_to_shoot 500000 -num_shadow_samples 500 -num_photons_to_collect 500 -num_bounces 1"
  "ph05|$S -input cornell_box_diffuse_sphere.obj -num_photons_to_shoot 100000 -num_shadow_samples 64 -gather_indirect"
  "ph06|$S -input glass_sphere_caustic.obj -num_photons_to_shoot 1000000 -num_shadow_samples 16 -num_bounces 6 -num_antialias_samples 4 -num_photons_to_collect 200"
  "ph07|$S -input reflective_ring.obj -num_photons_to_shoot 500000 --visualize photons"
  "ph08|$S -input glass_sphere_caustic.obj -num_photons_to_shoot 200000 --visualize photons"
  "ph09|$S -input cornell_box_diffuse_sphere.obj -num_photons_to_shoot 200000 --visualize kdtree"
)
accels=(bvh)
"$old" --help | grep -q embree && "$new" --plan -input "$scenes/cornell_box.obj" --accel embree >/dev/null 2>&1 && accels+=(embree)

failed=0
for entry in "${lines[@]}"; do
  name=${entry%%|*}
  args=${entry#*|}
  for accel in "${accels[@]}"; do
    for side in old new; do
      mkdir -p "$work/$side"
      bin=$old; [ "$side" = new ] && bin=$new
      # shellcheck disable=SC2086 # the line is split into arguments on purpose
      (cd "$scenes" && "$bin" $args --accel "$accel" --quiet -o "$work/$side/$name-$accel.png") \
        >"$work/$side/$name-$accel.log" 2>&1 && echo ok >"$work/$side/$name-$accel.rc" \
        || echo failed >"$work/$side/$name-$accel.rc"
    done
    verdict=same
    cmp -s "$work/old/$name-$accel.rc" "$work/new/$name-$accel.rc" || verdict="exit status differs"
    for f in "$work/old/$name-$accel".*; do
      case $f in *.log|*.rc) continue ;; esac
      g="$work/new/$(basename "$f")"
      [ -f "$g" ] && cmp -s "$f" "$g" || verdict="$(basename "$f") differs"
    done
    echo "$name $accel: $verdict ($(cat "$work/new/$name-$accel.rc"))"
    [ "$verdict" = same ] || failed=1
  done
done
exit $failed
