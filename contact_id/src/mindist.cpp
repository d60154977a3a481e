#include <hil/contact_id/mindist.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace hil::contact_id {

namespace {

constexpr double kParallel = 1e-6;  // |e_a × e_b| below this: parallel edges

inline void project(const std::vector<Vec3>& v, const Vec3& u, double& lo, double& hi) {
  lo = std::numeric_limits<double>::infinity();
  hi = -lo;
  for (const auto& p : v) {
    const double s = u.dot(p);
    lo = std::min(lo, s);
    hi = std::max(hi, s);
  }
}

/// A monotone substitute for atan2(y, x) on (-π, π], with values in (-2, 2] ("diamond angle").
inline double pseudo_angle(double y, double x) {
  const double l = std::abs(x) + std::abs(y);
  if (!(l > 0.0)) return 0.0;
  const double t = x / l;
  return y >= 0.0 ? 1.0 - t : t - 1.0;
}

/// Clips the polytope (pts/start of `in`) by {x : n.x <= d} into `out`.
/// `sd` holds the signed distances n.p - d of the points of `ip`.
void clip(const std::vector<Vec3>& ip, const std::vector<int>& is, const std::vector<double>& sd, std::vector<Vec3>& op,
          std::vector<int>& os, std::vector<Vec3>& cap, const Vec3& n, double tol) {
  op.clear();
  os.clear();
  cap.clear();
  const int faces = static_cast<int>(is.size()) - 1;
  for (int f = 0; f < faces; ++f) {
    const int b = is[static_cast<std::size_t>(f)], e = is[static_cast<std::size_t>(f) + 1];
    const int first = static_cast<int>(op.size());
    for (int i = b; i < e; ++i) {
      const auto iq = static_cast<std::size_t>(i + 1 < e ? i + 1 : b);
      const Vec3& P = ip[static_cast<std::size_t>(i)];
      const Vec3& Q = ip[iq];
      const double sp = sd[static_cast<std::size_t>(i)], sq = sd[iq];
      if (sp <= 0.0) op.push_back(P);
      if ((sp < 0.0 && sq > 0.0) || (sp > 0.0 && sq < 0.0)) {
        const Vec3 X = P + (sp / (sp - sq)) * (Q - P);
        op.push_back(X);
        cap.push_back(X);
      } else if (sp <= 0.0 && std::abs(sp) <= tol) {
        cap.push_back(P);
      }
    }
    if (static_cast<int>(op.size()) - first < 3) {
      op.resize(static_cast<std::size_t>(first));
    } else {
      os.push_back(first);
    }
  }
  // The cap polygon on the clipping plane.
  if (cap.size() >= 3) {
    // Remove duplicates.
    std::size_t m = 0;
    for (std::size_t i = 0; i < cap.size(); ++i) {
      bool dup = false;
      for (std::size_t j = 0; j < m && !dup; ++j) dup = (cap[i] - cap[j]).squaredNorm() <= tol * tol;
      if (!dup) cap[m++] = cap[i];
    }
    cap.resize(m);
    if (m >= 3) {
      Vec3 c = Vec3::Zero();
      for (const auto& p : cap) c += p;
      c /= static_cast<double>(m);
      const Vec3 a = (std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).cross(n).normalized();
      const Vec3 bb = n.cross(a);
      // Order by angle about c. The pseudo-angle is a monotone function of atan2 (same order, no
      // transcendental call inside the comparator).
      std::sort(cap.begin(), cap.end(), [&](const Vec3& p, const Vec3& q) {
        return pseudo_angle((p - c).dot(bb), (p - c).dot(a)) < pseudo_angle((q - c).dot(bb), (q - c).dot(a));
      });
      os.push_back(static_cast<int>(op.size()));
      op.insert(op.end(), cap.begin(), cap.end());
    }
  }
  os.push_back(static_cast<int>(op.size()));
}

}  // namespace

