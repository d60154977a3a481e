#include <hil/calibration/reduction.hpp>

#include <Eigen/Cholesky>
#include <Eigen/Jacobi>
#include <Eigen/LU>
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
/// Coupled groups from L (rank x |G3|): columns sharing a row with an entry above l_tolerance · max|L|
/// are coupled; a group's rank is the number of rows it holds. With `margin` > 1, every entry must
/// lie clearly on one side of the threshold (below it / margin or above it · margin), else no groups
/// are returned (the caller's verification fails).
std::vector<CoupledGroup> groups_of(const Eigen::MatrixXd& L, const std::vector<int>& g3, double l_tolerance, double margin) {
  const Eigen::Index r = L.rows(), n = L.cols();
  const double lmax = L.cwiseAbs().maxCoeff();
  const double t = l_tolerance * lmax;
  UnionFind uf(static_cast<std::size_t>(n));
  std::vector<int> row_root(static_cast<std::size_t>(r), -1);
  for (Eigen::Index i = 0; i < r; ++i) {
    int first = -1;
    for (Eigen::Index j = 0; j < n; ++j) {
      const double a = std::abs(L(i, j));
      if (margin > 0.0 && !(a * margin < t) && !(a > t * margin)) return {};
      if (a <= t) continue;
      if (first < 0) first = static_cast<int>(j);
      else uf.unite(first, static_cast<int>(j));
    }
    row_root[static_cast<std::size_t>(i)] = first;
  }
  std::map<int, CoupledGroup> groups;
  for (Eigen::Index j = 0; j < n; ++j) groups[uf.find(static_cast<int>(j))].cols.push_back(g3[static_cast<std::size_t>(j)]);
  for (Eigen::Index i = 0; i < r; ++i)
    if (row_root[static_cast<std::size_t>(i)] >= 0) ++groups[uf.find(row_root[static_cast<std::size_t>(i)])].rank;
  std::vector<CoupledGroup> out;
  for (auto& [root, g] : groups) out.push_back(g);
  std::sort(out.begin(), out.end(), [](const CoupledGroup& a, const CoupledGroup& b) { return a.cols.front() < b.cols.front(); });
  return out;
}
}  // namespace

