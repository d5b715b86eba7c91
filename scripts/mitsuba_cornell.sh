#!/usr/bin/env bash
# Mitsuba 3 next to glint on the whole-render benchmark's scene (see
# scripts/mitsuba_cornell.py): makes benches/.venv with a pinned Mitsuba
# (git-ignored), finds a libLLVM for the llvm_ad_rgb variant (Dr.Jit 1.5 needs
# LLVM 16 or newer: LLVM 15's x86 backend cannot select the fminimum it emits;
# on Debian 12 `apt-get install libllvm19`; set DRJIT_LIBLLVM_PATH to choose),
# builds glint and runs the comparison. Extra arguments go to the Python
# script (--rounds N, --size S, --spp N, --variants a,b).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
venv="$root/benches/.venv"
if [[ ! -x "$venv/bin/python" ]] || ! "$venv/bin/python" -c "import mitsuba" 2>/dev/null; then
  python3 -m venv "$venv"
  "$venv/bin/pip" install -q "mitsuba==3.9.1" "drjit==1.5.0" "numpy>=1.24"
fi
if [[ -z "${DRJIT_LIBLLVM_PATH:-}" ]]; then
  best=0
  for lib in /usr/lib/x86_64-linux-gnu/libLLVM*.so.* /usr/lib/llvm-*/lib/libLLVM*.so*; do
    [[ -e "$lib" ]] || continue
    major="$(basename "$lib" | grep -oE '[0-9]+' | head -1 || true)"
    [[ -n "$major" ]] || continue
    if (( major >= 16 && major > best )); then best=$major; export DRJIT_LIBLLVM_PATH="$lib"; fi
  done
fi
if [[ -z "${DRJIT_LIBLLVM_PATH:-}" ]]; then
  echo "no libLLVM 16+ found: Mitsuba's llvm_ad_rgb will be skipped (apt-get install libllvm19)"
  set -- --variants scalar_rgb "$@"
else
  echo "DRJIT_LIBLLVM_PATH=$DRJIT_LIBLLVM_PATH"
fi
cargo build --release --manifest-path "$root/Cargo.toml" --bin glint
target="${CARGO_TARGET_DIR:-$root/target}"
exec "$venv/bin/python" "$root/scripts/mitsuba_cornell.py" "$target/release/glint" "$@"
