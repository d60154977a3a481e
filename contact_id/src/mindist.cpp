#include "hil/contact_id/mindist.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hil::contact_id {

namespace {

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

/// One separating-axis pass over the candidate axes (faces of a, faces of b, edge pairs, in this
/// order). Returns the largest projection gap found (a lower bound on the distance, >= 0 when the
/// pair does not interfere); stops as soon as it exceeds `stop` (or reaches it, if `inclusive`).
/// While every axis overlaps, `best` is the smallest push separating the pair and `axis` its
/// direction (pushing a out of b).
double sat(const PosedPolyhedron& a, const PosedPolyhedron& b, double stop, bool inclusive, double& best, Vec3& axis) {
  double gap = -std::numeric_limits<double>::infinity();
  best = std::numeric_limits<double>::infinity();
  axis = Vec3::UnitZ();
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
    return inclusive ? gap >= stop : gap > stop;
  };
  for (const auto& n : a.normals)
    if (test(n)) return gap;
  for (const auto& n : b.normals)
    if (test(n)) return gap;
  for (const auto& ea : a.edge_dirs)
    for (const auto& eb : b.edge_dirs) {
      Vec3 c = ea.cross(eb);
      const double len = c.norm();
      if (len < 1e-6) continue;  // parallel edges: covered by the face normals
      c /= len;
      if (test(c)) return gap;
    }
  return gap;
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
  double best;
  Vec3 axis;
  if (sat(a, b, 0.0, true, best, axis) >= 0.0) return false;  // some axis separates (or touches)
  Vec3 centroid;
  intersection_centroid(a, b, centroid, ws);
  out.delta = best;
  out.normal = axis;
  out.point = centroid;
  return true;
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

}  // namespace hil::contact_id
