#!/usr/bin/env bash
# Runs every fuzzer of tests/fuzz/ (built into BUILD) on its seeds (make_seeds.py) and its kept
# regression inputs, for a bounded time or number of inputs each:
#
#   tests/fuzz/run_fuzzers.sh BUILD 60              # 60 s per harness (CI)
#   tests/fuzz/run_fuzzers.sh BUILD runs=1000000    # 10^6 inputs per harness
#
# A crash stops with a non-zero status; its input is in BUILD/artifacts/<harness>/. Fix it and
# keep the input in tests/fuzz/regressions/<harness>/ (replayed by ctest -R fuzz_regressions).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
build="$(cd "${1:?usage: run_fuzzers.sh BUILD SECONDS|runs=N}" && pwd)"
limit="${2:-60}"
case "$limit" in
  runs=*) budget="-runs=${limit#runs=}" ;;
  *) budget="-max_total_time=$limit" ;;
esac
rm -rf "$build/seeds" && /usr/bin/python3 "$here/make_seeds.py" "$build/seeds"
status=0
for h in msh stl off obj problem; do
  corpus="$build/corpus/$h" artifacts="$build/artifacts/$h/"
  mkdir -p "$corpus" "$artifacts"
  start=$(date +%s)
  # -timeout: an input that takes 10 s is a bug too; -rss_limit_mb: so is one that takes 2 GB.
  if "$build/fuzz_$h" "$budget" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
       -artifact_prefix="$artifacts" "$corpus" "$build/seeds/$h" "$here/regressions/$h" \
       > "$build/fuzz_$h.log" 2>&1; then
    echo "fuzz_$h: $(grep -o 'stat::number_of_executed_units: *[0-9]*' "$build/fuzz_$h.log" | grep -o '[0-9]*$') inputs in $(( $(date +%s) - start )) s, no crash"
  else
    echo "fuzz_$h: CRASH (see $build/fuzz_$h.log and $artifacts)" >&2
    tail -n 40 "$build/fuzz_$h.log" >&2
    status=1
  fi
done
exit $status
