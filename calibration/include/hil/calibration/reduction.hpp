#pragma once
/// \file Model reduction M1-M6 (paper sections IV-VI) and the calibration pipeline.
///
/// Physical steps need no data: M1 symmetrisation, M2 sparsing by a template, M3 aggregation of
/// joint springs into the preceding link. Algebraic steps work on the compressed weighted system of
/// the physically reduced set: M4a partition into G1/G2/G3 by SVD, M4b elimination of G2, M5a
/// splitting of G3 into coupled groups (L = V_r*⁻¹ V_rᵀ in block-diagonal form), M5b/M5c selection of
/// rank-many parameters per group by user priority and fixing of the others. The statistical step
/// M6 neglects parameters whose parameter-to-noise ratio stays below a threshold.
#include <array>
#include <map>
#include <string>
#include <vector>

#include <hil/calibration/identification.hpp>
#include <hil/calibration/observation.hpp>

namespace hil::calibration {

/// One line of the reduction table.
struct ReductionLine {
  std::string step;  ///< "complete", "M1", "M2", ...
  std::string description;
  int count = 0;  ///< parameters left after the step
  int rank = -1;  ///< rank of A for that set (-1: not computed)
};

/// Which entries of a link's 6x6 compliance (in its spring frame) may be non-zero.
using Template = Eigen::Matrix<bool, 6, 6>;
/// The beam template of eq. 12 for a link along the frame's x axis: the diagonal, the couplings
/// (y force, z moment) = entries 2-6 and (z force, y moment) = 3-5: 8 parameters once symmetric.
Template beam_template();
/// Every entry allowed.
Template full_template();

/// M1: one parameter per symmetric pair of link entries (36 → 21 per link).
ParameterSet m1_symmetrise(const ParameterSet& set);
/// M2: keeps link entries allowed by the link's template (`templates` by link index, else beam_template()).
ParameterSet m2_sparsify(const VjmModel& model, const ParameterSet& set, const std::map<int, Template>& templates = {});
/// M3: drops the compliance of every joint preceded by a compliant link (a link spring with at least
/// one parameter in the set); it is carried by that link's rotation (revolute) or translation
/// (prismatic) entry about the joint axis (see aggregate_joints).
ParameterSet m3_aggregate(const VjmModel& model, const ParameterSet& set);

struct AlgebraicOptions {
  RankOptions rank;
  double v_tolerance = 1e-7;  ///< a row of V counts as zero below this norm (rules 1 and 2)
  double l_tolerance = 1e-8;  ///< an entry of L counts as zero below this (relative to max |L|)
};

/// M4a: G1 identifiable (row of the null-space basis zero), G2 non-identifiable (row of the
/// range basis zero), G3 semi-identifiable. Entries are column indices of the compressed system.
struct Partition {
  std::vector<int> g1, g2, g3;
  int rank = 0;
  Eigen::VectorXd singular_values;
};
Partition m4a_partition(const CompressedSystem& sys, const std::vector<int>& cols, const AlgebraicOptions& options = {});
/// M4b: cols without G2.
std::vector<int> m4b_eliminate(const std::vector<int>& cols, const Partition& partition);

/// M5a: coupled groups of G3; each group's rank is the number of its parameters to keep.
struct CoupledGroup {
  std::vector<int> cols;
  int rank = 0;
};
struct Splitting {
  std::vector<CoupledGroup> groups;
  Eigen::MatrixXd L;  ///< rank x |G3|, identity on the pivot columns
  int rank = 0;
};
Splitting m5a_split(const CompressedSystem& sys, const std::vector<int>& g3, const AlgebraicOptions& options = {});

/// M5b/M5c: in each group, the highest-priority parameters that raise the rank are kept (ties:
/// column order); the rest are fixed. `priority` is indexed by column.
struct Selection {
  std::vector<int> identifiable;
  std::vector<int> fixed;
};
Selection m5bc_select(const CompressedSystem& sys, const Splitting& split, const std::vector<double>& priority,
                      const AlgebraicOptions& options = {});

/// Default priority of a parameter for M5b: joint springs 3, link diagonal entries 2, couplings 1.
double default_priority(const VjmModel& model, const Parameter& p);

/// Options of the whole pipeline.
struct PipelineOptions {
  bool symmetrise = true;
  bool sparsify = true;
  bool aggregate = true;
  std::map<int, Template> templates;           ///< M2 user templates by link index
  std::map<std::string, double> priorities;    ///< M5b, by parameter name (default_priority otherwise)
  std::map<std::string, double> fixed_values;  ///< M5c constants by parameter name (default 0)
  AlgebraicOptions algebraic;
  PnrThresholds pnr;
  double neglect_below = 2.0;   ///< M6 threshold on the parameter-to-noise ratio; 0 disables M6
  bool complete_ranks = false;  ///< also compute the rank of the complete and M1 models (costly)
};

/// The physically reduced set and the table lines of the steps run.
ParameterSet physical_reduction(const VjmModel& model, const PipelineOptions& options, std::vector<ReductionLine>& lines);

struct KeptParameter {
  Parameter parameter;
  double value = 0.0;
  double std_dev = 0.0;
  double ci95_low = 0.0, ci95_high = 0.0;  ///< value ∓ 1.96 σ
  double pnr = 0.0;
  PnrClass cls = PnrClass::g1_minus;
};
struct FixedParameter {
  Parameter parameter;
  double value = 0.0;
  std::string step;  ///< "M4b" (non-identifiable), "M5c" (assigned), "M6" (neglected)
};

/// Everything the `identify` report shows.
struct CalibrationResult {
  std::vector<ReductionLine> reduction;
  Partition partition;  ///< on the M3 set (column indices into `physical`)
  Splitting splitting;
  ParameterSet physical;  ///< the set after M1-M3
  ParameterSet base;      ///< the factorised set (before M3): column indices refer to it
  std::vector<KeptParameter> kept;
  std::vector<FixedParameter> fixed;
  int rank_physical = 0;   ///< rank of A for the physical set
  int rank_algebraic = 0;  ///< rank of A for the M5 output (= its dimension when complete)
  int rank_final = 0;      ///< after M6
  LsqSolution solution;    ///< of the final set
  NoiseModel noise;        ///< used for the weights
  bool noise_estimated = false;
  std::array<double, 6> residual_rms{};  ///< per axis dx dy dz rx ry rz (m, rad); NaN where nothing measured
  std::array<int, 6> residual_rows{};
  ComplianceSet compliance;  ///< identified + fixed values, per spring
  std::vector<SpdCheck> spd;
  std::size_t measurements = 0;
  Eigen::Index equations = 0;
};

/// M4-M6 on a compressed system whose columns are `base`; `cols` (the physical set) are reduced.
struct AlgebraicResult {
  Partition partition;
  Splitting splitting;
  int rank_algebraic = 0;
  std::vector<int> free_cols;   ///< kept (identified) columns
  std::vector<int> fixed_cols;  ///< G2, M5c and M6 columns
  std::vector<double> fixed_values;
  std::vector<std::string> fixed_steps;
  LsqSolution solution;  ///< of free_cols with the others fixed
};
AlgebraicResult reduce_algebraic(const VjmModel& model, const CompressedSystem& sys, const ParameterSet& base, const std::vector<int>& cols,
                                 const PipelineOptions& options, std::vector<ReductionLine>* lines = nullptr);

/// Re-verifies a cached reduce_algebraic result on a changed system (e.g. after more rows were
/// rotated into R): every decision of M4a (rank, G1/G2/G3), M5a (rank of G3, coupled groups and
/// their ranks), M5b (each kept/fixed choice) and M6 (each neglected parameter, in order, and the
/// stop) is recomputed from one QR of the kept columns instead of the SVDs, and must agree with
/// `previous` with a clear margin from its threshold. Returns false when any decision differs or is
/// too close to call: the caller then runs reduce_algebraic. On true, `out` holds what
/// reduce_algebraic would return (same columns and steps; the final solve is the same call, so the
/// same values), except `partition.singular_values` (empty) and `splitting.L` (the same matrix up to
/// rounding, from an equivalent basis).
bool reverify_algebraic(const VjmModel& model, const CompressedSystem& sys, const ParameterSet& base, const std::vector<int>& cols,
                        const PipelineOptions& options, const AlgebraicResult& previous, AlgebraicResult& out);

/// Runs M1-M6 and the final identification. A noise entry ≤ 0 is estimated from the residuals of
/// a first fit of the physical set. \throws std::invalid_argument on bad input.
CalibrationResult calibrate(const VjmModel& model, const std::vector<Measurement>& data, const NoiseModel& noise,
                            const PipelineOptions& options = {});

/// Identifies a given parameter set (no reduction), e.g. a joint-only model.
CalibrationResult identify_fixed_set(const VjmModel& model, const ParameterSet& set, const std::vector<Measurement>& data,
                                     const NoiseModel& noise, const PnrThresholds& pnr = {}, const RankOptions& rank = {});

/// Table I of the paper (KUKA KR-270): counts per step, for the side-by-side print.
struct PaperTableRow {
  const char* step;
  const char* description;
  const char* count;
};
const std::vector<PaperTableRow>& paper_table1();
/// Table I's count for a reduction step (e.g. "M4b"), or "" for a step the paper does not list.
std::string paper_count(const std::string& step);

}  // namespace hil::calibration
