#pragma once
/// \file "mindist": interference between two convex polyhedra (contact paper, sec. 2.3).
///
/// Conventions (docs/contact_id.md):
/// - One contact point per pair of convex polyhedra in interference, one polyhedron from each object.
/// - Interference distance δ: the exact penetration depth, i.e. the length of the minimum translation
///   that separates the two solids. For convex polyhedra it is the smallest overlap of their
///   projections over the candidate axes: the face normals of both and the cross products of their
///   edge directions (separating-axis theorem). δ is continuous in the poses (a minimum of
///   continuous functions) and exact for vertex-face, edge-edge and face-face contact.
/// - Normal e_n: the minimizing axis, oriented as the direction in which the contact pushes
///   object 1 (the outward normal of object 2's polyhedron at the contact).
/// - Contact point p: the volume centroid of the intersection of the two solids (the interference
///   region), computed exactly by clipping. It is continuous in the poses, lies inside the
///   interference region and, e.g., is the centre of the pressed area (at half depth) for flat
///   face-face contact.
/// - Ties between axes are broken by a fixed order (faces of object 1, faces of object 2, edge
///   pairs), so the result is deterministic.
#include <vector>

#include <hil/contact_id/geometry.hpp>

namespace hil::contact_id {

/// The result for one pair: δ > 0 when the solids interfere.
struct PairContact {
  double delta = 0.0;
  Vec3 point = Vec3::Zero();    ///< world
  Vec3 normal = Vec3::UnitZ();  ///< world, direction of the normal force on object 1
};

/// Reusable buffers for clipping (no allocation once warmed up).
struct ClipWorkspace {
  std::vector<Vec3> pts[2];
  std::vector<int> start[2];
  std::vector<Vec3> cap;
  std::vector<double> dist;
};

/// Penetration of `a` (object 1) and `b` (object 2). Returns false when they do not interfere
/// (δ <= 0); `out` is then untouched.
bool penetration(const PosedPolyhedron& a, const PosedPolyhedron& b, PairContact& out, ClipWorkspace& ws);

/// Volume and centroid of the intersection of two convex polyhedra (0 volume if disjoint).
double intersection_centroid(const PosedPolyhedron& a, const PosedPolyhedron& b, Vec3& centroid, ClipWorkspace& ws);

/// A lower bound on the distance between two polyhedra: the largest projection gap over the
/// separating-axis candidates (<= 0 when they interfere). Moving either by less than this keeps
/// them apart.
double separation_lower_bound(const PosedPolyhedron& a, const PosedPolyhedron& b);
/// The same with an early exit: returns as soon as the bound found exceeds `stop_above` (the value
/// returned is then a valid but possibly smaller lower bound, > stop_above); otherwise the full bound.
double separation_lower_bound(const PosedPolyhedron& a, const PosedPolyhedron& b, double stop_above);

/// `penetration` and `separation_lower_bound` in one separating-axis pass: true with `out` filled
/// (as `penetration`) when the solids interfere; otherwise false with `gap` >= 0 the lower bound on
/// their distance (as `separation_lower_bound(a, b, stop_above)`, same early exit; a negative
/// `stop_above` counts as 0).
bool penetration_or_gap(const PosedPolyhedron& a, const PosedPolyhedron& b, double stop_above, PairContact& out, double& gap,
                        ClipWorkspace& ws);

/// What a separating-axis pass found about a pair, so that the pair can be evaluated again after a
/// small rigid motion of either polyhedron without a new axis search (a solver's finite
/// differences move one feature by nanometres or microradians). Candidates are numbered in the
/// pass order: 2 k for +axis k, 2 k + 1 for -axis k.
struct SatRecord {
  static constexpr int kWatch = 8;
  double gap = 0.0;     ///< >= 0: apart, a lower bound on their distance; < 0: interfering
  double best = 0.0;    ///< interfering: the smallest push (δ)
  int best_index = -1;  ///< its candidate
  /// The other candidates that could come lowest after the motion (evaluated again)...
  int watch[kWatch] = {};
  int watched = 0;
  double second_still = 0.0;  ///< ...and the smallest push of all the rest (bound under translations)
  /// ...less the most a turn up to max_turn_rad can take off (bound under turns: each candidate's
  /// turn rate times max_turn_rad times the lever r_a + r_b + |c_a - c_b|)
  double second_turning = 0.0;
  double max_turn_rad = 0.0;
};

/// `near(a, b) && penetration(a, b, out, ws)`, recording the pass for rotations up to max_turn_rad.
bool penetration_recorded(const PosedPolyhedron& a, const PosedPolyhedron& b, double max_turn_rad, PairContact& out, SatRecord& record,
                          ClipWorkspace& ws);

/// `near(a, b) && penetration(a, b, out, ws)` for a pair recorded before a rigid motion of one of
/// them that moved no vertex more than moved_m and turned it by at most turn_rad. When the record
/// proves that the same axis still gives the smallest push, only that axis is evaluated (the
/// result is the full pass's); when it proves the pair still apart, nothing is; else a full pass.
bool penetration_after_motion(const PosedPolyhedron& a, const PosedPolyhedron& b, const SatRecord& record, double moved_m, double turn_rad,
                              PairContact& out, ClipWorkspace& ws);

/// Broad phase (bounding spheres, then world boxes): may the two polyhedra be closer than `margin`?
inline bool near(const PosedPolyhedron& a, const PosedPolyhedron& b, double margin = 0.0) {
  const double r = a.radius + b.radius + margin;
  if ((a.center - b.center).squaredNorm() > r * r) return false;
  return (a.lo.array() <= b.hi.array() + margin).all() && (b.lo.array() <= a.hi.array() + margin).all();
}

}  // namespace hil::contact_id
