#pragma once
/// \file Convex polyhedra, features, bodies and feature uncertainties (contact paper, sec. 2.3-2.4).
///
/// A body (object) is a union of convex polyhedra grouped into named features. A polyhedron is given
/// by its vertices; faces (outward unit normal n and offset d, so that the solid is {x : n.x <= d}),
/// face vertex loops and edge directions are derived once (`Polyhedron::from_vertices`). Posing a
/// polyhedron (rigid transform) keeps that topology, so the hot path only transforms vectors.
///
/// Feature uncertainties (the paper's x_u) move the polyhedra of one feature in the body frame:
/// translation by x along a unit axis, rotation by x (rad) about an axis through a point. Several
/// uncertainties on one feature compose in the order they are listed (the first acts first). The
/// vertices given describe the geometry at x_u = 0; the nominal model uses x_u = x_u^d.
#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace hil::contact_id {

using Vec3 = Eigen::Vector3d;

/// One face of a convex polyhedron: outward unit normal, offset (n.x <= d inside), vertex loop
/// (indices into the vertex list, counter-clockwise seen from outside).
struct Face {
  Vec3 normal = Vec3::UnitZ();
  double offset = 0.0;
  std::vector<int> loop;
};

/// A convex polyhedron in its body frame with derived topology.
class Polyhedron {
 public:
  /// Builds faces, edges and the bounding sphere from the vertices (convex hull by exhaustive
  /// plane search: meant for the small vertex counts of contact models, up to a few dozen).
  /// Interior points (not on the hull) are dropped. \throws std::invalid_argument if the
  /// vertices span no volume or are not finite.
  static Polyhedron from_vertices(const std::vector<Vec3>& vertices);

  const std::vector<Vec3>& vertices() const { return vertices_; }
  const std::vector<Face>& faces() const { return faces_; }
  /// Unit directions of the edges, parallel edges merged (for separating-axis tests).
  const std::vector<Vec3>& edge_directions() const { return edge_dirs_; }
  /// Pairs of vertex indices, one per edge.
  const std::vector<std::pair<int, int>>& edges() const { return edges_; }
  const Vec3& center() const { return center_; }
  double radius() const { return radius_; }
  double volume() const { return volume_; }

 private:
  std::vector<Vec3> vertices_;
  std::vector<Face> faces_;
  std::vector<std::pair<int, int>> edges_;
  std::vector<Vec3> edge_dirs_;
  Vec3 center_ = Vec3::Zero();
  double radius_ = 0.0;
  double volume_ = 0.0;
};

/// A polyhedron placed in the world: the same topology, world coordinates.
struct PosedPolyhedron {
  const Polyhedron* shape = nullptr;  ///< not owned
  std::vector<Vec3> vertices;
  std::vector<Vec3> normals;
  std::vector<double> offsets;
  std::vector<Vec3> edge_dirs;
  Vec3 center = Vec3::Zero();
  double radius = 0.0;
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();  ///< world axis-aligned bounding box

  /// Places `p` by `T` (reuses this object's buffers).
  void pose(const Polyhedron& p, const Eigen::Isometry3d& T);
};

struct Feature {
  std::string name;
  std::vector<Polyhedron> polyhedra;
};

/// A rigid body: object 1 is carried by the end effector, object 2 is fixed in the world.
struct Body {
  std::string name;
  std::vector<Feature> features;
  bool on_end_effector = false;  ///< true: T_world_body = T_world_ee * T_attach; false: T_world_body = T_attach
  Eigen::Isometry3d T_attach = Eigen::Isometry3d::Identity();
};

/// One geometric uncertainty x_u,j acting on one feature.
struct Uncertainty {
  enum class Kind { translation, rotation };
  std::string name;
  int body = 0;     ///< 0 = object 1 (held), 1 = object 2 (fixed)
  int feature = 0;  ///< index into Body::features
  Kind kind = Kind::translation;
  Vec3 axis = Vec3::UnitX();  ///< unit, body frame
  Vec3 point = Vec3::Zero();  ///< on the rotation axis, body frame (m)
  double design_value = 0.0;  ///< x_u^d (m or rad)
  double prior_std = 0.0;     ///< expected size of the error (m or rad), > 0 for fitting
};

/// The transform of one uncertainty at value x (body frame -> body frame).
Eigen::Isometry3d uncertainty_transform(const Uncertainty& u, double x);

/// The transform of feature (body, feature) for the uncertainty vector x: the composition, in list
/// order, of the transforms of the uncertainties acting on it (identity if none).
Eigen::Isometry3d feature_transform(const std::vector<Uncertainty>& us, const Eigen::VectorXd& x, int body, int feature);

}  // namespace hil::contact_id
