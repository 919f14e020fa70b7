#!/usr/bin/env bash
# The README's main command: on a fresh Debian 12 machine, install what is missing, build
# imu-sim and imu-fw (release preset), synthesise the default data (the first-order model plus rate
# random walk: the marble-slab recording of the example is not public), send it through the loopback
# bus to imu-fw running as a separate process, and leave the report in out/demo/:
#   report.txt      the text report (model in the example's layout, ADEV table with intervals,
#                   covariance check, frame statistics)
#   report.json     the same for machines
#   fig1_adev.svg/.png, fig2_covariance.svg/.png   the example's Fig. 1 and Fig. 2 (gnuplot)
#   *.csv           the data behind each figure; *.gp the gnuplot scripts
#   synth.mat       the synthesised recording; imu-fw.log the firmware node's own output
#   analysis.json, pushed/   imu-sim analyze's model, and the run with it pushed to the node
#   node_models.txt the node's filter with the first-order model and with the pushed one, side by side
# Needs nothing outside the repository (no ../shared). Usage: bash host_sim/demo.sh
set -euo pipefail
cd "$(dirname "$0")/.."
t0=$(date +%s.%N)
elapsed() { echo "$(date +%s.%N) $t0" | awk '{printf "%.1f", $1 - $2}'; }

echo "== 1/5 dependencies (toolchains/install-deps.sh core)"
toolchains/install-deps.sh core

echo "== 2/5 build (cmake --preset release; imu-sim, imu-fw)"
cmake --preset release >/dev/null
cmake --build --preset release --target imu-sim imu-fw -j"$(nproc)"
t_build=$(elapsed)
bin=build/host_sim/app
out=out/demo
mkdir -p "$out"

echo "== 3/5 synthesise the default data ($out/synth.mat)"
"$bin/imu-sim" synth --out "$out/synth.mat"

echo "== 4/5 run: emulator -> loopback bus -> imu-fw (separate process) -> telemetry -> report"
"$bin/imu-sim" run "$out/synth.mat" --channel acc_z --bus loopback --rate max \
  --node spawn --fw "$bin/imu-fw" --out "$out" --N 3.3e-3 --B 9e-4 --Tp 300 --K 1.4e-4

echo
echo "== 5/5 analyze, push its model to the node (imu-sim run --model), compare"
"$bin/imu-sim" analyze "$out/synth.mat" --channel acc_z --json "$out/analysis.json" >/dev/null
"$bin/imu-sim" run "$out/synth.mat" --channel acc_z --bus loopback --rate max --node spawn \
  --fw "$bin/imu-fw" --out "$out/pushed" --N 3.3e-3 --B 9e-4 --Tp 300 --K 1.4e-4 \
  --model "$out/analysis.json" --no-plots --quiet --sim-windows 10 >/dev/null
field() { grep -o "\"$2\": [^,}]*" "$1" | head -1 | sed 's/.*: //'; }
{
  printf '%-22s %-10s %-9s %-9s %-10s %s\n' "node filter (acc_z)" origin n_states nis_mean \
    whiteness cusum_alarm
  for f in "$out/report.json" "$out/pushed/report.json"; do
    node=$(mktemp)
    grep '"node":' "$f" | sed 's/.*"node": //' >"$node"
    printf '%-22s %-10s %-9s %-9s %-10s %s\n' "$([ "$f" = "$out/report.json" ] && echo "first-order model" || echo "pushed (analyze)")" \
      "$(field "$node" origin | tr -d '"')" "$(field "$node" n_states)" \
      "$(field "$node" nis_mean)" "$(field "$node" whiteness_ratio)" "$(field "$node" cusum_alarm)"
    rm -f "$node"
  done
  echo "(CUSUM slack 0.025, threshold 247.4 for an in-control run length of 1e8 updates;"
  echo " cusum_alarm: it detected a level shift, after which the node moves to the new level and"
  echo " re-arms: fw/include/imu/residual_monitor.hpp, fw/node/include/imu/node/node.hpp)"
} | tee "$out/node_models.txt"

echo
echo "report folder: $(cd "$out" && pwd)"
echo "elapsed: $(elapsed) s (dependencies + build: ${t_build} s)"
