#!/usr/bin/env bash
# Boots Debian's kernel under qemu-system-x86_64 (TCG) with an initramfs holding busybox,
# can-utils, gpiod tools, the CAN/gpio-sim modules and the project's binaries, runs
# tests/vm/guest-init.sh as /init and checks its results (docs: ../shared/docs/VM-TESTING.md).
#   tests/vm/vm-run.sh WORK_DIR [PROJECT_BINARY...]
# WORK_DIR holds the initramfs tree and the console log (vm-console.log). Environment:
#   IMU_VM_CACHE    cache for kernel and modules (default /var/cache/imu-vm, see vm-prepare.sh)
#   IMU_SHARED_DIR  shared data folder; an excerpt of its first data/*.mat goes to /data
#   IMU_VM_MAT_SAMPLES  samples of that excerpt (default 50000; "all": the whole file)
#   IMU_VM_TIMEOUT  seconds before the guest is killed (default 1200: the checks take 6 to 11
#                   minutes under TCG, depending on the host CPU and its load)
#   IMU_VM_TESTS    run only these guest checks (space-separated names, see guest-init.sh)
# Exit 0 when the guest printed its marker with fail=0, 77 (skip) when a prerequisite is
# missing, 1 otherwise. Prints "VM-TEST PASS|FAIL ..." with the total time.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
work=$1
shift
ms() { echo $(( $(date +%s%N) / 1000000 )); }
t_start=$(ms)
skip() { echo "vm-run: SKIP: $*"; exit 77; }

prep_out=$("$here/vm-prepare.sh") || { rc=$?; [ $rc = 77 ] && skip "prerequisite missing (see above)"; exit $rc; }
KROOT=$(sed -n 's/^KROOT=//p' <<<"$prep_out")
GPIOSIM=$(sed -n 's/^GPIOSIM=//p' <<<"$prep_out")
ABI=$(ls "$KROOT/lib/modules")
t_prep=$(ms)

root="$work/root"
rm -rf "$root"
mkdir -p "$root"/{bin,sbin,lib/modules/imu,opt/host/bin,opt/imu/bin,data,proc,sys,dev,tmp}

# A binary and every library ldd lists for it (with the loader), at their host paths.
copy_with_libs() {
  local bin=$1 dest=$2
  cp -L "$bin" "$root/$dest/"
  ldd "$bin" 2>/dev/null | grep -o '/[^ ]*' | while read -r lib; do
    [ -e "$root$lib" ] && continue
    mkdir -p "$root$(dirname "$lib")"
    cp -L "$lib" "$root$lib"
  done
}

cp "$(command -v busybox)" "$root/bin/busybox"
file -L "$root/bin/busybox" 2>/dev/null | grep -q 'statically linked' ||
  ldd "$root/bin/busybox" 2>&1 | grep -q 'not a dynamic' || skip "busybox is not static (install busybox-static)"
cp "$here/guest-init.sh" "$root/init"
chmod +x "$root/init"

host_tools=(ip candump cansend cangen canplayer gpiodetect gpioinfo gpiofind gpioget gpioset)
for tool in "${host_tools[@]}"; do
  path=$(PATH=/usr/sbin:/sbin:$PATH command -v "$tool") || skip "'$tool' not found (iproute2, can-utils, gpiod)"
  copy_with_libs "$path" opt/host/bin
done
for bin in "$@"; do
  if [ -x "$bin" ]; then
    copy_with_libs "$bin" opt/imu/bin
  else
    echo "vm-run: note: project binary $bin not built, its checks will SKIP"
  fi
done

m=$KROOT/lib/modules/$ABI/kernel
for ko in "$m/net/can/can.ko" "$m/net/can/can-raw.ko" "$m/drivers/net/can/dev/can-dev.ko" \
          "$m/drivers/net/can/vcan.ko" "$m/fs/configfs/configfs.ko" \
          "$GPIOSIM/irq_sim.ko" "$GPIOSIM/gpio-sim.ko"; do
  cp "$ko" "$root/lib/modules/imu/"
done

