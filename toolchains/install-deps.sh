#!/usr/bin/env bash
# Installs the Debian 12 packages a job needs, only those missing. Usage:
#   toolchains/install-deps.sh core     # build + run imu-sim / imu-fw (g++, cmake, libgpiod)
#   toolchains/install-deps.sh test     # core + GoogleTest, Benchmark, clang, fuzzing, cross, VM
#   toolchains/install-deps.sh bench    # core + GNU time, numpy/scipy (tests/bench/*.sh)
set -euo pipefail
group=${1:-core}
core=(cmake ninja-build g++ make pkg-config libgpiod-dev gpiod gnuplot-nox)
test=(clang clang-tidy libclang-rt-14-dev libfuzzer-14-dev libgtest-dev libbenchmark-dev
      binutils gcc-arm-none-eabi libnewlib-arm-none-eabi libstdc++-arm-none-eabi-newlib
      g++-aarch64-linux-gnu qemu-user qemu-system-x86 qemu-system-arm busybox-static can-utils
      iproute2 kmod cpio xz-utils python3 python3-rosbag python3-sensor-msgs)
bench=(time python3 python3-numpy python3-scipy)
case "$group" in
  core) want=("${core[@]}") ;;
  bench) want=("${core[@]}" "${bench[@]}") ;;
  test) want=("${core[@]}" "${test[@]}") ;;
  *) echo "install-deps.sh: unknown group '$group' (core|test|bench)" >&2; exit 2 ;;
esac
missing=()
for p in "${want[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO=sudo; fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
