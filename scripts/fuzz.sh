#!/usr/bin/env bash
# Fuzzes the core's text readers (BVH, skeleton and pose JSON, label tables, joint maps) with
# libFuzzer under AddressSanitizer and UndefinedBehaviorSanitizer, each for SECONDS (default 30),
# seeded from the shared data and Testing/Data. Prints a table: target, executions, new corpus
# entries, crashes. A crash, leak or sanitizer report fails the script and leaves the input as
# BUILD/crashes/<target>/crash-*. Longer runs: scripts/fuzz.sh 3600.
#   scripts/fuzz.sh --runs N   N executions per target from a fixed random seed: the same inputs on
#                              every machine, so a pass or a failure is reproducible (the CTest "Fuzz").
# Inputs that once crashed a reader live in tests/fuzz/seeds/ and are replayed first by every run.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
if [ "${1:-}" = "--runs" ]; then
  limit=(-runs="${2:?--runs needs a count}" -seed=1)
  budget="${2} runs"
else
  limit=(-max_total_time="${1:-30}")
  budget="${1:-30} s"
fi
build="${REPOSE_FUZZ_BUILD_DIR:-$root/build-fuzz}"
data="${REPOSE_SHARED_DATA:-$root/../shared/data}"
cmake -S "$root/tests/fuzz" -B "$build" -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build "$build" >/dev/null

seeds() {  # the seed files of a target
  case "$1" in
    fuzz_bvh) echo "$data/mocap/cmu_short_75frames.bvh" ;;
    fuzz_skeleton_json) echo "$root/Testing/Data/totalsegmentator_skeleton.json" ;;
    fuzz_pose_json) echo "$root/Testing/Data/tiny_pose.json $root/Testing/Data/totalsegmentator_hip_flexion.json $root/tests/fuzz/seeds/pose_json_huge_axis.json" ;;
    fuzz_label_table) echo "$data/totalsegmentator/labels_total_v2.tsv" ;;
    fuzz_joint_map) echo "$root/tests/fuzz/seeds/joint_map.json" ;;
  esac
}

status=0
printf '| target | budget | executions | corpus | crashes |\n|---|---|---|---|---|\n'
for target in fuzz_bvh fuzz_skeleton_json fuzz_pose_json fuzz_label_table fuzz_joint_map; do
  corpus="$build/corpus/$target"
  crashes="$build/crashes/$target"
  # A reproducible run starts from the seeds alone, not from a corpus grown by earlier runs.
  [ "${limit[0]}" = "${limit[0]#-runs}" ] || rm -rf "$corpus" "$crashes"
  mkdir -p "$corpus" "$crashes"
  for s in $(seeds "$target"); do [ -f "$s" ] && cp -f "$s" "$corpus/"; done
  log="$build/$target.log"
  if ! "$build/$target" "$corpus" "${limit[@]}" -max_len=65536 -timeout=10 -rss_limit_mb=2048 \
      -print_final_stats=1 -artifact_prefix="$crashes/" >"$log" 2>&1; then
    status=1
  fi
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  found=$(ls "$crashes" | wc -l)
  printf '| %s | %s | %s | %s | %s |\n' "$target" "$budget" "${runs:-?}" "$(ls "$corpus" | wc -l)" "$found"
  [ "$found" -eq 0 ] || status=1
done
if [ "$status" -ne 0 ]; then
  echo "fuzz: a target crashed or reported; see $build/*.log and $build/crashes/" >&2
fi
exit "$status"
