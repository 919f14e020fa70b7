#!/usr/bin/env bash
# Peak RSS and wall time of `imu-sim synth`, `adev`, `run` and `analyze` on synthesised records
# of 10^6, 10^7, ... samples (memory flat in the record's length, <= 64 MB at 10^8 for
# adev, run and analyze; analyze holds at most 2^20 samples, block means beyond). Not a test
# (ctest does not run it): it prints figures, with the load average, for the README.
#
#   tests/bench/bench_scale.sh [MAX_EXP [RUN_MAX_EXP]]
#     MAX_EXP      largest record, 10^MAX_EXP samples (default 8: 800 MB on disk, deleted after)
#     RUN_MAX_EXP  largest record given to `run` (default MAX_EXP; run sends every sample over
#                  the loopback bus to the node, ~6 s per 10^6 samples, so 10^8 takes ~10 min)
#   env IMU_SIM (default build/host_sim/app/imu-sim), TMPDIR (where the records go)
#
# Needs GNU time (/usr/bin/time, Debian package `time`: toolchains/install-deps.sh bench).
# Records: `imu-sim synth` defaults (100 Hz, seed 1), uncompressed MAT v5, 8 bytes per sample.
set -euo pipefail
max_exp=${1:-8}
run_max_exp=${2:-$max_exp}
imu_sim=${IMU_SIM:-build/host_sim/app/imu-sim}
if [ ! -x /usr/bin/time ]; then
  echo "bench_scale: needs GNU time at /usr/bin/time (toolchains/install-deps.sh bench)" >&2
  exit 2
fi
if [ ! -x "$imu_sim" ]; then
  echo "bench_scale: no $imu_sim (cmake --build build --target imu-sim, or set IMU_SIM)" >&2
  exit 2
fi
dir=$(mktemp -d "${TMPDIR:-/tmp}/imu-bench-scale.XXXXXX")
trap 'rm -rf "$dir"' EXIT
need_kb=$(( (8 * 10**max_exp) / 1024 + 65536 ))
free_kb=$(df -Pk "$dir" | awk 'NR == 2 { print $4 }')
if [ "$free_kb" -lt "$need_kb" ]; then
  echo "bench_scale: $dir has $((free_kb / 1024)) MB free, 10^$max_exp samples need $((need_kb / 1024)) MB" >&2
  exit 2
fi

# measure NAME CMD...: runs CMD under GNU time; sets rss_mb and wall_s; fails loudly.
measure() {
  local name=$1
  shift
  if ! /usr/bin/time -f "%M %e" -o "$dir/time" "$@" > "$dir/$name.out" 2> "$dir/$name.err"; then
    echo "bench_scale: $name failed: $*" >&2
    tail -5 "$dir/$name.err" >&2
    exit 1
  fi
  read -r rss_kb wall_s < <(tail -1 "$dir/time")
  rss_mb=$(awk -v k="$rss_kb" 'BEGIN { printf "%.1f", k / 1024 }')
}

echo "imu-sim: $imu_sim ($(git -C "$(dirname "$0")" rev-parse --short HEAD 2>/dev/null || echo '?'))"
echo "machine: $(nproc) cores, load average at start: $(cut -d' ' -f1-3 /proc/loadavg)"
printf '%-10s %8s | %-17s | %-26s | %-17s | %-17s\n' samples file_MB "synth RSS_MB wall_s" \
  "adev RSS_MB wall_s MB/s" "run RSS_MB wall_s" "analyze RSS wall"
for ((e = 6; e <= max_exp; ++e)); do
  n=$((10**e))
  mat="$dir/rec_1e$e.mat"
  measure synth "$imu_sim" synth --out "$mat" --duration $((n / 100))
  synth_rss=$rss_mb synth_wall=$wall_s
  file_mb=$(awk -v b="$(stat -c %s "$mat")" 'BEGIN { printf "%.0f", b / 1e6 }')
  measure adev "$imu_sim" adev "$mat" --channel acc_z --estimator online
  adev_rss=$rss_mb adev_wall=$wall_s
  adev_mbs=$(awk -v m="$file_mb" -v t="$wall_s" 'BEGIN { printf "%.0f", (t > 0) ? m / t : 0 }')
  run_rss="-" run_wall="-"
  if [ "$e" -le "$run_max_exp" ]; then
    measure run "$imu_sim" run "$mat" --channel acc_z --bus loopback --rate max \
      --out "$dir/run" --quiet --no-plots
    run_rss=$rss_mb run_wall=$wall_s
  fi
  measure analyze "$imu_sim" analyze "$mat" --channel acc_z
  analyze_rss=$rss_mb analyze_wall=$wall_s
  printf '%-10s %8s | %8s %8s | %8s %8s %8s | %8s %8s | %8s %8s\n' "1e$e" "$file_mb" \
    "$synth_rss" "$synth_wall" "$adev_rss" "$adev_wall" "$adev_mbs" "$run_rss" "$run_wall" \
    "$analyze_rss" "$analyze_wall"
  rm -f "$mat"
done
# Text input (CSV with a time column), streamed as MAT-files are: 10^6 and 10^7 rows (10^8
# rows of text is ~1.6 GB; TEXT_MAX_EXP=8 to include it). The rows hold a 0.37 Hz sinusoid, so
# analyze's sinusoid search (its spectrum: analyze's largest memory) runs on them.
text_max_exp=${TEXT_MAX_EXP:-7}
printf '%-10s %8s | %-26s | %-17s\n' rows file_MB "adev (CSV) RSS_MB wall_s MB/s" \
  "analyze RSS wall"
for ((e = 6; e <= text_max_exp; ++e)); do
  n=$((10**e))
  csv="$dir/rec_1e$e.csv"
  awk -v n="$n" 'BEGIN { srand(5); print "t,acc_z"
    for (i = 0; i < n; i++) printf "%.2f,%.4f\n", i * 0.01,
      9.81 + 0.01 * (rand() - 0.5) + 0.002 * sin(2.324779 * i * 0.01) }' > "$csv"
  file_mb=$(awk -v b="$(stat -c %s "$csv")" 'BEGIN { printf "%.0f", b / 1e6 }')
  measure adev_text "$imu_sim" adev "$csv" --channel acc_z --lsb 1e-4 --estimator online
  mbs=$(awk -v m="$file_mb" -v t="$wall_s" 'BEGIN { printf "%.0f", (t > 0) ? m / t : 0 }')
  adev_rss=$rss_mb adev_wall=$wall_s
  measure analyze_text "$imu_sim" analyze "$csv" --channel acc_z --lsb 1e-4
  printf '%-10s %8s | %8s %8s %8s | %8s %8s\n' "1e$e" "$file_mb" "$adev_rss" "$adev_wall" \
    "$mbs" "$rss_mb" "$wall_s"
  rm -f "$csv"
done
echo "load average at end: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "(RSS: peak resident set, GNU time %M; wall: whole process; adev MB/s: file MB / wall)"
