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

/// Clips the polytope (pts/start of `in`) by {x : n.x <= d} into `out`.
void clip(const std::vector<Vec3>& ip, const std::vector<int>& is, std::vector<Vec3>& op, std::vector<int>& os,
          std::vector<Vec3>& cap, const Vec3& n, double d, double tol) {
  op.clear();
  os.clear();
  cap.clear();
  const int faces = static_cast<int>(is.size()) - 1;
  for (int f = 0; f < faces; ++f) {
    const int b = is[static_cast<std::size_t>(f)], e = is[static_cast<std::size_t>(f) + 1];
    const int first = static_cast<int>(op.size());
    for (int i = b; i < e; ++i) {
      const Vec3& P = ip[static_cast<std::size_t>(i)];
      const Vec3& Q = ip[static_cast<std::size_t>(i + 1 < e ? i + 1 : b)];
      const double sp = n.dot(P) - d, sq = n.dot(Q) - d;
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
      std::sort(cap.begin(), cap.end(), [&](const Vec3& p, const Vec3& q) {
        return std::atan2((p - c).dot(bb), (p - c).dot(a)) < std::atan2((q - c).dot(bb), (q - c).dot(a));
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
  for (std::size_t k = 0; k < b.normals.size(); ++k) {
    bool all_in = true;
    for (const auto& p : *P) all_in = all_in && (b.normals[k].dot(p) <= b.offsets[k]);
    if (all_in) continue;
    clip(*P, *S, *P2, *S2, ws.cap, b.normals[k], b.offsets[k], tol);
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

double separation_lower_bound(const PosedPolyhedron& a, const PosedPolyhedron& b) {
  double gap = -std::numeric_limits<double>::infinity();
  auto test = [&](const Vec3& u) {
    double la, ha, lb, hb;
    project(a.vertices, u, la, ha);
    project(b.vertices, u, lb, hb);
    gap = std::max(gap, std::max(la - hb, lb - ha));
  };
  for (const auto& n : a.normals) test(n);
  for (const auto& n : b.normals) test(n);
  for (const auto& ea : a.edge_dirs)
    for (const auto& eb : b.edge_dirs) {
      const Vec3 c = ea.cross(eb);
      const double len = c.norm();
      if (len >= 1e-6) test(c / len);
    }
  return gap;
}

bool penetration(const PosedPolyhedron& a, const PosedPolyhedron& b, PairContact& out, ClipWorkspace& ws) {
  double best = std::numeric_limits<double>::infinity();
  Vec3 axis = Vec3::UnitZ();
  auto test = [&](const Vec3& u) {
    double la, ha, lb, hb;
    project(a.vertices, u, la, ha);
    project(b.vertices, u, lb, hb);
    const double push_plus = hb - la;   // translate a by +u * push_plus to separate
    const double push_minus = ha - lb;  // translate a by -u * push_minus to separate
    if (push_plus <= 0.0 || push_minus <= 0.0) return false;
    if (push_plus < best) {
      best = push_plus;
      axis = u;
    }
    if (push_minus < best) {
      best = push_minus;
      axis = -u;
    }
    return true;
  };
  for (const auto& n : a.normals)
    if (!test(n)) return false;
  for (const auto& n : b.normals)
    if (!test(n)) return false;
  for (const auto& ea : a.edge_dirs)
    for (const auto& eb : b.edge_dirs) {
      Vec3 c = ea.cross(eb);
      const double len = c.norm();
      if (len < 1e-6) continue;  // parallel edges: covered by the face normals
      c /= len;
      if (!test(c)) return false;
    }
  Vec3 centroid;
  intersection_centroid(a, b, centroid, ws);
  out.delta = best;
  out.normal = axis;
  out.point = centroid;
  return true;
}

}  // namespace hil::contact_id