Splitting m5a_split(const CompressedSystem& sys, const std::vector<int>& g3, const AlgebraicOptions& options) {
  Splitting out;
  if (g3.empty()) return out;
  const Eigen::MatrixXd M = scaled_columns(sys, g3);
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
  out.groups = groups_of(out.L, g3, options.l_tolerance, 0.0);
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

std::vector<double> priorities_of(const VjmModel& model, const ParameterSet& base, const PipelineOptions& options) {
  std::vector<double> priority(base.size());
  for (std::size_t i = 0; i < base.size(); ++i) {
    const auto it = options.priorities.find(base[i].name);
    priority[i] = it != options.priorities.end() ? it->second : default_priority(model, base[i]);
  }
  return priority;
}

/// The fixed columns of M4b (G2, at zero) and M5c (at their given values, else zero), in the order
/// both the full reduction and its re-verification list them.
void fix_m4b_m5c(const std::vector<int>& g2, const std::vector<int>& m5c, const ParameterSet& base, const PipelineOptions& options,
                 std::vector<int>& cols, std::vector<double>& values, std::vector<std::string>& steps) {
  for (int g : g2) {
    cols.push_back(g);
    values.push_back(0.0);
    steps.push_back("M4b");
  }
  for (int f : m5c) {
    cols.push_back(f);
    const auto it = options.fixed_values.find(base[static_cast<std::size_t>(f)].name);
    values.push_back(it != options.fixed_values.end() ? it->second : 0.0);
    steps.push_back("M5c");
  }
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
  const std::vector<double> priority = priorities_of(model, base, options);
  const Selection sel = m5bc_select(c, r.splitting, priority, options.algebraic);
  std::vector<int>& free_cols = r.free_cols;
  free_cols = r.partition.g1;
  free_cols.insert(free_cols.end(), sel.identifiable.begin(), sel.identifiable.end());
  std::sort(free_cols.begin(), free_cols.end());
  std::vector<int>& fixed_cols = r.fixed_cols;
  std::vector<double>& fixed_vals = r.fixed_values;
  std::vector<std::string>& fixed_steps = r.fixed_steps;
  fix_m4b_m5c(r.partition.g2, sel.fixed, base, options, fixed_cols, fixed_vals, fixed_steps);
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

namespace {

// Re-verification of a cached reduction (reverify_algebraic). A decision of the full reduction
// compares a computed quantity with a threshold; the verification recomputes the quantity by a
// cheaper route (or bounds it) and accepts only when it lies clearly on the cached side: by a factor
// kStructuralMargin for the rank, partition and coupling thresholds (their quantities sit at rounding
// level or at O(1), many orders from the thresholds), by kPnrMargin (relative) for the M6 comparisons
// (continuous statistics, computed to about ε·cond). Both routes are backward stable, so inside these
// margins the full reduction takes the same decisions.
constexpr double kStructuralMargin = 2.0;
constexpr double kPnrMargin = 1e-6;

bool clearly_below(double x, double t) { return x * kStructuralMargin < t; }
bool clearly_above(double x, double t) { return x > t * kStructuralMargin; }

/// Column norms of L⁻¹ B for a lower-triangular factor L.
Eigen::VectorXd solved_column_norms(const Eigen::MatrixXd& Lfac, const Eigen::MatrixXd& B) {
  return Lfac.triangularView<Eigen::Lower>().solve(B).colwise().norm().transpose();
}

/// Orthonormal basis, column by column (classical Gram-Schmidt, twice).
struct Basis {
  Eigen::MatrixXd Q;
  Eigen::Index k = 0;
  explicit Basis(Eigen::Index rows, Eigen::Index cap) : Q(rows, cap) {}
  /// v minus its projection; two passes keep a basis being built orthonormal, one suffices for a norm.
  Eigen::VectorXd residual(const Eigen::VectorXd& v, int passes = 2) const {
    Eigen::VectorXd r = v;
    for (int pass = 0; pass < passes; ++pass)
      if (k > 0) r -= Q.leftCols(k) * (Q.leftCols(k).transpose() * r);
    return r;
  }
  void push(const Eigen::VectorXd& r) { Q.col(k++) = r / r.norm(); }
};

}  // namespace

bool reverify_algebraic(const VjmModel& model, const CompressedSystem& c, const ParameterSet& base, const std::vector<int>& cols,
                        const PipelineOptions& options, const AlgebraicResult& previous, AlgebraicResult& out) {
  const AlgebraicOptions& ao = options.algebraic;
  const double tol = ao.rank.tolerance;
  const double vt = ao.v_tolerance;
  const Partition& part = previous.partition;
  if (cols.empty() || base.size() != static_cast<std::size_t>(c.R.cols())) return false;
  // Cached structure: the M5 output B (G1 and the selected G3 columns) = kept + M6 columns.
  std::vector<int> m6;
  for (std::size_t i = 0; i < previous.fixed_cols.size(); ++i)
    if (previous.fixed_steps[i] == "M6") m6.push_back(previous.fixed_cols[i]);
  std::vector<int> free_alg = previous.free_cols;
  free_alg.insert(free_alg.end(), m6.begin(), m6.end());
  std::sort(free_alg.begin(), free_alg.end());
  const auto r = static_cast<Eigen::Index>(free_alg.size());
  if (r == 0 || r != part.rank || previous.rank_algebraic != r) return false;
  std::vector<int> pos(base.size(), -1);  // column of the system -> position in cols
  for (std::size_t i = 0; i < cols.size(); ++i) pos[static_cast<std::size_t>(cols[i])] = static_cast<int>(i);
  for (int f : free_alg)
    if (f < 0 || static_cast<std::size_t>(f) >= base.size() || pos[static_cast<std::size_t>(f)] < 0) return false;

  // M = R restricted to cols, unit columns (zero columns: clearly below kZeroColumn · largest).
  const auto n = static_cast<Eigen::Index>(cols.size());
  const Eigen::Index m = c.R.rows();
  if (m < r) return false;
  double largest = 0.0;
  for (int col : cols) largest = std::max(largest, c.R.col(col).norm());
  for (int col : cols) {
    const double nrm = c.R.col(col).norm();
    if (!clearly_below(nrm, kZeroColumn * largest) && !clearly_above(nrm, kZeroColumn * largest)) return false;
  }
  const Eigen::MatrixXd M = scaled_columns(c, cols);

  // B = free_alg (independent), N = the rest. QR of M_B; X: coordinates of M_N in M_B; E: remainder.
  std::vector<char> in_b(static_cast<std::size_t>(n), 0);
  std::vector<Eigen::Index> bpos, npos;
  for (int f : free_alg) in_b[static_cast<std::size_t>(pos[static_cast<std::size_t>(f)])] = 1;
  for (Eigen::Index i = 0; i < n; ++i) (in_b[static_cast<std::size_t>(i)] ? bpos : npos).push_back(i);
  const auto nn = static_cast<Eigen::Index>(npos.size());
  Eigen::MatrixXd MB(m, r), MN(m, nn);
  for (Eigen::Index k = 0; k < r; ++k) MB.col(k) = M.col(bpos[static_cast<std::size_t>(k)]);
  for (Eigen::Index k = 0; k < nn; ++k) MN.col(k) = M.col(npos[static_cast<std::size_t>(k)]);
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(MB);
  Eigen::MatrixXd QtN = MN;
  QtN.applyOnTheLeft(qr.householderQ().adjoint());
  const Eigen::MatrixXd T = qr.matrixQR().topLeftCorner(r, r).triangularView<Eigen::Upper>();
  const Eigen::MatrixXd Tinv = T.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(r, r));
  const double s_lo = 1.0 / Tinv.norm();  // ≤ σ_min(M_B) ≤ σ_min of any subset of B
  const Eigen::MatrixXd X = Tinv * QtN.topRows(r);
  const Eigen::MatrixXd E = QtN.bottomRows(m - r);

  // M4a rank: σ_r(M) ≥ σ_min(M_B) and σ_{r+1}(M) ≤ ‖E‖_F; σ_1(M) ∈ [‖M‖_F / √min(m, n), ‖M‖_F].
  const double fro = M.norm();
  if (!clearly_above(s_lo, tol * fro)) return false;
  if (!clearly_below(E.norm(), tol * fro / std::sqrt(static_cast<double>(std::min(m, n))))) return false;

  // M4a partition from the projectors: null space spanned by [-X; I], row space by [I; Xᵀ] (B, N order);
  // the squared row norms of V's null and range parts are their diagonals.
  Eigen::VectorXd null_part = Eigen::VectorXd::Zero(n), range_part = Eigen::VectorXd::Ones(n);
  if (nn > 0) {
    const Eigen::LLT<Eigen::MatrixXd> kn(Eigen::MatrixXd::Identity(nn, nn) + X.transpose() * X);
    const Eigen::LLT<Eigen::MatrixXd> kr(Eigen::MatrixXd::Identity(r, r) + X * X.transpose());
    if (kn.info() != Eigen::Success || kr.info() != Eigen::Success) return false;
    const Eigen::MatrixXd Ln = kn.matrixL(), Lr = kr.matrixL();
    const Eigen::VectorXd nb = solved_column_norms(Ln, X.transpose());
    const Eigen::VectorXd nnn = solved_column_norms(Ln, Eigen::MatrixXd::Identity(nn, nn));
    const Eigen::VectorXd rb = solved_column_norms(Lr, Eigen::MatrixXd::Identity(r, r));
    const Eigen::VectorXd rn = solved_column_norms(Lr, X);
    for (Eigen::Index k = 0; k < r; ++k) {
      null_part[bpos[static_cast<std::size_t>(k)]] = nb[k];
      range_part[bpos[static_cast<std::size_t>(k)]] = rb[k];
    }
    for (Eigen::Index k = 0; k < nn; ++k) {
      null_part[npos[static_cast<std::size_t>(k)]] = nnn[k];
      range_part[npos[static_cast<std::size_t>(k)]] = rn[k];
    }
  }
  Partition p;
  p.rank = static_cast<int>(r);
  for (Eigen::Index i = 0; i < n; ++i) {
    const int col = cols[static_cast<std::size_t>(i)];
    if (clearly_below(null_part[i], vt)) p.g1.push_back(col);
    else if (!clearly_above(null_part[i], vt)) return false;
    else if (clearly_below(range_part[i], vt)) p.g2.push_back(col);
    else if (!clearly_above(range_part[i], vt)) return false;
    else p.g3.push_back(col);
  }
  if (p.g1 != part.g1 || p.g2 != part.g2 || p.g3 != part.g3) return false;

  // M5a: S = the selected G3 columns span G3. Rank: σ_min(M_S) ≥ s_lo; a G3 column outside S lies
  // within ‖E_j‖ + ‖M_G1‖_F ‖X_G1,j‖ of span(M_S).
  std::vector<int> bidx_of(static_cast<std::size_t>(n), -1), nidx_of(static_cast<std::size_t>(n), -1);
  for (Eigen::Index k = 0; k < r; ++k) bidx_of[static_cast<std::size_t>(bpos[static_cast<std::size_t>(k)])] = static_cast<int>(k);
  for (Eigen::Index k = 0; k < nn; ++k) nidx_of[static_cast<std::size_t>(npos[static_cast<std::size_t>(k)])] = static_cast<int>(k);
  const std::set<int> g1set(p.g1.begin(), p.g1.end());
  std::vector<int> s_rows, g1_rows;  // rows of X
  for (Eigen::Index k = 0; k < r; ++k)
    (g1set.count(cols[static_cast<std::size_t>(bpos[static_cast<std::size_t>(k)])]) ? g1_rows : s_rows).push_back(static_cast<int>(k));
  const auto r3 = static_cast<Eigen::Index>(s_rows.size());
  const auto n3 = static_cast<Eigen::Index>(p.g3.size());
  Splitting split;
  split.rank = static_cast<int>(r3);
  if (r3 != previous.splitting.rank) return false;
  if (n3 > 0 && r3 > 0) {
    double g3_fro_sq = 0.0, off_sq = 0.0;
    const double g1_fro = std::sqrt(static_cast<double>(g1_rows.size()));
    Eigen::MatrixXd W(r3, n3);  // [I, X_S] over G3: its row space is that of M_G3
    for (Eigen::Index j = 0; j < n3; ++j) {
      const int i = pos[static_cast<std::size_t>(p.g3[static_cast<std::size_t>(j)])];
      g3_fro_sq += M.col(i).squaredNorm();
      const int b = bidx_of[static_cast<std::size_t>(i)];
      if (b >= 0) {
        W.col(j).setZero();
        W(std::find(s_rows.begin(), s_rows.end(), b) - s_rows.begin(), j) = 1.0;
      } else {
        const int k = nidx_of[static_cast<std::size_t>(i)];
        for (Eigen::Index q = 0; q < r3; ++q) W(q, j) = X(s_rows[static_cast<std::size_t>(q)], k);
        double xg1 = 0.0;
        for (int q : g1_rows) xg1 += X(q, k) * X(q, k);
        const double d = E.col(k).norm() + g1_fro * std::sqrt(xg1);
        off_sq += d * d;
      }
    }
    const double g3_fro = std::sqrt(g3_fro_sq);
    if (!clearly_above(s_lo, tol * g3_fro)) return false;
    if (!clearly_below(std::sqrt(off_sq), tol * g3_fro / std::sqrt(static_cast<double>(std::min(m, n3))))) return false;
    // An orthonormal basis of that row space stands in for V_rᵀ: the column-pivoted QR's pivots
    // depend only on the row space (largest remaining column norm at each step, replayed here) and
    // L = V_r*⁻¹ V_rᵀ only on the pivots. Near-ties in the pivoting (this robot has G3 columns that
    // are exact multiples of each other) are broken by rounding here as in the full run, which is
    // harmless: the coupled groups are the connected components of the column matroid of M_G3, the
    // same whichever basis L is written in, and every entry of L must be clear of the threshold.
    const Eigen::HouseholderQR<Eigen::MatrixXd> wq(W.transpose());
    const Eigen::MatrixXd VrT = (wq.householderQ() * Eigen::MatrixXd::Identity(n3, r3)).transpose();
    Eigen::MatrixXd rest = VrT;
    Eigen::VectorXd norms = rest.colwise().squaredNorm().transpose();
    Eigen::VectorXd workspace(n3);
    std::vector<char> used(static_cast<std::size_t>(n3), 0);
    Eigen::MatrixXd Vstar(r3, r3);
    for (Eigen::Index k = 0; k < r3; ++k) {
      Eigen::Index best = -1;
      double b1 = -1.0;
      for (Eigen::Index j = 0; j < n3; ++j)
        if (!used[static_cast<std::size_t>(j)] && norms[j] > b1) {
          b1 = norms[j];
          best = j;
        }
      if (best < 0 || !(b1 > 0.0)) return false;
      used[static_cast<std::size_t>(best)] = 1;
      Vstar.col(k) = VrT.col(best);
      // Householder step on the remaining columns, as in the pivoted QR.
      const Eigen::Index len = r3 - k;
      Eigen::VectorXd essential(len > 1 ? len - 1 : 0);
      double tau = 0.0, beta = 0.0;
      rest.col(best).tail(len).makeHouseholder(essential, tau, beta);
      rest.bottomRows(len).applyHouseholderOnTheLeft(essential, tau, workspace.data());
      norms = rest.bottomRows(len - 1).colwise().squaredNorm().transpose();
    }
    split.L = Vstar.partialPivLu().solve(VrT);
    split.groups = groups_of(split.L, p.g3, ao.l_tolerance, kStructuralMargin);
    if (split.groups.empty()) return false;
  } else if (n3 > 0 || r3 > 0) {
    return false;
  }
  if (split.groups.size() != previous.splitting.groups.size()) return false;
  for (std::size_t g = 0; g < split.groups.size(); ++g)
    if (split.groups[g].cols != previous.splitting.groups[g].cols || split.groups[g].rank != previous.splitting.groups[g].rank)
      return false;

  // M5b: the greedy choice per group, replayed. A kept column joins a subset of B: the trial is full
  // rank (σ_min ≥ s_lo, σ_max ≤ √size); a fixed one lies within its residual of the span of those chosen
  // before it (σ_min ≤ residual, σ_max ≥ 1).
  const std::vector<double> priority = priorities_of(model, base, options);
  const std::set<int> kept(free_alg.begin(), free_alg.end());
  Selection sel;
  for (const CoupledGroup& g : split.groups) {
    std::vector<int> order = g.cols;
    std::stable_sort(order.begin(), order.end(),
                     [&](int a, int b) { return priority[static_cast<std::size_t>(a)] > priority[static_cast<std::size_t>(b)]; });
    Basis chosen(m, g.rank);
    for (int col : order) {
      if (chosen.k == g.rank) {
        sel.fixed.push_back(col);
        continue;
      }
      const Eigen::VectorXd v = M.col(pos[static_cast<std::size_t>(col)]);
      if (kept.count(col)) {
        if (!clearly_above(s_lo, tol * std::sqrt(static_cast<double>(chosen.k + 1)))) return false;
        chosen.push(chosen.residual(v));
        sel.identifiable.push_back(col);
      } else {
        if (!clearly_below(chosen.residual(v, 1).norm(), tol)) return false;
        sel.fixed.push_back(col);
      }
    }
  }
  std::sort(sel.identifiable.begin(), sel.identifiable.end());
  std::sort(sel.fixed.begin(), sel.fixed.end());
  std::vector<int> free_cols = p.g1;
  free_cols.insert(free_cols.end(), sel.identifiable.begin(), sel.identifiable.end());
  std::sort(free_cols.begin(), free_cols.end());
  if (free_cols != free_alg) return false;
  std::vector<int> fixed_cols;
  std::vector<double> fixed_vals;
  std::vector<std::string> fixed_steps;
  fix_m4b_m5c(p.g2, sel.fixed, base, options, fixed_cols, fixed_vals, fixed_steps);

  // M6 is not taken from the cache (its order changes with almost every measurement) but run again
  // on a QR of [M_free | rhs] (pnr is invariant to the column scaling), columns leaving it by Givens
  // rotations: each lowest pnr must be clearly below the threshold and clearly the lowest, the last
  // one clearly above. Every subset of B is full rank (see above), as the full loop requires.
  if (options.neglect_below > 0.0) {
    Eigen::VectorXd rhs = c.z;
    for (std::size_t i = 0; i < fixed_cols.size(); ++i) rhs.noalias() -= c.R.col(fixed_cols[i]) * fixed_vals[i];
    const Eigen::Index k0 = r;
    Eigen::MatrixXd A(m, k0 + 1);
    for (Eigen::Index k = 0; k < k0; ++k) A.col(k) = M.col(pos[static_cast<std::size_t>(free_cols[static_cast<std::size_t>(k)])]);
    A.col(k0) = rhs;
    const Eigen::HouseholderQR<Eigen::MatrixXd> aq(A);
    Eigen::MatrixXd Tf = aq.matrixQR().topLeftCorner(k0, k0).triangularView<Eigen::Upper>();
    Eigen::VectorXd y = aq.matrixQR().col(k0).head(k0);
    std::vector<int> fr = free_cols;
    const double thr = options.neglect_below;
    while (!fr.empty()) {
      const auto k = static_cast<Eigen::Index>(fr.size());
      const Eigen::MatrixXd Ti = Tf.topLeftCorner(k, k).triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(k, k));
      const Eigen::VectorXd x = Ti * y.head(k);
      Eigen::Index worst = 0;
      double lowest = std::numeric_limits<double>::infinity(), second = lowest;
      for (Eigen::Index i = 0; i < k; ++i) {
        const double pnr = std::abs(x[i]) / Ti.row(i).norm();
        if (pnr < lowest) {
          second = lowest;
          lowest = pnr;
          worst = i;
        } else if (pnr < second) second = pnr;
      }
      if (!(std::abs(lowest - thr) > kPnrMargin * thr)) return false;
      if (!(lowest < thr)) break;
      if (!(second > lowest * (1.0 + kPnrMargin))) return false;
      // Drop column `worst`: shift left and restore the triangle with Givens rotations.
      for (Eigen::Index j = worst; j + 1 < k; ++j) Tf.col(j).head(k) = Tf.col(j + 1).head(k);
      for (Eigen::Index j = worst; j + 1 < k; ++j) {
        Eigen::JacobiRotation<double> g;
        g.makeGivens(Tf(j, j), Tf(j + 1, j));
        Tf.block(0, j, k, k - 1 - j).applyOnTheLeft(j, j + 1, g.adjoint());
        y.applyOnTheLeft(j, j + 1, g.adjoint());
        Tf(j + 1, j) = 0.0;
      }
      fixed_cols.push_back(fr[static_cast<std::size_t>(worst)]);
      fixed_vals.push_back(0.0);
      fixed_steps.push_back("M6");
      fr.erase(fr.begin() + worst);
    }
    free_cols = fr;
  } else if (!m6.empty()) {
    return false;
  }

  out = AlgebraicResult{};
  out.partition = std::move(p);
  out.splitting = std::move(split);
  out.rank_algebraic = static_cast<int>(r);
  out.solution = solve(c, free_cols, fixed_cols,
                       Eigen::Map<const Eigen::VectorXd>(fixed_vals.data(), static_cast<Eigen::Index>(fixed_vals.size())), ao.rank);
  if (!out.solution.full_rank) return false;
  out.free_cols = std::move(free_cols);
  out.fixed_cols = std::move(fixed_cols);
  out.fixed_values = std::move(fixed_vals);
  out.fixed_steps = std::move(fixed_steps);
  return true;
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
