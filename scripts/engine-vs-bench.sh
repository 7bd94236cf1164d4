#!/usr/bin/env bash
# The ray tracer's ray rate against `render bench-accel` for the same kinds of rays.
#
# Each round renders the scene with the ray tracer and runs `render bench-accel` right after,
# for each backend, so that the machine's speed (noisy here: it changes by half within minutes)
# is about the same for the two figures a ratio is made of. The bench's rate for the engine's
# mix of rays is its camera closest-hit rate and its shadow occlusion rate (batched, all
# threads) weighted by the engine's own counts of camera and shadow rays:
#
#   mix = (camera + shadow) / (camera / camera_rate + shadow / shadow_rate)
#
# and the figure is engine rate / mix, one per round, with the median over the rounds.
#
# usage: scripts/engine-vs-bench.sh [ROUNDS=5] [SCENE=scenes/cornell_box_diffuse_sphere.obj]
# environment: RENDER (default target/release/render), ACCELS (default "embree bvh"),
#              RENDER_ARGS (default: BENCHMARKS.md's 512×512, 16 AA × 16 shadow samples)
set -euo pipefail

rounds=${1:-5}
scene=${2:-scenes/cornell_box_diffuse_sphere.obj}
render=${RENDER:-target/release/render}
accels=${ACCELS:-embree bvh}
render_args=${RENDER_ARGS:--size 512 512 -num_antialias_samples 16 -num_shadow_samples 16}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

printf '| round | backend | engine s | engine Mrays/s | bench camera | bench shadow | bench mix | engine / bench |\n'
printf '|---|---|---|---|---|---|---|---|\n'
for round in $(seq "$rounds"); do
  for accel in $accels; do
    # shellcheck disable=SC2086
    stats=$("$render" -input "$scene" $render_args --accel "$accel" -o "$out/image.png" \
      --quiet --stats 2>&1)
    bench=$("$render" bench-accel "$scene" --accel "$accel" --sets camera,shadow --modes batched \
      --rays 2000000 --repeats 5 2>&1)
    {
      echo "$stats"
      echo "$bench"
    } | awk -v round="$round" -v accel="$accel" -v threads="$(nproc)" '
      /^stats: .* render [0-9.]+ s/ { match($0, /render [0-9.]+ s/); secs = substr($0, RSTART + 7, RLENGTH - 9) }
      /^stats: rays cast/ {
        match($0, /\(([0-9.]+) Mrays/); engine = substr($0, RSTART + 1, RLENGTH - 7)
        match($0, /camera [0-9]+/); camera = substr($0, RSTART + 7, RLENGTH - 7)
        match($0, /shadow [0-9]+/); shadow = substr($0, RSTART + 7, RLENGTH - 7)
      }
      $2 == accel && $4 == "camera" && $6 == "closest" && $8 == "batched" && $10 == threads { cam = $12 }
      $2 == accel && $4 == "shadow" && $6 == "occluded" && $8 == "batched" && $10 == threads { sh = $12 }
      END {
        if (engine == "" || cam == "" || sh == "") { print "could not read the figures" > "/dev/stderr"; exit 1 }
        mix = (camera + shadow) / (camera / cam + shadow / sh)
        printf "| %d | %s | %.2f | %.2f | %.2f | %.2f | %.2f | %.3f |\n", round, accel, secs, engine, cam, sh, mix, engine / mix
      }'
  done
done | tee "$out/rows"

echo
echo "median engine / bench over $rounds rounds:"
for accel in $accels; do
  awk -F'|' -v accel="$accel" '$3 ~ " " accel " " { print $9 + 0 }' "$out/rows" | sort -g |
    awk -v accel="$accel" '{ v[NR] = $1 } END { m = (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2; printf "  %s: %.3f (range %.3f to %.3f)\n", accel, m, v[1], v[NR] }'
done
