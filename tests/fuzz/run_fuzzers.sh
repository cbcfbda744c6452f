#!/usr/bin/env bash
# Runs every fuzzer of tests/fuzz/ (built into BUILD) on its committed corpus (corpus/<harness>/),
# its seeds (make_seeds.py) and its kept regression inputs, for a bounded time or number of
# inputs each, two harnesses at a time (one per core of the CI machine):
#
#   tests/fuzz/run_fuzzers.sh BUILD 60              # 60 s per harness (CI: 4 rounds, about 4 min;
#                                                   # the seventh, packed, alone in the fourth)
#   tests/fuzz/run_fuzzers.sh BUILD runs=1000000    # 10^6 inputs per harness
#   tests/fuzz/run_fuzzers.sh BUILD 600 --grow      # then merge what is new into corpus/<harness>/
#
# New inputs go to BUILD/corpus/<harness>/ (the committed corpus is only read). With --grow, the
# inputs that reach code the seeds and the committed corpus do not are merged into the corpus
# (libFuzzer's -merge=1, inputs of at most 4 kB), so that it stays a few hundred small files.
# A crash stops with a non-zero status; its input is in BUILD/artifacts/<harness>/. Fix it and
# keep the input in tests/fuzz/regressions/<harness>/ (replayed by ctest -R fuzz_regressions).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
build="$(cd "${1:?usage: run_fuzzers.sh BUILD SECONDS|runs=N [--grow]}" && pwd)"
limit="${2:-60}"
grow="${3:-}"
case "$limit" in
  runs=*) budget="-runs=${limit#runs=}" ;;
  *) budget="-max_total_time=$limit" ;;
esac
rm -rf "$build/seeds" && /usr/bin/python3 "$here/make_seeds.py" "$build/seeds"
harnesses=(msh stl off obj problem saved packed)

run_one() { # run_one HARNESS: fuzz, then report one line; returns non-zero on a crash
  local h=$1 start corpus artifacts
  corpus="$build/corpus/$h" artifacts="$build/artifacts/$h/"
  mkdir -p "$corpus" "$artifacts" "$here/corpus/$h" "$here/regressions/$h" "$build/seeds/$h"
  start=$(date +%s)
  # -timeout: an input that takes 10 s is a bug too; -rss_limit_mb: so is one that takes 2 GB.
  if "$build/fuzz_$h" "$budget" -timeout=10 -rss_limit_mb=2048 -max_len=4096 -print_final_stats=1 \
       -artifact_prefix="$artifacts" "$corpus" "$here/corpus/$h" "$build/seeds/$h" "$here/regressions/$h" \
       > "$build/fuzz_$h.log" 2>&1; then
    echo "fuzz_$h: $(grep -o 'stat::number_of_executed_units: *[0-9]*' "$build/fuzz_$h.log" | grep -o '[0-9]*$') inputs in $(( $(date +%s) - start )) s, no crash"
  else
    echo "fuzz_$h: CRASH (see $build/fuzz_$h.log and $artifacts)" >&2
    tail -n 40 "$build/fuzz_$h.log" >&2
    return 1
  fi
}

# What is new against the seeds and the committed corpus goes into the committed corpus: the
# seeds (regenerated from the shipped files) are merged first and removed after.
grow_one() {
  local h=$1 merged="$build/merged/$h"
  rm -rf "$merged" && mkdir -p "$merged"
  cp "$here/corpus/$h/"* "$merged/" 2>/dev/null || true
  cp "$build/seeds/$h/"* "$merged/"
  "$build/fuzz_$h" -merge=1 -max_len=4096 "$merged" "$build/corpus/$h" > "$build/merge_$h.log" 2>&1
  for s in "$build/seeds/$h/"*; do rm -f "$merged/$(basename "$s")"; done
  rm -rf "$here/corpus/$h" && mkdir -p "$here/corpus/$h" && cp "$merged/"* "$here/corpus/$h/" 2>/dev/null || true
  echo "corpus/$h: $(ls "$here/corpus/$h" | wc -l) inputs, $(du -sk "$here/corpus/$h" | cut -f1) kB"
}

status=0
pids=()
for h in "${harnesses[@]}"; do # two at a time
  run_one "$h" & pids+=($!)
  if [ ${#pids[@]} -eq 2 ]; then
    for p in "${pids[@]}"; do wait "$p" || status=1; done
    pids=()
  fi
done
for p in "${pids[@]}"; do wait "$p" || status=1; done
if [ "$status" -eq 0 ] && [ "$grow" = "--grow" ]; then
  for h in "${harnesses[@]}"; do grow_one "$h"; done
fi
exit $status
