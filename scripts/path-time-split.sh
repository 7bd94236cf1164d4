#!/usr/bin/env bash
# Where the path tracers' time goes, ours against Mitsuba 3's, on the course's Cornell box with
# the diffuse sphere (256×256, both threads, light sampling by area as Mitsuba's): CPU time
# (both threads summed) split into ray casting and the rest (sampling, shading, the path
# loop), from `perf` samples: which half of the work a faster path tracer has to win:
#
#   scripts/path-time-split.sh REPEATS SPP RENDER[:ACCEL]
#
# Each repetition r (seed r) records Mitsuba (scripts/mitsuba_time.py: an untimed render, then
# the timed one, both counted here and halved; its kernels come from Dr.Jit's disk cache, so no
# compilation shows) and then RENDER (`--accel ACCEL`, default bvh), with `perf record -F 999`,
# whose samples are CPU time at 999 a second on each thread. Ray casting is, in Mitsuba, Embree
# (libembree3) and the sphere's intersection callbacks Embree calls (Mitsuba's `ray_intersect`
# and `ray_test` and its packet wrappers); in ours, the BVH's traversal and tests (symbols of
# `accel::bvh`, and the functions `pulp`'s dispatch compiled for its batched queries; or
# Embree's, our shim's (sys/shim.c) and the exact tests it calls back with `--accel embree`).
# Prints, per renderer, the medians of ray casting, the rest, and their sum in CPU seconds a
# render, and ours over Mitsuba's.
# Needs linux-perf and binutils (Debian), `pip install mitsuba`, Debian's libllvm19 and
# DRJIT_LIBLLVM_PATH (set by scripts/mitsuba-common.sh from ldconfig when unset).
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

# dispatched_casting RENDER: the addresses (hex, one a line) of the functions that `pulp`'s
# run-time dispatch compiled for the BVH's batched queries. They are all named
# `pulp::…::vectorize::imp_fastcall`, like the path tracer's own kernels, so they are told
# apart by who calls them: the BVH's functions (`objdump`).
dispatched_casting() {
  objdump -d -C --no-show-raw-insn "$1" | awk '
    /^[0-9a-f]+ <.*>:$/ { caller = $0 }
    /(call|jmp).*vectorize::imp/ && caller ~ /accel::bvh/ { print $(NF - 1) }' | sort -u
}

# cpu_split NAME RENDERS PERF_DATA [BINARY]: a CSV row of CPU seconds (casting, rest) a
# render. With BINARY (ours), its dispatched functions count as casting where the BVH calls
# them; a sample's function is found from its address less its offset in the function,
# against `nm`'s addresses (the program is loaded at an offset, found from a function whose
# name is its own).
cpu_split() {
  local dispatched="" symbols=""
  if [ -n "${4:-}" ]; then
    dispatched=$(dispatched_casting "$4" | tr '\n' ' ')
    symbols=$work/symbols.txt
    nm -C --defined-only "$4" >"$symbols"
  fi
  perf script -i "$3" -F ip,sym,symoff,dso 2>/dev/null | python3 -c '
import collections, os, re, sys
name, renders, dispatched, symbols = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4]
binary = sys.argv[5] and os.path.realpath(sys.argv[5])
casting = re.compile(
    r"libembree|embree_(intersect|occluded)|::ray_(intersect|test)|accel::bvh|accel::embree"
    # our C shim (sys/shim.c) around Embree: its calls and the callbacks Embree makes
    r"|^(tx_\w+|\w+_filter|user_(intersect|occluded)|exact_occludes|offer|best_of|load_ray|init_ray(hit)?)$"
)
dispatched = {int(a, 16) for a in dispatched.split()}
# Functions of the binary by name, for those with one address: the load offset.
addresses = collections.defaultdict(set)
if symbols:
    for line in open(symbols):
        parts = line.rstrip("\n").split(" ", 2)
        if len(parts) == 3 and parts[1] in "tTwW":
            addresses[parts[2]].add(int(parts[0], 16))
samples = []
for line in sys.stdin:
    m = re.match(r"\s*([0-9a-f]+) (.+)\+0x([0-9a-f]+) \((.*)\)$", line)
    if m:
        ip, sym, off, dso = int(m.group(1), 16), m.group(2), int(m.group(3), 16), m.group(4)
        ours = bool(binary) and os.path.realpath(dso) == binary
        samples.append((ip - off, sym, dso, ours))
    elif line.strip():
        samples.append((None, "", "", False))
base = next(
    (start - next(iter(addresses[sym])) for start, sym, _, ours in samples
     if ours and len(addresses.get(sym, ())) == 1),
    None,
)
cast = rest = 0
for start, sym, dso, ours in samples:
    if casting.search(dso) or casting.search(sym):
        cast += 1
    elif ours and base is not None and start - base in dispatched:
        cast += 1
    else:
        rest += 1
print(f"{name},{cast / 999 / renders:.4f},{rest / 999 / renders:.4f}")
' "$1" "$2" "$dispatched" "$symbols" "${4:-}"
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
  cpu_split "trilux ($accel)" 1 "$work/ours.data" "$render" >>"$csv"
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
