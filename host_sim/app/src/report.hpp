// The report of imu-sim run (what the example's notebook printed and drew, from our pipeline):
// text, JSON, CSV data and gnuplot-rendered SVG/PNG plots. Host code.
#ifndef IMU_SIM_REPORT_HPP
#define IMU_SIM_REPORT_HPP

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "imu/cli/json.hpp"
#include "imu/error_model.hpp"
#include "imu/online_adev.hpp"

namespace imu::sim {

/// One ADEV point as reported (JSON keys tau_s, adev, edf, ci_lo, ci_hi; plus n_terms). The
/// rows of `imu-sim adev --deviation` hold MDEV, HDEV or TDEV in `adev` (full_adev.hpp).
struct AdevRow {
  double tau_s = 0.0;
  double adev = 0.0;
  double edf = 0.0;
  double ci_lo = 0.0;
  double ci_hi = 0.0;
  std::uint64_t n_terms = 0;
  std::uint64_t af = 0;  ///< averaging factor tau / Ts
};

[[nodiscard]] std::vector<AdevRow> rows_from_points(const AdevPoint* p, std::size_t n);
/// Fixed-width table, one line per tau; `value` heads the deviation's column.
[[nodiscard]] std::string format_adev_table(const std::vector<AdevRow>& rows,
                                            const char* value = "adev");
/// JSON array of {"tau_s","adev","edf","ci_lo","ci_hi","n_terms","af"} objects; `value` is the
/// deviation's key ("mdev", ..).
[[nodiscard]] std::string adev_json_list(const std::vector<AdevRow>& rows,
                                         const char* value = "adev");
/// A JSON number (%.10g; non-finite -> null) and a JSON string literal: the CLI library's, one
/// writer for every command.
using imu::cli::json_num;
using imu::cli::json_str;

/// Counters of one part of the chain (sender, node, receiver), printed and written as JSON.
struct StatGroup {
  std::string key;   ///< its JSON key in "frame_stats" (snake_case, no spaces)
  std::string name;  ///< its heading in the text report
  std::vector<std::pair<std::string, double>> values;
};

struct ReportOptions {
  bool given_model = false;  ///< use n/b/tp_s/k below; otherwise the fitted model
  double n = 0.0;
  double b = 0.0;
  double tp_s = 0.0;
  double k = 0.0;
  double t_avg_s = 10.0;           ///< covariance check: bias averaging time
  double t_int_s = 20.0;           ///< covariance check: integration time
  std::size_t sim_windows = 1000;  ///< simulated trajectories
  std::uint64_t seed = 1;          ///< simulation seed
  bool plots = true;               ///< run gnuplot (CSV files are always written)
  std::string out_dir;             ///< report.txt, CSV, plots
  std::string json_path;           ///< report JSON
};

struct ReportInput {
  std::string source;              ///< data file
  std::string channel;             ///< e.g. acc_z
  std::size_t channel_index = 2;
  double fs_hz = 0.0;
  double lsb = 0.0;
  /// The channel's first samples for the covariance check: the whole record, or a prefix of
  /// whole windows (run keeps at most 400 windows: memory independent of the record's length).
  const std::vector<double>* data = nullptr;
  std::size_t n_samples = 0;       ///< the record's length (0: data->size())
  std::vector<AdevRow> adev;       ///< the node's ADEV of the channel
  std::string adev_origin;         ///< where adev came from (text)
  std::vector<StatGroup> stats;    ///< frame statistics
  struct Timing {
    std::string key;    ///< the JSON key (snake_case)
    std::string label;  ///< the text report's words
    double seconds = 0.0;
  };
  std::vector<Timing> timing_s;
  std::vector<std::string> notes;  ///< printed at the end
  std::string node_json;           ///< the run JSON's "node" object (empty: left out)
  /// The model the node runs for the channel when it is a pushed one (read back from its
  /// echo): the report's model under test is then this one, so that the text, Fig. 1, the
  /// simulation and the covariance check are about the filter on the node.
  bool node_model_pushed = false;
  ModelParams node_model{};
  std::string node_text;           ///< the node's per-channel monitors, a text table
};

/// Compute model, fit, simulation and covariance check; write out_dir/report.txt, the JSON,
/// the CSV files and (if plots) the SVG/PNG figures. text receives the text report. Returns
/// false with a one-line err if a file cannot be written or the model is invalid.
[[nodiscard]] bool write_report(const ReportInput& in, const ReportOptions& opt, std::string& text,
                                std::string& err);

}  // namespace imu::sim

#endif  // IMU_SIM_REPORT_HPP
