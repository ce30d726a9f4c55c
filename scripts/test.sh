#!/usr/bin/env bash
# The test command of the README (CI runs it through .ci/run): installs what
# is missing, then runs the stages in order, cheapest first, and stops at the
# first that fails:
#   1. format   cargo fmt --all -- --check
#   2. lint     cargo clippy --release --all-targets -- -D warnings
#   3. doc      cargo doc --no-deps with RUSTDOCFLAGS="-D warnings"
#   4. tests    cargo test --release --all-targets
#   5. python   scripts/python_checks.sh (outputs read back with pyvista/h5py,
#               FEniCSx cross-check on the shipped examples, with and
#               without friction)
#   6. bench    scripts/bench at its smallest size (numbers not kept)
# Everything builds in release: one build serves the tests, the Python checks
# and the benchmark, and clippy and rustdoc reuse the release check of the
# dependencies. Each stage prints its wall time on stderr (reported only).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh

stage_name=""
stage_start=0
stage() {
    [ -z "$stage_name" ] || echo "test.sh: $stage_name took $((SECONDS - stage_start)) s" >&2
    stage_name=$1
    stage_start=$SECONDS
    [ "$stage_name" = done ] || echo "test.sh: == $stage_name" >&2
    # free disk at each stage: a CI disk that fills shows here, not only as
    # a pip or linker error
    df -h . 2>/dev/null | awk 'NR == 2 { print "test.sh: disk free " $4 " of " $2 }' >&2 || true
}

stage format
if cargo fmt --version >/dev/null 2>&1; then
    cargo fmt --all -- --check
else
    echo "test.sh: rustfmt is not installed: the format check is skipped" >&2
fi

stage lint
if cargo clippy --version >/dev/null 2>&1; then
    cargo clippy --release --all-targets -- -D warnings
else
    echo "test.sh: clippy is not installed: the lint check is skipped" >&2
fi

stage doc
RUSTDOCFLAGS="-D warnings" cargo doc --release --no-deps

stage tests
cargo test --release --all-targets 2>&1

stage python
bash scripts/python_checks.sh
bash scripts/verify  # docs/verification.md: the coarse verification cases, each error within its tolerance

stage bench
bench_tmp=$(mktemp -d)
bash scripts/bench --sizes 10k --repeats 1 --budget 60 --check --families three_bodies,hertz \
    --work "$bench_tmp/work" --out "$bench_tmp/BENCHMARKS.md"
# rollers (the third family): the methods that finish there in seconds;
# asm-cgh needs minutes and the weak-preconditioner CG variants tens of
# seconds at 10k (README, "Comparing methods")
bash scripts/bench --sizes 10k --repeats 1 --budget 60 --check --families rollers \
    --methods ssn,mprgp,dual,asm,preelim,cgc+cholesky --peers clarabel \
    --work "$bench_tmp/work" --out "$bench_tmp/BENCHMARKS_rollers.md"
# 3D (issue 45): Hertz and the stack at 5 k DOFs, both paths and FEniCSx
python3 scripts/bench.py --solid --check --work "$bench_tmp/solid" --out "$bench_tmp/solid.md"
rm -rf "$bench_tmp"

stage done
