#!/usr/bin/env bash
# Builds the Cortex-M4F image with toolchains/arm-none-eabi-m4.cmake, runs it on QEMU's
# mps2-an386 with semihosting and compares its output with the host twin.
#   tests/vm/m4-qemu.sh SOURCE_DIR M4_BUILD_DIR IMU_M4_CHECK
# Exit 0 on "M4-CHECK PASS", 77 (skip) if arm-none-eabi-g++ or qemu-system-arm is missing.
set -euo pipefail
src=$1 bld=$2 check=$3
skip() { echo "m4-qemu: SKIP: $*"; exit 77; }
command -v arm-none-eabi-g++ >/dev/null || skip "arm-none-eabi-g++ not found (gcc-arm-none-eabi)"
command -v qemu-system-arm >/dev/null || skip "qemu-system-arm not found (qemu-system-arm)"
ms() { echo $(( $(date +%s%N) / 1000000 )); }
start=$(ms)
if [ ! -f "$bld/CMakeCache.txt" ]; then
  gen=()
  command -v ninja >/dev/null && gen=(-G Ninja)
  cmake -S "$src" -B "$bld" "${gen[@]}" -DCMAKE_TOOLCHAIN_FILE="$src/toolchains/arm-none-eabi-m4.cmake" \
        -DCMAKE_BUILD_TYPE=MinSizeRel >"$bld.configure.log" 2>&1 ||
    { cat "$bld.configure.log"; echo "m4-qemu: configure failed"; exit 1; }
fi
cmake --build "$bld" --target imu_m4_demo_c1 imu_m4_demo_c6 || { echo "m4-qemu: build failed"; exit 1; }
for c in 1 6; do
  tail -n1 "$bld/toolchains/m4/imu_m4_demo_c$c.elf.size"
done
log="$bld/imu_m4_demo_c6.qemu.log"
t0=$(ms)
# qemu exits with the code the program passes to SYS_EXIT_EXTENDED (0 = ok); the timeout
# catches a program that never exits (e.g. a fault before semihosting works).
rc=0
timeout 300 qemu-system-arm -M mps2-an386 -nographic -monitor none -serial none \
  -semihosting-config enable=on,target=native -kernel "$bld/toolchains/m4/imu_m4_demo_c6.elf" \
  >"$log" 2>&1 || rc=$?
t1=$(ms)
echo "m4-qemu: qemu-system-arm exit $rc, $(( t1 - t0 )) ms, $(wc -l <"$log") lines in $log"
if [ "$rc" != 0 ]; then
  tail -n 20 "$log"
  echo "m4-qemu: FAIL (qemu exit $rc)"
  exit 1
fi
"$check" --compare "$log"
echo "m4-qemu: total $(( $(ms) - start )) ms"
