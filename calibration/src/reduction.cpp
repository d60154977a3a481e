#include <hil/calibration/reduction.hpp>

#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <tuple>
#include <limits>
#include <numeric>
#include <set>
#include <stdexcept>

namespace hil::calibration {

Template beam_template() {
  Template t = Template::Zero();
  for (int i = 0; i < 6; ++i) t(i, i) = true;
  t(1, 5) = t(5, 1) = true;  // y force - z moment
  t(2, 4) = t(4, 2) = true;  // z force - y moment
  return t;
}

Template full_template() { return Template::Constant(true); }

ParameterSet m1_symmetrise(const ParameterSet& set) {
  ParameterSet out;
  std::set<std::tuple<int, int, int>> seen;
  for (const Parameter& p : set) {
    Parameter s = p;
    if (p.row != p.col) {
      s.row = std::min(p.row, p.col);
      s.col = std::max(p.row, p.col);
      s.symmetric = true;
      s.name = p.name.substr(0, p.name.find(".k") + 2) + std::to_string(s.row + 1) + std::to_string(s.col + 1);
    }
    if (seen.insert({s.spring, s.row, s.col}).second) out.push_back(s);
  }
  return out;
}

ParameterSet m2_sparsify(const VjmModel& model, const ParameterSet& set, const std::map<int, Template>& templates) {
  ParameterSet out;
  const Template beam = beam_template();
  for (const Parameter& p : set) {
    const Spring& s = model.springs()[static_cast<std::size_t>(p.spring)];
    if (s.kind == SpringKind::link) {
      const auto it = templates.find(s.index);
      const Template& t = it != templates.end() ? it->second : beam;
      if (!t(p.row, p.col) || !t(p.col, p.row)) continue;
    }
    out.push_back(p);
  }
  return out;
}

ParameterSet m3_aggregate(const VjmModel& model, const ParameterSet& set) {
  std::set<int> compliant_links;
  for (const Parameter& p : set)
    if (model.springs()[static_cast<std::size_t>(p.spring)].kind == SpringKind::link)
      compliant_links.insert(model.springs()[static_cast<std::size_t>(p.spring)].index);
  ParameterSet out;
  for (const Parameter& p : set) {
    const Spring& s = model.springs()[static_cast<std::size_t>(p.spring)];
    if (s.kind == SpringKind::joint && compliant_links.count(s.index - 1)) continue;
    out.push_back(p);
  }
  return out;
}

Partition m4a_partition(const CompressedSystem& sys, const std::vector<int>& cols, const AlgebraicOptions& options) {
  Partition out;
  if (cols.empty()) return out;
  const Eigen::MatrixXd M = scaled_columns(sys, cols);
  const auto n = static_cast<Eigen::Index>(cols.size());
  // Full V is needed for the null space; pad M with zero rows when it has fewer rows than columns.
  Eigen::MatrixXd Msq = Eigen::MatrixXd::Zero(std::max(M.rows(), n), n);
  Msq.topRows(M.rows()) = M;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(Msq, Eigen::ComputeFullV);
  out.singular_values = svd.singularValues();
  const Eigen::VectorXd& sv = out.singular_values;
  int r = 0;
  if (sv.size() && sv[0] > 0.0)
    for (Eigen::Index i = 0; i < sv.size(); ++i)
      if (sv[i] > options.rank.tolerance * sv[0]) ++r;
  out.rank = r;
  const Eigen::MatrixXd& V = svd.matrixV();
  for (Eigen::Index i = 0; i < n; ++i) {
    const double null_part = r < n ? V.row(i).tail(n - r).norm() : 0.0;
    const double range_part = r > 0 ? V.row(i).head(r).norm() : 0.0;
    const int c = cols[static_cast<std::size_t>(i)];
    if (null_part < options.v_tolerance) out.g1.push_back(c);        // rule 1
    else if (range_part < options.v_tolerance) out.g2.push_back(c);  // rule 2
    else out.g3.push_back(c);                                        // rule 3
  }
  return out;
}

std::vector<int> m4b_eliminate(const std::vector<int>& cols, const Partition& partition) {
  const std::set<int> g2(partition.g2.begin(), partition.g2.end());
  std::vector<int> out;
  for (int c : cols)
    if (!g2.count(c)) out.push_back(c);
  return out;
}

namespace {
struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[static_cast<std::size_t>(x)] != x)
      x = parent[static_cast<std::size_t>(x)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(x)])];
    return x;
  }
  void unite(int a, int b) { parent[static_cast<std::size_t>(find(a))] = find(b); }
};
}  // namespace

