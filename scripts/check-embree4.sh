#!/usr/bin/env bash
# Builds trilux against Embree 4 and runs the test suite with it, on a machine whose system
# has only Embree 3 (Debian 12). Nothing is installed system-wide and nothing enters the
# checkout: everything lives under WORK.
#
# Where it gets Embree 4 (package registries only):
#   * the library: libembree4 4.4.0 and its TBB, from the `embreex` wheel, through pip;
#   * the headers: Embree 4.2.0's, from the `embree4-sys` crate, fetched by cargo through a
#     throwaway crate that depends on it (`cargo fetch`; nothing is built). Embree 4.3
#     added instance arrays, and a library built with them (as this one is) writes
#     `instPrimID` after `instID` in every hit; the 4.2 headers are brought up to that layout
#     (RTC_GEOMETRY_INSTANCE_ARRAY defined, `instPrimID` added to the hits and the ray query
#     context). With the unchanged 4.2 headers closest-hit queries overrun the hit structs
#     and crash — a header/library mismatch, not something a real Embree 4 install has.
#
# usage: scripts/check-embree4.sh [WORK=/tmp/trilux-embree4] [cargo test arguments...]
set -euo pipefail

work=${1:-/tmp/trilux-embree4}
shift || true
prefix=$work/embree4
mkdir -p "$prefix/include" "$prefix/lib" "$work/download"

if [ ! -e "$prefix/lib/libembree4.so" ]; then
  python3 -m pip download --quiet --no-deps --only-binary=:all: --python-version 3.11 \
    --platform manylinux_2_28_x86_64 embreex==4.4.0.post1 -d "$work/download"
  (cd "$work/download" && python3 -m zipfile -e embreex-*.whl wheel)
  cp "$work"/download/wheel/embreex.libs/*.so* "$prefix/lib/"
  library=$(cd "$prefix/lib" && ls libembree4-*.so.4)
  ln -sf "$library" "$prefix/lib/libembree4.so"
fi

if [ ! -e "$prefix/include/embree4/rtcore.h" ]; then
  fetcher=$work/download/fetch-embree4-sys
  mkdir -p "$fetcher/src"
  printf '[package]\nname = "fetch-embree4-sys"\nversion = "0.0.0"\nedition = "2021"\n\n[dependencies]\nembree4-sys = "=0.0.12"\n' \
    >"$fetcher/Cargo.toml"
  : >"$fetcher/src/lib.rs"
  (cd "$fetcher" && cargo fetch --quiet)
  sources=$(ls -d "${CARGO_HOME:-$HOME/.cargo}"/registry/src/*/embree4-sys-0.0.12 | head -n 1)
  headers=$prefix/include/embree4
  cp -r "$sources/lib/embree4" "$headers"
  sed -i 's|^#define RTC_MAX_INSTANCE_LEVEL_COUNT 1$|&\n#define RTC_GEOMETRY_INSTANCE_ARRAY|' \
    "$headers/rtcore_config.h"
  sed -i -E 's|^(  unsigned int )instID(\[RTC_MAX_INSTANCE_LEVEL_COUNT\])(\[[0-9]+\])?;.*$|&\n\1instPrimID\2\3;|' \
    "$headers/rtcore_ray.h"
  sed -i -E 's|^(  unsigned int )instID(\[RTC_MAX_INSTANCE_LEVEL_COUNT\]);( // The current stack of instance ids.)$|&\n\1instPrimID\2;|' \
    "$headers/rtcore_common.h"
  [ "$(grep -c instPrimID "$headers/rtcore_ray.h")" -eq 4 ] &&
    [ "$(grep -c instPrimID "$headers/rtcore_common.h")" -eq 1 ] ||
    { echo "check-embree4: the header layout was not as expected" >&2; exit 1; }
fi

export EMBREE_DIR=$prefix
export CARGO_TARGET_DIR=$work/target
export LD_LIBRARY_PATH=$prefix/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
if ! cargo build --release 2>"$work/build.log"; then
  cat "$work/build.log" >&2
  exit 1
fi
grep -F "using Embree 4" "$work/build.log" ||
  { echo "check-embree4: the build did not pick Embree 4 (see $work/build.log)" >&2; exit 1; }
cargo test --release "$@"
