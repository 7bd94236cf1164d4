#!/usr/bin/env bash
# Soft shadows by light sampling (BENCHMARKS.md, "Light sampling"): on a course scene,
# shadow rays per pixel and RMSE against a converged render (4,096 shadow rays by solid angle,
# the same camera samples) for jittered and solid-angle sampling at N = 4, 16, 64 shadow rays
# and for adaptive sampling at depths 1–4:
#
#   scripts/light-sampling.sh SCENE [RENDER FLAGS…]
#
# e.g. scripts/light-sampling.sh ../shared/course-scenes/textured_plane_reflective_sphere.obj -num_bounces 1
# Prints a markdown table; the images go to a temporary folder it names.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
render=${RENDER:-$here/../target/release/render}
scene=$1
shift
work=$(mktemp -d)
echo "light-sampling: images in $work" >&2
run() { # NAME FLAGS…: renders, prints shadow rays per pixel
  local name=$1
  shift
  "$render" -input "$scene" -size 256 256 "$@" "${extra[@]}" --stats -o "$work/$name.exr" 2>&1 |
    awk '/^stats: rays cast/ { for (i = 1; i <= NF; i++) if ($i == "shadow") print $(i + 1) / 65536 }'
}
extra=("$@")
run reference -num_shadow_samples 4096 --light-sampling solid-angle >/dev/null
echo "| sampling | shadow rays per pixel | RMSE |"
echo "|---|---|---|"
row() {
  local name=$1 label=$2
  shift 2
  local rays
  rays=$(run "$name" "$@")
  printf '| %s | %.1f | %s |\n' "$label" "$rays" \
    "$("$render" compare "$work/$name.exr" "$work/reference.exr" | awk '/^rmse/ { print $2 }')"
}
for n in 4 16 64; do
  row "jittered$n" "jittered, N = $n" -num_shadow_samples "$n" --light-sampling jittered
  row "solid$n" "solid angle, N = $n" -num_shadow_samples "$n" --light-sampling solid-angle
done
for d in 1 2 3 4; do
  row "adaptive$d" "adaptive, depth $d" -num_shadow_samples 4 --light-sampling adaptive --adaptive-depth "$d"
done
