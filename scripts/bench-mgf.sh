#!/usr/bin/env bash
# Radiosity on RenderPark's MGF scenes: each scene with both Accels and both
# solvers (the progressive one only where it can finish in reasonable time), visibility on,
# tolerance 1e-3. Prints one table row per run: input patches, elements, links, rays,
# wall time, peak memory (from /usr/bin/time), residual.
#
#   scripts/bench-mgf.sh [RENDER] [MGF_DIR]
#
# RENDER defaults to target/release/render, MGF_DIR to ../shared/mgf-scenes beside the
# checkout. PROGRESSIVE_MAX (default 13000) is the largest input-patch count the
# progressive solver is run on.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
render=$(realpath "${1:-$here/target/release/render}")
mgf=$(realpath "${2:-$here/../shared/mgf-scenes}")
progressive_max=${PROGRESSIVE_MAX:-13000}
scenes=(
  "cube.mgf|$mgf/cube.mgf"
  "office3|$mgf/office3/office.mgf"
  "classroom|$mgf/salon/classroom.mgf"
  "hospital|$mgf/hospital/hosp.mgf"
  "soda|$mgf/soda.mgf"
  "hospital twice|$here/scenes/hospital_twice.mgf"
)
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
echo "| scene | solver | accel | input patches | elements | links | visibility rays | wall s | peak MB | residual |"
echo "|---|---|---|---|---|---|---|---|---|---|"
for entry in "${scenes[@]}"; do
  name=${entry%%|*}
  file=${entry#*|}
  patches=$("$render" -input "$file" --engine radiosity --plan 2>/dev/null |
    sed -n 's/^radiosity mesh: yes (\([0-9]*\) patches.*/\1/p')
  for solver in hierarchical progressive; do
    if [ "$solver" = progressive ] && [ "$patches" -gt "$progressive_max" ]; then
      continue
    fi
    for accel in embree bvh; do
      log="$out/log"
      /usr/bin/time -f "%e %M" -o "$out/time" "$render" -input "$file" --engine radiosity \
        --radiosity-solver "$solver" --accel "$accel" -num_shadow_samples 1 \
        -o "$out/image.png" >"$log" 2>&1 || { echo "| $name | $solver | $accel | failed |"; continue; }
      summary=$(grep '^radiosity:' "$log" || true)
      read -r wall kb <"$out/time"
      field() { sed -n "s/.*$1.*/\1/p" <<<"$summary" | head -1; }
      elements=$(field ' \([0-9]*\) elements')
      links=$(field ' \([0-9]*\) links')
      rays=$(field ' \([0-9]*\) visibility rays')
      residual=$(field 'residual \([0-9.e+-]*\)')
      echo "| $name | $solver | $accel | $patches | ${elements:--} | ${links:--} | $rays | $wall | $((kb / 1024)) | $residual |"
    done
  done
done