Splitting m5a_split(const CompressedSystem& sys, const std::vector<int>& g3, const AlgebraicOptions& options) {
  Splitting out;
  if (g3.empty()) return out;
  const Eigen::MatrixXd M = scaled_columns(sys, g3);
  const auto n = static_cast<Eigen::Index>(g3.size());
  Eigen::BDCSVD<Eigen::MatrixXd> svd(M, Eigen::ComputeThinV);
  const Eigen::VectorXd& sv = svd.singularValues();
  int r = 0;
  if (sv.size() && sv[0] > 0.0)
    for (Eigen::Index i = 0; i < sv.size(); ++i)
      if (sv[i] > options.rank.tolerance * sv[0]) ++r;
  out.rank = r;
  if (r == 0) return out;
  // V_rᵀ (r x n); V_r* = r well-conditioned columns of it (column-pivoted QR); L = V_r*⁻¹ V_rᵀ.
  const Eigen::MatrixXd VrT = svd.matrixV().leftCols(r).transpose();
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(VrT);
  Eigen::MatrixXd Vstar(r, r);
  for (int k = 0; k < r; ++k) Vstar.col(k) = VrT.col(qr.colsPermutation().indices()[k]);
  out.L = Vstar.partialPivLu().solve(VrT);
  const double lmax = out.L.cwiseAbs().maxCoeff();
  UnionFind uf(static_cast<std::size_t>(n));
  std::vector<int> row_root(static_cast<std::size_t>(r), -1);
  for (Eigen::Index i = 0; i < r; ++i) {
    int first = -1;
    for (Eigen::Index j = 0; j < n; ++j) {
      if (std::abs(out.L(i, j)) <= options.l_tolerance * lmax) continue;
      if (first < 0) first = static_cast<int>(j);
      else uf.unite(first, static_cast<int>(j));
    }
    row_root[static_cast<std::size_t>(i)] = first;
  }
  std::map<int, CoupledGroup> groups;
  for (Eigen::Index j = 0; j < n; ++j) groups[uf.find(static_cast<int>(j))].cols.push_back(g3[static_cast<std::size_t>(j)]);
  for (Eigen::Index i = 0; i < r; ++i)
    if (row_root[static_cast<std::size_t>(i)] >= 0) ++groups[uf.find(row_root[static_cast<std::size_t>(i)])].rank;
  for (auto& [root, g] : groups) out.groups.push_back(g);
  std::sort(out.groups.begin(), out.groups.end(),
            [](const CoupledGroup& a, const CoupledGroup& b) { return a.cols.front() < b.cols.front(); });
  return out;
}

Selection m5bc_select(const CompressedSystem& sys, const Splitting& split, const std::vector<double>& priority,
                      const AlgebraicOptions& options) {
  Selection out;
  for (const CoupledGroup& g : split.groups) {
    std::vector<int> order = g.cols;
    std::stable_sort(order.begin(), order.end(),
                     [&](int a, int b) { return priority[static_cast<std::size_t>(a)] > priority[static_cast<std::size_t>(b)]; });
    std::vector<int> chosen;
    for (int c : order) {
      if (static_cast<int>(chosen.size()) == g.rank) {
        out.fixed.push_back(c);
        continue;
      }
      std::vector<int> trial = chosen;
      trial.push_back(c);
      if (rank_of(sys, trial, options.rank) == static_cast<int>(trial.size())) chosen.push_back(c);
      else out.fixed.push_back(c);
    }
    out.identifiable.insert(out.identifiable.end(), chosen.begin(), chosen.end());
  }
  std::sort(out.identifiable.begin(), out.identifiable.end());
  std::sort(out.fixed.begin(), out.fixed.end());
  return out;
}

