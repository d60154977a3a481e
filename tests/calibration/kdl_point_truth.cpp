#include "kdl_point_truth.hpp"

#include <kdl/chaindynparam.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/tree.hpp>
#include <kdl_parser/kdl_parser.hpp>

#include <stdexcept>

namespace hil::test {

std::vector<PointSample> generate_points(const std::string& urdf, const std::string& base, const std::string& tip, const PointTruth& truth,
                                         int n, std::mt19937& rng, const std::vector<std::pair<double, double>>& range_rad) {
  KDL::Tree tree;
  if (!kdl_parser::treeFromFile(urdf, tree)) throw std::runtime_error("KDL cannot read " + urdf);
  KDL::Chain chain;
  if (!tree.getChain(base, tip, chain)) throw std::runtime_error("no chain " + base + " -> " + tip);
  const unsigned dof = chain.getNrOfJoints();
  KDL::ChainFkSolverPos_recursive fk(chain);
  KDL::ChainDynParam dyn(chain, KDL::Vector(0.0, 0.0, -9.80665));
  std::normal_distribution<double> noise(0.0, truth.noise_m);
  const int stations = static_cast<int>(truth.T_station_base.size());
  if (!range_rad.empty() && range_rad.size() != dof) throw std::invalid_argument("one joint range per joint of the chain");
  std::vector<PointSample> out;
  for (int k = 0; k < n; ++k) {
    PointSample s;
    s.q.resize(dof);
    for (unsigned j = 0; j < dof && !range_rad.empty(); ++j)
      s.q[j] = std::uniform_real_distribution<double>(range_rad[j].first, range_rad[j].second)(rng);
    for (unsigned j = 0; j < dof && range_rad.empty(); ++j) {
      // Shoulder lift in [-2.6, -0.5], elbow in [-2.5, 2.5] away from the stretched arm: postures a
      // lab would measure (the arm above the table, not folded into itself).
      const double lo = j == 1 ? -2.6 : j == 2 ? 0.4 : -3.0, hi = j == 1 ? -0.5 : j == 2 ? 2.5 : 3.0;
      s.q[j] = std::uniform_real_distribution<double>(lo, hi)(rng);
      if (j == 2 && std::uniform_int_distribution<int>(0, 1)(rng)) s.q[j] = -s.q[j];
    }
    s.station = k % stations;
    KDL::JntArray q(dof), G(dof), qe(dof);
    for (unsigned j = 0; j < dof; ++j) q(j) = s.q[j];
    dyn.JntToGravity(q, G);
    for (unsigned j = 0; j < dof; ++j) {
      qe(j) = q(j);
      if (truth.joint_offset_rad.size()) qe(j) += truth.joint_offset_rad[j];
      if (truth.joint_compliance.size()) qe(j) -= truth.joint_compliance[j] * G(j);
    }
    KDL::Frame F;
    fk.JntToCart(qe, F);
    const KDL::Vector p = F * KDL::Vector(truth.tool_point_m.x(), truth.tool_point_m.y(), truth.tool_point_m.z());
    const Eigen::Vector3d p_base(p.x(), p.y(), p.z());
    s.p_station_m = truth.T_station_base[static_cast<std::size_t>(s.station)] * p_base;
    for (int a = 0; a < 3; ++a) s.p_station_m[a] += noise(rng);
    out.push_back(s);
  }
  return out;
}

Eigen::Isometry3d random_station(std::mt19937& rng, double angle_rad, double distance_m) {
  std::normal_distribution<double> g(0.0, 1.0);
  const Eigen::Vector3d axis = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(std::uniform_real_distribution<double>(-angle_rad, angle_rad)(rng), axis).toRotationMatrix();
  for (int a = 0; a < 3; ++a) T.translation()[a] = std::uniform_real_distribution<double>(-distance_m, distance_m)(rng);
  return T;
}

}  // namespace hil::test
