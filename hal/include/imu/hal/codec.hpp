// IMU frame protocol: frame type, CRC-32C, record layouts, encoders and record parsers.
//
// Platform-free and allocation-free (plain C++17, no heap, no exceptions, no OS headers): the
// same code runs in host_sim, in the Linux co-processor node and, later, on a Cortex-M4. The
// protocol itself is specified in hal/README.md; this header is its single implementation.
//
// Byte order on the wire is little-endian for every multi-byte field, written byte by byte, so
// the encoding does not depend on the host. Every record ends with a CRC-32C (Castagnoli) of
// all its preceding bytes. A record goes out either as one CAN FD frame (Layout::kFd) or as
// ceil(len / 7) classic 8-byte frames (Layout::kClassic) whose first byte carries a 4-bit
// transfer counter and a 4-bit fragment index.
#ifndef IMU_HAL_CODEC_HPP
#define IMU_HAL_CODEC_HPP

#include <cstddef>
#include <cstdint>

namespace imu::hal {

// ---- The frame: byte-for-byte the kernel's struct canfd_frame (linux/can.h) ----------------

inline constexpr std::uint32_t kCanEffFlag = 0x80000000U;  ///< CAN_EFF_FLAG: 29-bit identifier
inline constexpr std::uint32_t kCanRtrFlag = 0x40000000U;  ///< CAN_RTR_FLAG: remote request
inline constexpr std::uint32_t kCanErrFlag = 0x20000000U;  ///< CAN_ERR_FLAG: error frame
inline constexpr std::uint32_t kCanSffMask = 0x000007FFU;  ///< CAN_SFF_MASK
inline constexpr std::uint32_t kCanErrMask = 0x1FFFFFFFU;  ///< CAN_ERR_MASK
inline constexpr std::uint8_t kCanFdBrs = 0x01;            ///< CANFD_BRS: bit rate switch
inline constexpr std::uint8_t kCanFdEsi = 0x02;            ///< CANFD_ESI
inline constexpr std::uint8_t kCanFdFdf = 0x04;            ///< CANFD_FDF: frame is CAN FD
inline constexpr std::size_t kCanMtu = 16;                 ///< sizeof(struct can_frame)
inline constexpr std::size_t kCanFdMtu = 72;               ///< sizeof(struct canfd_frame)
/// Error-frame classes (linux/can/error.h, bits of can_id): TX_TIMEOUT, LOSTARB, CRTL, PROT,
/// TRX, ACK, BUSOFF, BUSERROR, RESTARTED, CNT. RxStats::err_class[i] counts bit i.
inline constexpr std::size_t kErrClasses = 10;

/// Same layout as struct canfd_frame; a classic frame is the first 16 bytes (struct can_frame,
/// whose `len` byte is can_dlc and whose `flags` byte is __pad).
struct CanFrame {
  std::uint32_t can_id;  ///< identifier plus EFF/RTR/ERR flags, host byte order as in the kernel
  std::uint8_t len;      ///< payload bytes: 0..8 classic, 0..8,12,16,20,24,32,48,64 FD
  std::uint8_t flags;    ///< CANFD_* flags (0 for classic)
  std::uint8_t res0;
  std::uint8_t res1;
  alignas(8) std::uint8_t data[64];
};
static_assert(sizeof(CanFrame) == kCanFdMtu, "CanFrame must mirror struct canfd_frame");

/// Bytes to write for this frame: kCanFdMtu if it is an FD frame (FDF flag or len > 8),
/// otherwise kCanMtu. Constant time.
[[nodiscard]] inline std::size_t wire_size(const CanFrame& f) {
  return ((f.flags & kCanFdFdf) != 0 || f.len > 8) ? kCanFdMtu : kCanMtu;
}

/// Smallest valid CAN FD payload length >= n (n <= 64), e.g. 41 -> 48. Constant time.
[[nodiscard]] std::uint8_t fd_len_for(std::size_t n);

// ---- CRC ---------------------------------------------------------------------------------

/// CRC-32C (Castagnoli): polynomial 0x1EDC6F41 (reflected 0x82F63B78), init 0xFFFFFFFF, input
/// and output reflected, final xor 0xFFFFFFFF; check value crc32c("123456789") = 0xE3069283.
/// Table driven (1 KiB constant table), O(n), re-entrant.
[[nodiscard]] std::uint32_t crc32c(const std::uint8_t* data, std::size_t n);

// ---- Identifiers and records ---------------------------------------------------------------

enum class Layout : std::uint8_t { kFd, kClassic };

/// Record kinds. Each has an 11-bit identifier per layout (FD id even, classic id = FD id + 1);
/// a lower identifier wins arbitration, so configuration beats samples beats telemetry.
/// kRejects was added after the first version: a receiver that predates it counts its frames as
/// unknown_id and loses nothing else (no existing layout or identifier changed).
/// kModel (host -> node), kModelEcho and kChannelMonitor (node -> host) came later in the same
/// way.
/// kModel2 / kModelEcho2 carry the model record version 2 (kModelVersion2, 64 bytes: version 1's
/// fields, then the white noise's output filter and the narrowband oscillation). They are kinds
/// of their own rather than a second length on the version 1 identifiers: every identifier keeps
/// one record length, which the receiver checks against the FD `len` and counts classic fragments
/// by before the version byte is readable, and a receiver that knows only version 1 counts them
/// as unknown_id instead of bad_dlc or bad_fragment. Both parse into ModelRecord and arrive as
/// RxEvent kModel / kModelEcho; ModelRecord::version tells which.
/// kModelSignals (host -> node) / kModelSignalsEcho (node -> host) carry a channel's
/// deterministic terms (ModelSignalsRecord), which ModelRecord has no slot for; added in the same
/// way, next to the model identifiers.
enum class RecordKind : std::uint8_t {
  kConfig, kSample, kAdev, kBias, kMonitor, kStats, kRejects, kModel, kModelEcho, kChannelMonitor,
  kModel2, kModelEcho2, kModelSignals, kModelSignalsEcho
};
inline constexpr std::size_t kRecordKinds = 14;

inline constexpr std::uint32_t kIdConfigFd = 0x080;
inline constexpr std::uint32_t kIdSampleFd = 0x100;
inline constexpr std::uint32_t kIdAdevFd = 0x200;
inline constexpr std::uint32_t kIdBiasFd = 0x210;
inline constexpr std::uint32_t kIdMonitorFd = 0x220;
inline constexpr std::uint32_t kIdStatsFd = 0x230;
inline constexpr std::uint32_t kIdRejectsFd = 0x240;
inline constexpr std::uint32_t kIdModelFd = 0x090;      ///< after config, before samples
inline constexpr std::uint32_t kIdModel2Fd = 0x092;     ///< next to kIdModelFd (classic 0x093)
inline constexpr std::uint32_t kIdModelSignalsFd = 0x094;  ///< after kIdModel2Fd (classic 0x095)
inline constexpr std::uint32_t kIdModelEchoFd = 0x250;
inline constexpr std::uint32_t kIdModelEcho2Fd = 0x252; ///< next to kIdModelEchoFd (classic 0x253)
/// After kIdModelEcho2Fd (classic 0x255).
inline constexpr std::uint32_t kIdModelSignalsEchoFd = 0x254;
inline constexpr std::uint32_t kIdChannelMonitorFd = 0x260;

inline constexpr std::size_t kChannels = 6;  ///< ax, ay, az (accelerometer), gx, gy, gz (gyro)

// Recommended LSBs (hal/README.md, "Resolution and range"). Counts are int32 per channel and
// the LSB of each channel travels in the ConfigRecord, so any of these can be used:
/// ADIS16405 native resolution (3.33 mg, 0.05 deg/s): the sensor's counts travel unchanged.
inline constexpr double kAdisAccLsb_mps2 = 0.00333 * 9.80665;
inline constexpr double kAdisGyroLsb_rps = 0.05 * 3.14159265358979323846 / 180.0;
/// For double-precision records (simulation, other sensors): range +-219 g and
/// +-12,300 deg/s in int32; quantisation noise LSB/sqrt(12) = 2.9e-7 m/s^2 and 2.9e-8 rad/s.
inline constexpr double kFineAccLsb_mps2 = 1e-6;
inline constexpr double kFineGyroLsb_rps = 1e-7;
inline constexpr std::size_t kClassicPayload = 7;  ///< record bytes per classic frame
inline constexpr std::size_t kMaxRecordLen = 64;
inline constexpr std::size_t kMaxFragments = 10;   ///< ceil(64 / 7)

/// Sensor information; sent at start-up and periodically (e.g. 1 Hz). 64 bytes.
struct ConfigRecord {
  std::uint8_t cfg_id;           ///< changes whenever rate or an LSB changes
  double rate_hz;                ///< output data rate (Ts = 1 / rate_hz)
  double lsb[kChannels];         ///< physical value of one count: m/s^2 (acc), rad/s (gyro)
};

/// One IMU sample. 42 bytes.
struct SampleRecord {
  std::uint32_t seq;             ///< +1 per sample, wraps at 2^32
  std::uint64_t t_sensor_ns;     ///< sensor clock at the sample instant
  std::int32_t counts[kChannels];///< value / lsb, rounded to nearest (imu::quantize)
  std::uint8_t cfg_id;           ///< ConfigRecord::cfg_id these counts refer to
  std::uint8_t sat_mask;         ///< bit c set: channel c was clipped to int32 range
};

/// One point of an ADEV curve computed by the co-processor. 28 bytes. float32 fields carry
/// 24-bit mantissas: relative precision 6e-8, far below any confidence interval width.
struct AdevRecord {
  std::uint8_t channel;          ///< 0..5 as in SampleRecord::counts
  std::uint8_t index;            ///< point index in the curve, 0..n_points-1
  std::uint8_t n_points;         ///< points in the curve being sent
  float tau_s;
  float adev;                    ///< channel units (m/s^2 or rad/s)
  float ci_lo;
  float ci_hi;
  std::uint32_t n_terms;         ///< saturates at 2^32-1
};

/// BiasRecord::flags bits.
inline constexpr std::uint8_t kBiasStatic = 1U << 0;  ///< "static" input active (filter updating)
/// MonitorRecord::flags bits.
inline constexpr std::uint16_t kMonitorCusum = 1U << 0;      ///< a channel's CUSUM in alarm
inline constexpr std::uint16_t kMonitorWhiteness = 1U << 1;  ///< a whiteness check failed
inline constexpr std::uint16_t kMonitorAlarmLine = 1U << 2;  ///< the alarm output is set

/// Bias estimate and its variance for all channels, as of sample `seq`. 60 bytes.
struct BiasRecord {
  std::uint32_t seq;
  float bias[kChannels];         ///< channel units
  float var[kChannels];          ///< channel units squared
  std::uint8_t flags;            ///< kBiasStatic
};

/// Residual-monitor state as of sample `seq`. 20 bytes.
struct MonitorRecord {
  std::uint32_t seq;
  float nis_mean;                ///< running mean of the normalised innovation squared
  float whiteness;               ///< whiteness statistic (e.g. normalised autocorrelation)
  std::uint16_t flags;           ///< kMonitorCusum | kMonitorWhiteness | kMonitorAlarmLine
  std::uint8_t cusum_mask;       ///< bit c: CUSUM alarm on channel c
};

/// ChannelMonitorRecord::flags bits.
inline constexpr std::uint8_t kChanMonCusum = 1U << 0;       ///< the CUSUM detected a level shift
inline constexpr std::uint8_t kChanMonCusumDown = 1U << 1;   ///< ... the last one downward
inline constexpr std::uint8_t kChanMonWhiteness = 1U << 2;   ///< the last block failed whiteness
inline constexpr std::uint8_t kChanMonPushed = 1U << 3;      ///< the channel runs a pushed model

/// One channel's residual monitors as of sample `seq` (MonitorRecord is the summary over the
/// channels). Sent for every active channel after each MonitorRecord. 44 bytes. Counters
/// saturate. A consumer tells a model that fits (NIS mean near 1, whiteness failures near the
/// test's false-alarm rate, no CUSUM alarm) from one that does not, channel by channel.
struct ChannelMonitorRecord {
  std::uint8_t channel;          ///< 0..5
  std::uint8_t n_states;         ///< filter states the channel runs
  std::uint8_t flags;            ///< kChanMonCusum | kChanMonCusumDown | kChanMonWhiteness | kChanMonPushed
  std::uint8_t cusum_detections; ///< level shifts the CUSUM detected (saturates at 255)
  std::uint32_t seq;
  std::uint32_t updates;         ///< filter updates since the stream started
  float nis_mean;                ///< mean NIS over all those updates
  float nis_last_block;          ///< mean NIS of the last complete block
  float whiteness;               ///< last block's Box-Pierce statistic / its bound
  std::uint32_t blocks;          ///< complete monitor blocks
  std::uint32_t nis_flagged;     ///< blocks whose NIS mean left its chi-square interval
  std::uint32_t white_flagged;   ///< blocks that failed the whiteness test
  std::uint32_t cusum_step_update; ///< the update after which the last detected step began
};

/// Frame statistics of the sender's own receiver (see RxStats). 44 bytes. Counters saturate.
struct StatsRecord {
  std::uint32_t frames;
  std::uint32_t samples;
  std::uint32_t missing;
  std::uint32_t crc_errors;
  std::uint32_t bad_mtu_or_dlc;
  std::uint32_t unknown_id;
  std::uint32_t duplicates;
  std::uint32_t truncated;
  std::uint32_t error_frames;
  std::uint32_t kernel_drops;
};

/// Everything the sender refused or could not do, beyond StatsRecord (its own receiver, node and
/// link). 64 bytes. Counters saturate. Sent after each StatsRecord/BiasRecord/MonitorRecord set.
struct RejectsRecord {
  std::uint32_t bad_config;             ///< ConfigRecords refused (values out of range)
  std::uint32_t config_same_values;     ///< new cfg_id with unchanged values: kept, no restart
  std::uint32_t model_rejected;         ///< channel filters that could not be configured
  std::uint32_t samples_before_config;  ///< samples ignored: no ConfigRecord yet
  std::uint32_t cfg_mismatch;           ///< samples whose cfg_id is not the last config's
  std::uint32_t late;                   ///< samples after their slot was declared missing
  std::uint32_t resyncs;                ///< sequence jumped back: sender restart assumed
  std::uint32_t remote_frames;          ///< RTR frames
  std::uint32_t bad_fragment;           ///< classic fragment index beyond the record
  std::uint32_t orphan_fragments;       ///< classic fragment without its transfer start
  std::uint32_t busy;                   ///< receiver push refused until events were read
  std::uint32_t telemetry_failures;     ///< telemetry frames the link refused
  std::uint32_t gpio_errors;            ///< static input / alarm output failures
  std::uint32_t peer_refused;           ///< loopback peers refused (other user id)
  std::uint32_t bad_record;             ///< CRC-valid records refused (RxStats::bad_record)
};

/// ModelRecord::version: it selects the layout and the record kinds.
inline constexpr std::uint8_t kModelVersion1 = 1;  ///< 48 bytes, kModel / kModelEcho
inline constexpr std::uint8_t kModelVersion2 = 2;  ///< 64 bytes, kModel2 / kModelEcho2
/// ModelRecord::flags bits (echo only).
inline constexpr std::uint8_t kModelPushed = 1U << 0;  ///< the node runs a pushed model (else its default first-order)
/// Stochastic error model of one channel (imu::ModelParams without the deterministic terms,
/// ramp and sinusoids: ModelSignalsRecord carries those). 48 bytes (version 1) or 64 bytes
/// (version 2: the last four fields; a version 1 record has no slot for them and parses them as
/// 0). Sent by the host as kModel / kModel2 (n_states and flags 0); echoed by the node as
/// kModelEcho / kModelEcho2 with what it runs. A zero parameter means the term is absent;
/// gm_sb = 0 drops that GM; bi = 0 drops the flicker bank; osc_sigma = 0 drops the oscillation.
struct ModelRecord {
  std::uint8_t version;          ///< kModelVersion1 or kModelVersion2
  std::uint8_t channel;          ///< 0..5
  std::uint8_t n_states;         ///< echo: the model's states the node runs (0 in a push);
                                 ///< its filter has one more, the sample mean
  std::uint8_t flags;            ///< echo: kModelPushed
  float n;                       ///< white N [unit/sqrt(Hz)]
  float q;                       ///< quantization Q [unit s]
  float gm_sb[2];                ///< GM drive PSD [unit^2/s]
  float gm_tb_s[2];              ///< GM correlation time [s]
  float k;                       ///< rate random walk K [unit/sqrt(s)]
  float bi;                      ///< bias instability B [unit] (node rebuilds the flicker bank)
  float bi_tau_lo_s;
  float bi_tau_hi_s;
  float n_filter_s;              ///< v2: time constant of the sensor's first-order output filter
                                 ///< the white noise is seen through [s] (0: none; 1 state)
  float osc_sigma;               ///< v2: narrowband oscillation, std [unit] (0: absent; 2 states)
  float osc_f0_hz;               ///< v2: its centre frequency [Hz]
  float osc_beta_per_s;          ///< v2: its damping rate [1/s]
};

/// The deterministic terms of one channel's model: a ramp and up to two sinusoids (e.g. a line
/// and its harmonic). Pushed by the host as kModelSignals before the channel's ModelRecord (the
/// node applies it with the next ModelRecord of that channel); echoed by the node as
/// kModelSignalsEcho with what it runs (flags kModelPushed). A zero parameter means the term is
/// absent. 32 bytes on the wire, CRC included (bytes 2-3 reserved: written 0, ignored when
/// parsed).
struct ModelSignalsRecord {
  std::uint8_t channel;          ///< 0..5
  std::uint8_t flags;            ///< echo: kModelPushed when the node runs these terms; 0 in a push
  float ramp_r;                  ///< ramp R [unit/s] (signed; 0: none)
  float sin_a[2];                ///< sinusoid amplitudes [unit] (0: none)
  float sin_f0_hz[2];            ///< their frequencies [Hz]
  float memory_s;                ///< time over which the record established them [s] (0: unknown)
};

/// Record lengths in bytes on the wire, CRC included.
inline constexpr std::size_t kConfigLen = 64;
inline constexpr std::size_t kSampleLen = 42;
inline constexpr std::size_t kAdevLen = 28;
inline constexpr std::size_t kBiasLen = 60;
inline constexpr std::size_t kMonitorLen = 20;
inline constexpr std::size_t kStatsLen = 44;
inline constexpr std::size_t kRejectsLen = 64;
inline constexpr std::size_t kModelLen = 48;   ///< version 1
inline constexpr std::size_t kModel2Len = 64;  ///< version 2
inline constexpr std::size_t kChannelMonitorLen = 44;
inline constexpr std::size_t kModelSignalsLen = 32;

/// Wire length of a record kind; FD identifier of a kind. Constant time.
[[nodiscard]] std::size_t record_len(RecordKind k);
[[nodiscard]] std::uint32_t fd_id(RecordKind k);
/// The ModelRecord version a kind carries: kModelVersion1 (kModel, kModelEcho), kModelVersion2
/// (kModel2, kModelEcho2), 0 for the other kinds. Constant time.
[[nodiscard]] std::uint8_t model_version(RecordKind k);
/// Kind of an identifier (FD or classic), false if the id is not part of the protocol.
[[nodiscard]] bool kind_of_id(std::uint32_t can_id, RecordKind& kind, Layout& layout);

// ---- Encoders --------------------------------------------------------------------------------

/// Frames of one encoded record: 1 (FD) or ceil(len / 7) (classic).
struct EncodedFrames {
  CanFrame frame[kMaxFragments];
  std::size_t count;
};

/// Encode a record into `out` (overwritten). `transfer_id` is the 4-bit counter of the classic
/// layout (samples use seq & 0xF); ignored for FD. FD frames get flags FDF|BRS. Never fails:
/// every record fits both layouts by construction. O(record length), re-entrant.
void encode(const ConfigRecord& r, Layout layout, std::uint8_t transfer_id, EncodedFrames& out);
void encode(const SampleRecord& r, Layout layout, EncodedFrames& out);
void encode(const AdevRecord& r, Layout layout, std::uint8_t transfer_id, EncodedFrames& out);
void encode(const BiasRecord& r, Layout layout, std::uint8_t transfer_id, EncodedFrames& out);
void encode(const MonitorRecord& r, Layout layout, std::uint8_t transfer_id, EncodedFrames& out);
void encode(const StatsRecord& r, Layout layout, std::uint8_t transfer_id, EncodedFrames& out);
void encode(const RejectsRecord& r, Layout layout, std::uint8_t transfer_id, EncodedFrames& out);
/// echo = true: kModelEcho (node telemetry), else kModel (host -> node); kModelEcho2 / kModel2
/// when r.version is kModelVersion2 (any other version: the version 1 layout and kinds).
void encode(const ModelRecord& r, bool echo, Layout layout, std::uint8_t transfer_id,
            EncodedFrames& out);
void encode(const ChannelMonitorRecord& r, Layout layout, std::uint8_t transfer_id,
            EncodedFrames& out);
/// echo = true: kModelSignalsEcho (node telemetry), else kModelSignals (host -> node).
void encode(const ModelSignalsRecord& r, bool echo, Layout layout, std::uint8_t transfer_id,
            EncodedFrames& out);

// ---- Record serialisation (used by the encoders and by Receiver) ------------------------------

/// Write a record's wire bytes, CRC included, into buf (at least record_len bytes; a
/// ModelRecord: kModel2Len bytes if its version is kModelVersion2, else kModelLen).
void serialize(const ConfigRecord& r, std::uint8_t* buf);
void serialize(const SampleRecord& r, std::uint8_t* buf);
void serialize(const AdevRecord& r, std::uint8_t* buf);
void serialize(const BiasRecord& r, std::uint8_t* buf);
void serialize(const MonitorRecord& r, std::uint8_t* buf);
void serialize(const StatsRecord& r, std::uint8_t* buf);
void serialize(const RejectsRecord& r, std::uint8_t* buf);
void serialize(const ModelRecord& r, std::uint8_t* buf);
void serialize(const ChannelMonitorRecord& r, std::uint8_t* buf);
void serialize(const ModelSignalsRecord& r, std::uint8_t* buf);

/// True if the last 4 bytes of buf[0, len) are the CRC-32C of the bytes before them.
[[nodiscard]] bool crc_ok(const std::uint8_t* buf, std::size_t len);

/// Parse wire bytes (CRC already checked by the caller). Constant time. A ModelRecord's layout
/// is chosen by its version byte (buf[0]), as serialize chose it; the caller has checked that
/// the byte matches the record kind (Receiver does).
void parse(const std::uint8_t* buf, ConfigRecord& r);
void parse(const std::uint8_t* buf, SampleRecord& r);
void parse(const std::uint8_t* buf, AdevRecord& r);
void parse(const std::uint8_t* buf, BiasRecord& r);
void parse(const std::uint8_t* buf, MonitorRecord& r);
void parse(const std::uint8_t* buf, StatsRecord& r);
void parse(const std::uint8_t* buf, RejectsRecord& r);
void parse(const std::uint8_t* buf, ModelRecord& r);
void parse(const std::uint8_t* buf, ChannelMonitorRecord& r);
void parse(const std::uint8_t* buf, ModelSignalsRecord& r);

}  // namespace imu::hal

#endif  // IMU_HAL_CODEC_HPP