double default_priority(const VjmModel& model, const Parameter& p) {
  if (model.springs()[static_cast<std::size_t>(p.spring)].kind == SpringKind::joint) return 3.0;
  return p.diagonal() ? 2.0 : 1.0;
}

ParameterSet physical_reduction(const VjmModel& model, const PipelineOptions& options, std::vector<ReductionLine>& lines) {
  ParameterSet set = complete_parameters(model);
  const int n = model.dof();
  lines.push_back({"complete", std::to_string(n) + " joints + " + std::to_string(n + 1) + " links (36 par. each)",
                   static_cast<int>(set.size()), -1});
  if (options.symmetrise) {
    set = m1_symmetrise(set);
    lines.push_back({"M1", "symmetrisation: 21 par. per link", static_cast<int>(set.size()), -1});
  }
  if (options.sparsify) {
    set = m2_sparsify(model, set, options.templates);
    lines.push_back({"M2", options.templates.empty() ? "sparsing: beam template (eq. 12) per link" : "sparsing: beam and user templates",
                     static_cast<int>(set.size()), -1});
  }
  if (options.aggregate) {
    const std::size_t before = set.size();
    set = m3_aggregate(model, set);
    lines.push_back({"M3", "aggregation: " + std::to_string(before - set.size()) + " joint springs into the preceding links",
                     static_cast<int>(set.size()), -1});
  }
  return set;
}

namespace {

std::string fmt_double(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

std::vector<int> iota_cols(std::size_t n) {
  std::vector<int> c(n);
  std::iota(c.begin(), c.end(), 0);
  return c;
}

/// Unweighted per-axis residual RMS of a solution on the full system.
void residual_stats(const WeightedSystem& sys, const Eigen::VectorXd& all_values, CalibrationResult& out) {
  const Eigen::VectorXd r_w = sys.t_w - sys.A_w * all_values;
  std::array<double, 6> ss{};
  out.residual_rows.fill(0);
  for (Eigen::Index i = 0; i < r_w.size(); ++i) {
    const auto a = static_cast<std::size_t>(sys.axis[static_cast<std::size_t>(i)]);
    const double r = r_w[i] * sys.sigma[i];
    ss[a] += r * r;
    ++out.residual_rows[a];
  }
  for (std::size_t a = 0; a < 6; ++a)
    out.residual_rms[a] = out.residual_rows[a] ? std::sqrt(ss[a] / out.residual_rows[a]) : std::numeric_limits<double>::quiet_NaN();
}

/// Noise per group (position rows, rotation rows) from the residuals of a first, unweighted fit.
NoiseModel estimate_noise(const VjmModel& model, const ParameterSet& set, const std::vector<Measurement>& data, const NoiseModel& given,
                          const RankOptions& rank) {
  const NoiseModel unit{1.0, 1.0};
  const WeightedSystem sys = build_system(model, set, data, unit);
  const CompressedSystem c = compress(sys.A_w, sys.t_w);
  const LsqSolution s = solve(c, rank);
  const Eigen::VectorXd r = sys.t_w - sys.A_w * s.value;
  double ss[2] = {0.0, 0.0};
  double cnt[2] = {0.0, 0.0};
  for (Eigen::Index i = 0; i < r.size(); ++i) {
    const int g = sys.axis[static_cast<std::size_t>(i)] < 3 ? 0 : 1;
    ss[g] += r[i] * r[i];
    cnt[g] += 1.0;
  }
  const double m = static_cast<double>(r.size());
  const double keep = std::max(1e-3, 1.0 - static_cast<double>(s.rank) / m);  // share of dof left per row
  NoiseModel out = given;
  const double floor = 1e-15;
  if (!(out.position_m > 0.0)) out.position_m = cnt[0] > 0 ? std::max(floor, std::sqrt(ss[0] / (cnt[0] * keep))) : 1.0;
  if (!(out.rotation_rad > 0.0)) out.rotation_rad = cnt[1] > 0 ? std::max(floor, std::sqrt(ss[1] / (cnt[1] * keep))) : 1.0;
  return out;
}

bool needs_noise_estimate(const std::vector<Measurement>& data, const NoiseModel& noise) {
  bool pos = false, rot = false;
  for (const auto& d : data) {
    pos = true;
    rot = rot || d.kind == MeasurementKind::pose6;
  }
  return (pos && !(noise.position_m > 0.0)) || (rot && !(noise.rotation_rad > 0.0));
}

void fill_outputs(const VjmModel& model, const ParameterSet& base, const WeightedSystem& sys, const std::vector<int>& free_cols,
                  const std::vector<int>& fixed_cols, const Eigen::VectorXd& fixed_values, const std::vector<std::string>& fixed_steps,
                  const PnrThresholds& pnr, CalibrationResult& out) {
  const LsqSolution& s = out.solution;
  Eigen::VectorXd all = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(base.size()));
  out.kept.clear();
  for (std::size_t i = 0; i < free_cols.size(); ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    KeptParameter kp;
    kp.parameter = base[static_cast<std::size_t>(free_cols[i])];
    kp.value = s.value[k];
    kp.std_dev = s.std_dev.size() ? s.std_dev[k] : std::numeric_limits<double>::quiet_NaN();
    kp.ci95_low = kp.value - 1.959963984540054 * kp.std_dev;
    kp.ci95_high = kp.value + 1.959963984540054 * kp.std_dev;
    kp.pnr = std::abs(kp.value) / kp.std_dev;
    kp.cls = classify(kp.pnr, pnr);
    out.kept.push_back(kp);
    all[free_cols[i]] = kp.value;
  }
  out.fixed.clear();
  for (std::size_t i = 0; i < fixed_cols.size(); ++i) {
    out.fixed.push_back({base[static_cast<std::size_t>(fixed_cols[i])], fixed_values[static_cast<Eigen::Index>(i)], fixed_steps[i]});
    all[fixed_cols[i]] = fixed_values[static_cast<Eigen::Index>(i)];
  }
  residual_stats(sys, all, out);
  out.compliance = assemble(model, base, all);
  out.spd = check_spd(model, out.compliance);
}

}  // namespace

