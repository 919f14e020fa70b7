// Time-domain likelihood test for a rate random walk ("RRW vs a GM peaking near T/10").
//
// Over taus up to T/10 the ADEV of a Gauss-Markov term whose peak (1.89 Tb) sits near the end of
// the range is the same curve as a rate random walk, and the few degrees of freedom there cannot
// tell them apart. The record can: a random walk keeps wandering over the whole record, a GM with
// Tb <= T/10 reverts to its mean many times. This module compares the two with the exact Gaussian
// likelihood of the record's block means:
//
//   y_k = (1/h) int_{kh}^{(k+1)h} (sum_i g_i(t) + w(t)) dt + e_k,     e_k ~ N(0, white_var)
//
// g_i first-order GM (drive PSD sb_i, time tb_i), w a random walk of intensity K^2 with a diffuse
// start (K = 0: an unknown constant, the record's offset), e_k the block mean of the white and
// other short-correlated noise. The states at block boundaries are Markov; the block integral
// shares its noise with the next state, which the Kalman filter below carries as the
// cross-covariance S (closed forms, no matrix exponential). The first block is conditioned on
// (the diffuse start), in both hypotheses alike.
//
// test_rrw(): H0 = white + GMs (tb <= tb_max), H1 = H0 + K; each maximised by Nelder-Mead in
// log parameters from several starts; LR = 2 (l1 - l0) is chi-square(1)-like under H0 (K = 0 is
// on the boundary, so the 1 % level of chi2(1), 6.63, is conservative). With a ramp in the model
// the record is detrended first, so the ramp is not taken for a random walk.
//
// Cost: one likelihood is O(blocks) with n_gm + 1 <= 3 states (about 20 us for 2048 blocks); a
// test is a few thousand of them, about 0.05-0.2 s. Host only (std::vector).
#ifndef IMU_ANALYZE_LONG_MEMORY_HPP
#define IMU_ANALYZE_LONG_MEMORY_HPP

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "imu/error_model.hpp"

