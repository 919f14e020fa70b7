#!/bin/busybox sh
# /init of the test VM (Debian's kernel, busybox userland, see tests/vm/vm-run.sh).
# Every check is a function t_<name> that ends with exactly one call of
#   result <name> PASS|FAIL|SKIP "<detail>"
# which prints "VMTEST <name> <status> <detail>" on the console; the host parses those lines and
# the final marker "VMTEST-DONE pass=<p> fail=<f> skip=<s> uptime_s=<t>". Adding a check: write
# t_<name>, append <name> to TESTS. The project's binaries are in /opt/imu/bin (copied with
# their libraries by vm-run.sh); a check whose binary is missing reports SKIP with the reason.
/bin/busybox mkdir -p /proc /sys /dev /tmp /run /sys/kernel/config
/bin/busybox --install -s /bin
export PATH=/opt/imu/bin:/opt/host/bin:/bin:/sbin
mount -t proc proc /proc
mount -t sysfs sysfs /sys
mount -t devtmpfs devtmpfs /dev
mount -t tmpfs tmpfs /tmp
echo "VMTEST-BOOT kernel=$(uname -r) uptime_s=$(cut -d' ' -f1 /proc/uptime)"

pass=0 fail=0 skip=0
result() {
  echo "VMTEST $1 $2 $3"
  case $2 in
    PASS) pass=$((pass + 1)) ;;
    SKIP) skip=$((skip + 1)) ;;
    *) fail=$((fail + 1)) ;;
  esac
}
have() { command -v "$1" >/dev/null 2>&1; }
mods=/lib/modules/imu
# insmod in dependency order; a failure names the module.
load() {
  for m in "$@"; do
    insmod "$mods/$m.ko" 2>/tmp/insmod.err || { echo "insmod $m: $(cat /tmp/insmod.err)"; return 1; }
  done
}

# ---------------------------------------------------------------------------------------------
# Kernel plumbing (independent of the project's binaries)

t_can_vcan_fd() {
  local why
  why=$(load can can-raw can-dev vcan 2>&1) || { result can_vcan_fd FAIL "$why"; return; }
  ip link add dev vcan0 type vcan && ip link set vcan0 mtu 72 up ||
    { result can_vcan_fd FAIL "ip link add/set vcan0 failed"; return; }
  local mtu
  mtu=$(cat /sys/class/net/vcan0/mtu)
  [ "$mtu" = 72 ] && result can_vcan_fd PASS "vcan0 up, mtu $mtu (CAN FD)" ||
    result can_vcan_fd FAIL "vcan0 mtu is $mtu, want 72"
}

# cangen -> vcan0 -> candump: N CAN FD frames sent, N logged, all FD (## in the log format).
t_can_roundtrip() {
  local n=500
  timeout 10 candump -n $n -L vcan0 >/tmp/roundtrip.log &
  local dump=$!
  sleep 0.3
  # 1 ms gap (1000 frames/s, a realistic IMU rate); -g 0 overruns candump's socket buffer.
  cangen vcan0 -f -n $n -g 1 -p 10 -I i
  wait $dump
  local got fd
  got=$(wc -l </tmp/roundtrip.log)
  fd=$(grep -c '##' /tmp/roundtrip.log)
  [ "$got" = $n ] && [ "$fd" = $n ] &&
    result can_roundtrip PASS "cangen sent $n CAN FD frames, candump logged $got ($fd FD)" ||
    result can_roundtrip FAIL "sent $n, candump logged $got ($fd FD)"
}

# canplayer replays the candump log; a second candump must see the same frames in order.
t_can_replay() {
  [ -s /tmp/roundtrip.log ] || { result can_replay SKIP "no log from can_roundtrip"; return; }
  local n
  n=$(wc -l </tmp/roundtrip.log)
  timeout 10 candump -n "$n" -L vcan0 >/tmp/replay.log &
  local dump=$!
  sleep 0.3
  canplayer -I /tmp/roundtrip.log
  wait $dump
  cut -d' ' -f2- /tmp/roundtrip.log >/tmp/a
  cut -d' ' -f2- /tmp/replay.log >/tmp/b
  cmp -s /tmp/a /tmp/b && result can_replay PASS "canplayer replayed $n frames, identical ids/payloads" ||
    result can_replay FAIL "replayed log differs ($(wc -l </tmp/replay.log) of $n lines)"
}

