#!/usr/bin/env bash
# Whole-process `imu-sim adev` against allantools' `oadev` (taus="octave") on the same MAT-file,
# alternating runs, medians and their ratio (target >= 40). Not a test (ctest does not
# run it): it prints figures, with the load average.
#
#   tests/bench/bench_vs_allantools.sh [RUNS [FILE [CHANNEL]]]
#     RUNS     runs of each (default 9), FILE (default ../shared/data/adis16405_imu1.mat),
#     CHANNEL  (default acc_z)
#   env IMU_SIM (default build/host_sim/app/imu-sim), PYTHON (default /usr/bin/python3: Debian's,
#       with python3-numpy and python3-scipy), ALLANTOOLS_DIR (default /tmp/allantools)
#
# allantools is never part of this repository. To get it (outside the repository):
#   git clone https://github.com/aewallin/allantools /tmp/allantools   (or an archive of it)
# and `toolchains/install-deps.sh bench` for numpy/scipy. Without it the script prints our
# figures alone and says so.
#
# Both sides pay for a whole process: ours reads and inflates the file with our own reader and
# computes OnlineAdev<8,22>'s fixed tau grid (8 taus per octave, up to 2^22 samples); the Python
# side starts the interpreter, imports numpy/scipy/allantools, loads the file with
# scipy.io.loadmat and computes oadev at octave taus (1, 2, 4, ... samples). The tau sets differ
# (ours has more taus); neither side's output is compared here.
set -euo pipefail
runs=${1:-9}
root=$(cd "$(dirname "$0")/../.." && pwd)
file=${2:-$root/../shared/data/adis16405_imu1.mat}
chan=${3:-acc_z}
imu_sim=${IMU_SIM:-$root/build/host_sim/app/imu-sim}
py=${PYTHON:-/usr/bin/python3}
at_dir=${ALLANTOOLS_DIR:-/tmp/allantools}
if [ ! -x "$imu_sim" ]; then
  echo "bench_vs_allantools: no $imu_sim (cmake --build build --target imu-sim)" >&2
  exit 2
fi
if [ ! -f "$file" ]; then
  echo "bench_vs_allantools: no $file (the shared data)" >&2
  exit 2
fi
file=$(cd "$(dirname "$file")" && pwd)/$(basename "$file")
case "$at_dir" in
  "$root"|"$root"/*) echo "bench_vs_allantools: ALLANTOOLS_DIR must be outside the repository" >&2
                     exit 2 ;;
esac
pycode='
import sys
import numpy as np, scipy.io, allantools
m = scipy.io.loadmat(sys.argv[1])
x = np.asarray(m[sys.argv[2]], dtype=float).ravel()
fs = float(np.asarray(m["fs"]).ravel()[0])
taus, ad, ade, ns = allantools.oadev(x, rate=fs, data_type="freq", taus="octave")
print(len(x), len(taus), taus[0], ad[0], taus[-1], ad[-1])
'
have_at=1
if ! (cd /tmp && PYTHONPATH="$at_dir" "$py" -c 'import numpy, scipy.io, allantools' 2>/dev/null); then
  have_at=0
fi

# Times: bash's own clock ($EPOCHREALTIME, bash 5, microseconds), read without a subprocess:
# `$(date +%s.%N)` forked and exec'd a process per reading, and the second reading's start-up
# (3-4 ms on this machine) was counted in the interval of both sides.
median() { sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }

ours=()
theirs=()
echo "file: $file, channel $chan, $runs runs each, alternating"
echo "imu-sim: $imu_sim ($(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo '?'))"
if [ "$have_at" = 1 ]; then
  echo "allantools: $at_dir ($(git -C "$at_dir" rev-parse --short HEAD 2>/dev/null || \
    (cd /tmp && PYTHONPATH="$at_dir" "$py" -c 'import allantools; print(allantools.__version__)' \
    2>/dev/null) || echo '?')), python $("$py" -c 'import sys, numpy, scipy; print(sys.version.split()[0], "numpy", numpy.__version__, "scipy", scipy.__version__)')"
else
  echo "allantools: NOT AVAILABLE (no importable allantools at $at_dir with $py + numpy/scipy):"
  echo "            our figures alone, no ratio"
fi
echo "load average at start: $(cut -d' ' -f1-3 /proc/loadavg)"
for ((i = 0; i < runs; ++i)); do
  t0=${EPOCHREALTIME/,/.}
  "$imu_sim" adev "$file" --channel "$chan" --estimator online > /tmp/bench_vs_at.ours.$$ 2>&1
  t1=${EPOCHREALTIME/,/.}
  ours+=("$(awk -v a="$t0" -v b="$t1" 'BEGIN { print b - a }')")
  if [ "$have_at" = 1 ]; then
    t0=${EPOCHREALTIME/,/.}
    (cd /tmp && PYTHONPATH="$at_dir" "$py" -c "$pycode" "$file" "$chan") > /tmp/bench_vs_at.theirs.$$
    t1=${EPOCHREALTIME/,/.}
    theirs+=("$(awk -v a="$t0" -v b="$t1" 'BEGIN { print b - a }')")
  fi
done
m_ours=$(printf '%s\n' "${ours[@]}" | median)
echo "imu-sim adev:      median $(awk -v m="$m_ours" 'BEGIN { printf "%.4f", m }') s  (runs: ${ours[*]})"
grep -E '^time:' /tmp/bench_vs_at.ours.$$ | sed 's/^/  last run /' || true
if [ "$have_at" = 1 ]; then
  m_theirs=$(printf '%s\n' "${theirs[@]}" | median)
  echo "allantools oadev:  median $(awk -v m="$m_theirs" 'BEGIN { printf "%.4f", m }') s  (runs: ${theirs[*]})"
  echo "  last run: samples, octave taus, tau[0] adev[0], tau[-1] adev[-1]: $(cat /tmp/bench_vs_at.theirs.$$)"
  echo "ratio (allantools / imu-sim, medians): $(awk -v a="$m_theirs" -v b="$m_ours" 'BEGIN { printf "%.1f", a / b }')"
fi
rm -f /tmp/bench_vs_at.ours.$$ /tmp/bench_vs_at.theirs.$$
echo "load average at end: $(cut -d' ' -f1-3 /proc/loadavg)"