double intersection_centroid(const PosedPolyhedron& a, const PosedPolyhedron& b, Vec3& centroid, ClipWorkspace& ws) {
  auto* P = &ws.pts[0];
  auto* S = &ws.start[0];
  auto* P2 = &ws.pts[1];
  auto* S2 = &ws.start[1];
  P->clear();
  S->clear();
  for (const auto& f : a.shape->faces()) {
    S->push_back(static_cast<int>(P->size()));
    for (int i : f.loop) P->push_back(a.vertices[static_cast<std::size_t>(i)]);
  }
  S->push_back(static_cast<int>(P->size()));
  const double tol = 1e-12 * (a.radius + b.radius);
  auto& sd = ws.dist;
  for (std::size_t k = 0; k < b.normals.size(); ++k) {
    const Vec3& n = b.normals[k];
    const double d = b.offsets[k];
    sd.resize(P->size());
    bool all_in = true;
    for (std::size_t i = 0; i < P->size(); ++i) {
      sd[i] = n.dot((*P)[i]) - d;
      all_in = all_in && sd[i] <= 0.0;
    }
    if (all_in) continue;
    clip(*P, *S, sd, *P2, *S2, ws.cap, n, tol);
    std::swap(P, P2);
    std::swap(S, S2);
    if (S->size() < 2) break;
  }
  if (P->empty() || S->size() < 2) return 0.0;
  Vec3 c0 = Vec3::Zero();
  for (const auto& p : *P) c0 += p;
  c0 /= static_cast<double>(P->size());
  double vol = 0.0;
  Vec3 m = Vec3::Zero();
  for (std::size_t f = 0; f + 1 < S->size(); ++f) {
    const int s = (*S)[f], e = (*S)[f + 1];
    const Vec3& v0 = (*P)[static_cast<std::size_t>(s)];
    for (int i = s + 1; i + 1 < e; ++i) {
      const Vec3& v1 = (*P)[static_cast<std::size_t>(i)];
      const Vec3& v2 = (*P)[static_cast<std::size_t>(i + 1)];
      const double dv = std::abs((v0 - c0).dot((v1 - c0).cross(v2 - c0))) / 6.0;
      vol += dv;
      m += dv * (c0 + v0 + v1 + v2) / 4.0;
    }
  }
  centroid = vol > 0.0 ? Vec3(m / vol) : c0;
  return vol;
}

namespace {

/// Keeps, during a pass, what a SatRecord needs: the best candidate, the kWatch others most at
/// risk under a turn (smallest push - turn allowance), and bounds on the rest.
class PassRecorder {
 public:
  explicit PassRecorder(double allowance) : allowance_(allowance) {}
  void add(double push, double turn, int index) {
    if (push < best_) {
      best_ = push;
      best_index_ = index;
    }
    const double key = push - turn * allowance_;
    if (n_ == kKeep && key >= keys_[kKeep - 1]) {
      evict(key, push);
      return;
    }
    if (n_ == kKeep) evict(keys_[kKeep - 1], pushes_[kKeep - 1]);
    int i = n_ < kKeep ? n_++ : kKeep - 1;
    for (; i > 0 && keys_[i - 1] > key; --i) {
      keys_[i] = keys_[i - 1];
      pushes_[i] = pushes_[i - 1];
      index_[i] = index_[i - 1];
    }
    keys_[i] = key;
    pushes_[i] = push;
    index_[i] = index;
  }
  void finish(SatRecord& r, bool unsafe) {
    r.best = best_;
    r.best_index = best_index_;
    r.watched = 0;
    for (int i = 0; i < n_; ++i) {
      if (index_[i] == best_index_) continue;
      if (r.watched == SatRecord::kWatch) {  // the best was not kept: the last kept joins the rest
        evict(keys_[i], pushes_[i]);
        continue;
      }
      r.watch[r.watched++] = index_[i];
    }
    r.second_still = rest_push_;
    // A pair of edges that may cross the parallel threshold changes the set of candidates.
    r.second_turning = unsafe ? -std::numeric_limits<double>::infinity() : rest_key_;
  }