AlgebraicResult reduce_algebraic(const VjmModel& model, const CompressedSystem& c, const ParameterSet& base,
                                 const std::vector<int>& phys_cols, const PipelineOptions& options, std::vector<ReductionLine>* lines) {
  AlgebraicResult r;
  // M4
  r.partition = m4a_partition(c, phys_cols, options.algebraic);
  if (lines)
    lines->push_back({"M4a",
                      "partitioning: G1 " + std::to_string(r.partition.g1.size()) + ", G2 " + std::to_string(r.partition.g2.size()) +
                          ", G3 " + std::to_string(r.partition.g3.size()),
                      static_cast<int>(phys_cols.size()), r.partition.rank});
  const std::vector<int> after_m4 = m4b_eliminate(phys_cols, r.partition);
  if (lines)
    lines->push_back({"M4b", "elimination of G2", static_cast<int>(after_m4.size()), rank_of(c, after_m4, options.algebraic.rank)});

  // M5
  r.splitting = m5a_split(c, r.partition.g3, options.algebraic);
  std::string groups_text;
  for (const auto& g : r.splitting.groups) {
    if (g.cols.size() < 2) continue;
    if (!groups_text.empty()) groups_text += ", ";
    groups_text += std::to_string(g.rank) + " of " + std::to_string(g.cols.size());
  }
  if (lines)
    lines->push_back({"M5a",
                      "splitting G3 into " + std::to_string(r.splitting.groups.size()) + " coupled groups (keep " +
                          (groups_text.empty() ? std::string("-") : groups_text) + ")",
                      static_cast<int>(after_m4.size()), -1});
  std::vector<double> priority(base.size());
  for (std::size_t i = 0; i < base.size(); ++i) {
    const auto it = options.priorities.find(base[i].name);
    priority[i] = it != options.priorities.end() ? it->second : default_priority(model, base[i]);
  }
  const Selection sel = m5bc_select(c, r.splitting, priority, options.algebraic);
  std::vector<int>& free_cols = r.free_cols;
  free_cols = r.partition.g1;
  free_cols.insert(free_cols.end(), sel.identifiable.begin(), sel.identifiable.end());
  std::sort(free_cols.begin(), free_cols.end());
  std::vector<int>& fixed_cols = r.fixed_cols;
  std::vector<double>& fixed_vals = r.fixed_values;
  std::vector<std::string>& fixed_steps = r.fixed_steps;
  for (int g2 : r.partition.g2) {
    fixed_cols.push_back(g2);
    fixed_vals.push_back(0.0);
    fixed_steps.push_back("M4b");
  }
  for (int f : sel.fixed) {
    fixed_cols.push_back(f);
    const auto it = options.fixed_values.find(base[static_cast<std::size_t>(f)].name);
    fixed_vals.push_back(it != options.fixed_values.end() ? it->second : 0.0);
    fixed_steps.push_back("M5c");
  }
  r.rank_algebraic = rank_of(c, free_cols, options.algebraic.rank);
  if (lines)
    lines->push_back({"M5b/c", "selection and assigning: " + std::to_string(sel.fixed.size()) + " fixed",
                      static_cast<int>(free_cols.size()), r.rank_algebraic});

  // M6: neglect, one at a time, the parameter with the lowest parameter-to-noise ratio below the threshold.
  auto solve_now = [&] {
    return solve(c, free_cols, fixed_cols,
                 Eigen::Map<const Eigen::VectorXd>(fixed_vals.data(), static_cast<Eigen::Index>(fixed_vals.size())),
                 options.algebraic.rank);
  };
  LsqSolution s = solve_now();
  int neglected = 0;
  while (options.neglect_below > 0.0 && s.full_rank && !free_cols.empty()) {
    Eigen::Index worst = 0;
    const Eigen::VectorXd pnr = s.value.cwiseAbs().cwiseQuotient(s.std_dev);
    const double lowest = pnr.minCoeff(&worst);
    if (!(lowest < options.neglect_below)) break;
    fixed_cols.push_back(free_cols[static_cast<std::size_t>(worst)]);
    fixed_vals.push_back(0.0);
    fixed_steps.push_back("M6");
    free_cols.erase(free_cols.begin() + worst);
    ++neglected;
    s = solve_now();
  }
  if (options.neglect_below > 0.0 && lines)
    lines->push_back({"M6", "neglecting: " + std::to_string(neglected) + " with pnr < " + fmt_double(options.neglect_below),
                      static_cast<int>(free_cols.size()), s.rank});
  r.solution = std::move(s);
  return r;
}

