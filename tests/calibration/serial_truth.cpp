#include "serial_truth.hpp"

#include <kdl/chain.hpp>
#include <kdl/chaindynparam.hpp>
#include <kdl/frames.hpp>
#include <kdl/jntarray.hpp>
#include <kdl/tree.hpp>
#include <kdl_parser/kdl_parser.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace hil::test::serial {

namespace {

using Vec = Eigen::Vector3d;

Vec ev(const KDL::Vector& v) { return {v.x(), v.y(), v.z()}; }
KDL::Vector kv(const Vec& v) { return KDL::Vector(v.x(), v.y(), v.z()); }

KDL::Rotation rotation(const Vec& rotation_vector) {
  const double a = rotation_vector.norm();
  if (a == 0.0) return KDL::Rotation::Identity();
  const Eigen::Matrix3d R = Eigen::AngleAxisd(a, rotation_vector / a).toRotationMatrix();
  return KDL::Rotation(R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0), R(2, 1), R(2, 2));
}

// The small rigid motion of the world x ↦ D + δ + R(θ)(x − D): the end D of a bent beam moves by δ
// and turns by the rotation vector θ, and carries everything beyond it rigidly.
KDL::Frame motion_about(const Vec& D, const Vec& delta, const Vec& theta) {
  KDL::Frame W;
  W.M = rotation(theta);
  W.p = kv(D + delta) - W.M * kv(D);
  return W;
}

void check_size(const Eigen::VectorXd& v, unsigned dof, const char* name) {
  if (v.size() != 0 && v.size() != static_cast<Eigen::Index>(dof))
    throw std::invalid_argument(std::string(name) + ": " + std::to_string(v.size()) + " values for a chain of " + std::to_string(dof) +
                                " moving joints (give one per joint, or none)");
}

void check_not_negative(const Eigen::VectorXd& v, const char* name) {
  for (Eigen::Index i = 0; i < v.size(); ++i)
    if (!(v[i] >= 0.0)) throw std::invalid_argument(std::string(name) + "[" + std::to_string(i) + "] must be >= 0");
}

double at(const Eigen::VectorXd& v, unsigned i, double otherwise) { return v.size() ? v[static_cast<Eigen::Index>(i)] : otherwise; }

// A beam resolved on the chain: segment `s` is the link, its distal end is the origin of the joint
// of segment `d` (the next moving joint), or the tip frame's origin when d == number of segments.
struct ChainBeam {
  unsigned s = 0, d = 0;
  double EI = 0.0, GJ = 0.0;
};

}  // namespace

std::vector<Eigen::VectorXd> draw_postures(int n, const std::vector<std::pair<double, double>>& range_rad, std::mt19937& rng) {
  if (n < 0) throw std::invalid_argument("draw_postures: negative number of postures");
  if (range_rad.empty()) throw std::invalid_argument("draw_postures: one (lower, upper) range per joint is needed");
  for (const auto& [lo, hi] : range_rad)
    if (!(lo <= hi)) throw std::invalid_argument("draw_postures: a range with lower > upper");
  std::vector<Eigen::VectorXd> out;
  for (int k = 0; k < n; ++k) {
    Eigen::VectorXd q(static_cast<Eigen::Index>(range_rad.size()));
    for (std::size_t j = 0; j < range_rad.size(); ++j)
      q[static_cast<Eigen::Index>(j)] = std::uniform_real_distribution<double>(range_rad[j].first, range_rad[j].second)(rng);
    out.push_back(q);
  }
  return out;
}

std::vector<Sample> generate(const Truth& t, const std::vector<Eigen::VectorXd>& postures, std::mt19937& rng) {
  return generate(t, postures, {}, rng);
}