 private:
  void evict(double key, double push) {
    rest_key_ = std::min(rest_key_, key);
    rest_push_ = std::min(rest_push_, push);
  }
  static constexpr int kKeep = SatRecord::kWatch + 1;
  double allowance_;
  double best_ = std::numeric_limits<double>::infinity();
  int best_index_ = -1;
  double keys_[kKeep] = {}, pushes_[kKeep] = {};
  int index_[kKeep] = {};
  int n_ = 0;
  double rest_key_ = std::numeric_limits<double>::infinity(), rest_push_ = std::numeric_limits<double>::infinity();
};

/// One separating-axis pass over the candidate axes (faces of a, faces of b, edge pairs, in this
/// order). Returns the largest projection gap found (a lower bound on the distance, >= 0 when the
/// pair does not interfere); stops as soon as it exceeds `stop` (or reaches it, if `inclusive`).
/// While every axis overlaps, `best` is the smallest push separating the pair and `axis` its
/// direction (pushing a out of b). With `record`, also what `penetration_after_motion` needs to
/// replay the pass after a turn of up to max_turn_rad.
double sat(const PosedPolyhedron& a, const PosedPolyhedron& b, double stop, bool inclusive, double& best, Vec3& axis,
           SatRecord* record = nullptr, double max_turn_rad = 0.0) {
  const double span = record ? a.radius + b.radius + (a.center - b.center).norm() : 0.0;
  PassRecorder rec(max_turn_rad * span * 1.001);  // (the motion itself may lengthen the lever a little)
  double gap = -std::numeric_limits<double>::infinity();
  best = std::numeric_limits<double>::infinity();
  axis = Vec3::UnitZ();
  int k = 0;          // candidate axis index
  double turn = 1.0;  // how fast the candidate axis turns per radian of rotation of a or b
  bool unsafe = false;
  auto test = [&](const Vec3& u) {
    double la, ha, lb, hb;
    project(a.vertices, u, la, ha);
    project(b.vertices, u, lb, hb);
    const double push_plus = hb - la;   // translate a by +u * push_plus to separate
    const double push_minus = ha - lb;  // translate a by -u * push_minus to separate
    gap = std::max(gap, std::max(-push_plus, -push_minus));
    if (push_plus < best) {
      best = push_plus;
      axis = u;
    }
    if (push_minus < best) {
      best = push_minus;
      axis = -u;
    }
    if (record) {
      rec.add(push_plus, turn, 2 * k);
      rec.add(push_minus, turn, 2 * k + 1);
    }
    ++k;
    return inclusive ? gap >= stop : gap > stop;
  };
  auto finish = [&](double g) {
    if (record) {
      *record = SatRecord{};
      record->gap = g;
      record->max_turn_rad = max_turn_rad;
      if (g < 0.0) rec.finish(*record, unsafe);
    }
    return g;
  };
  for (const auto& n : a.normals)
    if (test(n)) return finish(gap);
  for (const auto& n : b.normals)
    if (test(n)) return finish(gap);
  for (const auto& ea : a.edge_dirs)
    for (const auto& eb : b.edge_dirs) {
      Vec3 c = ea.cross(eb);
      const double len = c.norm();
      // A pair of edges that may cross the parallel threshold under the allowed turn changes the
      // set of candidates: such a record is not replayed under a turn. (|Δ(e_a × e_b)| <= the turn.)
      if (record && std::abs(len - kParallel) <= max_turn_rad + 1e-15) unsafe = true;
      if (len < kParallel) {  // parallel edges: covered by the face normals
        ++k;
        continue;
      }
      c /= len;
      if (record) turn = 2.0 / len;  // |Δ(c/|c|)| <= 2 |Δc|/|c| (only a recorded pass uses it)
      if (test(c)) return finish(gap);
    }
  return finish(gap);
}

/// The push of candidate `index` (as recorded by `sat`), with its direction.
double push_along(const PosedPolyhedron& a, const PosedPolyhedron& b, int index, Vec3& axis) {
  const int k = index / 2;
  const int na = static_cast<int>(a.normals.size()), nb = static_cast<int>(b.normals.size());
  Vec3 u;
  if (k < na) {
    u = a.normals[static_cast<std::size_t>(k)];
  } else if (k < na + nb) {
    u = b.normals[static_cast<std::size_t>(k - na)];
  } else {
    const int e = k - na - nb, m = static_cast<int>(b.edge_dirs.size());
    u = a.edge_dirs[static_cast<std::size_t>(e / m)].cross(b.edge_dirs[static_cast<std::size_t>(e % m)]);
    u /= u.norm();
  }
  double la, ha, lb, hb;
  project(a.vertices, u, la, ha);
  project(b.vertices, u, lb, hb);
  axis = index % 2 == 0 ? u : Vec3(-u);
  return index % 2 == 0 ? hb - la : ha - lb;
}

}  // namespace

