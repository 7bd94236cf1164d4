#!/usr/bin/env bash
# Times our path tracer against Mitsuba 3's on the course's Cornell box with the diffuse sphere
# (256×256, both threads), times only, in one run (BENCHMARKS.md, "The path tracer against Mitsuba 3"):
#
#   scripts/path-time-vs-mitsuba.sh REPEATS RENDER[:ACCEL] [RENDER[:ACCEL] ...]
#
# Each repetition r (seed r) renders, for 64 and 256 samples a pixel, Mitsuba's `path`
# integrator (llvm_ad_rgb; scripts/mitsuba_time.py, which times the render after an untimed
# one) and then each of our RENDER binaries with `--engine path` and its default flags (light
# points by area, as Mitsuba's; the Accel its default picks for the scene) or `--accel ACCEL`,
# so that every binary and backend meets the same machine. Prints, per setting, the times, their median and the ratio of that
# median to Mitsuba's.
#
# REFERENCE=FILE.exr (a converged image of the scene, e.g. Mitsuba at 16k spp averaged) adds
# each image's relMSE against it (`render compare`, of the first RENDER), its median, its ratio
# to Mitsuba's and the ratio of time × relMSE, which is the time each needs for equal error.
# MITSUBA_SAMPLERS="independent ldsampler" times Mitsuba with each of those samplers (default:
# independent, as ../shared/peers/mitsuba_cornell.py sets it; the ratios are to the first).
# MITSUBA_WIDTHS="8 4" also times Mitsuba (the first sampler) with its kernels built for AVX2
# with 8 or 4 lanes instead of for the host (scripts/mitsuba_time.py, MITSUBA_VECTOR_WIDTH);
# rows `mitsuba-w8`, `mitsuba-w4`. TRILUX_SIMD=avx2 runs our kernels in AVX2 (8 lanes) too
# (src/simd.rs): with MITSUBA_WIDTHS=8, both as an AVX2 host would run them.
# Needs `pip install mitsuba`, Debian's libllvm19 and DRJIT_LIBLLVM_PATH (set by
# scripts/mitsuba-common.sh from ldconfig when unset).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
repeats=$1
shift
source "$here/mitsuba-common.sh"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
scene=$(scene_for_mitsuba cornell_box_diffuse_sphere.obj "$work")

csv=$work/times.csv
samplers=(${MITSUBA_SAMPLERS:-independent})
first=${1%:*}
relmse() { # the image's relMSE against REFERENCE, or 0 without one
  if [ -n "${REFERENCE:-}" ]; then
    "$first" compare "$1" "$REFERENCE" | awk '/^relmse/ { print $2 }'
  else
    echo 0
  fi
}
mitsuba() { # NAME SAMPLER WIDTH SPP SEED: one timed Mitsuba render as a row (WIDTH empty: the host's)
  local t
  t=$(MITSUBA_SAMPLER=$2 MITSUBA_VECTOR_WIDTH=$3 python3 "$here/mitsuba_time.py" "$4" "$work/mitsuba.exr" 256 "$5")
  echo "$1,$4,$t,$(relmse "$work/mitsuba.exr")" >>"$csv"
}
for r in $(seq "$repeats"); do
  for spp in 64 256; do
    for sampler in "${samplers[@]}"; do
      name=mitsuba
      [ "$sampler" = "${samplers[0]}" ] || name=mitsuba-$sampler
      mitsuba "$name" "$sampler" "" "$spp" "$r"
    done
    for width in ${MITSUBA_WIDTHS:-}; do
      mitsuba "mitsuba-w$width" "${samplers[0]}" "$width" "$spp" "$r"
    done
    for who in "$@"; do
      render=${who%%:*} accel=()
      [ "$render" = "$who" ] || accel=(--accel "${who#*:}")
      start=$(date +%s.%N)
      "$render" -input "$scene" --engine path -num_antialias_samples "$spp" \
        "${accel[@]}" --seed "$r" --quiet -o "$work/ours.exr"
      end=$(date +%s.%N)
      echo "$who,$spp,$(awk -v s="$start" -v e="$end" 'BEGIN { print e - s }'),$(relmse "$work/ours.exr")" >>"$csv"
    done
  done
done

python3 - "$csv" "${REFERENCE:-}" <<'PY'
import collections, csv, statistics, sys
times = collections.defaultdict(list)
errors = collections.defaultdict(list)
for who, spp, t, e in csv.reader(open(sys.argv[1])):
    times[(who, int(spp))].append(float(t))
    errors[(who, int(spp))].append(float(e))
with_error = bool(sys.argv[2])
head = "| renderer | spp | times (s) | median (s) | / Mitsuba |"
if with_error:
    head += " median relMSE | / Mitsuba | time × relMSE / Mitsuba's |"
print(head)
print("|---" * (head.count("|") - 1) + "|")
for (who, spp), ts in sorted(times.items(), key=lambda item: item[0][1]):
    m = statistics.median(ts)
    mitsuba_t = statistics.median(times[("mitsuba", spp)])
    row = f"| {who} | {spp} | {' '.join(f'{t:.3f}' for t in ts)} | {m:.3f} | {m / mitsuba_t:.2f} |"
    if with_error:
        e = statistics.median(errors[(who, spp)])
        mitsuba_e = statistics.median(errors[("mitsuba", spp)])
        row += f" {e:.3e} | {e / mitsuba_e:.3f} | {m * e / (mitsuba_t * mitsuba_e):.2f} |"
    print(row)
PY
