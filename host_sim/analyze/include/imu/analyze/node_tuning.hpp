// The node's model tuned to its own filter by the record's Whittle likelihood.
//
// The analysis selects terms and fits them to the Allan deviation, a moment estimator whose
// resolution at the shortest taus is a few points. The node's filter needs more: its
// innovations are white only if the model's spectrum matches the data's at every frequency the
// filter sees, and its whiteness monitor tests exactly that at lags of one to four samples. So
// before a model is pushed, the parameters of its fast terms (white noise N, the output
// filter's time constant, Gauss-Markov terms whose corner lies inside the band, the narrowband
// oscillation) are re-estimated by maximum likelihood in the node's own discrete model (the
// state-space model node::discretize_pushed builds, averaging sampler included), with the slow
// terms held: the Whittle likelihood of the periodogram (P. Whittle, "Estimation and
// information in stationary time series", Ark. Mat. 2, 1953), which for a stationary Gaussian
// record is the exact likelihood up to O(1) terms and is maximal where the filter's
// innovations are white (D. R. Brillinger, "Time Series: Data Analysis and Theory", 1981,
// ch. 5). A narrowband oscillation the model lacks is offered at the periodogram's three
// largest excesses over the model (in a model that fills the node's states, with each way of
// making room: the bias-instability bank's short end up a decade while a decade is left, the
// fastest GM in the band to the white noise, the output filter left out); of those whose
// likelihood ratio passes a Bonferroni level over the bins searched, the one whose innovations
// are predicted whitest at the node's whiteness-monitor lags is kept (the node has one
// oscillation slot), the likelihood deciding near-ties.
//
// The periodogram: the longest stretch of finite samples (at least 2^12) in Welch segments of
// the largest power of two up to 2^18 (at most 16 of them), each with its line removed and a
// Hann taper; its ordinates from 1/1024 of the rate up to Nyquist averaged in
// bins 3 % wide (at most rate/1000 wide, so a resonance's peak is resolved), each weighted by
// the ordinates it holds over the taper's variance inflation 35/18. Steps, ramps and slow
// terms sit below the band. The model's spectrum: S(w) = h (zI - Phi)^-1 Qd (zI - Phi)^-H h^T
// + R at z = e^(iw) (x_{k+1} = Phi x_k + w_k, z_k = h x_k + v_k).
//
// Cost: one FFT per segment, then a few hundred likelihoods of about a thousand bins, each a
// complex solve of the model's states: about 0.2-1.5 s per channel, a few seconds where room
// has to be made. Host only (std::vector).
#ifndef IMU_ANALYZE_NODE_TUNING_HPP
#define IMU_ANALYZE_NODE_TUNING_HPP

#include <cstddef>
#include <string>

#include "imu/hal/codec.hpp"

namespace imu::analyze {

struct NodeTuning {
  bool tuned = false;               ///< the record's parameters changed
  std::size_t samples = 0;          ///< the stretch the periodogram used (0: none, see note)
  double two_ln_lr = 0.0;           ///< Whittle 2 ln LR of the tuned record over the one given
  bool oscillation_added = false;   ///< an oscillation the record lacked was added
  double oscillation_two_ln_lr = 0.0;  ///< its 2 ln LR beside the tuned record without it
  double oscillation_level = 0.0;      ///< the level it had to pass
  std::string note;                 ///< what changed, in one line (for the report)
};

/// Tune `rec` (a model the node runs beside reserved_states states of deterministic terms:
/// node::model_record_valid(rec, p, reserved_states) holds) to the record x[0..n) at fs_hz as
/// described above; x holds no deterministic term (the caller removes them: they are no part
/// of the spectrum tuned). rec is changed only where the likelihood rises and the result is
/// still a record the node runs. A record without a usable stretch (fewer than 2^12 finite
/// samples in a row) is left as it is, said in the note.
[[nodiscard]] NodeTuning tune_node_record(const double* x, std::size_t n, double fs_hz,
                                          hal::ModelRecord& rec,
                                          std::size_t reserved_states = 0);

/// x[0..n) at fs_hz less its least-squares fit of a constant, a line and a sine and cosine at
/// each frequency of `signals` (its sinusoids present): what tune_node_record needs of a record
/// whose model has deterministic terms. Non-finite samples stay as they are and take no part in
/// the fit. False (x unchanged) if the fit's normal equations are singular. O(n).
bool remove_signals(double* x, std::size_t n, double fs_hz, const hal::ModelSignalsRecord& signals);

/// Move rec's bias-instability bank's short end up a decade at a time (one state less each)
/// while the node would not run rec (beside reserved_states states of deterministic terms) and
/// the bank keeps a span of at least min_span (its upper end over its lower) after the move;
/// the node then realises B from there up. Returns whether the bank moved. O(moves), each a
/// model_record_valid.
bool narrow_flicker_bank(hal::ModelRecord& rec, float min_span, std::size_t reserved_states = 0);

}  // namespace imu::analyze

#endif  // IMU_ANALYZE_NODE_TUNING_HPP
