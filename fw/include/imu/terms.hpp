// The term registry: one row per kind of noise term of an IMU channel's error model (its name,
// parameters with units, states, Allan variance, fit basis, where it travels to the node and
// its Kalibr YAML key), and the accessors that read a
// term's instances out of a ModelParams. The model's AVAR (model_avar), the fit's term names,
// the analysis's effects and its report iterate over this table instead of spelling each term.
//
// Parameters are in the channel's unit u (m/s^2 or rad/s) and seconds; a term's "main"
// parameter is the one that says its size (N, Q, sigma, K, R, A, B) and is > 0 when the term is
// present (the ramp: != 0). A ModelParams holds up to max_instances of a kind: two GMs, two
// sinusoids, one of every other kind.
//
// AVAR of each kind: MODELS.md (error_model.hpp avar_*). No heap; every accessor O(1) but
// term_avar (that of the AVAR formula, a few exp()).
#ifndef IMU_TERMS_HPP
#define IMU_TERMS_HPP

#include <cstddef>
#include <cstdint>

#include "imu/error_model.hpp"

namespace imu {

enum class TermKind : std::uint8_t {
  kWhite = 0,       ///< velocity / angle random walk N (through the sensor's output filter)
  kQuantization,    ///< Q
  kGaussMarkov,     ///< first-order Gauss-Markov (sigma, Tb)
  kRateRandomWalk,  ///< K
  kRamp,            ///< R
  kSinusoid,        ///< A sin(2 pi f0 t + phase)
  kBiasInstability, ///< B, realised by a flicker bank of GMs
  kOscillation,     ///< narrowband (damped, randomly driven) oscillation
};
inline constexpr std::size_t kTermKinds = 8;
inline constexpr std::size_t kMaxTermParams = 3;

struct TermParamInfo {
  const char* key;     ///< JSON key of the parameter in a report's effect and its interval
  const char* symbol;  ///< its symbol in text
  const char* unit;    ///< its unit; u is the channel's unit
};

/// The record that carries a term to the node (hal/include/imu/hal/codec.hpp): the channel's
/// ModelRecord (version 2, 64 bytes) or its ModelSignalsRecord (32 bytes); none for none.
enum class WireRecord : std::uint8_t { kNone = 0, kModel, kSignals };
inline constexpr std::size_t kMaxWireFields = 3;
inline constexpr std::size_t kMaxWireInstances = 2;

/// Where a term's instances lie in their record: the record's fields (their names in
/// codec.hpp), each a little-endian IEEE 754 float32 at a byte offset from the record's first
/// byte, per instance. The wire carries the node's parameterisation, which is not always the
/// report's: a GM as its drive Sb and Tb, the oscillation's damping beta in 1/s.
struct TermWire {
  WireRecord record;
  const char* fields[kMaxWireFields];  ///< codec.hpp's member names ("gm_sb", "gm_tb_s")
  std::uint8_t offset[kMaxWireInstances][kMaxWireFields];  ///< byte offsets (instance, field)
  std::uint8_t n_fields;
};

struct TermInfo {
  const char* name;            ///< the term's name in reports and JSON ("rate_random_walk")
  const char* label;           ///< its name for people (plot legends: "rate random walk")
  const char* avar;            ///< its Allan variance (MODELS.md), for help and reports
  TermParamInfo params[kMaxTermParams];
  std::uint32_t fit_bit;       ///< its basis in the ADEV fit (FitTerm); the first GM's bit
  TermKind kind;
  std::uint8_t states;         ///< filter states of one instance (bias instability: per GM)
  std::uint8_t max_instances;  ///< how many a ModelParams holds
  std::uint8_t first_order;    ///< how many the first-order model (white noise + one GM) holds
  bool deterministic;          ///< a signal of the record (a regressor), not a noise process
  std::uint8_t main_param;     ///< index of the parameter that says its size
  std::uint8_t n_params;
  TermWire wire;               ///< its slot in the node's model records
  /// Its key in Kalibr's imu.yaml after the sensor's prefix ("accelerometer_" / "gyroscope_"):
  /// "noise_density" (N), "random_walk" (K); nullptr where Kalibr's model has no such term.
  const char* yaml;
};

/// The registry, indexed by TermKind. Every row's kind is its index (test_terms checks it).
extern const TermInfo kTermTable[kTermKinds];

[[nodiscard]] inline const TermInfo& term_info(TermKind k) {
  return kTermTable[static_cast<std::size_t>(k)];
}
/// The row whose name is `name`; nullptr if none.
[[nodiscard]] const TermInfo* term_by_name(const char* name);
/// The row whose fit basis is `bit` (kFitGm2: the Gauss-Markov row); nullptr if none.
[[nodiscard]] const TermInfo* term_by_fit_bit(std::uint32_t bit);

/// Instances of kind k present in p (main parameter > 0; a GM counts up to p.n_gm).
[[nodiscard]] std::size_t term_instances(const ModelParams& p, TermKind k);
/// Parameter `param` (the row's order) of instance `instance` of kind k in p; 0 if absent.
[[nodiscard]] double term_param(const ModelParams& p, TermKind k, std::size_t instance,
                                std::size_t param);
/// AVAR at tau_s of instance `instance` of kind k in p (0 if absent or incomplete, e.g. a
/// sinusoid without a frequency).
[[nodiscard]] double term_avar(const ModelParams& p, TermKind k, std::size_t instance,
                               double tau_s);
/// One-sided power spectral density at f_hz > 0 of instance `instance` of kind k in p
/// [u^2/Hz], the continuous process's, in the convention AVAR(tau) = 2 int_0^inf S(f)
/// sin^4(pi f tau) / (pi f tau)^2 df (IEEE Std 1139): white 2 N^2 (through the output filter:
/// / (1 + (2 pi f Tf)^2)), quantization 8 pi^2 Ts Q^2 f^2 below 1 / (2 Ts) (ts_s: the sampling
/// period; 0 above), a GM 2 Sb Tb^2 / (1 + (2 pi f Tb)^2), the walk K^2 / (2 pi^2 f^2), bias
/// instability its GM bank's, the oscillation 2 sigma^2 (beta / (beta^2 + (2 pi (f - f0))^2) +
/// beta / (beta^2 + (2 pi (f + f0))^2)). 0 for the deterministic kinds (ramp, sinusoid) and
/// for an absent instance.
[[nodiscard]] double term_psd(const ModelParams& p, TermKind k, std::size_t instance,
                              double f_hz, double ts_s);
/// Remove the instances of kind k from `instance` on (0: all of them).
void remove_term(ModelParams& p, TermKind k, std::size_t from_instance = 0);

}  // namespace imu

#endif  // IMU_TERMS_HPP
