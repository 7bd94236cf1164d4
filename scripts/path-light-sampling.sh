#!/usr/bin/env bash
# The path tracer's light sampling, error against time (BENCHMARKS.md, "Light sampling in the
# path tracer"): for each scene, a converged reference (64 × SPP samples a pixel, by solid
# angle), then REPEATS renders at SPP samples a pixel with each `--light-sampling` mode,
# interleaved, each repeat with its own seed. Prints a markdown table: the median time, the
# mean relMSE (ε = 1e-2) against the reference, and time × relMSE over solid angle's.
#
#   scripts/path-light-sampling.sh REPEATS SPP SCENE… [-- RENDER FLAGS…]
#
# e.g. scripts/path-light-sampling.sh 3 64 ../shared/course-scenes/*.obj
# SIZE (default 128) sets the image's side, RENDER the program; the images go to a
# temporary folder it names.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
render=${RENDER:-$here/../target/release/render}
size=${SIZE:-128}
repeats=$1
spp=$2
shift 2
scenes=()
while (($#)) && [[ $1 != -- ]]; do
  scenes+=("$1")
  shift
done
(($#)) && shift
extra=("$@")
modes=(solid-angle random)
work=$(mktemp -d)
echo "path-light-sampling: images in $work" >&2
run() { # OUT SPP SEED MODE: renders, prints its wall time in seconds
  local start end
  start=$(date +%s.%N)
  "$render" -input "$scene" --engine path -size "$size" "$size" -num_antialias_samples "$2" \
    --seed "$3" --light-sampling "$4" "${extra[@]}" --quiet -o "$1"
  end=$(date +%s.%N)
  awk -v s="$start" -v e="$end" 'BEGIN { print e - s }'
}
median() { sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }
echo "| scene | light sampling | median s | relMSE | time × relMSE / solid angle's |"
echo "|---|---|---|---|---|"
for scene in "${scenes[@]}"; do
  name=$(basename "$scene")
  run "$work/$name-reference.exr" $((64 * spp)) 1000 solid-angle >/dev/null
  declare -A times=() errors=()
  for ((r = 0; r < repeats; r++)); do
    for mode in "${modes[@]}"; do
      out="$work/$name-$mode-$r.exr"
      times[$mode]+="$(run "$out" "$spp" "$r" "$mode") "
      errors[$mode]+="$("$render" compare "$out" "$work/$name-reference.exr" | awk '/^relmse/ { print $2 }') "
    done
  done
  base=""
  for mode in "${modes[@]}"; do
    t=$(tr ' ' '\n' <<<"${times[$mode]}" | grep . | median)
    e=$(tr ' ' '\n' <<<"${errors[$mode]}" | grep . | awk '{ s += $1 } END { printf "%.3e", s / NR }')
    product=$(awk -v t="$t" -v e="$e" 'BEGIN { print t * e }')
    [[ -z $base ]] && base=$product
    printf '| %s | %s | %.3f | %s | %.2f |\n' "$name" "$mode" "$t" "$e" "$(awk -v p="$product" -v b="$base" 'BEGIN { print p / b }')"
  done
  unset times errors
done
