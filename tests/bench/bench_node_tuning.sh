#!/usr/bin/env bash
# The node's monitors with the pushed models as the analysis wrote them (`run --model
# --model-as-is`) and tuned to the node's filter on the record (`run --model`, the default):
# per channel the whiteness test's failing blocks against those its own false-alarm rate
# allows, the NIS mean and the CUSUM's level shifts. On `imu-sim synth` records of the
# first-order model plus a walk (twelve: six parameter sets, two seeds each, acc_z alone), and
# on both shared ADIS16405 units (all six channels) when ../shared/data holds them. Not a test
# (ctest does not run it): it prints a table for the README.
#
#   tests/bench/bench_node_tuning.sh [SHARED_DATA_DIR]
#   env IMU_SIM (default build/host_sim/app/imu-sim), TMPDIR (where the records go)
set -euo pipefail
shared=${1:-../shared/data}
imu_sim=${IMU_SIM:-build/host_sim/app/imu-sim}
if [ ! -x "$imu_sim" ]; then
  echo "bench_node_tuning: no $imu_sim (cmake --build build --target imu-sim, or set IMU_SIM)" >&2
  exit 2
fi
dir=$(mktemp -d "${TMPDIR:-/tmp}/imu-bench-tuning.XXXXXX")
trap 'rm -rf "$dir"' EXIT

# rows RUN_DIR MODE LABEL: the report's per-channel rows of the node, one line each.
rows() {
  awk -v mode="$2" -v label="$3" '
    /^channel +model +states/ { on = 1; next }
    on && /^(acc|gyro)_/ { printf "| %s | %s | %s | %s | %s | %s |\n", label, $1, mode, $4,
                           $6 " " $7, ($8 == "quiet" ? "quiet" : $8) ; next }
    on { on = 0 }' "$1/report.txt"
}

# both RECORD ANALYSIS LABEL [run options]: the run with the models as written, then tuned.
both() {
  local mat=$1 json=$2 label=$3
  shift 3
  for mode in as-is tuned; do
    local extra=()
    [ "$mode" = as-is ] && extra=(--model-as-is)
    "$imu_sim" run "$mat" --no-plots --quiet --sim-windows 10 --out "$dir/run" \
      --model "$json" "${extra[@]}" "$@" > "$dir/run.out" 2>&1 ||
      { cat "$dir/run.out" >&2; exit 1; }
    rows "$dir/run" "$mode" "$label"
  done
}

echo "| record | channel | models | NIS mean | whiteness: failing blocks | CUSUM shifts |"
echo "|---|---|---|---|---|---|"
i=0
for spec in "--N 3.3e-3 --B 9e-4 --Tp 300 --K 1.4e-4 --fs 100" \
            "--N 1e-3 --B 2e-4 --Tp 50 --K 0 --fs 200" \
            "--N 5e-3 --B 1e-3 --Tp 1000 --K 5e-5 --fs 100" \
            "--N 2e-4 --B 5e-5 --Tp 20 --K 0 --fs 400" \
            "--N 3e-3 --B 3e-3 --Tp 5 --K 0 --fs 100" \
            "--N 1e-2 --B 1e-3 --Tp 200 --K 1e-4 --fs 50"; do
  for seed in 8101 8102; do
    i=$((i + 1))
    # shellcheck disable=SC2086  # the spec is a list of options
    "$imu_sim" synth --out "$dir/s.mat" --duration 5000 --seed "$seed" $spec > /dev/null
    "$imu_sim" analyze "$dir/s.mat" --channel acc_z --json "$dir/a.json" > /dev/null
    local_spec=${spec#--}
    both "$dir/s.mat" "$dir/a.json" "synth $i (seed $seed, ${local_spec// --/, })" \
      --channel acc_z --only-channel
  done
done
for unit in adis16405_imu1 adis16405_imu2; do
  mat="$shared/$unit.mat"
  [ -f "$mat" ] || { echo "($mat absent: skipped)"; continue; }
  "$imu_sim" analyze "$mat" --channel all --json "$dir/all.json" > /dev/null
  both "$mat" "$dir/all.json" "$unit" --channel acc_x
done
echo "(whiteness: blocks of 1000 updates failing the 95 % Box-Pierce test / blocks, and ok"
echo " while within the test's own 5 % false-alarm rate at the 1 % level)"