double separation_lower_bound(const PosedPolyhedron& a, const PosedPolyhedron& b) {
  return separation_lower_bound(a, b, std::numeric_limits<double>::infinity());
}

double separation_lower_bound(const PosedPolyhedron& a, const PosedPolyhedron& b, double stop_above) {
  double best;
  Vec3 axis;
  return sat(a, b, stop_above, false, best, axis);
}

bool penetration(const PosedPolyhedron& a, const PosedPolyhedron& b, PairContact& out, ClipWorkspace& ws) {
  double gap;
  return penetration_or_gap(a, b, 0.0, out, gap, ws);  // stops at the first axis that separates (or touches)
}

bool penetration_or_gap(const PosedPolyhedron& a, const PosedPolyhedron& b, double stop_above, PairContact& out, double& gap,
                        ClipWorkspace& ws) {
  double best;
  Vec3 axis;
  // An early exit is only taken once the pair is known to be apart (stop >= 0), so a negative gap
  // always comes from the full pass.
  gap = sat(a, b, std::max(stop_above, 0.0), false, best, axis);
  if (gap >= 0.0) return false;
  Vec3 centroid;
  intersection_centroid(a, b, centroid, ws);
  out.delta = best;
  out.normal = axis;
  out.point = centroid;
  return true;
}

bool penetration_recorded(const PosedPolyhedron& a, const PosedPolyhedron& b, double max_turn_rad, PairContact& out, SatRecord& record,
                          ClipWorkspace& ws) {
  if (!near(a, b)) {
    // A lower bound on the distance from the broad phase: bounding spheres or world boxes.
    double g = (a.center - b.center).norm() - a.radius - b.radius;
    for (int i = 0; i < 3; ++i) g = std::max({g, a.lo[i] - b.hi[i], b.lo[i] - a.hi[i]});
    record = SatRecord{};
    record.gap = g;
    return false;
  }
  double best;
  Vec3 axis;
  if (sat(a, b, 0.0, true, best, axis, &record, max_turn_rad) >= 0.0) return false;
  Vec3 centroid;
  intersection_centroid(a, b, centroid, ws);
  out.delta = best;
  out.normal = axis;
  out.point = centroid;
  return true;
}

bool penetration_after_motion(const PosedPolyhedron& a, const PosedPolyhedron& b, const SatRecord& record, double moved_m, double turn_rad,
                              PairContact& out, ClipWorkspace& ws) {
  // The distance of convex sets changes by at most the largest vertex displacement.
  if (record.gap >= 0.0 && record.gap > moved_m) return false;
  // A push changes by at most moved_m + (turn rate) turn_rad span (docs/contact_id.md). The best
  // and the watched candidates are evaluated again; when their smallest push stays below every
  // bound on the others, and positive, the result is the full pass's.
  if (record.gap < 0.0 && record.best_index >= 0 && turn_rad <= record.max_turn_rad) {
    Vec3 axis;
    int index = record.best_index;
    double best = push_along(a, b, index, axis);
    for (int i = 0; i < record.watched; ++i) {
      Vec3 u;
      const double push = push_along(a, b, record.watch[i], u);
      // The pass order breaks ties: the lower index wins.
      if (push < best || (push == best && record.watch[i] < index)) {
        best = push;
        index = record.watch[i];
        axis = u;
      }
    }
    const double others = (turn_rad > 0.0 ? record.second_turning : record.second_still) - moved_m;
    if (best > 0.0 && best < others) {
      out.delta = best;
      out.normal = axis;
      intersection_centroid(a, b, out.point, ws);
      return true;
    }
  }
  return near(a, b) && penetration(a, b, out, ws);
}

}  // namespace hil::contact_id
