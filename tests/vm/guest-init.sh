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
# Console copy of files that explain a failure: "VMLOG <file>| <line>" (first 4 and last 12
# lines of each).
dump() {
  local f
  for f in "$@"; do
    [ -f "$f" ] || continue
    { head -n 4 "$f"; echo ...; tail -n 12 "$f"; } | sed "s|^|VMLOG $f\| |"
  done
}
result() {
  echo "VMTEST $1 $2 $3 (uptime $(cut -d' ' -f1 /proc/uptime) s)"
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
  # Paced as the stream test is: an unpaced burst overflows the receive buffer of a slow
  # (emulated, loaded) guest, and kernel drops would hide the one skipped sample.
  imu-can-probe --bus vcan0 --send 1000 --skip 500 --rate-hz 1000 >/tmp/tx_gap.txt 2>&1
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
# The firmware node end to end: imu-sim (sensor emulator) -> vcan0 -> imu-fw (the node, with
# the fw/ ADEV, bias filter and monitors), can-utils as the independent peer, gpio-sim lines.
MAT=$(ls /data/*.mat 2>/dev/null | head -n1)
# The acc_z ADEV table (tau, adev, ci, edf, n_terms rows) from imu-fw's or imu-sim adev's output.
fw_table() { sed -n '/^final ADEV of acc_z/,/^$/p' "$1" | grep -E '^ +[0-9]'; }
adev_table() { grep -E '^ +[0-9]' "$1"; }
fw_header() { grep '^final ADEV of acc_z' "$1"; }
# "imu-fw: stream ended (...): S samples, M missing, F frames, C crc errors, ..." fields.
fw_field() { sed -n "s/^imu-fw: stream ended.* \([0-9][0-9]*\) $2.*/\1/p" "$1" | head -n1; }
fw_drops() { sed -n 's/^imu-fw: stream ended.*kernel drops \([0-9]*\).*/\1/p' "$1" | head -n1; }
# Starts imu-fw on vcan0 in the background (extra options in "$@"), output to $FW_OUT.
start_fw() {
  FW_OUT=$1
  shift
  # timeout: imu-fw only starts its idle clock at the first frame. busybox timeout execs the
  # program in place, so $! is imu-fw itself.
  timeout 240 imu-fw --bus vcan0 --exit-idle-s 4 "$@" >"$FW_OUT" 2>&1 &
  FW_PID=$!
  # Highest priority for the node: the guest has one CPU and on a real bus the sensor is another
  # machine; at --rate max a sender with equal priority overruns imu-fw's socket buffer.
  renice -20 $FW_PID >/dev/null 2>&1
  sleep 0.7
}
sim_run() {  # sim_run MAT OUTDIR [options]: imu-sim as the sensor on vcan0, node external
  local mat=$1 out=$2
  shift 2
  timeout 240 imu-sim run --mat "$mat" --bus vcan0 --node external --no-plots --quiet \
    --sim-windows 20 --timeout 200 --out "$out" "$@" >"$out.txt" 2>&1
}

# A recorded ADIS16405 MAT-file (1e6 samples) through vcan0 at full speed with back-pressure:
# imu-fw's online ADEV of acc_z equals the in-process one (imu-sim adev, same fw code on the
# same counts) line for line; no sample missing, no kernel drop.
t_imu_stream() {
  have imu-sim && have imu-fw || { result imu_stream SKIP "imu-sim/imu-fw not built"; return; }
  [ -n "$MAT" ] || { result imu_stream SKIP "no MAT-file in /data (IMU_SHARED_DIR unset?)"; return; }
  local t0 t1
  t0=$(cut -d' ' -f1 /proc/uptime)
  start_fw /tmp/fw_stream.txt
  sim_run "$MAT" /tmp/run_stream --rate max
  local sim_rc=$?
  wait $FW_PID
  t1=$(cut -d' ' -f1 /proc/uptime)
  imu-sim adev "$MAT" --channel acc_z --estimator online >/tmp/adev_inproc.txt 2>&1
  fw_table /tmp/fw_stream.txt >/tmp/t_fw
  adev_table /tmp/adev_inproc.txt >/tmp/t_in
  local rows samples missing drops
  rows=$(wc -l </tmp/t_fw)
  samples=$(fw_field /tmp/fw_stream.txt samples)
  missing=$(fw_field /tmp/fw_stream.txt missing)
  drops=$(fw_drops /tmp/fw_stream.txt)
  if [ $sim_rc = 0 ] && [ "$rows" -gt 10 ] && cmp -s /tmp/t_fw /tmp/t_in && [ "$missing" = 0 ] &&
     [ "$drops" = 0 ] && [ "$samples" -gt 0 ]; then
    result imu_stream PASS "$(basename "$MAT"): $samples samples over vcan0, missing 0, kernel drops 0; acc_z ADEV identical to in-process ($rows taus); $(awk "BEGIN{print $t1-$t0}") s"
  else
    dump /tmp/fw_stream.txt /tmp/run_stream.txt
    result imu_stream FAIL "imu-sim exit $sim_rc, rows $rows, samples '$samples' missing '$missing' drops '$drops'; $(tail -n 3 /tmp/run_stream.txt | tr '\n' ' ') | $(diff /tmp/t_fw /tmp/t_in | head -n 4 | tr '\n' ' ')"
  fi
}

# A realistic rate: 20 s of synthetic acc_z at the IMU's real 100 Hz (imu-sim --rate realtime),
# candump recording the sensor's frames (config 0x080, repeated by imu-sim, and samples 0x100)
# as the independent log; candump is stopped with SIGINT once imu-fw has finished.
t_imu_realtime() {
  have imu-sim && have imu-fw && have imu-vm-stepmat ||
    { result imu_realtime SKIP "imu-sim/imu-fw/imu-vm-stepmat not built"; return; }
  imu-vm-stepmat --out /tmp/clean.mat --duration 20 >/dev/null || { result imu_realtime FAIL "stepmat"; return; }
  candump -L vcan0,080:7FF,100:7FF >/tmp/rt.log &
  local dump=$!
  start_fw /tmp/fw_rt.txt
  sim_run /tmp/clean.mat /tmp/run_rt --rate realtime
  local sim_rc=$?
  wait $FW_PID
  kill -INT $dump
  wait $dump
  imu-sim adev /tmp/clean.mat --channel acc_z --estimator online >/tmp/adev_clean.txt 2>&1
  fw_table /tmp/fw_rt.txt >/tmp/t_fw
  adev_table /tmp/adev_clean.txt >/tmp/t_in
  local samples missing drops logged configs
  samples=$(fw_field /tmp/fw_rt.txt samples)
  missing=$(fw_field /tmp/fw_rt.txt missing)
  drops=$(fw_drops /tmp/fw_rt.txt)
  logged=$(grep -c ' 100##' /tmp/rt.log)
  configs=$(grep -c ' 080##' /tmp/rt.log)
  if [ $sim_rc = 0 ] && [ "$samples" = 2000 ] && [ "$missing" = 0 ] && [ "$drops" = 0 ] &&
     [ "$logged" = 2000 ] && [ "$configs" -ge 1 ] && cmp -s /tmp/t_fw /tmp/t_in; then
    result imu_realtime PASS "2000 samples at 100 Hz real time: missing 0, kernel drops 0, candump logged 2000 sample + $configs config frames, ADEV identical to in-process"
  else
    dump /tmp/fw_rt.txt /tmp/run_rt.txt
    result imu_realtime FAIL "imu-sim exit $sim_rc samples '$samples' missing '$missing' drops '$drops' candump $logged samples, $configs configs; $(tail -n 2 /tmp/run_rt.txt | tr '\n' ' ')"
  fi
}

# A model push over the real kernel's vcan0. imu-sim analyze fits a model to a
# synthetic record; imu-sim run --model sends it to imu-fw (external node) as a ModelRecord over
# vcan0 and reads the node's echo (0x252, model record version 2) back from the bus: the run's
# JSON must report the pushed model as the one the node runs (origin "pushed", model_pushed
# true, none rejected) with the white noise N that analyze wrote (float32 on the wire: 1e-6
# relative; --model-as-is: not tuned to the record first).
t_imu_model_push() {
  have imu-sim && have imu-fw || { result imu_model_push SKIP "imu-sim/imu-fw not built"; return; }
  imu-sim synth --out /tmp/push.mat --duration 300 >/dev/null 2>&1 ||
    { result imu_model_push FAIL "synth"; return; }
  imu-sim analyze /tmp/push.mat --channel acc_z --json /tmp/push_a.json >/tmp/push_a.txt 2>&1 ||
    { dump /tmp/push_a.txt; result imu_model_push FAIL "analyze exit $?"; return; }
  start_fw /tmp/fw_push.txt
  sim_run /tmp/push.mat /tmp/run_push --rate max --model /tmp/push_a.json --model-as-is
  local sim_rc=$?
  wait $FW_PID
  local fw_rc=$?
  local j=/tmp/run_push/report.json
  # "n" of model_after in analyze's JSON, and of the node's echoed model in the run's JSON.
  local n_sent n_echo
  n_sent=$(sed -n 's/.*"model_after": *{[^}]*"n": *\([-0-9.e+]*\).*/\1/p' /tmp/push_a.json | head -n1)
  n_echo=$(sed -n 's/.*"node": *{ *"model": *{[^}]*"n": *\([-0-9.e+]*\).*/\1/p' "$j" | head -n1)
  if [ $sim_rc = 0 ] && [ $fw_rc = 0 ] && grep -q '"origin": "pushed"' "$j" &&
     grep -q '"model_pushed": true' "$j" && grep -q '"model_rejected": 0' "$j" &&
     [ -n "$n_sent" ] && [ -n "$n_echo" ] &&
     awk "BEGIN{d=($n_echo)-($n_sent); if (d<0) d=-d; exit !(d <= 1e-6*($n_sent))}"; then
    result imu_model_push PASS "model pushed over vcan0 and echoed by imu-fw: origin pushed, N sent $n_sent echoed $n_echo, $(grep -o '"n_states": [0-9]*' "$j" | head -n1)"
  else
    dump /tmp/fw_push.txt /tmp/run_push.txt
    result imu_model_push FAIL "imu-sim exit $sim_rc imu-fw exit $fw_rc, N sent '$n_sent' echoed '$n_echo'; $(grep -o '"node": {[^]]*' "$j" 2>/dev/null | head -c 300)"
  fi
}

# The whole IMU over the real kernel's vcan0: imu-sim analyze --channel all's model of each
# channel of the recorded excerpt (/data/models.json, fitted by vm-run.sh on the host; else
# analysed here); imu-sim run --model pushes the six to imu-fw (external node) and reads back
# each channel's monitors (ChannelMonitorRecord, 0x260): the run's JSON must list six channels,
# each running its pushed model, none refused (--model-as-is: the tuning to the record, native
# seconds, would take minutes under TCG; the host tests cover it).
t_imu_model_push_all() {
  have imu-sim && have imu-fw ||
    { result imu_model_push_all SKIP "imu-sim/imu-fw not built"; return; }
  [ -n "$MAT" ] || { result imu_model_push_all SKIP "no MAT-file in /data"; return; }
  local models=/data/models.json
  if [ ! -s "$models" ]; then
    models=/tmp/all_a.json
    imu-sim analyze "$MAT" --channel all --json "$models" >/tmp/all_a.txt 2>&1 ||
      { dump /tmp/all_a.txt; result imu_model_push_all FAIL "analyze exit $?"; return; }
  fi
  start_fw /tmp/fw_all.txt
  sim_run "$MAT" /tmp/run_all --rate max --channel acc_x --model "$models" --model-as-is
  local sim_rc=$?
  wait $FW_PID
  local fw_rc=$?
  local j=/tmp/run_all/report.json rows pushed
  # The node's per-channel rows: {"channel": NAME, "origin": ...} (each row also holds a list).
  rows=$(grep -o '"channel": "[a-z_]*", "origin": "[a-z]*"' "$j" | wc -l)
  pushed=$(grep -o '"channel": "[a-z_]*", "origin": "pushed"' "$j" | wc -l)
  if [ $sim_rc = 0 ] && [ $fw_rc = 0 ] && [ "$rows" = 6 ] && [ "$pushed" = 6 ] &&
     grep -q '"model_rejected": 0' "$j"; then
    result imu_model_push_all PASS "six models pushed over vcan0; imu-fw reports six channels' monitors, all running the pushed model: $(grep -A8 '^channel ' /tmp/run_all/report.txt | grep -E '^(acc|gyro)' | awk '{printf "%s %s states NIS %s CUSUM %s; ", $1, $3, $4, ($8 == "quiet" ? "quiet" : $8 " shifts")}')"
  else
    dump /tmp/fw_all.txt /tmp/run_all.txt
    result imu_model_push_all FAIL "imu-sim exit $sim_rc imu-fw exit $fw_rc, channel rows '$rows', pushed '$pushed'"
  fi
}

# canplayer replays candump's log into a fresh imu-fw: same ADEV, same bias estimate.
t_imu_replay() {
  have imu-fw || { result imu_replay SKIP "imu-fw not built"; return; }
  [ -s /tmp/rt.log ] && [ -s /tmp/fw_rt.txt ] || { result imu_replay SKIP "no log from imu_realtime"; return; }
  start_fw /tmp/fw_replay.txt
  canplayer -t -g 1 -I /tmp/rt.log
  wait $FW_PID
  fw_table /tmp/fw_replay.txt >/tmp/t_rp
  fw_table /tmp/fw_rt.txt >/tmp/t_rt
  local samples missing
  samples=$(fw_field /tmp/fw_replay.txt samples)
  missing=$(fw_field /tmp/fw_replay.txt missing)
  if [ "$samples" = 2000 ] && [ "$missing" = 0 ] && cmp -s /tmp/t_rp /tmp/t_rt &&
     [ "$(fw_header /tmp/fw_replay.txt)" = "$(fw_header /tmp/fw_rt.txt)" ]; then
    result imu_replay PASS "canplayer replay: 2000 samples, missing 0, ADEV and bias line identical to the live stream ($(fw_header /tmp/fw_replay.txt | sed 's/.*(//; s/).*//'))"
  else
    dump /tmp/fw_replay.txt /tmp/rt.log
    result imu_replay FAIL "samples '$samples' missing '$missing'; $(diff /tmp/t_rp /tmp/t_rt | head -n 4 | tr '\n' ' ') $(fw_header /tmp/fw_replay.txt) vs $(fw_header /tmp/fw_rt.txt)"
  fi
}

# The same replay with cangen flooding random frames of every kind alongside: they are counted
# (frames beyond those of the log) and rejected; the estimate does not change.
t_imu_flood() {
  have imu-fw || { result imu_flood SKIP "imu-fw not built"; return; }
  [ -s /tmp/fw_replay.txt ] || { result imu_flood SKIP "no clean replay to compare with"; return; }
  start_fw /tmp/fw_flood.txt
  cangen vcan0 -m -g 1 -n 2000 -p 10 &
  local gen=$!
  canplayer -t -g 1 -I /tmp/rt.log
  wait $gen
  wait $FW_PID
  local fw_rc=$?
  fw_table /tmp/fw_flood.txt >/tmp/t_fl
  fw_table /tmp/fw_replay.txt >/tmp/t_rp
  local samples missing frames rejected
  samples=$(fw_field /tmp/fw_flood.txt samples)
  missing=$(fw_field /tmp/fw_flood.txt missing)
  frames=$(fw_field /tmp/fw_flood.txt frames)
  rejected=$((${frames:-0} - $(wc -l </tmp/rt.log)))  # frames beyond the replayed log
  if [ $fw_rc = 0 ] && [ "$samples" = 2000 ] && [ "$missing" = 0 ] && [ $rejected -gt 0 ] &&
     cmp -s /tmp/t_fl /tmp/t_rp && [ "$(fw_header /tmp/fw_flood.txt)" = "$(fw_header /tmp/fw_replay.txt)" ]; then
    result imu_flood PASS "2000 cangen -m frames alongside: $rejected frames rejected, imu-fw exit 0, 2000 samples, ADEV and bias unchanged"
  else
    dump /tmp/fw_flood.txt
    result imu_flood FAIL "imu-fw exit $fw_rc samples '$samples' missing '$missing' rejected $rejected; $(fw_header /tmp/fw_flood.txt)"
  fi
}

# GPIO: "static" gates the bias filter updates (static_flag and the filter's std follow the
# line), "alarm" stays low on clean data and goes high on data with an injected step (read on
# the simulator side while imu-fw holds the line), a missing line name is a clear error.
ALARM_CLEAN="" ALARM_STEP=""
gpio_run() {  # gpio_run TAG MAT PULL: stream MAT with static pulled PULL; sets ALARM_VALUE
  echo "$3" >$GPIO_SIM/sim_gpio0/pull
  start_fw /tmp/fw_$1.txt --gpio-chip "$GPIO_CHIP" --static-line static --alarm-line alarm
  sim_run "$2" /tmp/run_$1 --rate max
  ALARM_VALUE=$(cat $GPIO_SIM/sim_gpio1/value)  # imu-fw is still running (exit-idle 4 s)
  wait $FW_PID
}
static_flag() { sed -n 's/.*static_flag \([0-9]\).*/\1/p' "$1" | tail -n1; }
filter_bias() { sed -n 's/^  bias \([^ ]*\) std [^ ]* static_flag.*/\1/p' "$1" | tail -n1; }
filter_std() { sed -n 's/^  bias [^ ]* std \([^ ]*\) static_flag.*/\1/p' "$1" | tail -n1; }
t_imu_gpio() {
  have imu-sim && have imu-fw && have imu-vm-stepmat ||
    { result imu_gpio SKIP "imu-sim/imu-fw/imu-vm-stepmat not built"; return; }
  [ -n "$GPIO_CHIP" ] || { result imu_gpio SKIP "no gpio-sim chip"; return; }
  imu-vm-stepmat --out /tmp/g_clean.mat --duration 30 >/dev/null &&
    imu-vm-stepmat --out /tmp/g_step.mat --duration 30 --step 0.1 --step-at-s 20 >/dev/null ||
    { result imu_gpio FAIL "stepmat"; return; }
  gpio_run moving /tmp/g_clean.mat pull-down
  local a_moving=$ALARM_VALUE
  gpio_run static /tmp/g_clean.mat pull-up
  local a_clean=$ALARM_VALUE
  gpio_run step /tmp/g_step.mat pull-up
  local a_step=$ALARM_VALUE
  local f_mov f_sta s_mov s_sta b_mov
  f_mov=$(static_flag /tmp/run_moving/report.txt)
  f_sta=$(static_flag /tmp/run_static/report.txt)
  s_mov=$(filter_std /tmp/run_moving/report.txt)
  s_sta=$(filter_std /tmp/run_static/report.txt)
  b_mov=$(filter_bias /tmp/run_moving/report.txt)
  # Gated: with "static" low the filter never updates, so its bias stays at the prior (exactly
  # 0: x0 = 0 and the prediction only scales it) and its std stays at the prior's, above the
  # std of the filter that did update.
  local gated
  gated=$(awk "BEGIN{print ($b_mov == 0 && $s_mov > $s_sta) ? 1 : 0}" 2>/dev/null)
  local msg rc_missing
  msg=$(imu-fw --bus vcan0 --gpio-chip "$GPIO_CHIP" --static-line no_such_line 2>&1) && rc_missing=0 || rc_missing=$?
  local detail="static low: flag $f_mov bias $b_mov std $s_mov; static high: flag $f_sta std $s_sta; alarm clean $a_clean, step $a_step (moving $a_moving); missing line: exit $rc_missing '$(echo "$msg" | head -n1)'"
  if [ "$f_mov" = 0 ] && [ "$f_sta" = 1 ] && [ "$gated" = 1 ] && [ "$a_clean" = 0 ] &&
     [ "$a_step" = 1 ] && [ $rc_missing != 0 ] && echo "$msg" | grep -q no_such_line; then
    result imu_gpio PASS "$detail"
  else
    dump /tmp/run_moving/report.txt /tmp/fw_step.txt
    result imu_gpio FAIL "$detail"
  fi
}

TESTS="can_vcan_fd can_roundtrip can_replay gpio_sim gpio_static_input gpio_alarm_output
       gpio_missing_line hal_can_stream hal_can_replay hal_can_flood hal_can_gap hal_gpio
       imu_stream imu_realtime imu_replay imu_flood imu_gpio imu_model_push
       imu_model_push_all"
# Kernel command line "imu_tests=a,b" (vm-run.sh: IMU_VM_TESTS="a b") runs only those checks
# after the two set-up ones (vcan0, gpio-sim): for quick iterations on one check.
only=$(sed -n 's/.*imu_tests=\([^ ]*\).*/\1/p' /proc/cmdline | tr ',' ' ')
if [ -n "$only" ]; then
  TESTS="can_vcan_fd gpio_sim $only"
fi
for t in $TESTS; do
  t_$t
done
echo "VMTEST-DONE pass=$pass fail=$fail skip=$skip uptime_s=$(cut -d' ' -f1 /proc/uptime)"
sync
reboot -f