shared=${IMU_SHARED_DIR:-}
# The recorded data for the end-to-end check, only when the project's binaries are there: an
# excerpt (IMU_VM_MAT_SAMPLES, default 50000 = 500 s at 100 Hz) of the first recording, cut on
# the host by imu-vm-stepmat (the emulated CPU streams 1e6 samples in about 4 minutes, too long
# for every run). IMU_VM_MAT_SAMPLES=all copies the whole file instead.
stepmat=""
sim=""
for bin in "$@"; do
  [ "$(basename "$bin")" = imu-vm-stepmat ] && [ -x "$bin" ] && stepmat=$bin
  [ "$(basename "$bin")" = imu-sim ] && [ -x "$bin" ] && sim=$bin
done
mat_src=$(ls "$shared"/data/*.mat 2>/dev/null | head -n1 || true)
if [ $# -gt 0 ] && [ -n "$mat_src" ]; then
  n=${IMU_VM_MAT_SAMPLES:-50000}
  if [ "$n" = all ] || [ -z "$stepmat" ]; then
    cp "$mat_src" "$root/data/"
  else
    "$stepmat" --excerpt "$mat_src" --samples "$n" \
      --out "$root/data/$(basename "$mat_src" .mat)_first$n.mat" >/dev/null
  fi
  # The six channels' models for the push check, fitted here at native speed (the analysis
  # of the excerpt takes about 20 s of CPU, over ten minutes under TCG); the guest checks the
  # push over its kernel's vcan0, not the analysis. Without it the guest analyses itself.
  mat_in=$(ls "$root"/data/*.mat | head -n1)
  if [ -n "$sim" ] && ! "$sim" analyze "$mat_in" --channel all --json "$root/data/models.json" \
       >"$work/analyze.txt" 2>&1; then
    echo "vm-run: host analysis of $mat_in failed (the guest analyses): $(tail -n1 "$work/analyze.txt")"
    rm -f "$root/data/models.json"
  fi
fi

initrd="$work/initrd.gz"
(cd "$root" && find . | busybox cpio -o -H newc 2>/dev/null | gzip -1) >"$initrd"
t_initrd=$(ms)

log="$work/vm-console.log"
echo "vm-run: kernel $ABI, initramfs $(du -h "$initrd" | cut -f1), booting (TCG)..."
rc=0
timeout "${IMU_VM_TIMEOUT:-1200}" qemu-system-x86_64 -accel tcg -cpu max -m 512 -nographic \
  -no-reboot -nic none -kernel "$KROOT/boot/vmlinuz-$ABI" -initrd "$initrd" \
  -append "console=ttyS0 panic=-1 quiet${IMU_VM_TESTS:+ imu_tests=${IMU_VM_TESTS// /,}}" \
  </dev/null >"$log" 2>&1 || rc=$?
t_end=$(ms)
tr -d '\r' <"$log" >"$log.txt"
grep -E '^VM(TEST|LOG)' "$log.txt" || true

secs() { printf '%d.%03d' $(( $1 / 1000 )) $(( $1 % 1000 )); }
timing="prepare $(secs $((t_prep - t_start))) s, initramfs $(secs $((t_initrd - t_prep))) s, boot+tests $(secs $((t_end - t_initrd))) s, total $(secs $((t_end - t_start))) s"
# qemu exits 0 whatever happens in the guest (-no-reboot): only the marker counts.
done_line=$(grep -E '^VMTEST-DONE ' "$log.txt" | tail -n1 || true)
if [ -z "$done_line" ]; then
  echo "vm-run: no VMTEST-DONE marker (qemu exit $rc); last console lines:"
  tail -n 30 "$log.txt"
  echo "VM-TEST FAIL (no marker) $timing"
  exit 1
fi
if grep -qE '^VMTEST [a-z0-9_]+ FAIL' "$log.txt" || ! grep -q ' fail=0 ' <<<"$done_line"; then
  echo "VM-TEST FAIL $done_line; $timing"
  exit 1
fi
echo "VM-TEST PASS $done_line; $timing"
