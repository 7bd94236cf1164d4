#!/usr/bin/env bash
# Times our path tracer against Mitsuba 3's on the course's Cornell box with the diffuse sphere
# (256×256, both threads), times only, in one run — issue #16's first acceptance item:
#
#   scripts/path-time-vs-mitsuba.sh REPEATS RENDER:ACCEL [RENDER:ACCEL ...]
#
# Each repetition r (seed r) renders, for 64 and 256 samples a pixel, Mitsuba's `path`
# integrator (llvm_ad_rgb; scripts/mitsuba_time.py, which times the render after an untimed
# one) and then each of our RENDER binaries with `--engine path --light-sampling random`
# (light sampling by area, as Mitsuba's) and `--accel ACCEL`, so that every binary and backend
# meets the same machine. Prints, per setting, the times, their median and the ratio of that
# median to Mitsuba's. No reference image is needed: the error side is scripts/vs-mitsuba.sh's.
# Needs `pip install mitsuba`, Debian's libllvm19 and DRJIT_LIBLLVM_PATH (set here from
# ldconfig when unset).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
repeats=$1
shift
if [ -z "${DRJIT_LIBLLVM_PATH:-}" ]; then
  DRJIT_LIBLLVM_PATH=$(ldconfig -p | awk '/libLLVM.so.19/ { print $NF; exit }')
  export DRJIT_LIBLLVM_PATH
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
scene=$work/cornell_box_diffuse_sphere.obj
cp "$here/../scenes/cornell_box_diffuse_sphere.obj" "$scene"
echo "background_color 0 0 0" >>"$scene" # Mitsuba's scene has no background light either

csv=$work/times.csv
for r in $(seq "$repeats"); do
  for spp in 64 256; do
    t=$(python3 "$here/mitsuba_time.py" "$spp" "$work/mitsuba.exr" 256 "$r")
    echo "mitsuba,$spp,$t" >>"$csv"
    for who in "$@"; do
      render=${who%:*} accel=${who##*:}
      start=$(date +%s.%N)
      "$render" -input "$scene" --engine path -num_antialias_samples "$spp" \
        --light-sampling random --accel "$accel" --seed "$r" --quiet -o "$work/ours.exr"
      end=$(date +%s.%N)
      echo "$who,$spp,$(echo "$end - $start" | bc -l)" >>"$csv"
    done
  done
done

python3 - "$csv" <<'PY'
import collections, csv, statistics, sys
times = collections.defaultdict(list)
for who, spp, t in csv.reader(open(sys.argv[1])):
    times[(who, int(spp))].append(float(t))
print("| renderer | spp | times (s) | median (s) | / Mitsuba |")
print("|---|---|---|---|---|")
for (who, spp), ts in sorted(times.items(), key=lambda item: item[0][1]):
    m = statistics.median(ts)
    ratio = m / statistics.median(times[("mitsuba", spp)])
    print(f"| {who} | {spp} | {' '.join(f'{t:.3f}' for t in ts)} | {m:.3f} | {ratio:.2f} |")
PY