# gpio-sim chip with named lines "static" (input to the firmware) and "alarm" (its output).
GPIO_CHIP="" GPIO_SIM=""
t_gpio_sim() {
  local why
  why=$(load configfs irq_sim gpio-sim 2>&1) || { result gpio_sim FAIL "$why"; return; }
  mount -t configfs none /sys/kernel/config || { result gpio_sim FAIL "mount configfs"; return; }
  local c=/sys/kernel/config/gpio-sim/imu
  mkdir $c $c/bank0 $c/bank0/line0 $c/bank0/line1 &&
    echo 4 >$c/bank0/num_lines && echo static >$c/bank0/line0/name &&
    echo alarm >$c/bank0/line1/name && echo 1 >$c/live ||
    { result gpio_sim FAIL "configfs chip creation failed"; return; }
  GPIO_CHIP=$(cat $c/bank0/chip_name)
  GPIO_SIM=/sys/devices/platform/$(cat $c/dev_name)/$GPIO_CHIP
  local found
  found=$(gpiofind static)
  [ "$found" = "$GPIO_CHIP 0" ] && [ "$(gpiofind alarm)" = "$GPIO_CHIP 1" ] &&
    result gpio_sim PASS "chip $GPIO_CHIP live, lines static=0 alarm=1 ($(gpiodetect | tr '\n' ' '))" ||
    result gpio_sim FAIL "gpiofind static gave '$found' on chip $GPIO_CHIP"
}

# Simulator drives "static" (pull), the consumer side (gpioget) must read it.
t_gpio_static_input() {
  [ -n "$GPIO_CHIP" ] || { result gpio_static_input SKIP "no gpio-sim chip"; return; }
  echo pull-up >$GPIO_SIM/sim_gpio0/pull
  local hi lo
  hi=$(gpioget "$GPIO_CHIP" 0)
  echo pull-down >$GPIO_SIM/sim_gpio0/pull
  lo=$(gpioget "$GPIO_CHIP" 0)
  [ "$hi" = 1 ] && [ "$lo" = 0 ] && result gpio_static_input PASS "pull-up read $hi, pull-down read $lo" ||
    result gpio_static_input FAIL "pull-up read '$hi', pull-down read '$lo'"
}

# The consumer (gpioset) drives "alarm"; the simulator side must see it.
t_gpio_alarm_output() {
  [ -n "$GPIO_CHIP" ] || { result gpio_alarm_output SKIP "no gpio-sim chip"; return; }
  gpioset --mode=time --sec=2 "$GPIO_CHIP" 1=1 &
  local setter=$!
  sleep 0.5
  local v
  v=$(cat $GPIO_SIM/sim_gpio1/value)
  wait $setter
  [ "$v" = 1 ] && result gpio_alarm_output PASS "gpioset alarm=1 read 1 on the simulator side" ||
    result gpio_alarm_output FAIL "simulator read '$v' while gpioset held alarm=1"
}

# A line name that does not exist must be an error, not a silent default.
t_gpio_missing_line() {
  [ -n "$GPIO_CHIP" ] || { result gpio_missing_line SKIP "no gpio-sim chip"; return; }
  if gpiofind no_such_line >/dev/null 2>&1; then
    result gpio_missing_line FAIL "gpiofind found a line that does not exist"
  else
    result gpio_missing_line PASS "gpiofind no_such_line fails (exit non-zero)"
  fi
}

# ---------------------------------------------------------------------------------------------
# The project's HAL on the real kernel: imu-can-probe (SocketCAN transport + receiver) and
# imu-gpio-probe (libgpiod wrapper). key=value output, parsed with kv.
kv() { sed -n "s/.*[ ^]$2=\([0-9]*\).*/\1/p" "$1" | head -n1; }

