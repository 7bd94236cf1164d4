#!/usr/bin/env bash
# Where the path tracers' time goes, ours against Mitsuba 3's, on the course's Cornell box with
# the diffuse sphere (256×256, both threads, light sampling by area as Mitsuba's): CPU time
# (both threads summed) split into ray casting and the rest (sampling, shading, the path
# loop), from `perf` samples — issue #16's question of which half of the work a faster path
# tracer has to win:
#
#   scripts/path-time-split.sh REPEATS SPP RENDER[:ACCEL]
#
# Each repetition r (seed r) records Mitsuba (scripts/mitsuba_time.py: an untimed render, then
# the timed one, both counted here and halved; its kernels come from Dr.Jit's disk cache, so no
# compilation shows) and then RENDER (`--accel ACCEL`, default bvh), with `perf record -F 999`,
# whose samples are CPU time at 999 a second on each thread. Ray casting is, in Mitsuba, Embree
# (libembree3) and the sphere's intersection callbacks Embree calls (Mitsuba's `ray_intersect`
# and `ray_test` and its packet wrappers); in ours, the BVH's traversal and tests (symbols of
# `accel::bvh`, or Embree's, our shim's (sys/shim.c) and the exact tests it calls back with
# `--accel embree`). Prints, per renderer, the medians of ray casting, the rest, and their sum
# in CPU seconds a render, and ours over Mitsuba's.
# Needs linux-perf (Debian), `pip install mitsuba`, Debian's libllvm19 and DRJIT_LIBLLVM_PATH
# (set by scripts/mitsuba-common.sh from ldconfig when unset).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
repeats=$1 spp=$2 who=$3
render=${who%:*}
accel=bvh
[ "$who" = "$render" ] || accel=${who##*:}
source "$here/mitsuba-common.sh"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
scene=$(scene_for_mitsuba cornell_box_diffuse_sphere.obj "$work")

# cpu_split NAME RENDERS PERF_DATA: a CSV row of CPU seconds (casting, rest) a render.
cpu_split() {
  perf report -i "$3" --no-children --sort dso,sym --stdio -n -g none --percent-limit 0 \
    2>/dev/null | python3 -c '
import re, sys
name, renders = sys.argv[1], int(sys.argv[2])
casting = re.compile(
    r"libembree|embree_(intersect|occluded)|::ray_(intersect|test)|accel::bvh|accel::embree"
    # our C shim (sys/shim.c) around Embree: its calls and the callbacks Embree makes
    r"|^(tx_\w+|\w+_filter|user_(intersect|occluded)|exact_occludes|offer|best_of|load_ray|init_ray(hit)?)$"
)
cast = rest = 0
for line in sys.stdin:
    m = re.match(r"\s*[\d.]+%\s+(\d+)\s+(.+?)\s+\[[.k]\]\s+(.*)", line)
    if not m:
        continue
    n, dso, sym = int(m.group(1)), m.group(2), m.group(3).strip()
    if casting.search(dso) or casting.search(sym):
        cast += n
    else:
        rest += n
print(f"{name},{cast / 999 / renders:.4f},{rest / 999 / renders:.4f}")
' "$1" "$2"
}

csv=$work/split.csv
for r in $(seq "$repeats"); do
  perf record -q -F 999 -o "$work/mitsuba.data" \
    python3 "$here/mitsuba_time.py" "$spp" "$work/mitsuba.exr" 256 "$r" >/dev/null 2>&1
  cpu_split mitsuba 2 "$work/mitsuba.data" >>"$csv"
  perf record -q -F 999 -o "$work/ours.data" \
    "$render" -input "$scene" --engine path -num_antialias_samples "$spp" \
    --light-sampling random --accel "$accel" --seed "$r" --quiet -o "$work/ours.exr" \
    >/dev/null 2>&1
  cpu_split "trilux ($accel)" 1 "$work/ours.data" >>"$csv"
done

python3 - "$csv" "$spp" <<'PY'
import collections, csv, statistics, sys
rows = collections.defaultdict(list)
for name, cast, rest in csv.reader(open(sys.argv[1])):
    rows[name].append((float(cast), float(rest)))
med = {
    name: tuple(statistics.median(v[i] for v in vs) for i in range(2))
    for name, vs in rows.items()
}
print(f"CPU seconds a render at {sys.argv[2]} spp (both threads summed), medians of {len(rows['mitsuba'])}:")
print("| renderer | ray casting | the rest | total | casting share |")
print("|---|---|---|---|---|")
for name, (cast, rest) in med.items():
    print(f"| {name} | {cast:.3f} | {rest:.3f} | {cast + rest:.3f} | {cast / (cast + rest):.2f} |")
m = med["mitsuba"]
for name, (cast, rest) in med.items():
    if name != "mitsuba":
        print(f"| {name} / mitsuba | {cast / m[0]:.2f} | {rest / m[1]:.2f} | {(cast + rest) / sum(m):.2f} | |")
PY