namespace imu::analyze {

struct BlockModel {
  double white_var = 0.0;  ///< variance of the white part of one block mean [unit^2]
  std::size_t n_gm = 0;
  GmParam gm[kMaxGmTerms] = {};  ///< drive PSD sb [unit^2/s], correlation time tb_s [s]
  double k = 0.0;          ///< rate random walk K [unit/sqrt(s)]; 0: the walk is a constant
  /// Bias instability B (flicker bank over [bi_tau_lo_s, bi_tau_hi_s], error_model.hpp); the
  /// bank's members shorter than half a block are white at this scale and go to white_var.
  double bi = 0.0;
  double bi_tau_lo_s = 0.0;
  double bi_tau_hi_s = 0.0;
};

/// The unbiased sample variance of v (0 for fewer than two values).
[[nodiscard]] double sample_variance(const std::vector<double>& v);

/// Means of consecutive blocks of `per_block` samples (a trailing partial block is dropped).
[[nodiscard]] std::vector<double> block_means(const std::vector<double>& y, std::size_t per_block);

/// Remove v's mean and, with detrend, its least-squares line through the points' centres (as
/// test_rrw prepares the block means, and a regressor tested against them must be prepared).
void remove_mean_and_line(std::vector<double>& v, bool detrend);

/// Remove v's least-squares polynomial of the given degree in the points' index (degree 0 and 1:
/// remove_mean_and_line; higher: Gram-Schmidt over the powers of the index scaled to [-1, 1],
/// each basis vector orthogonalised twice, conditioned at any length).
void remove_polynomial(std::vector<double>& v, std::size_t degree);

/// Log-likelihood (without the 2 pi constant) of the block means under m, block length block_s.
/// w0_var < 0: the walk starts diffuse and the first block is conditioned on (its term left
/// out); w0_var >= 0: w(0) ~ N(0, w0_var) and every block counts (tests). resets: sorted block
/// indices before which the walk's level becomes unknown again (a bias step already found and
/// removed: what its estimate left behind is not evidence of a walk); their terms are left out.
/// Returns -inf for an invalid model (non-positive white_var, tb or sb).
[[nodiscard]] double block_loglik(const std::vector<double>& means, double block_s,
                                  const BlockModel& m, double w0_var = -1.0,
                                  const std::vector<std::size_t>& resets = {});

/// Nelder-Mead minimisation of f from x0 with initial steps `step` in every coordinate, at
/// most max_iterations per pass, then one restart from the best with a quarter of the steps.
/// Converged: f within 1e-4 and the coordinates within 1e-3 over the simplex. Returns the best
/// point. Cost: about max_iterations x (1 to dims + 2) calls of f per pass.
[[nodiscard]] std::vector<double> nelder_mead(
    const std::function<double(const std::vector<double>&)>& f, std::vector<double> x0,
    double step, int max_iterations);

struct LikelihoodFit {
  bool ok = false;
  BlockModel model{};
  double loglik = 0.0;
};

/// Maximise block_loglik over white_var, each GM's (sb, tb) with tb in [tb_min_s, tb_max_s],
/// B if start.bi > 0 (its range fixed), and K if fit_k (else K stays at start.k). n_gm is
/// start.n_gm. Nelder-Mead in log parameters.
[[nodiscard]] LikelihoodFit fit_block_model(const std::vector<double>& means, double block_s,
                                            const BlockModel& start, bool fit_k,
                                            double tb_min_s, double tb_max_s,
                                            const std::vector<std::size_t>& resets = {});

struct RrwLikelihoodTest {
  bool ok = false;
  double block_s = 0.0;
  std::size_t blocks = 0;
  LikelihoodFit h0{};  ///< white + GMs
  LikelihoodFit h1{};  ///< white + GMs + K
  double lr = 0.0;     ///< 2 (l1 - l0), >= 0
  std::size_t per_block = 0;
  std::vector<double> means;         ///< the (de-meaned, maybe detrended) block means tested
  std::vector<std::size_t> resets;   ///< level resets at the steps given
};

/// The first-order model (white + one GM) with its correlation time free over [block, tb_hi_s]
/// on the block means of `test`, against the test's walk model (test.h1, white + GMs with
/// tb <= tb_max + K). A GM whose Tb is a sizeable fraction of the record or beyond it has the
/// walk's covariance over the record as nearly as its Tb is long (its PSD sb tb^2 / (1 + (w tb)^2)
/// is the walk's K^2 / w^2 with K^2 = sb wherever w tb >> 1): where the walk does not beat it,
/// the record does not tell a GM slower than it resolves from a walk. Starts: the test's H0 GM,
/// and a GM carrying the walk's power (sb = K^2) at tb = T / 4, T, 10 T. The 95 % set of Tb is
/// the profile likelihood's, {tb : 2 (l_max - l(tb)) <= 3.84} (chi-square(1) at 0.95), tb held
/// and white and sb refitted; tb_hi_95_s is +inf where the set reaches tb_hi_s (the record
/// bounds Tb from below only).
struct SlowGmFit {
  bool ok = false;
  LikelihoodFit fit{};      ///< white + one GM, tb in [block_s, tb_hi_s]
  double lr_walk = 0.0;     ///< 2 (l(test.h1) - l(fit)): the walk against the free GM (may be < 0)
  double lr_reverts = 0.0;  ///< 2 (l(fit) - l(tb = tb_hi_s)): the GM against one as slow as allowed
  double tb_lo_95_s = 0.0;  ///< the 95 % set of the GM's Tb: from
  double tb_hi_95_s = 0.0;  ///< to (+inf: open-ended)
};
[[nodiscard]] SlowGmFit slow_gm_against_walk(const RrwLikelihoodTest& test, double tb_hi_s);

/// The likelihood-ratio set of a change point's time (Siegmund, "Confidence sets in
/// change-point problems", Int. Stat. Rev. 56, 1988): beside the true time the profile's
/// 2 ln LR falls as 2 W(s) - |s| on either side (W a Brownian motion, s in units of the
/// step's sd^2 / size^2), whose supremum on each side is exponential with mean 2; both stay
/// below c with probability (1 - e^(-c/2))^2 = 0.95 at c = -2 ln(1 - sqrt(0.95)) = 7.35 (not
/// chi-square(1)'s 3.84: the time is not a regular parameter). Its coverage:
/// tests/bench/bench_selection.
inline constexpr double kChangePointSet95 = 7.35;
/// The positions of that set: the first and last index i whose two_ln_l[i] (2 ln L of the
/// change at position i; NaN where not profiled) lies within kChangePointSet95 of
/// two_ln_l[best]. Callers widen it by one position either side (a step between two positions
/// peaks at either).
struct PositionRange {
  std::size_t first = 0;
  std::size_t last = 0;
};
[[nodiscard]] PositionRange change_point_set(const std::vector<double>& two_ln_l,
                                             std::size_t best);

/// A bias step against the test's H0, by the record's profile likelihood: for every block
/// boundary b at least `margin_blocks` from either end, the GLS size of a level shift at b under
/// H0 (the whitened innovations of the data and of the unit step at b, one Kalman pass each;
/// H0's parameters fixed) and lr(b) = (sum a e)^2 / sum e^2 = 2 (l(b) - l0), chi-square(1) at a
/// fixed b. The best b is returned; its lr is compared by the caller with a threshold over the
/// number of positions and with the walk's lr. The step's time has a 95 % set from the
/// profile (change_point_set over the boundaries), from the block before its first boundary to
/// the block after its last. Cost: O(blocks^2 * states^2), ~0.1 s.
struct StepLikelihood {
  bool ok = false;
  std::uint64_t sample = 0;  ///< first sample after the step
  double lr = 0.0;
  double size = 0.0;         ///< [unit]
  std::size_t positions = 0;  ///< boundaries profiled
  std::uint64_t first_sample = 0;  ///< the 95 % set of `sample`: from
  std::uint64_t last_sample = 0;   ///< to
};
/// 2 ln LR of a deterministic regressor u (one value per block of the test) against the test's
/// H0, by GLS as for a step: e.g. a quadratic trend left after a line was removed. 0 if n/a.
/// size (if given): the regressor's GLS coefficient (0 if n/a). nuisance (if given, one value
/// per block): a second regressor fitted beside u in both hypotheses (the partial 2 ln LR of u).
[[nodiscard]] double regressor_lr(const RrwLikelihoodTest& test, const std::vector<double>& u,
                                  double* size = nullptr,
                                  const std::vector<double>* nuisance = nullptr);

/// only_block != kEveryBlock: that boundary alone (the GLS size of a step found elsewhere).
/// nuisance (if given, one value per block): a regressor fitted beside the step in both
/// hypotheses (e.g. a ramp's line: the step's partial 2 ln LR).
inline constexpr std::size_t kEveryBlock = static_cast<std::size_t>(-1);
[[nodiscard]] StepLikelihood profile_step(const RrwLikelihoodTest& test,
                                          std::size_t margin_blocks,
                                          std::size_t only_block = kEveryBlock,
                                          const std::vector<double>* nuisance = nullptr);

/// Block means the walk's test uses by default (test_rrw's target_blocks).
inline constexpr std::size_t kRrwTestBlocks = 2048;

/// The test on the record y (sample period ts_s), in about target_blocks blocks. start: the
/// ADEV fit's parameters (its GMs, at least one, B and K if any), tb_max_s: the largest GM
/// correlation time H0 may use (a GM beyond it is what the record calls a random walk).
/// detrend: remove the least-squares line first (when a ramp is already in the model; a walk
/// that happens to run one way over the record is then largely removed with it).
/// step_samples: sample indices of bias steps found and removed (the level is reset there).
/// with_walk = false: H0 alone (h1 = h0, lr = 0), for callers that need only its likelihood.
/// trend_degree: with detrend, the degree of the least-squares polynomial removed (1: the line;
/// 3: a smooth drift that bends, which a walk must explain better than to be a walk).
[[nodiscard]] RrwLikelihoodTest test_rrw(const std::vector<double>& y, double ts_s,
                                         const ModelParams& start, double tb_max_s, bool detrend,
                                         const std::vector<std::uint64_t>& step_samples = {},
                                         std::size_t target_blocks = kRrwTestBlocks,
                                         bool with_walk = true, std::size_t trend_degree = 1);

/// test_rrw on block means already formed (m: per_block samples each, their mean and any trend
/// removed), e.g. the test's own means less a fitted regressor.
[[nodiscard]] RrwLikelihoodTest test_rrw_on_means(std::vector<double> m, std::size_t per_block,
                                                  double ts_s, const ModelParams& start,
                                                  double tb_max_s,
                                                  const std::vector<std::uint64_t>& step_samples,
                                                  bool with_walk = true);

}  // namespace imu::analyze

#endif  // IMU_ANALYZE_LONG_MEMORY_HPP