CalibrationResult calibrate(const VjmModel& model, const std::vector<Measurement>& data, const NoiseModel& noise_in,
                            const PipelineOptions& options) {
  if (data.empty()) throw std::invalid_argument("no measurements");
  CalibrationResult out;
  out.measurements = data.size();
  // Physical reduction; the data matrix is built for the set before M3 (a superset of the M3 set),
  // so that the ranks of both are known from one factorisation.
  PipelineOptions pre = options;
  pre.aggregate = false;
  std::vector<ReductionLine> lines;
  const ParameterSet before_m3 = physical_reduction(model, pre, lines);
  const ParameterSet physical = options.aggregate ? m3_aggregate(model, before_m3) : before_m3;
  if (options.aggregate)
    lines.push_back({"M3", "aggregation: " + std::to_string(before_m3.size() - physical.size()) + " joint springs into the preceding links",
                     static_cast<int>(physical.size()), -1});

  out.noise = noise_in;
  if (needs_noise_estimate(data, noise_in)) {
    out.noise = estimate_noise(model, physical, data, noise_in, options.algebraic.rank);
    out.noise_estimated = true;
  }
  const WeightedSystem sys = build_system(model, before_m3, data, out.noise);
  out.equations = sys.A_w.rows();
  const CompressedSystem c = compress(sys.A_w, sys.t_w);

  if (options.complete_ranks) {
    const ParameterSet complete = complete_parameters(model);
    const WeightedSystem s0 = build_system(model, complete, data, out.noise);
    lines[0].rank = rank_of(compress(s0.A_w, s0.t_w), iota_cols(complete.size()), options.algebraic.rank);
    if (options.symmetrise && lines.size() > 1 && lines[1].step == "M1") {
      const ParameterSet s1 = m1_symmetrise(complete);
      const WeightedSystem w1 = build_system(model, s1, data, out.noise);
      lines[1].rank = rank_of(compress(w1.A_w, w1.t_w), iota_cols(s1.size()), options.algebraic.rank);
    }
  }
  // Columns of the physical set inside the factorised (pre-M3) set.
  std::vector<int> phys_cols;
  for (const Parameter& p : physical) phys_cols.push_back(find_parameter(before_m3, p.name));
  out.rank_physical = rank_of(c, phys_cols, options.algebraic.rank);
  if (options.aggregate) {
    lines[lines.size() - 2].rank = rank_of(c, iota_cols(before_m3.size()), options.algebraic.rank);
  }
  lines.back().rank = out.rank_physical;
  out.physical = physical;

  out.physical = physical;
  out.base = before_m3;
  AlgebraicResult a = reduce_algebraic(model, c, before_m3, phys_cols, options, &lines);
  out.partition = std::move(a.partition);
  out.splitting = std::move(a.splitting);
  out.rank_algebraic = a.rank_algebraic;
  out.solution = std::move(a.solution);
  out.rank_final = out.solution.rank;
  const std::vector<int>& free_cols = a.free_cols;
  const std::vector<int>& fixed_cols = a.fixed_cols;
  const std::vector<double>& fixed_vals = a.fixed_values;
  const std::vector<std::string>& fixed_steps = a.fixed_steps;
  out.reduction = lines;
  fill_outputs(model, before_m3, sys, free_cols, fixed_cols,
               Eigen::Map<const Eigen::VectorXd>(fixed_vals.data(), static_cast<Eigen::Index>(fixed_vals.size())), fixed_steps, options.pnr,
               out);
  return out;
}

