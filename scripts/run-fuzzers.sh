#!/usr/bin/env bash
# Runs each libFuzzer target of a sanitizer build for a bounded time on a copy of its seed corpus.
#   bash scripts/run-fuzzers.sh BUILD_DIR [SECONDS_PER_TARGET]
# A crash, a leak, a sanitizer report or a timeout fails the run; the input that caused it is left in
# BUILD_DIR/fuzz-artifacts/. The mutation seed is fixed (FUZZ_SEED, default 20261201) so that a run
# explores the same inputs each time; set another to explore further. An input counts as a hang after
# 60 s: the coverage hooks slow OpenVDB's templates far more than the sanitizers alone (one 11 KB
# standard .vdb resamples in 0.13 s in Release and 23 s here), and a real endless loop still fails.
set -euo pipefail
build="${1:?usage: run-fuzzers.sh BUILD_DIR [SECONDS]}"
seconds="${2:-60}"
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
artifacts="$build/fuzz-artifacts"
mkdir -p "$artifacts"
for target in vdb_reader standard_vdb script_parser mesh_writers mesh_import region_codec camera_path store_rows session_file; do
    case "$target" in
        vdb_reader) corpus_name=vdb ;;
        standard_vdb) corpus_name=standard ;;
        script_parser) corpus_name=script ;;
        mesh_writers) corpus_name=mesh ;;
        mesh_import) corpus_name=import ;;
        region_codec) corpus_name=region ;;
        camera_path) corpus_name=camera ;;
        store_rows) corpus_name=store ;;
        session_file) corpus_name=session ;;
    esac
    work="$build/fuzz-corpus/$target"
    mkdir -p "$work"
    cp -n "$repo/tests/fuzz/corpus/$corpus_name/"* "$work/" 2>/dev/null || true
    printf '==> fuzz %s for %ss\n' "$target" "$seconds"
    log="$artifacts/$target.log"
    status=0
    ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=1 LSAN_OPTIONS="suppressions=$repo/tests/sanitizer/lsan.supp" UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1:suppressions=$repo/tests/sanitizer/ubsan.supp" \
        "$build/bin/fuzz_$target" "$work" -seed="${FUZZ_SEED:-20261201}" -max_total_time="$seconds" -timeout=60 -rss_limit_mb=2048 \
        -max_len=65536 -print_final_stats=1 -artifact_prefix="$artifacts/$target-" >"$log" 2>&1 || status=$?
    grep -E '^#[0-9]+.*(DONE|pulse)|stat::number_of_executed_units|stat::peak_rss_mb' "$log" | tail -n 3 || true
    if [[ $status -ne 0 ]]; then
        tail -n 60 "$log" >&2
        printf 'fuzz %s failed (exit %s); inputs in %s\n' "$target" "$status" "$artifacts" >&2
        exit 1
    fi
done