# The protocol over vcan0 at a realistic rate (1 kHz), candump recording alongside:
# every sample received, none missing, no CRC error, no kernel drop; candump saw every frame.
IMU_N=2000
t_hal_can_stream() {
  have imu-can-probe || { result hal_can_stream SKIP "imu-can-probe not built"; return; }
  local frames=$((IMU_N + 1))  # FD layout: one frame per sample + the config record
  timeout 20 candump -n $frames -L vcan0 >/tmp/imu.log &
  local dump=$!
  imu-can-probe --bus vcan0 --recv --count $IMU_N --timeout-ms 3000 >/tmp/rx_stream.txt 2>&1 &
  local rx=$!
  sleep 0.5
  imu-can-probe --bus vcan0 --send $IMU_N --rate-hz 1000 >/tmp/tx_stream.txt 2>&1
  wait $rx
  wait $dump
  local samples missing crc drops logged
  samples=$(kv /tmp/rx_stream.txt samples)
  missing=$(kv /tmp/rx_stream.txt missing)
  crc=$(kv /tmp/rx_stream.txt crc_errors)
  drops=$(kv /tmp/rx_stream.txt kernel_drops)
  logged=$(wc -l </tmp/imu.log)
  if [ "$samples" = $IMU_N ] && [ "$missing" = 0 ] && [ "$crc" = 0 ] && [ "$drops" = 0 ] &&
     [ "$logged" = $frames ]; then
    result hal_can_stream PASS "$IMU_N samples at 1 kHz: received $samples, missing 0, crc 0, kernel drops 0; candump logged $logged frames"
  else
    result hal_can_stream FAIL "samples=$samples missing=$missing crc=$crc kernel_drops=$drops candump=$logged/$frames: $(tr '\n' ' ' </tmp/rx_stream.txt)"
  fi
}

# canplayer (independent sender) replays candump's log of the stream into the receiver.
t_hal_can_replay() {
  have imu-can-probe || { result hal_can_replay SKIP "imu-can-probe not built"; return; }
  [ -s /tmp/imu.log ] || { result hal_can_replay SKIP "no candump log from hal_can_stream"; return; }
  imu-can-probe --bus vcan0 --recv --count $IMU_N --timeout-ms 3000 >/tmp/rx_replay.txt 2>&1 &
  local rx=$!
  sleep 0.5
  canplayer -I /tmp/imu.log
  wait $rx
  local samples missing crc
  samples=$(kv /tmp/rx_replay.txt samples)
  missing=$(kv /tmp/rx_replay.txt missing)
  crc=$(kv /tmp/rx_replay.txt crc_errors)
  [ "$samples" = $IMU_N ] && [ "$missing" = 0 ] && [ "$crc" = 0 ] &&
    result hal_can_replay PASS "canplayer replay: received $samples samples, missing 0, crc 0" ||
    result hal_can_replay FAIL "$(tr '\n' ' ' </tmp/rx_replay.txt)"
}

# cangen floods random frames (every kind: -m) alongside the stream: they are counted as
# rejected, the stream is intact, nothing crashes.
t_hal_can_flood() {
  have imu-can-probe || { result hal_can_flood SKIP "imu-can-probe not built"; return; }
  imu-can-probe --bus vcan0 --recv --count $IMU_N --timeout-ms 3000 >/tmp/rx_flood.txt 2>&1 &
  local rx=$!
  sleep 0.5
  cangen vcan0 -m -g 1 -n 1500 -p 10 &
  local gen=$!
  imu-can-probe --bus vcan0 --send $IMU_N --rate-hz 1000 >/tmp/tx_flood.txt 2>&1
  wait $gen
  wait $rx
  local rc=$?
  local samples missing rejected=0 f
  samples=$(kv /tmp/rx_flood.txt samples)
  missing=$(kv /tmp/rx_flood.txt missing)
  for f in crc_errors bad_mtu bad_dlc unknown_id remote error_frames orphan_fragments; do
    rejected=$((rejected + $(kv /tmp/rx_flood.txt $f)))
  done
  [ $rc = 0 ] && [ "$samples" = $IMU_N ] && [ "$missing" = 0 ] && [ $rejected -gt 0 ] &&
    result hal_can_flood PASS "1500 cangen -m frames alongside: $rejected rejected, $samples samples intact, missing 0" ||
    result hal_can_flood FAIL "exit $rc rejected=$rejected: $(tr '\n' ' ' </tmp/rx_flood.txt)"
}

