#!/usr/bin/env bash
# Fetches and caches what the VM test needs that is not in the build: Debian's kernel image and
# the modules for CAN/configfs, and gpio-sim + irq_sim built out of tree against the matching
# headers (docs: ../shared/docs/VM-TESTING.md). Idempotent: every step is skipped when its
# output is already in the cache, so a rerun costs about 1 s.
#   tests/vm/vm-prepare.sh [CACHE_DIR]      (default: $IMU_VM_CACHE or /var/cache/imu-vm)
# On success prints "KROOT=<dir>" and "GPIOSIM=<dir>" (cache paths) and exits 0.
# Exit 77 (ctest SKIP_RETURN_CODE) with a reason on stderr when a prerequisite is missing and
# cannot be installed (no root, no apt network, no qemu...). Any other failure exits 1.
set -euo pipefail
cache=${1:-${IMU_VM_CACHE:-/var/cache/imu-vm}}
skip() { echo "vm-prepare: SKIP: $*" >&2; exit 77; }
log() { echo "vm-prepare: $*" >&2; }

for tool in qemu-system-x86_64 busybox gzip dpkg-deb apt-get make; do
  command -v "$tool" >/dev/null || skip "'$tool' not found (toolchains/install-deps.sh test installs it)"
done
mkdir -p "$cache" 2>/dev/null || skip "cannot create cache directory $cache"
[ -w "$cache" ] || skip "cache directory $cache is not writable"

SUDO=""
if [ "$(id -u)" != 0 ]; then
  if sudo -n true 2>/dev/null; then SUDO="sudo -n"; else SUDO=none; fi
fi
installed() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q "install ok installed"; }
# apt-get install, serialised against other jobs of this script; never interactive.
apt_install() {
  [ "$SUDO" != none ] || skip "need root (or sudo) to install $*"
  log "installing $*"
  export DEBIAN_FRONTEND=noninteractive
  if ! $SUDO apt-get install -y -qq --no-install-recommends "$@" >"$cache/apt.log" 2>&1; then
    $SUDO apt-get update -qq >>"$cache/apt.log" 2>&1 || skip "apt-get update failed (no network?): see $cache/apt.log"
    $SUDO apt-get install -y -qq --no-install-recommends "$@" >>"$cache/apt.log" 2>&1 ||
      skip "apt-get install $* failed (no network?): see $cache/apt.log"
  fi
}

# The kernel ABI: the one linux-image-amd64 points at. Cached so that an apt list refresh does
# not silently switch kernels in the middle of a day (delete $cache/abi to follow a new one).
if [ -s "$cache/abi" ]; then
  ABI=$(cat "$cache/abi")
else
  ABI=$(apt-cache depends linux-image-amd64 2>/dev/null |
        sed -n 's/.*Depends: linux-image-\(.*-amd64\)$/\1/p' | head -n1)
  [ -n "$ABI" ] || skip "cannot resolve linux-image-amd64 (apt lists missing? run apt-get update)"
  echo "$ABI" >"$cache/abi"
fi

# 1. Kernel image and the few modules the guest loads (about 70 MB download, once).
kroot="$cache/kroot-$ABI"
if [ ! -f "$kroot/.done" ]; then
  debdir="$cache/deb"
  mkdir -p "$debdir"
  if ! ls "$debdir"/linux-image-"${ABI}"_*.deb >/dev/null 2>&1; then
    log "downloading linux-image-$ABI"
    (cd "$debdir" && apt-get download "linux-image-$ABI" >"$cache/download.log" 2>&1) ||
      skip "apt-get download linux-image-$ABI failed (no network?): see $cache/download.log"
  fi
  rm -rf "$kroot.tmp" && mkdir -p "$kroot.tmp"
  deb=$(ls "$debdir"/linux-image-"${ABI}"_*.deb | head -n1)
  m=./lib/modules/$ABI/kernel
  dpkg-deb --fsys-tarfile "$deb" | tar -x -C "$kroot.tmp" ./boot/vmlinuz-"$ABI" \
      "$m/net/can" "$m/drivers/net/can" "$m/fs/configfs"
  rm -rf "$kroot" && mv "$kroot.tmp" "$kroot" && touch "$kroot/.done"
fi

# 2. gpio-sim and irq_sim, out of tree, against the headers of the same version.
installed "linux-headers-$ABI" || apt_install "linux-headers-$ABI"
V=$(dpkg-query -W -f='${Version}' "linux-headers-$ABI")
gsim="$cache/gpio-sim-$ABI-$V"
if [ ! -f "$gsim/.done" ]; then
  if [ "$(dpkg-query -W -f='${Version}' linux-source-6.1 2>/dev/null || true)" != "$V" ]; then
    apt_install "linux-source-6.1=$V"
  fi
  rm -rf "$gsim.tmp" && mkdir -p "$gsim.tmp"
  log "extracting gpio-sim sources from linux-source-6.1 $V (10-15 s)"
  tar -xJf /usr/src/linux-source-6.1.tar.xz -C "$gsim.tmp" --strip-components=3 \
      linux-source-6.1/drivers/gpio/gpio-sim.c linux-source-6.1/drivers/gpio/gpiolib.h \
      linux-source-6.1/kernel/irq/irq_sim.c
  # irq_sim.c uses irq_to_desc, which the kernel does not export (VM-TESTING.md).
  sed -i 's/handle_simple_irq(irq_to_desc(irqnum));/generic_handle_irq(irqnum);/' "$gsim.tmp/irq_sim.c"
  grep -q 'generic_handle_irq(irqnum);' "$gsim.tmp/irq_sim.c" || { log "irq_sim.c patch did not apply"; exit 1; }
  printf '#include <linux/module.h>\nMODULE_LICENSE("GPL");\n' >>"$gsim.tmp/irq_sim.c"
  echo 'obj-m += irq_sim.o gpio-sim.o' >"$gsim.tmp/Kbuild"
  log "building gpio-sim.ko, irq_sim.ko"
  make -s -C "/usr/src/linux-headers-$ABI" M="$gsim.tmp" modules >"$cache/kbuild.log" 2>&1 ||
    { log "module build failed: see $cache/kbuild.log"; exit 1; }
  [ -f "$gsim.tmp/gpio-sim.ko" ] && [ -f "$gsim.tmp/irq_sim.ko" ] || { log "modules missing after build"; exit 1; }
  rm -rf "$gsim" && mv "$gsim.tmp" "$gsim" && touch "$gsim/.done"
fi

# 3. Host tools copied into the guest.
installed gpiod || apt_install gpiod
command -v candump >/dev/null || apt_install can-utils
[ -x /sbin/ip ] || [ -x /usr/sbin/ip ] || apt_install iproute2

echo "KROOT=$kroot"
echo "GPIOSIM=$gsim"