std::vector<Sample> generate(const Truth& t, const std::vector<Eigen::VectorXd>& postures, const std::vector<bool>& flags,
                             std::mt19937& rng) {
  // --- The robot, from KDL only.
  // The file is read here: Debian's kdl_parser 1.14 treeFromFile dereferences a null model when the
  // file is missing, whereas treeFromString checks it.
  std::ifstream in(t.urdf);
  std::ostringstream xml;
  xml << in.rdbuf();
  KDL::Tree tree;
  if (!in || xml.str().empty() || !kdl_parser::treeFromString(xml.str(), tree))
    throw std::invalid_argument("KDL cannot read the URDF file '" + t.urdf + "'");
  KDL::Chain chain;
  if (!tree.getChain(t.base, t.tip, chain) || chain.getNrOfSegments() == 0)
    throw std::invalid_argument("no chain from '" + t.base + "' to '" + t.tip + "' in " + t.urdf);
  const unsigned dof = chain.getNrOfJoints(), nseg = chain.getNrOfSegments();
  std::vector<int> joint_of(nseg, -1);  // index of each segment's joint in q, −1 for a fixed joint
  for (unsigned i = 0, j = 0; i < nseg; ++i)
    if (chain.getSegment(i).getJoint().getType() != KDL::Joint::Fixed) joint_of[i] = static_cast<int>(j++);

  // --- The truth, checked.
  check_size(t.joint_offset_rad, dof, "joint_offset_rad");
  check_size(t.flag_offset_rad, dof, "flag_offset_rad");
  check_size(t.joint_stiffness_Nm_per_rad, dof, "joint_stiffness_Nm_per_rad");
  check_size(t.backlash_rad, dof, "backlash_rad");
  check_size(t.encoder_error_rad, dof, "encoder_error_rad");
  check_size(t.encoder_phase_rad, dof, "encoder_phase_rad");
  check_size(t.backlash_friction_Nm, dof, "backlash_friction_Nm");
  check_not_negative(t.joint_stiffness_Nm_per_rad, "joint_stiffness_Nm_per_rad");
  check_not_negative(t.backlash_rad, "backlash_rad");
  check_not_negative(t.backlash_friction_Nm, "backlash_friction_Nm");
  if (!(t.base_stiffness_Nm_per_rad >= 0.0)) throw std::invalid_argument("base_stiffness_Nm_per_rad must be >= 0");
  if (!(t.payload_kg >= 0.0)) throw std::invalid_argument("payload_kg must be >= 0");
  if (!(t.noise_m >= 0.0)) throw std::invalid_argument("noise_m must be >= 0");
  if (!(t.tilt_noise_rad >= 0.0)) throw std::invalid_argument("tilt_noise_rad must be >= 0");
  if (!(t.noise_rad >= 0.0)) throw std::invalid_argument("noise_rad must be >= 0");
  if (!flags.empty() && flags.size() != postures.size())
    throw std::invalid_argument("flags: " + std::to_string(flags.size()) + " for " + std::to_string(postures.size()) +
                                " postures (give one per posture, or none)");
  if (t.T_station_base.empty()) throw std::invalid_argument("T_station_base: at least one station is needed");
  for (std::size_t k = 0; k < postures.size(); ++k)
    if (postures[k].size() != static_cast<Eigen::Index>(dof))
      throw std::invalid_argument("posture " + std::to_string(k) + " has " + std::to_string(postures[k].size()) + " values for " +
                                  std::to_string(dof) + " moving joints");

  std::vector<ChainBeam> beams;
  for (const Beam& b : t.beams) {
    ChainBeam c;
    while (c.s < nseg && chain.getSegment(c.s).getName() != b.link) ++c.s;
    if (c.s == nseg) throw std::invalid_argument("beam link '" + b.link + "' is not a link of the chain " + t.base + " -> " + t.tip);
    for (const ChainBeam& o : beams)
      if (o.s == c.s) throw std::invalid_argument("beam link '" + b.link + "' is listed twice");
    if (!(b.EI_Nm2 > 0.0)) throw std::invalid_argument("beam '" + b.link + "': EI_Nm2 must be > 0");
    if (!(b.GJ_Nm2 >= 0.0)) throw std::invalid_argument("beam '" + b.link + "': GJ_Nm2 must be >= 0 (0 = rigid in torsion)");
    c.d = c.s + 1;
    while (c.d < nseg && joint_of[c.d] < 0) ++c.d;
    // The segment s+1..d−1 are fixed, so the beam's length does not depend on the posture.
    KDL::Frame rel = KDL::Frame::Identity();
    for (unsigned j = c.s + 1; j < c.d; ++j) rel = rel * chain.getSegment(j).pose(0.0);
    const KDL::Vector end = c.d < nseg ? rel * chain.getSegment(c.d).getJoint().JointOrigin() : rel.p;
    if (end.Norm() < 1e-9) throw std::invalid_argument("beam link '" + b.link + "' has zero length (its distal joint sits at its origin)");
    c.EI = b.EI_Nm2;
    c.GJ = b.GJ_Nm2;
    beams.push_back(c);
  }

  // --- Gravity torques: KDL's holding torques of the chain with the payload as one more rigid body
  // fixed to the tip frame.
  KDL::Chain loaded = chain;
  if (t.payload_kg > 0.0)
    loaded.addSegment(KDL::Segment("serial_truth_payload", KDL::Joint(KDL::Joint::Fixed), KDL::Frame::Identity(),
                                   KDL::RigidBodyInertia(t.payload_kg, kv(t.payload_com_tip_m))));
  const Vec g(0.0, 0.0, -kGravity_m_per_s2);
  KDL::ChainDynParam dyn(loaded, kv(g));
  const bool joints_move = t.joint_stiffness_Nm_per_rad.size() || t.backlash_rad.size();

  // The base link's own weight also rests on the base springs (the chain starts after it).
  double base_mass = 0.0;
  Vec base_com = Vec::Zero();
  if (const auto it = tree.getSegment(t.base); it != tree.getSegments().end()) {
    const KDL::RigidBodyInertia& I = GetTreeElementSegment(it->second).getInertia();
    base_mass = I.getMass();
    base_com = ev(I.getCOG());
  }

  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<double> side(dof, 1.0);  // backlash: where the play left each joint (+1 before any move)
  std::vector<Sample> out;
  out.reserve(postures.size());
  for (std::size_t k = 0; k < postures.size(); ++k) {
    Sample smp;
    smp.q = postures[k];
    smp.station = static_cast<int>(k % t.T_station_base.size());
    smp.flag = !flags.empty() && flags[k];
    // The posture's offsets: the flag's come on top of the joints' own, on the link side alike.
    std::vector<double> offset(dof);
    for (unsigned i = 0; i < dof; ++i) offset[i] = at(t.joint_offset_rad, i, 0.0) + (smp.flag ? at(t.flag_offset_rad, i, 0.0) : 0.0);
    // The encoder reads q where the link stands at q + A sin(q + φ): on the link side like an offset.
    for (unsigned i = 0; i < dof; ++i) offset[i] += at(t.encoder_error_rad, i, 0.0) * std::sin(smp.q[i] + at(t.encoder_phase_rad, i, 0.0));

    // --- 1. Joints. The side of the play a joint under small torque sits on follows its last move:
    // the motor pushed the link, which lags behind it (−b after a positive move, +b after a negative).
    for (unsigned i = 0; i < dof && k > 0; ++i) {
      const double move = postures[k][i] - postures[k - 1][i];
      if (move > 0.0) side[i] = -1.0;
      if (move < 0.0) side[i] = 1.0;
    }
    KDL::JntArray ql(dof), tau(dof);
    for (unsigned i = 0; i < dof; ++i) ql(i) = smp.q[i] + offset[i];
    if (joints_move) {
      // Equilibrium link side: ql = q + offset + b·side − τ(ql)/k, with τ the holding torque at the
      // link side and side = −sign τ where |τ| overcomes the friction. Fixed-point iteration: the
      // map contracts by about |∂τ/∂q|/k, tiny for any realistic joint.
      std::vector<double> s(side);
      for (int it = 0; it < 50; ++it) {
        dyn.JntToGravity(ql, tau);
        double change = 0.0;
        for (unsigned i = 0; i < dof; ++i) {
          const double b = at(t.backlash_rad, i, 0.0), kj = at(t.joint_stiffness_Nm_per_rad, i, 0.0);
          s[i] = std::abs(tau(i)) > at(t.backlash_friction_Nm, i, 2.0) ? (tau(i) > 0.0 ? -1.0 : 1.0) : side[i];
          const double next = smp.q[i] + offset[i] + b * s[i] - (kj > 0.0 ? tau(i) / kj : 0.0);
          change = std::max(change, std::abs(next - ql(i)));
          ql(i) = next;
        }
        if (change < 1e-12) break;
      }
      side = s;  // gravity pushed the play to its side: the next small-torque posture starts there
    }
    smp.q_link.resize(dof);
    for (unsigned i = 0; i < dof; ++i) smp.q_link[i] = ql(i);

    // Nominal frames of the segments (link side, no beam, no tilt): the configuration the loads of
    // the beams and of the base are computed on (their effect on those loads is second order).
    std::vector<KDL::Frame> F(nseg);
    KDL::Frame f = KDL::Frame::Identity();
    for (unsigned i = 0; i < nseg; ++i) F[i] = f = f * chain.getSegment(i).pose(joint_of[i] < 0 ? 0.0 : ql(joint_of[i]));
    std::vector<double> m(nseg);
    std::vector<Vec> c(nseg);
    for (unsigned i = 0; i < nseg; ++i) {
      m[i] = chain.getSegment(i).getInertia().getMass();
      c[i] = ev(F[i] * chain.getSegment(i).getInertia().getCOG());
    }
    const Vec c_payload = ev(F[nseg - 1] * kv(t.payload_com_tip_m));

    // --- 2. Beams: each inserts, at its distal end, the small motion of a clamped cantilever,
    // expressed in the frame there so that the rest of the chain rides on it.
    std::vector<KDL::Frame> insert(nseg + 1, KDL::Frame::Identity());
    std::vector<bool> inserted(nseg + 1, false);
    for (const ChainBeam& b : beams) {
      const KDL::Frame& ref = F[b.d - 1];  // the frame just before the distal end
      const Vec P = ev(F[b.s].p), D = b.d < nseg ? ev(ref * chain.getSegment(b.d).getJoint().JointOrigin()) : ev(ref.p);
      const double L = (D - P).norm();
      const Vec e = (D - P) / L;
      const auto transverse = [&e](const Vec& v) -> Vec { return v - v.dot(e) * e; };
      // Loads: the link's own weight spread along it; at the end, the weight of everything beyond
      // (further links at their centres of mass, payload) as a force and a moment about D.
      const Vec w = transverse(m[b.s] * g / L);
      Vec P_end = t.payload_kg * g, M_end = (c_payload - D).cross(t.payload_kg * g);
      for (unsigned j = b.s + 1; j < nseg; ++j) {
        P_end += m[j] * g;
        M_end += (c[j] - D).cross(m[j] * g);
      }
      const Vec Pt = transverse(P_end);
      const double T = M_end.dot(e);
      const Vec Mb = M_end - T * e;
      // Euler–Bernoulli cantilever closed forms; a transverse load v turns the end about e × v and
      // moves it along v; a bending moment M turns it about M and moves it along M × e.
      const double EI = b.EI, L2 = L * L, L3 = L2 * L;
      Vec theta = e.cross(w) * L3 / (6.0 * EI) + e.cross(Pt) * L2 / (2.0 * EI) + Mb * L / EI;
      if (b.GJ > 0.0) theta += e * (T * L / b.GJ);
      const Vec delta = w * L3 * L / (8.0 * EI) + Pt * L3 / (3.0 * EI) + Mb.cross(e) * L2 / (2.0 * EI);
      insert[b.d] = insert[b.d] * (ref.Inverse() * motion_about(D, delta, theta) * ref);
      inserted[b.d] = true;
    }

    // --- 3. Base: the weight's moment about the base origin tilts it by M/k (about x and y only,
    // gravity being vertical), a pure rotation about that origin (F_tilt.p stays zero). The base
    // inclinometer reads the rotation vector; a rotation leaves its own axis unchanged, so it is the
    // same in the untilted and in the tilted base frame.
    KDL::Frame F_tilt = KDL::Frame::Identity();
    Vec tilt = Vec::Zero();
    if (t.base_stiffness_Nm_per_rad > 0.0) {
      Vec M = base_com.cross(base_mass * g) + c_payload.cross(t.payload_kg * g);
      for (unsigned i = 0; i < nseg; ++i) M += c[i].cross(m[i] * g);
      tilt = M / t.base_stiffness_Nm_per_rad;
      F_tilt.M = rotation(tilt);
    }
    smp.base_tilt_rad = tilt.head<2>();

    // --- The deflected chain and the measurement.
    f = F_tilt;
    for (unsigned i = 0; i < nseg; ++i) {
      if (inserted[i]) f = f * insert[i];
      f = f * chain.getSegment(i).pose(joint_of[i] < 0 ? 0.0 : ql(joint_of[i]));
    }
    if (inserted[nseg]) f = f * insert[nseg];
    smp.p_base_m = ev(f * kv(t.tool_point_m));
    smp.p_station_m = t.T_station_base[static_cast<std::size_t>(smp.station)] * smp.p_base_m;
    if (t.noise_m > 0.0)
      for (int a = 0; a < 3; ++a) smp.p_station_m[a] += t.noise_m * noise(rng);
    // After the point's noise, and only when there is tilt noise: the stream of runs without it is
    // unchanged.
    if (t.tilt_noise_rad > 0.0)
      for (int a = 0; a < 2; ++a) smp.base_tilt_rad[a] += t.tilt_noise_rad * noise(rng);
    // The measured frame's orientation (a 6-D tracker's probe on the tip), its noise last and only
    // when asked: a small rotation about a random direction in the station's frame.
    Eigen::Matrix3d R_base_tip;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) R_base_tip(i, j) = f.M(i, j);
    Eigen::Matrix3d R = t.T_station_base[static_cast<std::size_t>(smp.station)].linear() * R_base_tip * t.measured_frame_tip;
    if (t.noise_rad > 0.0) {
      Vec n;
      for (int a = 0; a < 3; ++a) n[a] = t.noise_rad * noise(rng);
      if (n.norm() > 0) R = Eigen::AngleAxisd(n.norm(), n.normalized()).toRotationMatrix() * R;
    }
    const Eigen::AngleAxisd aa(R);
    smp.r_station_rad = aa.angle() * aa.axis();
    out.push_back(smp);
  }
  return out;
}

Eigen::Isometry3d random_station(std::mt19937& rng, double angle_rad, double distance_m) {
  std::normal_distribution<double> n(0.0, 1.0);
  const Vec axis = Vec(n(rng), n(rng), n(rng)).normalized();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(std::uniform_real_distribution<double>(-angle_rad, angle_rad)(rng), axis).toRotationMatrix();
  for (int a = 0; a < 3; ++a) T.translation()[a] = std::uniform_real_distribution<double>(-distance_m, distance_m)(rng);
  return T;
}

}  // namespace hil::test::serial
