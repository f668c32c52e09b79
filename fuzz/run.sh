#!/usr/bin/env bash
# Fuzzes each target for SECONDS (default 60): `bash fuzz/run.sh SECONDS [TARGET...]`, every
# target when none is named. Seeds the corpus first (fuzz/seed.sh), builds with debug
# assertions and overflow checks, and fails on the first target that finds a crash, a
# timeout or an allocation past the memory limit. Each target's log is kept in fuzz/logs/;
# the last line of each is libFuzzer's count of executions.
set -euo pipefail
cd "$(dirname "$0")"
seconds=${1:-60}
shift || true
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
    targets=(read_medit read_gmsh read_vtk read_tetgen read_obj read_off read_ply scene mesh_spec)
fi
command -v cargo-fuzz >/dev/null 2>&1 || cargo install -q cargo-fuzz --locked
# cargo fuzz passes unstable compiler flags: nightly where it is installed, otherwise the
# stable compiler with its unstable features unlocked.
if cargo +nightly --version >/dev/null 2>&1; then
    fuzz=(cargo +nightly fuzz)
else
    export RUSTC_BOOTSTRAP=1
    fuzz=(cargo fuzz)
fi
bash seed.sh
# No sanitizer: the code under test is safe Rust, so AddressSanitizer would mostly halve the
# executions; -a keeps debug assertions and overflow checks on in the optimised build.
"${fuzz[@]}" build -O -a -s none
mkdir -p logs
# Stepping scenes would use every core; one thread keeps each run to one.
export RAYON_NUM_THREADS=1
for t in "${targets[@]}"; do
    log=logs/$t.log
    echo "fuzzing $t for ${seconds}s (log: fuzz/$log)"
    if ! "${fuzz[@]}" run -O -a -s none "$t" "corpus/$t" -- \
        -max_total_time="$seconds" -max_len=131072 -timeout=20 -rss_limit_mb=2048 \
        -print_final_stats=1 >"$log" 2>&1; then
        tail -n 60 "$log"
        echo "fuzz target $t failed: see fuzz/$log and fuzz/artifacts/$t/" >&2
        exit 1
    fi
    grep -E '^Done [0-9]+ runs|stat::number_of_executed_units' "$log" | tail -n 1
done
