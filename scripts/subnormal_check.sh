#!/usr/bin/env bash
# Finds renders that lose time to subnormal floats, which callgrind cannot show (it
# counts instructions; x86 runs subnormal arithmetic in microcode, at many times the
# cost). Renders every scene in scenes/ on one thread, alternately as is and with the
# CPU's flush-to-zero and denormals-are-zero modes set (a preloaded library sets MXCSR
# before main; threads inherit it), and prints the times and their ratio. A ratio well
# above 1 means some computation of that scene runs on subnormals, as ray origins off
# a plane through zero did until 1 December 2026 (Cornell render 2x slower).
#   scripts/subnormal_check.sh [ROUNDS] [extra glint render args...]   (x86-64, gcc)
# GLINT=path checks that binary instead of building this checkout's.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
rounds="${1:-3}"
shift $(( $# > 0 ? 1 : 0 ))
target="${CARGO_TARGET_DIR:-$root/target}"
glint="${GLINT:-}"
if [[ -z "$glint" ]]; then
  cargo build --release --manifest-path "$root/Cargo.toml" --bin glint >&2
  glint="$target/release/glint"
fi
if [[ "$(uname -m)" != x86_64 ]]; then
  echo "subnormal_check.sh: x86-64 only (it sets the SSE control register MXCSR)" >&2
  exit 2
fi
for tool in gcc bc; do
  command -v "$tool" >/dev/null || { echo "subnormal_check.sh: needs $tool" >&2; exit 2; }
done
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
cat >"$tmp/ftz.c" <<'EOF'
#include <xmmintrin.h>
__attribute__((constructor)) static void ftz(void) { _mm_setcsr(_mm_getcsr() | 0x8040); }
EOF
gcc -O2 -shared -fPIC -o "$tmp/libftz.so" "$tmp/ftz.c"
# Seconds of one render (wall clock, whole process).
seconds() {
  local start end
  start="$(date +%s.%N)"
  "$@" >/dev/null 2>&1
  end="$(date +%s.%N)"
  echo "$end - $start" | bc
}
printf '%-40s %10s %10s %7s\n' scene "as is, s" "FTZ, s" ratio
for scene in "$root"/scenes/*.ron; do
  plain=() ftz=()
  for ((r = 0; r < rounds; r++)); do
    args=(render "$scene" --threads 1 -o "$tmp/out.png" "$@")
    plain+=("$(seconds "$glint" "${args[@]}")")
    ftz+=("$(LD_PRELOAD="$tmp/libftz.so" seconds "$glint" "${args[@]}")")
  done
  median() { printf '%s\n' "$@" | sort -g | sed -n "$(( ($# + 1) / 2 ))p"; }
  p="$(median "${plain[@]}")" f="$(median "${ftz[@]}")"
  printf '%-40s %10.3f %10.3f %7.2f\n' "$(basename "$scene")" "$p" "$f" "$(echo "$p / $f" | bc -l)"
done
