#!/usr/bin/env bash
# Measures trilux against Mitsuba 3's path tracer on the course's Cornell box with the diffuse
# sphere (256×256), in one run, as BENCHMARKS.md quotes it:
#
#   scripts/vs-mitsuba.sh REFERENCE.exr [REPEATS] [RENDER]
#
# 1. Mitsuba's `path` integrator (llvm_ad_rgb; scripts/mitsuba_time.py, the scene of
#    ../shared/peers/mitsuba_cornell.py) and our path tracer at 16, 64 and 256 samples a pixel,
#    with its default light sampling (`path`) and by area as Mitsuba's (`path-area`,
#    `--light-sampling random`), REPEATS times (default 3) interleaved; the median time of
#    each and the relMSE of each image against REFERENCE (`render compare`, ε = 1e-2).
# 2. From Mitsuba's points (relMSE ∝ 1/spp for an unbiased path tracer), the time Mitsuba
#    needs for relMSE 1e-2 and 2e-3, by log-log interpolation between its measured points.
# 3. Each of our engines with --time-limit equal to those two times: the relMSE it reaches
#    (skipped with VS_SPP_ONLY=1).
#
# REFERENCE: a converged image of the same scene (e.g. Mitsuba at 32k spp, averaged). Our
# scene is scenes/cornell_box_diffuse_sphere.obj with a black background, as Mitsuba's.
# VS_ACCEL=bvh (or embree) passes `--accel` to every render of ours (default: the build's best).
# VS_SCENE=caustic measures scenes/glass_sphere_caustic.obj instead (Mitsuba's side:
# scripts/mitsuba_caustic.py, which also makes its reference), with -num_bounces 6 for the
# engines that trace glass by recursion.
# Needs `pip install mitsuba numpy`, Debian's libllvm19 and DRJIT_LIBLLVM_PATH (set by
# scripts/mitsuba-common.sh from ldconfig when unset). Writes its images and a CSV into a
# temporary folder it names.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
reference=$(realpath "$1")
repeats=${2:-3}
render=$(realpath "${3:-$here/../target/release/render}")
accel=()
if [ -n "${VS_ACCEL:-}" ]; then
  accel=(--accel "$VS_ACCEL")
fi
source "$here/mitsuba-common.sh"
work=$(mktemp -d)
echo "vs-mitsuba: images and CSV in $work"
if [ "${VS_SCENE:-cornell}" = caustic ]; then
  name=glass_sphere_caustic.obj mitsuba=mitsuba_caustic.py bounces="-num_bounces 6"
else
  name=cornell_box_diffuse_sphere.obj mitsuba=mitsuba_time.py bounces=""
fi
scene=$(scene_for_mitsuba "$name" "$work")

relmse() { "$render" compare "$1" "$reference" | awk '/^relmse/ { print $2 }'; }
seconds() { # runs the command, prints its wall time
  local start end
  start=$(date +%s.%N)
  "$@" >/dev/null 2>&1
  end=$(date +%s.%N)
  echo "$end - $start" | bc -l
}
median() { sort -g | awk '{ a[NR] = $1 } END { print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2 }'; }

csv=$work/vs-mitsuba.csv
echo "renderer,setting,seconds,relmse" >"$csv"
for r in $(seq "$repeats"); do
  for spp in 16 64 256; do
    t=$(python3 "$here/$mitsuba" "$spp" "$work/mi_$spp.exr" 256 "$r")
    echo "mitsuba,$spp spp,$t,$(relmse "$work/mi_$spp.exr")" >>"$csv"
    t=$(seconds "$render" -input "$scene" --engine path -num_antialias_samples "$spp" \
      "${accel[@]}" --seed "$r" --quiet -o "$work/path_$spp.exr")
    echo "path,$spp spp,$t,$(relmse "$work/path_$spp.exr")" >>"$csv"
    t=$(seconds "$render" -input "$scene" --engine path -num_antialias_samples "$spp" \
      --light-sampling random "${accel[@]}" --seed "$r" --quiet -o "$work/path_area_$spp.exr")
    echo "path-area,$spp spp,$t,$(relmse "$work/path_area_$spp.exr")" >>"$csv"
  done
done

echo
echo "| renderer | spp | median time (s) | median relMSE |"
echo "|---|---|---|---|"
for who in mitsuba path path-area; do
  for spp in 16 64 256; do
    t=$(grep "^$who,$spp spp," "$csv" | cut -d, -f3 | median)
    e=$(grep "^$who,$spp spp," "$csv" | cut -d, -f4 | median)
    printf '| %s | %s | %.3f | %.3g |\n' "$who" "$spp" "$t" "$e"
  done
done

# Mitsuba's time to a relMSE, by log-log interpolation between its two bracketing medians
# (extrapolated from the nearest pair outside them).
time_to() {
  local target=$1
  for spp in 16 64 256; do
    echo "$(grep "^mitsuba,$spp spp," "$csv" | cut -d, -f3 | median) $(grep "^mitsuba,$spp spp," "$csv" | cut -d, -f4 | median)"
  done | awk -v e="$target" '
    { t[NR] = log($1); r[NR] = log($2) }
    END {
      i = 1
      while (i < NR - 1 && r[i + 1] > log(e)) i++
      s = (t[i + 1] - t[i]) / (r[i + 1] - r[i])
      printf "%.3f\n", exp(t[i] + s * (log(e) - r[i]))
    }'
}
t1=$(time_to 1e-2)
t2=$(time_to 2e-3)
echo
echo "Mitsuba's time to relMSE 1e-2: $t1 s; to 2e-3: $t2 s"
if [ "${VS_SPP_ONLY:-0}" = 1 ]; then
  exit 0
fi

engines=(
  "path|--engine path -num_antialias_samples 4"
  "sppm|--engine sppm"
  "raytrace + radiosity|--indirect radiosity --subdivide 3 -interpolate -num_shadow_samples 16 -num_antialias_samples 4 $bounces"
  "photon + final gathering|--engine photon -num_photons_to_shoot 50000 -gather_indirect -num_shadow_samples 16 -num_antialias_samples 4 $bounces"
)
echo
echo "| engine (our flags) | --time-limit (s) | wall time (s) | relMSE |"
echo "|---|---|---|---|"
for limit in "$t1" "$t2"; do
  for line in "${engines[@]}"; do
    name=${line%%|*}
    flags=${line#*|}
    out="$work/limit_${limit}_${name// /_}.exr"
    # shellcheck disable=SC2086
    t=$(seconds "$render" -input "$scene" $flags "${accel[@]}" --time-limit "$limit" --quiet -o "$out")
    e=$(relmse "$out")
    echo "$name,limit $limit,$t,$e" >>"$csv"
    printf '| %s (`%s`) | %s | %.2f | %.3g |\n' "$name" "$flags" "$limit" "$t" "$e"
  done
done
