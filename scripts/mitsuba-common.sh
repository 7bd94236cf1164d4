# Sourced by the scripts that run Mitsuba 3 beside our renderer (path-time-vs-mitsuba.sh,
# path-time-split.sh, vs-mitsuba.sh).

# Dr.Jit's LLVM backend (llvm_ad_rgb) loads the library DRJIT_LIBLLVM_PATH names: Debian's
# libLLVM.so.19 (package libllvm19) unless the caller set it.
if [ -z "${DRJIT_LIBLLVM_PATH:-}" ]; then
  DRJIT_LIBLLVM_PATH=$(ldconfig -p | awk '/libLLVM.so.19/ { print $NF; exit }')
  export DRJIT_LIBLLVM_PATH
fi

# scene_for_mitsuba NAME DIR: copies scenes/NAME into DIR with a black background, as the
# Mitsuba side's scene has no background light, and prints the copy's path.
scene_for_mitsuba() {
  local scene=$2/$1
  cp "$(dirname "${BASH_SOURCE[0]}")/../scenes/$1" "$scene"
  echo "background_color 0 0 0" >>"$scene"
  echo "$scene"
}
