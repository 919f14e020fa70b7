#!/usr/bin/env bash
# The README's main command: on a fresh Debian 12 machine, install what is missing, build
# imu-sim and imu-fw (release preset), synthesise the default data (the seed's model plus rate
# random walk: the seed's marble-slab recording is not public), send it through the loopback
# bus to imu-fw running as a separate process, and leave the report in out/demo/:
#   report.txt      the text report (model in the seed's layout, ADEV table with intervals,
#                   covariance check, frame statistics)
#   report.json     the same for machines
#   fig1_adev.svg/.png, fig2_covariance.svg/.png   the seed's Fig. 1 and Fig. 2 (gnuplot)
#   *.csv           the data behind each figure; *.gp the gnuplot scripts
#   synth.mat       the synthesised recording; imu-fw.log the firmware node's own output
# Needs nothing outside the repository (no ../shared). Usage: bash host_sim/demo.sh
set -euo pipefail
cd "$(dirname "$0")/.."
t0=$(date +%s.%N)
elapsed() { echo "$(date +%s.%N) $t0" | awk '{printf "%.1f", $1 - $2}'; }

echo "== 1/4 dependencies (toolchains/install-deps.sh core)"
toolchains/install-deps.sh core

echo "== 2/4 build (cmake --preset release; imu-sim, imu-fw)"
cmake --preset release >/dev/null
cmake --build --preset release --target imu-sim imu-fw -j"$(nproc)"
t_build=$(elapsed)
bin=build/host_sim/app
out=out/demo
mkdir -p "$out"

echo "== 3/4 synthesise the default data ($out/synth.mat)"
"$bin/imu-sim" synth --out "$out/synth.mat"

echo "== 4/4 run: emulator -> loopback bus -> imu-fw (separate process) -> telemetry -> report"
"$bin/imu-sim" run "$out/synth.mat" --channel acc_z --bus loopback --rate max \
  --node spawn --fw "$bin/imu-fw" --out "$out" --N 3.3e-3 --B 9e-4 --Tp 300 --K 1.4e-4

echo
echo "report folder: $(cd "$out" && pwd)"
echo "elapsed: $(elapsed) s (dependencies + build: ${t_build} s)"