# A gap in the stream (sample 500 not sent) is reported as exactly one missing sample.
t_hal_can_gap() {
  have imu-can-probe || { result hal_can_gap SKIP "imu-can-probe not built"; return; }
  imu-can-probe --bus vcan0 --recv --count 1000 --timeout-ms 3000 >/tmp/rx_gap.txt 2>&1 &
  local rx=$!
  sleep 0.5
  imu-can-probe --bus vcan0 --send 1000 --skip 500 >/tmp/tx_gap.txt 2>&1
  wait $rx
  local samples missing gaps
  samples=$(kv /tmp/rx_gap.txt samples)
  missing=$(kv /tmp/rx_gap.txt missing)
  gaps=$(kv /tmp/rx_gap.txt gaps)
  [ "$samples" = 999 ] && [ "$missing" = 1 ] && [ "$gaps" = 1 ] &&
    result hal_can_gap PASS "sample 500 skipped: received 999, missing 1, gaps 1" ||
    result hal_can_gap FAIL "$(tr '\n' ' ' </tmp/rx_gap.txt)"
}

# The HAL's GPIO wrapper on gpio-sim: reads "static", drives "alarm", and a missing line is a
# clear error (exit 3 and a message naming it).
t_hal_gpio() {
  have imu-gpio-probe || { result hal_gpio SKIP "imu-gpio-probe not built"; return; }
  [ -n "$GPIO_CHIP" ] || { result hal_gpio SKIP "no gpio-sim chip"; return; }
  local hi lo alarm rc_missing msg
  echo pull-up >$GPIO_SIM/sim_gpio0/pull
  hi=$(imu-gpio-probe --chip "$GPIO_CHIP" --line static 2>&1)
  echo pull-down >$GPIO_SIM/sim_gpio0/pull
  lo=$(imu-gpio-probe --chip "$GPIO_CHIP" --line static 2>&1)
  imu-gpio-probe --chip "$GPIO_CHIP" --line alarm --set 1 --hold-ms 1500 >/tmp/alarm.txt 2>&1 &
  local setter=$!
  sleep 0.7
  alarm=$(cat $GPIO_SIM/sim_gpio1/value)
  wait $setter
  msg=$(imu-gpio-probe --chip "$GPIO_CHIP" --line no_such_line 2>&1) && rc_missing=0 || rc_missing=$?
  if [ "$hi" = value=1 ] && [ "$lo" = value=0 ] && [ "$alarm" = 1 ] && [ "$rc_missing" = 3 ]; then
    result hal_gpio PASS "static read 1/0 with pull-up/down, alarm driven high seen by the simulator, missing line: exit 3 '$msg'"
  else
    result hal_gpio FAIL "static '$hi'/'$lo' alarm '$alarm' missing-line exit $rc_missing '$msg'"
  fi
}

# ---------------------------------------------------------------------------------------------
# The firmware node end to end (issue 7). TODO: wire these when imu-sim / imu-fw land: each
# runs the real check when its binaries are in /opt/imu/bin, else SKIPs.

t_imu_stream() {
  have imu-sim && have imu-fw || { result imu_stream SKIP "TODO: imu-sim/imu-fw not built yet"; return; }
  result imu_stream SKIP "TODO: imu-sim -> vcan0 -> imu-fw ADEV vs in-process, frame counters"
}
t_imu_replay() {
  have imu-fw || { result imu_replay SKIP "TODO: imu-fw not built yet"; return; }
  result imu_replay SKIP "TODO: candump log of the stream replayed by canplayer into imu-fw"
}
t_imu_flood() {
  have imu-fw || { result imu_flood SKIP "TODO: imu-fw not built yet"; return; }
  result imu_flood SKIP "TODO: cangen flood alongside, counted as rejected, estimate unchanged"
}
t_imu_gpio() {
  have imu-fw || { result imu_gpio SKIP "TODO: imu-fw (GPIO) not built yet"; return; }
  result imu_gpio SKIP "TODO: static gates bias updates, alarm high on injected step, missing line error"
}

TESTS="can_vcan_fd can_roundtrip can_replay gpio_sim gpio_static_input gpio_alarm_output
       gpio_missing_line hal_can_stream hal_can_replay hal_can_flood hal_can_gap hal_gpio
       imu_stream imu_replay imu_flood imu_gpio"
for t in $TESTS; do
  t_$t
done
echo "VMTEST-DONE pass=$pass fail=$fail skip=$skip uptime_s=$(cut -d' ' -f1 /proc/uptime)"
sync
reboot -f
