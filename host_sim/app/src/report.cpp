// Report of imu-sim run (see report.hpp).
#include "report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "common.hpp"
#include "imu/cli/file_out.hpp"
#include "imu/covariance_check.hpp"
#include "imu/error_model.hpp"
#include "imu/model_fit.hpp"
#include "imu/model_text.hpp"
#include "imu/noise_sim.hpp"
#include "imu/terms.hpp"

namespace imu::sim {
namespace {

// The fitted model (white + quantization + GM + RRW) needs 2 states, a model the node runs at
// most node::kNodeProcessStates (8).
constexpr std::size_t kStates = 8;

struct Curve {
  std::vector<double> tau_s;
  std::vector<double> term[kTermKinds];  // ADEV of each kind of term (its instances together)
  std::vector<double> total;             // ADEV of the model
};

Curve model_curve(const ModelParams& p, double ts_s, double tau_max_s) {
  Curve c;
  const double lo = std::log10(ts_s);
  const double hi = std::log10(tau_max_s);
  const int n = 120;
  for (int i = 0; i <= n; ++i) {
    const double tau = std::pow(10.0, lo + (hi - lo) * i / n);
    c.tau_s.push_back(tau);
    for (const TermInfo& t : kTermTable) {
      double v = 0.0;
      for (std::size_t k = 0; k < t.max_instances; ++k) {
        v += term_avar(p, t.kind, k, tau);
      }
      c.term[static_cast<std::size_t>(t.kind)].push_back(std::sqrt(v));
    }
    c.total.push_back(std::sqrt(model_avar(p, tau)));
  }
  return c;
}

// The fit input: AdevPoint from a reported row (af and stride recovered from tau and Ts).
std::vector<AdevPoint> points_from_rows(const std::vector<AdevRow>& rows, double ts_s) {
  std::vector<AdevPoint> pts;
  for (const AdevRow& r : rows) {
    AdevPoint p{};
    p.tau_s = r.tau_s;
    p.af = static_cast<std::uint32_t>(std::lround(r.tau_s / ts_s));
    p.stride = 1;
    p.n_terms = r.n_terms;
    p.avar = r.adev * r.adev;
    p.adev = r.adev;
    p.edf = r.edf;
    p.ci_lo = r.ci_lo;
    p.ci_hi = r.ci_hi;
    pts.push_back(p);
  }
  return pts;
}

struct CovResult {
  std::size_t n_avg = 0, n_int = 0;
  std::size_t data_windows = 0, sim_windows = 0;
  std::vector<double> pred_exact, pred_uncorr, emp_sim, emp_data;
  std::vector<double> traj_sim, traj_data;  // windows x n_int, row-major
};

std::vector<double> column_robust_std(const std::vector<double>& traj, std::size_t windows,
                                      std::size_t n_int) {
  std::vector<double> out(n_int, 0.0);
  std::vector<double> col(windows);
  for (std::size_t j = 0; j < n_int && windows > 0; ++j) {
    for (std::size_t w = 0; w < windows; ++w) {
      col[w] = traj[w * n_int + j];
    }
    out[j] = robust_std(col.data(), windows);
  }
  return out;
}

std::string fmt_stats_value(double v) {
  std::string s;
  if (std::fabs(v - std::round(v)) < 1e-9 && std::fabs(v) < 1e15) {
    appendf(s, "%.0f", v);
  } else {
    appendf(s, "%.4g", v);
  }
  return s;
}

}  // namespace

std::vector<AdevRow> rows_from_points(const AdevPoint* p, std::size_t n) {
  std::vector<AdevRow> rows;
  for (std::size_t i = 0; i < n; ++i) {
    rows.push_back(AdevRow{p[i].tau_s, p[i].adev, p[i].edf, p[i].ci_lo, p[i].ci_hi,
                           p[i].n_terms, p[i].af});
  }
  return rows;
}

std::string format_adev_table(const std::vector<AdevRow>& rows, const char* value) {
  std::string s;
  appendf(s, "%12s %10s %12s %12s %12s %10s %10s\n", "tau_s", "af", value, "ci_lo", "ci_hi",
          "edf", "n_terms");
  for (const AdevRow& r : rows) {
    appendf(s, "%12.4g %10llu %12.4e %12.4e %12.4e %10.4g %10llu\n", r.tau_s,
            static_cast<unsigned long long>(r.af), r.adev, r.ci_lo, r.ci_hi, r.edf,
            static_cast<unsigned long long>(r.n_terms));
  }
  return s;
}

std::string adev_json_list(const std::vector<AdevRow>& rows, const char* value) {
  std::string s = "[";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const AdevRow& r = rows[i];
    s += i == 0 ? "\n" : ",\n";
    s += "    {\"tau_s\": " + json_num(r.tau_s) + ", " + json_str(value) + ": " +
         json_num(r.adev) +
         ", \"edf\": " + json_num(r.edf) + ", \"ci_lo\": " + json_num(r.ci_lo) +
         ", \"ci_hi\": " + json_num(r.ci_hi) +
         ", \"n_terms\": " + std::to_string(r.n_terms) + ", \"af\": " + std::to_string(r.af) +
         "}";
  }
  s += rows.empty() ? "]" : "\n  ]";
  return s;
}

