#!/usr/bin/env bash
# Times the generated `mass_cqd_g` kernels of the paper finger, PUMA 560 and iiwa7 against
# CasADi-generated C for the same scenes, in one process per scene (see harness.c for the
# protocol). Not part of the build or the tests.
#
# Needs python3 (with venv), a C compiler (cc) and cargo. CasADi comes from PyPI into a
# throwaway virtual environment. Environment:
#   BF_CASADI_WORK   working directory (default: a new temporary directory)
#   BF_CASADI_VENV   an existing virtual environment with casadi (skips the install)
#   CARGO_TARGET_DIR target directory for the Rust side (default: <repo>/target, so the
#                    workspace's compiled dependencies are reused)
#   RUSTFLAGS        e.g. "-C target-cpu=native" to give the Rust side the CPU features that
#                    the C side gets from -march=native (rebuilds the kernels)
# Usage: benches/casadi/run.sh [scene ...]   (default: paper puma560 iiwa7)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$here/../.." && pwd)
work=${BF_CASADI_WORK:-$(mktemp -d)}
scenes=("$@")
[ ${#scenes[@]} -gt 0 ] || scenes=(paper puma560 iiwa7)
mkdir -p "$work"
echo "working directory: $work"

venv=${BF_CASADI_VENV:-$work/venv}
if [ ! -x "$venv/bin/python" ] || ! "$venv/bin/python" -c "import casadi" 2>/dev/null; then
  python3 -m venv "$venv"
  "$venv/bin/pip" install --quiet casadi
fi
echo "CasADi $("$venv/bin/python" -c 'import casadi; print(casadi.__version__)')"

for s in "${scenes[@]}"; do
  "$venv/bin/python" "$here/casadi_model.py" "$repo/scenes/$s.toml" "$work/gen"
done

# The Rust kernels as a static library with C entry points (outside the workspace).
mkdir -p "$work/shim/src"
cp "$here/shim.rs" "$work/shim/src/lib.rs"
cp "$repo/Cargo.lock" "$work/shim/Cargo.lock"
cat > "$work/shim/Cargo.toml" <<TOML
[package]
name = "bf-casadi-shim"
version = "0.1.0"
edition = "2024"
publish = false

[lib]
crate-type = ["staticlib"]

[dependencies]
bf-generated = { path = "$repo/generated" }

[profile.release]
debug = false

[workspace]
TOML
target=${CARGO_TARGET_DIR:-$repo/target}
(cd "$work/shim" && CARGO_TARGET_DIR="$target" cargo build --release --quiet)
lib="$target/release/libbf_casadi_shim.a"

for s in "${scenes[@]}"; do
  nq=$(grep -c '^\[\[links\]\]' "$repo/scenes/$s.toml")
  cc -O3 -march=native -c "$work/gen/${s}_casadi.c" -o "$work/${s}_casadi.o"
  cc -O3 -march=native -DSCENE="$s" -DNQ="$nq" -I"$work/gen" "$here/harness.c" \
    "$work/${s}_casadi.o" "$lib" -lm -lpthread -ldl -o "$work/harness_$s"
  "$work/harness_$s"
done
