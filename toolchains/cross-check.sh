#!/usr/bin/env bash
# Builds both cross targets and runs what can run on this machine (CI calls this):
#  1. aarch64-linux-gnu: the whole project, then the `unit` tests under qemu-aarch64 user mode;
#  2. arm-none-eabi Cortex-M4F: fw/, the hal MCU backend and board (hal/src/mcu/boards) and the
#     M4 images (demo 1 and 6 channels, node, production node), heap check on the link maps,
#     arm-none-eabi-size, the 6-channel demo's budget (flash < 32 KiB, RAM < 48 KiB);
#  3. the 6-channel image under qemu-system-arm (mps2-an386, semihosting), every number it prints
#     compared with the host twin (imu_m4_check) and a direct ADEV.
# Usage: toolchains/cross-check.sh            (build dirs build-aarch64, build-m4, build-m4host)
#        IMU_CROSS_PREFIX=build-x toolchains/cross-check.sh   (build-x-aarch64, build-x-m4, ...)
#        IMU_CROSS_ONLY=aarch64|m4 toolchains/cross-check.sh  (one target only)
# Installs the arm64 multiarch libraries (gtest, benchmark, libgpiod) if missing (root/sudo).
# Every stage runs even if an earlier one failed (a failing aarch64 test must not hide the M4
# results); the script exits 1 at the end if any stage failed, listing them.
set -uo pipefail
cd "$(dirname "$0")/.."
prefix=${IMU_CROSS_PREFIX:-build}
only=${IMU_CROSS_ONLY:-}
jobs=${IMU_CROSS_JOBS:-$(nproc)}
ms() { echo $(( $(date +%s%N) / 1000000 )); }
secs() { printf '%d.%d' $(( $1 / 1000 )) $(( $1 % 1000 / 100 )); }
t0=$(ms)
stage_t=$t0
stage() {
  local now
  now=$(ms)
  echo "=== cross-check: $1 (at $(secs $((now - t0))) s)"
  stage_t=$now
}
gen=()
command -v ninja >/dev/null && gen=(-G Ninja)
failed=()
check() {  # check NAME COMMAND...: run, record a failure under NAME
  local name=$1
  shift
  "$@" || { echo "cross-check: FAILED: $name"; failed+=("$name"); return 1; }
}

if [ "$only" != m4 ]; then
stage "arm64 multiarch libraries"
need=()
for p in libgtest-dev:arm64 libbenchmark-dev:arm64 libgpiod-dev:arm64; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || need+=("$p")
done
if [ ${#need[@]} -gt 0 ]; then
  SUDO=""
  [ "$(id -u)" = 0 ] || SUDO=sudo
  dpkg --print-foreign-architectures | grep -qx arm64 || $SUDO dpkg --add-architecture arm64
  export DEBIAN_FRONTEND=noninteractive
  check "arm64 libraries" $SUDO apt-get update -qq &&
    check "arm64 libraries" $SUDO apt-get install -y -qq --no-install-recommends "${need[@]}" >/dev/null
fi

stage "aarch64: configure + build everything"
a64=$prefix-aarch64
if check "aarch64 configure" cmake -S . -B "$a64" "${gen[@]}" \
     -DCMAKE_TOOLCHAIN_FILE=toolchains/aarch64-linux-gnu.cmake -DCMAKE_BUILD_TYPE=Release >/dev/null &&
   check "aarch64 build" cmake --build "$a64" -j"$jobs"; then
  stage "aarch64: unit tests under qemu-aarch64"
  # qemu-aarch64 user mode hangs on a second thread here: the tools run single-threaded.
  check "aarch64 unit tests" env IMU_NO_THREADS=1 ctest --test-dir "$a64" -L unit -j"$jobs" \
    --output-on-failure
fi
fi  # aarch64

if [ "$only" != aarch64 ]; then

stage "m4: configure + build fw and the bare-metal program"
m4=$prefix-m4
# The build's post-build step fails on a heap symbol in a link map (check_m4_image.cmake).
budget() {
  local summary6 flash ram
  for c in 1 6; do
    cat "$m4/toolchains/m4/imu_m4_demo_c$c.elf.size"
  done
  summary6=$(tail -n1 "$m4/toolchains/m4/imu_m4_demo_c6.elf.size")
  flash=$(sed -n 's/.* flash=\([0-9]*\).*/\1/p' <<<"$summary6")
  ram=$(sed -n 's/.* ram=\([0-9]*\).*/\1/p' <<<"$summary6")
  if [ "$flash" -ge 32768 ] || [ "$ram" -ge 49152 ]; then
    echo "cross-check: 6-channel image over budget: flash $flash (< 32768), RAM $ram (< 49152)"
    return 1
  fi
  echo "cross-check: 6-channel image within budget: flash $flash < 32768, RAM $ram < 49152"
}
m4_ok=0
check "m4 configure" cmake -S . -B "$m4" "${gen[@]}" \
    -DCMAKE_TOOLCHAIN_FILE=toolchains/arm-none-eabi-m4.cmake -DCMAKE_BUILD_TYPE=MinSizeRel >/dev/null &&
  check "m4 build (incl. link-map heap check)" cmake --build "$m4" -j"$jobs" && m4_ok=1
[ $m4_ok = 1 ] && check "m4 size budget" budget

stage "m4: qemu-system-arm mps2-an386 vs host twin"
host=$prefix-m4host
log="$m4/imu_m4_demo_c6.qemu.log"
if [ $m4_ok = 1 ] &&
   check "host twin configure" cmake -S . -B "$host" "${gen[@]}" -DCMAKE_BUILD_TYPE=Release >/dev/null &&
   check "host twin build" cmake --build "$host" --target imu_m4_check -j"$jobs"; then
  check "m4 under qemu-system-arm" timeout 300 qemu-system-arm -M mps2-an386 -nographic \
      -monitor none -serial none -semihosting-config enable=on,target=native \
      -kernel "$m4/toolchains/m4/imu_m4_demo_c6.elf" >"$log" 2>&1 &&
    check "m4 output vs host twin" "$host/tests/vm/m4/imu_m4_check" --compare "$log"
fi
fi  # m4

stage "done"
if [ ${#failed[@]} -gt 0 ]; then
  echo "cross-check: FAIL (${failed[*]}) in $(secs $(( $(ms) - t0 ))) s"
  exit 1
fi
echo "cross-check: PASS in $(secs $(( $(ms) - t0 ))) s"
