#include <hil/contact_id/geometry.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace hil::contact_id {

namespace {

/// Orders the vertex indices of one face counter-clockwise about its outward normal.
void order_loop(const std::vector<Vec3>& v, const Vec3& n, std::vector<int>& loop) {
  Vec3 c = Vec3::Zero();
  for (int i : loop) c += v[static_cast<std::size_t>(i)];
  c /= static_cast<double>(loop.size());
  const Vec3 a = (std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).cross(n).normalized();
  const Vec3 b = n.cross(a);
  std::sort(loop.begin(), loop.end(), [&](int i, int j) {
    const Vec3 di = v[static_cast<std::size_t>(i)] - c, dj = v[static_cast<std::size_t>(j)] - c;
    return std::atan2(di.dot(b), di.dot(a)) < std::atan2(dj.dot(b), dj.dot(a));
  });
}

}  // namespace

Polyhedron Polyhedron::from_vertices(const std::vector<Vec3>& in) {
  if (in.size() < 4) throw std::invalid_argument("a polyhedron needs at least 4 vertices");
  for (const auto& p : in)
    if (!p.allFinite()) throw std::invalid_argument("a polyhedron vertex is not finite");
  Vec3 lo = in[0], hi = in[0];
  for (const auto& p : in) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double scale = (hi - lo).norm();
  if (!(scale > 0.0)) throw std::invalid_argument("a polyhedron's vertices coincide");
  const double tol = 1e-9 * scale;
  const std::size_t n = in.size();

  // Every supporting plane through three vertices with all others on one side is a face plane.
  std::vector<std::pair<Vec3, double>> planes;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j)
      for (std::size_t k = j + 1; k < n; ++k) {
        Vec3 nn = (in[j] - in[i]).cross(in[k] - in[i]);
        const double len = nn.norm();
        if (len < 1e-12 * scale * scale) continue;
        nn /= len;
        const double d = nn.dot(in[i]);
        bool below = true, above = true;
        for (std::size_t m = 0; m < n && (below || above); ++m) {
          const double s = nn.dot(in[m]) - d;
          if (s > tol) below = false;
          if (s < -tol) above = false;
        }
        if (!below && !above) continue;
        if (below && above) throw std::invalid_argument("a polyhedron's vertices are coplanar (no volume)");
        if (above) nn = -nn;
        const double dd = nn.dot(in[i]);
        bool dup = false;
        for (const auto& [pn, pd] : planes)
          if ((pn - nn).norm() < 1e-9 && std::abs(pd - dd) < tol) dup = true;
        if (!dup) planes.emplace_back(nn, dd);
      }
  if (planes.size() < 4) throw std::invalid_argument("a polyhedron's vertices span no volume");

  Polyhedron P;
  // Keep only vertices on the hull.
  std::vector<int> map(n, -1);
  for (std::size_t m = 0; m < n; ++m) {
    int on = 0;
    for (const auto& [pn, pd] : planes)
      if (std::abs(pn.dot(in[m]) - pd) <= tol) ++on;
    if (on >= 3) {
      map[m] = static_cast<int>(P.vertices_.size());
      P.vertices_.push_back(in[m]);
    }
  }
  for (const auto& [pn, pd] : planes) {
    Face f;
    f.normal = pn;
    f.offset = pd;
    for (std::size_t m = 0; m < P.vertices_.size(); ++m)
      if (std::abs(pn.dot(P.vertices_[m]) - pd) <= tol) f.loop.push_back(static_cast<int>(m));
    order_loop(P.vertices_, pn, f.loop);
    P.faces_.push_back(std::move(f));
  }
  for (const auto& f : P.faces_)
    for (std::size_t a = 0; a < f.loop.size(); ++a) {
      int i = f.loop[a], j = f.loop[(a + 1) % f.loop.size()];
      if (i > j) std::swap(i, j);
      if (std::find(P.edges_.begin(), P.edges_.end(), std::make_pair(i, j)) == P.edges_.end()) P.edges_.emplace_back(i, j);
    }
  for (const auto& [i, j] : P.edges_) {
    const Vec3 d = (P.vertices_[static_cast<std::size_t>(j)] - P.vertices_[static_cast<std::size_t>(i)]).normalized();
    bool dup = false;
    for (const auto& e : P.edge_dirs_)
      if (std::abs(std::abs(e.dot(d)) - 1.0) < 1e-12) dup = true;
    if (!dup) P.edge_dirs_.push_back(d);
  }
  Vec3 c = Vec3::Zero();
  for (const auto& p : P.vertices_) c += p;
  P.center_ = c / static_cast<double>(P.vertices_.size());
  for (const auto& p : P.vertices_) P.radius_ = std::max(P.radius_, (p - P.center_).norm());
  for (const auto& f : P.faces_)
    for (std::size_t a = 1; a + 1 < f.loop.size(); ++a) {
      const Vec3& v0 = P.vertices_[static_cast<std::size_t>(f.loop[0])];
      const Vec3& v1 = P.vertices_[static_cast<std::size_t>(f.loop[a])];
      const Vec3& v2 = P.vertices_[static_cast<std::size_t>(f.loop[a + 1])];
      P.volume_ += std::abs((v0 - P.center_).dot((v1 - P.center_).cross(v2 - P.center_))) / 6.0;
    }
  return P;
}

void PosedPolyhedron::pose(const Polyhedron& p, const Eigen::Isometry3d& T) {
  shape = &p;
  const auto R = T.linear();
  const auto& v = p.vertices();
  vertices.resize(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) vertices[i].noalias() = R * v[i] + T.translation();
  lo = hi = vertices[0];
  for (const auto& q : vertices) {
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  const auto& f = p.faces();
  normals.resize(f.size());
  offsets.resize(f.size());
  for (std::size_t i = 0; i < f.size(); ++i) {
    normals[i].noalias() = R * f[i].normal;
    offsets[i] = f[i].offset + normals[i].dot(T.translation());
  }
  const auto& e = p.edge_directions();
  edge_dirs.resize(e.size());
  for (std::size_t i = 0; i < e.size(); ++i) edge_dirs[i].noalias() = R * e[i];
  center = T * p.center();
  radius = p.radius();
}

Eigen::Isometry3d uncertainty_transform(const Uncertainty& u, double x) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  if (u.kind == Uncertainty::Kind::translation) {
    T.translation() = x * u.axis;
  } else {
    T.linear() = Eigen::AngleAxisd(x, u.axis).toRotationMatrix();
    T.translation() = u.point - T.linear() * u.point;
  }
  return T;
}

Eigen::Isometry3d feature_transform(const std::vector<Uncertainty>& us, const Eigen::VectorXd& x, int body, int feature) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (std::size_t j = 0; j < us.size(); ++j)
    if (us[j].body == body && us[j].feature == feature) T = uncertainty_transform(us[j], x[static_cast<Eigen::Index>(j)]) * T;
  return T;
}

}  // namespace hil::contact_id