namespace {

// What write_report's steps compute, in order: the model, its simulation, the covariance
// check, the text, the plots.
struct ReportState {
  double ts_s = 0.0;
  const char* unit = "";
  std::size_t n_samples = 0;
  double tau_max_s = 1.0;
  FitOptions fo;
  FitResult fr{};
  ModelParams mp{};
  FirstOrderGm gm{};
  bool have_gm = false;
  std::string model_origin;
  DiscreteModel<kStates> dm;
  ModelSimulator<kStates> sim;
  std::vector<AdevRow> sim_rows;
  double t_sim0 = 0.0;
  CovResult cov;
  double t_sim = 0.0;
  std::string text;
  std::string plot_note;
  std::vector<std::string> plot_files;
};

// The model under test: given (--N --B --Tp --K) or fitted to the data's ADEV (always fitted,
// for the report), built and discretised. False with err.
bool report_model(const ReportInput& in, const ReportOptions& opt, ReportState& rs,
                  std::string& err) {
  const double ts_s = rs.ts_s;
  const double tau_max_s = rs.tau_max_s;
  FitOptions& fo = rs.fo;
  FitResult& fr = rs.fr;
  ModelParams& mp = rs.mp;
  FirstOrderGm& gm = rs.gm;
  bool& have_gm = rs.have_gm;
  std::string& model_origin = rs.model_origin;
  DiscreteModel<kStates>& dm = rs.dm;
  // ---- Fit (always) and the model under test -------------------------------------------
  const std::vector<AdevPoint> pts = points_from_rows(in.adev, ts_s);
  fo.terms = kFitWhite | kFitQuantization | kFitGm1 | kFitRrw;
  fo.tau_min_s = ts_s;
  fo.tau_max_s = tau_max_s;
  fo.edf_cap = 1000.0;  // neighbouring taus are correlated: keep the short taus from deciding alone
  fr = fit(pts.data(), pts.size(), fo);

  if (in.node_model_pushed) {
    mp = in.node_model;
    model_origin = "the model pushed to the node, as it echoes it";
  } else if (opt.given_model) {
    if (first_order_gm_from_asd(opt.n, opt.b, opt.tp_s, in.fs_hz, gm) != ModelStatus::kOk ||
        opt.k < 0.0) {
      err = "model parameters rejected (N, B, Tp must be > 0, K >= 0)";
      return false;
    }
    have_gm = true;
    mp.n = opt.n;
    mp.n_gm = 1;
    mp.gm[0] = GmParam{gm.sb, gm.tb_s};
    mp.k = opt.k;
    appendf(model_origin, "given: N = %.4g, B = %.4g, Tp = %.4g s, K = %.4g", opt.n, opt.b,
            opt.tp_s, opt.k);
  } else if (fr.status == FitStatus::kOk) {
    mp = fr.params;
    model_origin = "fitted: white + quantization + first-order GM + rate random walk";
  } else {
    err = "no model: the fit failed (status " +
          std::to_string(static_cast<int>(fr.status)) + ") and no --N/--B/--Tp were given";
    return false;
  }
  // The example's layout of the first GM (given: already made from N, B, Tp).
  if (!have_gm && mp.n > 0.0 && mp.n_gm >= 1 && mp.gm[0].sb > 0.0) {
    const double b = kGmPeakAdevFactor * std::sqrt(mp.gm[0].sb * mp.gm[0].tb_s);
    have_gm = first_order_gm_from_asd(mp.n, b, kGmPeakTauFactor * mp.gm[0].tb_s, in.fs_hz, gm) ==
              ModelStatus::kOk;
  }
  // The simulation takes point samples: through the sensor's output filter their variance
  // would be N^2 / 2 Tf, not the node's averaged N^2 / Ts, so the filter is drawn (the model's
  // AVAR) but not simulated.
  ModelParams simulated = mp;
  if (simulated.n_filter_s > 0.0) {
    appendf(model_origin, "; its output filter (Tf = %.3g s) is in the model's ADEV but not "
            "simulated (point samples)", simulated.n_filter_s);
    simulated.n_filter_s = 0.0;
  }
  ContinuousModel<kStates> cm;
  if (build_model(simulated, cm) != ModelStatus::kOk ||
      discretize(cm, ts_s, dm) != ModelStatus::kOk) {
    err = "the model could not be built or discretised";
    return false;
  }
  return true;
}

// The model simulated over as many samples as the data, and its ADEV. False with err.
bool report_simulation(const ReportOptions& opt, ReportState& rs, std::string& err) {
  const double ts_s = rs.ts_s;
  const std::size_t n_samples = rs.n_samples;
  DiscreteModel<kStates>& dm = rs.dm;
  ModelSimulator<kStates>& sim = rs.sim;
  std::vector<AdevRow>& sim_rows = rs.sim_rows;
  // ---- Simulated model: ADEV over as many samples as the data -------------------------------
  rs.t_sim0 = now_s();
  if (sim.configure(dm, opt.seed) != ModelStatus::kOk) {
    err = "the model could not be simulated (covariance not positive semi-definite)";
    return false;
  }
  const double sim_lsb = std::max(std::sqrt(dm.r_filter()) * 1e-4, 1e-12);
  OnlineAdev<8, 22> sim_adev(ts_s, sim_lsb);
  (void)simulate_adev(sim, n_samples, sim_lsb, sim_adev);  // lsb > 0 by construction
  AdevPoint sim_pts[OnlineAdev<8, 22>::kMaxPoints];
  sim_rows =
      rows_from_points(sim_pts, sim_adev.snapshot(sim_pts, OnlineAdev<8, 22>::kMaxPoints));
  return true;
}

// The covariance check: the integrated error's std over windows of the data and of the
// simulated model, against the model's prediction (exact, and the example's). False with err.
bool report_covariance(const ReportInput& in, const ReportOptions& opt, ReportState& rs,
                       std::string& err) {
  const double ts_s = rs.ts_s;
  const std::vector<double>& data = *in.data;
  DiscreteModel<kStates>& dm = rs.dm;
  ModelSimulator<kStates>& sim = rs.sim;
  CovResult& cov = rs.cov;
  // ---- Covariance check -------------------------------------------------------------------
  cov.n_avg = static_cast<std::size_t>(std::lround(opt.t_avg_s * in.fs_hz));
  cov.n_int = static_cast<std::size_t>(std::lround(opt.t_int_s * in.fs_hz));
  if (cov.n_avg == 0 || cov.n_int == 0) {
    err = "covariance check: T_avg and T_int must be at least one sample";
    return false;
  }
  const std::size_t win = cov.n_avg + cov.n_int;
  cov.pred_exact.assign(cov.n_int, 0.0);
  cov.pred_uncorr.assign(cov.n_int, 0.0);
  if (predict_integral_std(dm, cov.n_avg, cov.n_int, cov.pred_exact.data(),
                           CovPrediction::kExact) != ModelStatus::kOk ||
      predict_integral_std(dm, cov.n_avg, cov.n_int, cov.pred_uncorr.data(),
                           CovPrediction::kCorrelationIgnored) != ModelStatus::kOk) {
    err = "covariance prediction failed";
    return false;
  }
  // A window holding a non-finite sample (a gap) is left out: a gap is not a number.
  const std::size_t all_windows = data.size() / win;
  cov.traj_data.assign(all_windows * cov.n_int, 0.0);
  cov.data_windows = 0;
  for (std::size_t w = 0; w < all_windows; ++w) {
    const double* x = &data[w * win];
    if (std::all_of(x, x + win, [](double v) { return std::isfinite(v); })) {
      integrate_window(x, cov.n_avg, cov.n_int, ts_s, &cov.traj_data[cov.data_windows * cov.n_int]);
      ++cov.data_windows;
    }
  }
  cov.traj_data.resize(cov.data_windows * cov.n_int);
  cov.sim_windows = opt.sim_windows;
  cov.traj_sim.assign(cov.sim_windows * cov.n_int, 0.0);
  {
    std::vector<double> z(win);
    for (std::size_t w = 0; w < cov.sim_windows; ++w) {
      sim.restart();
      for (double& v : z) {
        v = sim.next();
      }
      integrate_window(z.data(), cov.n_avg, cov.n_int, ts_s, &cov.traj_sim[w * cov.n_int]);
    }
  }
  cov.emp_data = column_robust_std(cov.traj_data, cov.data_windows, cov.n_int);
  cov.emp_sim = column_robust_std(cov.traj_sim, cov.sim_windows, cov.n_int);
  rs.t_sim = now_s() - rs.t_sim0;
  return true;
}

// The model's terms beyond white noise and its first GM (the example's layout), one line each
// with its parameters and units from the term registry.
std::string beyond_first_order(const ModelParams& mp, const char* unit) {
  std::string t;
  for (const TermInfo& row : kTermTable) {
    for (std::size_t i = row.first_order; i < row.max_instances; ++i) {
      if (!(std::fabs(term_param(mp, row.kind, i, row.main_param)) > 0.0)) {
        continue;
      }
      appendf(t, "%sBeyond the first-order model: %s", t.empty() ? "\n" : "", row.label);
      for (std::size_t j = 0; j < row.n_params; ++j) {
        const TermParamInfo& par = row.params[j];
        // the registry's "u" is the channel's unit
        const std::string u = par.unit[0] == 'u' ? unit + std::string(par.unit + 1) : par.unit;
        appendf(t, "%s %s = %.4e %s", j == 0 ? "" : ",", par.symbol,
                term_param(mp, row.kind, i, j), u.c_str());
      }
      appendf(t, " (AVAR %s).\n", row.avar);
    }
  }
  return t;
}

// The text report (report.txt) up to the plots' line.
void report_text(const ReportInput& in, const ReportOptions& opt, ReportState& rs) {
  const double ts_s = rs.ts_s;
  const char* unit = rs.unit;
  const std::vector<double>& data = *in.data;
  const std::size_t n_samples = rs.n_samples;
  FitOptions& fo = rs.fo;
  FitResult& fr = rs.fr;
  ModelParams& mp = rs.mp;
  FirstOrderGm& gm = rs.gm;
  bool& have_gm = rs.have_gm;
  std::string& model_origin = rs.model_origin;
  CovResult& cov = rs.cov;
  std::string& t = rs.text;
  const std::size_t win = rs.cov.n_avg + rs.cov.n_int;
  // ---- Text ------------------------------------------------------------------------------
  appendf(t, "imu-sim report\n==============\n");
  appendf(t, "data: %s, channel %s [%s], %zu samples at %.6g Hz (%.6g s), LSB %.6g %s\n",
          in.source.c_str(), in.channel.c_str(), unit, n_samples, in.fs_hz,
          static_cast<double>(n_samples) * ts_s, in.lsb, unit);
  appendf(t, "\n== Error model in the example's layout (%s)\n\n", model_origin.c_str());
  if (have_gm) {
    t += format_first_order_model(gm);
  } else {
    t += "(no first-order Gauss-Markov term: the example's layout does not apply)\n";
  }
  t += beyond_first_order(mp, unit);
  appendf(t, "\n== Weighted least-squares fit of the ADEV (white + quantization + GM + RRW, tau in [%.4g, %.4g] s,\n   weights 1/var with the EDF capped at %.0f)\n\n",
          fo.tau_min_s, fo.tau_max_s, fo.edf_cap);
  if (fr.status == FitStatus::kOk) {
    t += format_model_params(fr.params);
    appendf(t, "points %zu, RMS relative ADEV misfit %.3f%s\n", fr.n_points, fr.rms_rel,
            fr.tb_at_bound ? ", Tb at the end of its search range (not determined by the data)"
                           : "");
  } else {
    appendf(t, "fit failed (status %d)\n", static_cast<int>(fr.status));
  }
  appendf(t, "\n== ADEV of %s (%s; 68.3 %% intervals) with the model's ADEV\n\n",
          in.channel.c_str(), in.adev_origin.c_str());
  appendf(t, "%12s %12s %12s %12s %10s %10s %12s\n", "tau_s", "adev", "ci_lo", "ci_hi", "edf",
          "n_terms", "model");
  for (const AdevRow& r : in.adev) {
    appendf(t, "%12.4g %12.4e %12.4e %12.4e %10.4g %10llu %12.4e\n", r.tau_s, r.adev, r.ci_lo,
            r.ci_hi, r.edf, static_cast<unsigned long long>(r.n_terms),
            std::sqrt(model_avar(mp, r.tau_s)));
  }
  const std::size_t j_end = cov.n_int - 1;
  appendf(t, "\n== Covariance check (T_avg = %.4g s, T_int = %.4g s): std of the integrated error\n\n",
          opt.t_avg_s, opt.t_int_s);
  appendf(t, "%-28s %8s %14s %14s %14s %8s\n", "at t = T_int", "windows", "empirical",
          "predicted", "pred. (uncorr.)", "ratio");
  appendf(t, "%-28s %8zu %14.4e %14.4e %14.4e %8.3f\n", "simulated model", cov.sim_windows,
          cov.emp_sim[j_end], cov.pred_exact[j_end], cov.pred_uncorr[j_end],
          cov.emp_sim[j_end] / cov.pred_exact[j_end]);
  if (cov.data_windows > 0) {
    appendf(t, "%-28s %8zu %14.4e %14.4e %14.4e %8.3f\n", "data", cov.data_windows,
            cov.emp_data[j_end], cov.pred_exact[j_end], cov.pred_uncorr[j_end],
            cov.emp_data[j_end] / cov.pred_exact[j_end]);
    if (data.size() < n_samples) {
      appendf(t, "(data windows from the first %zu of the %zu samples: a bounded prefix)\n",
              data.size(), n_samples);
    }
  } else {
    appendf(t, "data: fewer samples than one window (%zu)\n", win);
  }
  appendf(t, "empirical = robust std (1.4826 MAD) over the windows; predicted = exact propagation\n"
             "of the model (averaging error and its correlation with the bias); pred. (uncorr.) =\n"
             "the example's prediction, which ignores that correlation. Integrated error unit: %s s.\n",
          unit);
  if (!in.node_text.empty()) {
    appendf(t, "\n== Firmware node: the model each channel runs and its residual monitors\n\n");
    t += in.node_text;
  }
  appendf(t, "\n== Frame statistics\n\n");
  for (const StatGroup& g : in.stats) {
    appendf(t, "%s:\n", g.name.c_str());
    std::string line = " ";
    for (const auto& kv : g.values) {
      std::string item = " " + kv.first + " " + fmt_stats_value(kv.second);
      if (line.size() + item.size() > 96) {
        t += line + "\n";
        line = " ";
      }
      line += item;
    }
    t += line + "\n";
  }
  appendf(t, "\n== Timing\n\n");
  for (const auto& tm : in.timing_s) {
    appendf(t, "  %-34s %8.3f s\n", tm.label.c_str(), tm.seconds);
  }
  appendf(t, "  %-34s %8.3f s\n", "model simulation + covariance check", rs.t_sim);
  for (const std::string& n : in.notes) {
    appendf(t, "\nnote: %s", n.c_str());
  }
  if (!in.notes.empty()) {
    t += "\n";
  }
}

// The figures' data as CSV files in opt.out_dir. False with err.
bool report_csvs(const ReportInput& in, const ReportOptions& opt, ReportState& rs,
                 std::string& err) {
  const double ts_s = rs.ts_s;
  const double tau_max_s = rs.tau_max_s;
  ModelParams& mp = rs.mp;
  std::vector<AdevRow>& sim_rows = rs.sim_rows;
  CovResult& cov = rs.cov;
  // ---- CSV -------------------------------------------------------------------------------
  const std::string& d = opt.out_dir;
  {
    std::string c = "tau_s,adev,ci_lo,ci_hi,edf,n_terms\n";
    for (const AdevRow& r : in.adev) {
      appendf(c, "%.10g,%.10g,%.10g,%.10g,%.6g,%llu\n", r.tau_s, r.adev, r.ci_lo, r.ci_hi, r.edf,
              static_cast<unsigned long long>(r.n_terms));
    }
    if (!write_file(d + "/fig1_adev_data.csv", c, err)) {
      return false;
    }
    c = "tau_s,adev,ci_lo,ci_hi,edf,n_terms\n";
    for (const AdevRow& r : sim_rows) {
      appendf(c, "%.10g,%.10g,%.10g,%.10g,%.6g,%llu\n", r.tau_s, r.adev, r.ci_lo, r.ci_hi, r.edf,
              static_cast<unsigned long long>(r.n_terms));
    }
    if (!write_file(d + "/fig1_adev_sim.csv", c, err)) {
      return false;
    }
    const Curve mc = model_curve(mp, ts_s, tau_max_s * 2.0);
    c = "tau_s";
    for (const TermInfo& t : kTermTable) {
      c += std::string(",") + t.name;
    }
    c += ",total\n";
    for (std::size_t i = 0; i < mc.tau_s.size(); ++i) {
      appendf(c, "%.10g", mc.tau_s[i]);
      for (const std::vector<double>& v : mc.term) {
        appendf(c, ",%.10g", v[i]);
      }
      appendf(c, ",%.10g\n", mc.total[i]);
    }
    if (!write_file(d + "/fig1_adev_model.csv", c, err)) {
      return false;
    }
    c = "t_s,empirical_sim,empirical_data,predicted_exact,predicted_uncorrelated\n";
    for (std::size_t j = 0; j < cov.n_int; ++j) {
      appendf(c, "%.6g,%.10g,%.10g,%.10g,%.10g\n", static_cast<double>(j + 1) * ts_s,
              cov.emp_sim[j], cov.data_windows > 0 ? cov.emp_data[j] : 0.0, cov.pred_exact[j],
              cov.pred_uncorr[j]);
    }
    if (!write_file(d + "/fig2_std.csv", c, err)) {
      return false;
    }
    // Trajectories: at most 100 per source, about 200 points each (the figure, not the
    // statistics, which use every window and every sample).
    const std::size_t step = std::max<std::size_t>(1, cov.n_int / 200);
    for (int src = 0; src < 2; ++src) {
      const std::vector<double>& tr = src == 0 ? cov.traj_sim : cov.traj_data;
      const std::size_t nw = std::min<std::size_t>(
          100, src == 0 ? cov.sim_windows : cov.data_windows);
      c = "t_s";
      for (std::size_t w = 0; w < nw; ++w) {
        appendf(c, ",w%zu", w);
      }
      c += "\n";
      for (std::size_t j = step - 1; j < cov.n_int; j += step) {
        appendf(c, "%.6g", static_cast<double>(j + 1) * ts_s);
        for (std::size_t w = 0; w < nw; ++w) {
          appendf(c, ",%.6g", tr[w * cov.n_int + j]);
        }
        c += "\n";
      }
      if (!write_file(d + (src == 0 ? "/fig2_traj_sim.csv" : "/fig2_traj_data.csv"), c, err)) {
        return false;
      }
    }
  }
  return true;
}

// Fig. 1's gnuplot script: the data's ADEV with its intervals, one dashed line per term of the
// model (a term absent from the model would be a curve without a single defined point, which
// gnuplot rejects), the model's total and the simulated model's ADEV. `here` starts it in the
// report's folder.
std::string fig1_script(const std::string& here, const char* unit, const std::string& title_chan,
                        const ModelParams& mp, bool simulated) {
  std::string g1 = here;
  appendf(g1,
          "set datafile separator ','\n"
          "set logscale xy\nset format y '10^{%%L}'\nset format x '10^{%%L}'\n"
          "set grid xtics ytics mxtics mytics lc rgb '#dddddd'\n"
          "set key bottom left box opaque\n"
          "set xlabel 'tau [s]'\nset ylabel 'Allan deviation [%s]'\n"
          "set title 'ADEV of %s: data (node telemetry, 68.3%% intervals), model, simulated "
          "model'\n"
          "plot 'fig1_adev_data.csv' skip 1 using 1:2:3:4 with yerrorbars pt 7 ps 0.6 "
          "lc rgb '#1f77b4' title 'data'",
          unit, title_chan.c_str());
  // Columns of fig1_adev_model.csv: tau, one per registry row, total.
  constexpr const char* kColors[kTermKinds] = {"#2ca02c", "#8c564b", "#ff7f0e", "#9467bd",
                                               "#e377c2", "#17becf", "#bcbd22", "#7f7f7f"};
  for (const TermInfo& row : kTermTable) {
    const std::size_t k = static_cast<std::size_t>(row.kind);
    if (term_instances(mp, row.kind) > 0) {
      appendf(g1,
              ", \\\n  'fig1_adev_model.csv' skip 1 using 1:($%zu>0?$%zu:1/0) with lines dt 2 "
              "lw 2 lc rgb '%s' title 'model: %s'",
              k + 2, k + 2, kColors[k], row.label);
    }
  }
  appendf(g1,
          ", \\\n  'fig1_adev_model.csv' skip 1 using 1:%zu with lines lw 2 lc rgb 'black' "
          "title 'model: total'",
          kTermKinds + 2);
  if (simulated) {
    g1 += ", \\\n  'fig1_adev_sim.csv' skip 1 using 1:2 with points pt 6 ps 0.8 lc rgb "
          "'#d62728' title 'simulated model'";
  }
  g1 += "\n";
  return g1;
}

// One panel of Fig. 2: `shown` of `windows` trajectories from `traj_csv`, the robust std of
// fig2_std.csv's column `std_col` and the predicted std (columns 4 and 5), each +-.
void fig2_panel(std::string& g2, const char* traj_csv, std::size_t shown, std::size_t std_col) {
  appendf(g2,
          "plot for [i=2:%zu] '%s' skip 1 using 1:i with lines lw 0.5 lc rgb '#c8c8c8' "
          "notitle, \\\n"
          "  'fig2_std.csv' skip 1 using 1:%zu with lines lw 2 lc rgb '#1f77b4' title 'robust "
          "std (1.4826 MAD)', '' skip 1 using 1:(-$%zu) with lines lw 2 lc rgb '#1f77b4' "
          "notitle, \\\n"
          "  '' skip 1 using 1:4 with lines lw 2 lc rgb 'black' title 'predicted std', '' "
          "skip 1 using 1:(-$4) with lines lw 2 lc rgb 'black' notitle, \\\n"
          "  '' skip 1 using 1:5 with lines dt 2 lw 1.5 lc rgb '#d62728' title 'predicted "
          "(uncorrelated)', '' skip 1 using 1:(-$5) with lines dt 2 lw 1.5 lc rgb '#d62728' "
          "notitle\n",
          shown + 1, traj_csv, std_col, std_col);
}

// Fig. 2's gnuplot script: the integrated error of the simulated model's windows and of the
// data's (when it has windows), against the predicted std.
std::string fig2_script(const std::string& here, const char* unit, const std::string& title_chan,
                        const CovResult& cov, double t_avg_s) {
  const std::size_t nw_sim = std::min<std::size_t>(100, cov.sim_windows);
  const std::size_t nw_data = std::min<std::size_t>(100, cov.data_windows);
  std::string g2 = here;
  appendf(g2,
          "set datafile separator ','\n"
          "set multiplot layout 2,1\n"
          "set grid lc rgb '#dddddd'\nset key top left box opaque\n"
          "set xlabel 't [s] after the %.4g s bias average'\nset ylabel 'integrated error [%s s]'\n"
          "set title 'Simulated model: %zu of %zu windows, robust std and predicted std'\n",
          t_avg_s, unit, nw_sim, cov.sim_windows);
  fig2_panel(g2, "fig2_traj_sim.csv", nw_sim, 2);
  if (nw_data > 0) {
    appendf(g2, "set title 'Data (%s): %zu of %zu windows, robust std and predicted std'\n",
            title_chan.c_str(), nw_data, cov.data_windows);
    fig2_panel(g2, "fig2_traj_data.csv", nw_data, 3);
  }
  g2 += "unset multiplot\n";
  return g2;
}

// The figures' SVG/PNG from the scripts in d (unless --no-plots, or no gnuplot: said in
// plot_note); the files written go to plot_files.
void render_plots(const ReportOptions& opt, std::string& plot_note,
                  std::vector<std::string>& plot_files) {
  const std::string& d = opt.out_dir;
  if (!opt.plots) {
    plot_note = "plots: skipped (--no-plots); gnuplot scripts fig1_adev.gp, fig2_covariance.gp";
    return;
  }
  if (!imu::cli::gnuplot_available()) {
    plot_note =
        "plots: gnuplot NOT FOUND, no SVG/PNG written (install gnuplot-nox: "
        "toolchains/install-deps.sh core); the CSV files and the gnuplot scripts are there";
    return;
  }
  bool ok = true;
  for (const char* base : {"fig1_adev", "fig2_covariance"}) {
    const std::string b = base;
    if (!imu::cli::gnuplot_render(d, b, b == "fig1_adev" ? 700 : 900)) {
      ok = false;
      appendf(plot_note, "plots: gnuplot failed on %s.gp (see %s.gnuplot.log)\n", b.c_str(),
              b.c_str());
    } else {
      for (const char* ext : {".svg", ".png"}) {
        plot_files.push_back(d);
        plot_files.back() += "/" + b + ext;
      }
    }
  }
  if (ok) {
    plot_note = "plots: fig1_adev.svg/.png (the example's Fig. 1), fig2_covariance.svg/.png "
                "(the example's Fig. 2)";
  }
}

// The gnuplot scripts, and their SVG/PNG unless --no-plots (or no gnuplot: said). False with
// err.
bool report_plots(const ReportInput& in, const ReportOptions& opt, ReportState& rs,
                  std::string& err) {
  const std::string& d = opt.out_dir;
  std::string title_chan;  // gnuplot enhanced text: '_' would start a subscript
  for (char ch : in.channel) {
    title_chan += ch == '_' ? std::string("\\_") : std::string(1, ch);
  }
  // The scripts run from any directory: they start in the report's folder (absolute).
  std::error_code ec;
  const std::string here =
      "cd " + imu::cli::gnuplot_str(std::filesystem::absolute(d, ec).lexically_normal().string()) +
      "\n";
  if (!write_file(d + "/fig1_adev.gp",
                  fig1_script(here, rs.unit, title_chan, rs.mp, !rs.sim_rows.empty()), err) ||
      !write_file(d + "/fig2_covariance.gp",
                  fig2_script(here, rs.unit, title_chan, rs.cov, opt.t_avg_s), err)) {
    return false;
  }
  render_plots(opt, rs.plot_note, rs.plot_files);
  appendf(rs.text, "\n%s\nfiles in %s: report.txt, %s, fig1_adev_{data,model,sim}.csv, "
                   "fig2_std.csv, fig2_traj_{sim,data}.csv\n",
          rs.plot_note.c_str(), d.c_str(), opt.json_path.c_str());
  return true;
}

// The JSON report.
std::string report_json(const ReportInput& in, const ReportOptions& opt, ReportState& rs) {
  const char* unit = rs.unit;
  const std::size_t n_samples = rs.n_samples;
  FitResult& fr = rs.fr;
  ModelParams& mp = rs.mp;
  FirstOrderGm& gm = rs.gm;
  bool& have_gm = rs.have_gm;
  std::string& model_origin = rs.model_origin;
  std::vector<AdevRow>& sim_rows = rs.sim_rows;
  CovResult& cov = rs.cov;
  std::vector<std::string>& plot_files = rs.plot_files;
  const std::size_t j_end = rs.cov.n_int - 1;
  // ---- JSON ------------------------------------------------------------------------------
  // One shape with adev's and analyze's (host_sim/cli/imu-sim.schema.json): the run's channel under "channels",
  // the bus, the node and the timings beside it.
  std::string j = "{\n" + imu::cli::json_head("run", in.source, "  ");
  j += "  \"channels\": {" + json_str(in.channel) + ": {\n";
  j += "  \"channel\": " + json_str(in.channel) + ",\n";
  j += "  \"unit\": " + json_str(unit) + ",\n";
  j += "  \"fs_hz\": " + json_num(in.fs_hz) + ",\n";
  j += "  \"lsb\": " + json_num(in.lsb) + ",\n";
  j += "  \"n_samples\": " + std::to_string(n_samples) + ",\n";
  j += "  \"adev_origin\": " + json_str(in.adev_origin) + ",\n";
  j += "  \"adev\": " + adev_json_list(in.adev) + ",\n";
  j += "  \"adev_simulated_model\": " + adev_json_list(sim_rows) + ",\n";
  j += "  \"units\": " + imu::cli::json_units(unit) + ",\n";
  j += "  \"model\": {\"origin\": " + json_str(model_origin) + ", \"n\": " + json_num(mp.n) +
       ", \"q\": " + json_num(mp.q) + ", \"k\": " + json_num(mp.k) + ", \"gm\": [";
  for (std::size_t i = 0; i < mp.n_gm; ++i) {
    j += (i == 0 ? "" : ", ") + std::string("{\"sb\": ") + json_num(mp.gm[i].sb) +
         ", \"tb_s\": " + json_num(mp.gm[i].tb_s) + "}";
  }
  j += "]";
  if (have_gm) {
    j += ",\n    \"example_layout\": {\"mu_per_s\": " + json_num(gm.mu_per_s) +
         ", \"sn\": " + json_num(gm.sn) + ", \"sw\": " + json_num(gm.sb) +
         ", \"pss_c\": " + json_num(gm.pss) + ", \"phi\": " + json_num(gm.phi) +
         ", \"qn\": " + json_num(gm.qn) + ", \"qw\": " + json_num(gm.qw) +
         ", \"pss_d\": " + json_num(gm.pss_d) + "}";
  }
  j += "},\n";
  j += "  \"fit\": {\"status\": " + std::to_string(static_cast<int>(fr.status)) +
       ", \"n\": " + json_num(fr.params.n) + ", \"q\": " + json_num(fr.params.q) +
       ", \"k\": " + json_num(fr.params.k) + ", \"gm\": [";
  for (std::size_t i = 0; i < fr.params.n_gm; ++i) {
    j += (i == 0 ? "" : ", ") + std::string("{\"sb\": ") + json_num(fr.params.gm[i].sb) +
         ", \"tb_s\": " + json_num(fr.params.gm[i].tb_s) + "}";
  }
  j += "], \"rms_rel\": " + json_num(fr.rms_rel) + ", \"n_points\": " +
       std::to_string(fr.n_points) + ", \"tb_at_bound\": " +
       (fr.tb_at_bound ? "true" : "false") + "},\n";
  j += "  \"covariance_check\": {\"t_avg_s\": " + json_num(opt.t_avg_s) +
       ", \"t_int_s\": " + json_num(opt.t_int_s) +
       ", \"sim_windows\": " + std::to_string(cov.sim_windows) +
       ", \"data_windows\": " + std::to_string(cov.data_windows) +
       ",\n    \"at_t_int\": {\"empirical_sim\": " + json_num(cov.emp_sim[j_end]) +
       ", \"empirical_data\": " +
       (cov.data_windows > 0 ? json_num(cov.emp_data[j_end]) : std::string("null")) +
       ", \"predicted\": " + json_num(cov.pred_exact[j_end]) +
       ", \"predicted_uncorrelated\": " + json_num(cov.pred_uncorr[j_end]) + "}}\n";
  j += "  }},\n";
  j += "  \"frame_stats\": {";
  for (std::size_t gi = 0; gi < in.stats.size(); ++gi) {
    j += (gi == 0 ? "\n" : ",\n") + std::string("    ") + json_str(in.stats[gi].key) + ": {";
    for (std::size_t k = 0; k < in.stats[gi].values.size(); ++k) {
      j += (k == 0 ? "" : ", ") + json_str(in.stats[gi].values[k].first) + ": " +
           json_num(in.stats[gi].values[k].second);
    }
    j += "}";
  }
  j += "\n  },\n";
  if (!in.node_json.empty()) {
    j += "  \"node\": " + in.node_json + ",\n";
  }
  j += "  \"notes\": [";
  for (std::size_t k = 0; k < in.notes.size(); ++k) {
    j += (k == 0 ? "" : ", ") + json_str(in.notes[k]);
  }
  j += "],\n";
  j += "  \"timing_s\": {";
  for (std::size_t k = 0; k < in.timing_s.size(); ++k) {
    j += (k == 0 ? "" : ", ") + json_str(in.timing_s[k].key) + ": " +
         json_num(in.timing_s[k].seconds);
  }
  j += "},\n  \"plots\": [";
  for (std::size_t k = 0; k < plot_files.size(); ++k) {
    j += (k == 0 ? "" : ", ") + json_str(plot_files[k]);
  }
  j += "]\n}\n";
  return j;
}

}  // namespace

bool write_report(const ReportInput& in, const ReportOptions& opt, std::string& text,
                  std::string& err) {
  if (!make_dirs(opt.out_dir, err)) {
    return false;
  }
  ReportState r;
  r.ts_s = 1.0 / in.fs_hz;
  r.unit = channel_unit(in.channel_index);
  r.n_samples = in.n_samples > 0 ? in.n_samples : in.data->size();
  for (const AdevRow& row : in.adev) {
    r.tau_max_s = std::max(r.tau_max_s, row.tau_s);
  }
  if (!report_model(in, opt, r, err) || !report_simulation(opt, r, err) ||
      !report_covariance(in, opt, r, err)) {
    return false;
  }
  report_text(in, opt, r);
  if (!report_csvs(in, opt, r, err) || !report_plots(in, opt, r, err)) {
    return false;
  }
  if (!write_file(opt.json_path, report_json(in, opt, r), err) ||
      !write_file(opt.out_dir + "/report.txt", r.text, err)) {
    return false;
  }
  text = r.text;
  return true;
}

}  // namespace imu::sim
