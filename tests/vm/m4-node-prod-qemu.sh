#!/usr/bin/env bash
# The production node image (imu_m4_node_prod.elf: the node's MCU main loop, fw/node, on the
# mps2-an386 board of the hal MCU backend, hal/src/mcu/boards/mps2_an386; assembled in
# toolchains/m4) and its smoke variant, built with
# toolchains/arm-none-eabi-m4.cmake in M4_BUILD_DIR (the same folder as m4-node-qemu.sh).
#   tests/vm/m4-node-prod-qemu.sh smoke SOURCE_DIR M4_BUILD_DIR
#     builds the production image and its smoke variant, prints both sizes, runs the smoke
#     variant on QEMU's mps2-an386 (-icount shift=0: deterministic) and passes on
#     "PROD-SMOKE PASS" (frames injected through the receive interrupt path, telemetry out).
#   tests/vm/m4-node-prod-qemu.sh ram64k SOURCE_DIR M4_BUILD_DIR
#     builds the production image and passes if its RAM (.data + .bss, the stack included) is
#     at most 64 KiB, printing the figures (the link itself fails above IMU_M4_PROD_RAM_LIMIT;
#     this checks the target whatever that cache variable says).
# Exit 0 on pass, 77 (skip) if arm-none-eabi-g++ or qemu-system-arm is missing.
set -euo pipefail
mode=$1 src=$2 bld=$3
skip() { echo "m4-node-prod: SKIP: $*"; exit 77; }
command -v arm-none-eabi-g++ >/dev/null || skip "arm-none-eabi-g++ not found (gcc-arm-none-eabi)"
if [ ! -f "$bld/CMakeCache.txt" ]; then
  gen=()
  command -v ninja >/dev/null && gen=(-G Ninja)
  cmake -S "$src" -B "$bld" "${gen[@]}" \
        -DCMAKE_TOOLCHAIN_FILE="$src/toolchains/arm-none-eabi-m4.cmake" -DCMAKE_BUILD_TYPE=MinSizeRel >"$bld.configure.log" 2>&1 ||
    { cat "$bld.configure.log"; echo "m4-node-prod: configure failed"; exit 1; }
fi
dir="$bld/toolchains/m4"
case "$mode" in
  smoke)
    command -v qemu-system-arm >/dev/null || skip "qemu-system-arm not found (qemu-system-arm)"
    cmake --build "$bld" --target imu_m4_node_prod imu_m4_node_prod_smoke ||
      { echo "m4-node-prod: build failed"; exit 1; }
    echo "m4-node-prod: production image: $(tail -n1 "$dir/imu_m4_node_prod.elf.size")"
    echo "m4-node-prod: smoke variant:    $(tail -n1 "$dir/imu_m4_node_prod_smoke.elf.size")"
    log="$bld/imu_m4_node_prod_smoke.qemu.log"
    rc=0
    timeout 300 qemu-system-arm -M mps2-an386 -nographic -monitor none -serial none \
      -icount shift=0 -semihosting-config enable=on,target=native \
      -kernel "$dir/imu_m4_node_prod_smoke.elf" >"$log" 2>&1 || rc=$?
    cat "$log"
    echo "m4-node-prod: qemu-system-arm exit $rc"
    [ "$rc" = 0 ] && grep -q '^PROD-SMOKE PASS' "$log"
    ;;
  ram64k)
    cmake --build "$bld" --target imu_m4_node_prod || { echo "m4-node-prod: build failed"; exit 1; }
    sizes=$(sed -n 2p "$dir/imu_m4_node_prod.elf.size")
    read -r _ data bss _ <<<"$sizes"
    stack=$(arm-none-eabi-size -A "$dir/imu_m4_node_prod.elf" | awk '$1 == ".stack" {print $2}')
    echo "m4-node-prod: production image RAM: data $data + bss $bss = $((data + bss)) bytes" \
         "(stack $stack included; without it $((data + bss - stack)))"
    if [ $((data + bss)) -le 65536 ]; then
      echo "m4-node-prod: 64 KiB RAM target: fits, $((65536 - data - bss)) bytes to spare"
      echo "PROD-RAM-64K FITS"
    else
      echo "m4-node-prod: 64 KiB RAM target: does not fit ($((data + bss - 65536)) bytes over)"
      exit 1
    fi
    ;;
  *) echo "usage: $0 smoke|ram64k SOURCE_DIR M4_BUILD_DIR"; exit 2 ;;
esac
