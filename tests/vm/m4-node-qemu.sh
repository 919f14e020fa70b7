#!/usr/bin/env bash
# The same firmware Node on the Cortex-M4: builds imu_m4_node.elf with
# toolchains/arm-none-eabi-m4.cmake, checks that imu::node::Node::on_frame is in its symbol
# table, runs it on QEMU's mps2-an386 with -icount shift=0 (one virtual-clock step per guest
# instruction, so the image's SysTick readings count instructions) and compares its telemetry
# with the host's run of the same frames through the same Node (imu_m4_node_check --compare:
# every telemetry frame byte for byte).
#   tests/vm/m4-node-qemu.sh SOURCE_DIR M4_BUILD_DIR IMU_M4_NODE_CHECK
# Exit 0 on "NODE-CHECK PASS", 77 (skip) if arm-none-eabi-g++ or qemu-system-arm is missing.
set -euo pipefail
src=$1 bld=$2 check=$3
skip() { echo "m4-node-qemu: SKIP: $*"; exit 77; }
command -v arm-none-eabi-g++ >/dev/null || skip "arm-none-eabi-g++ not found (gcc-arm-none-eabi)"
command -v qemu-system-arm >/dev/null || skip "qemu-system-arm not found (qemu-system-arm)"
if [ ! -f "$bld/CMakeCache.txt" ]; then
  gen=()
  command -v ninja >/dev/null && gen=(-G Ninja)
  cmake -S "$src" -B "$bld" "${gen[@]}" \
        -DCMAKE_TOOLCHAIN_FILE="$src/toolchains/arm-none-eabi-m4.cmake" -DCMAKE_BUILD_TYPE=MinSizeRel >"$bld.configure.log" 2>&1 ||
    { cat "$bld.configure.log"; echo "m4-node-qemu: configure failed"; exit 1; }
fi
cmake --build "$bld" --target imu_m4_node || { echo "m4-node-qemu: build failed"; exit 1; }
elf="$bld/toolchains/m4/imu_m4_node.elf"
tail -n1 "$elf.size"
# The symbol table into a variable first: `nm | grep -q` under pipefail fails on nm's SIGPIPE.
syms=$(arm-none-eabi-nm -C -S "$elf")
on_frame=$(grep ' T imu::node::Node::on_frame(' <<<"$syms" || true)
if [ -z "$on_frame" ]; then
  echo "m4-node-qemu: FAIL: imu::node::Node::on_frame is not in $elf"
  exit 1
fi
echo "m4-node-qemu: symbol: $on_frame"
echo "m4-node-qemu: the Node object: $(grep 'g_node$' <<<"$syms" || true)"
log="$bld/imu_m4_node.qemu.log"
rc=0
timeout 300 qemu-system-arm -M mps2-an386 -nographic -monitor none -serial none -icount shift=0 \
  -semihosting-config enable=on,target=native -kernel "$elf" >"$log" 2>&1 || rc=$?
echo "m4-node-qemu: qemu-system-arm exit $rc, $(wc -l <"$log") lines in $log"
if [ "$rc" != 0 ]; then
  tail -n 20 "$log"
  echo "m4-node-qemu: FAIL (qemu exit $rc)"
  exit 1
fi
"$check" --compare "$log"