CalibrationResult identify_fixed_set(const VjmModel& model, const ParameterSet& set, const std::vector<Measurement>& data,
                                     const NoiseModel& noise, const PnrThresholds& pnr, const RankOptions& rank) {
  if (data.empty()) throw std::invalid_argument("no measurements");
  CalibrationResult out;
  out.measurements = data.size();
  out.noise = noise;
  if (needs_noise_estimate(data, noise)) {
    out.noise = estimate_noise(model, set, data, noise, rank);
    out.noise_estimated = true;
  }
  const WeightedSystem sys = build_system(model, set, data, out.noise);
  out.equations = sys.A_w.rows();
  const CompressedSystem c = compress(sys.A_w, sys.t_w);
  const std::vector<int> cols = iota_cols(set.size());
  out.physical = set;
  out.base = set;
  out.solution = solve(c, cols, {}, Eigen::VectorXd(), rank);
  out.rank_physical = out.rank_algebraic = out.rank_final = out.solution.rank;
  out.reduction.push_back({"given", "parameter set as given", static_cast<int>(set.size()), out.solution.rank});
  fill_outputs(model, set, sys, cols, {}, Eigen::VectorXd(), {}, pnr, out);
  return out;
}

const std::vector<PaperTableRow>& paper_table1() {
  static const std::vector<PaperTableRow> rows = {
      {"complete", "6 joints + 7 links (36 par. each)", "258"},
      {"M1", "6 joints + 7 links (21 par. each)", "153"},
      {"M2", "6 joints + 7 links (8 par. each)", "62"},
      {"M3", "7 links (8 par. each)", "56"},
      {"M4a", "G1 4, G2 4, G3 48", "56"},
      {"M4b", "elimination of G2", "52"},
      {"M5a", "28 par. in one group of 48 semi-identifiable", "52"},
      {"M5b/c", "selection and assigning", "32"},
      {"M6", "neglecting (depends on M5)", "25-30"},
  };
  return rows;
}

std::string paper_count(const std::string& step) {
  for (const auto& row : paper_table1())
    if (step == row.step) return row.count;
  return "";
}

}  // namespace hil::calibration
