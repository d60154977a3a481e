#include <hil/format/urdf.hpp>

#include <console_bridge/console.h>
#include <kdl/tree.hpp>
#include <kdl_parser/kdl_parser.hpp>
#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <mutex>
#include <set>
#include <sstream>

#include <hil/error/error.hpp>

namespace hil::format {
namespace {

using error::FormatError;

/// urdfdom and kdl_parser report through console_bridge, a process-wide logger: while one parse
/// runs, its warnings and errors are collected here so that the FormatError can quote them.
class CollectLog : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_WARN) lines.push_back(text);
  }
  std::vector<std::string> lines;
};

std::mutex& log_mutex() {
  static std::mutex m;
  return m;
}

std::string joined(const std::vector<std::string>& lines) {
  std::string s;
  for (const auto& l : lines) s += (s.empty() ? "" : "; ") + l;
  return s;
}

Eigen::Isometry3d to_isometry(const KDL::Frame& f) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) T.linear()(r, c) = f.M(static_cast<unsigned>(r), static_cast<unsigned>(c));
    T.translation()(r) = f.p(static_cast<unsigned>(r));
  }
  return T;
}

/// KDL's inertia (about the reference frame's origin) as mass, centre of mass and inertia about it.
InertialSpec to_inertial(const KDL::RigidBodyInertia& I) {
  InertialSpec s;
  s.mass_kg = I.getMass();
  const KDL::Vector c = I.getCOG();
  s.com_m = Eigen::Vector3d(c.x(), c.y(), c.z());
  const KDL::RotationalInertia Io = I.getRotationalInertia();
  Eigen::Matrix3d M;
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k) M(r, k) = Io.data[3 * r + k];
  // Parallel axis: I_c = I_o - m (|c|² 1 - c cᵀ).
  s.inertia_kgm2 = M - s.mass_kg * (s.com_m.squaredNorm() * Eigen::Matrix3d::Identity() - s.com_m * s.com_m.transpose());
  return s;
}

bool is_revolute(KDL::Joint::JointType t) {
  return t == KDL::Joint::RotAxis || t == KDL::Joint::RotX || t == KDL::Joint::RotY || t == KDL::Joint::RotZ;
}
bool is_prismatic(KDL::Joint::JointType t) {
  return t == KDL::Joint::TransAxis || t == KDL::Joint::TransX || t == KDL::Joint::TransY || t == KDL::Joint::TransZ;
}

std::string link_list(const urdf::ModelInterface& m) {
  std::vector<urdf::LinkSharedPtr> links;
  m.getLinks(links);
  std::string s;
  for (const auto& l : links) s += (s.empty() ? "" : ", ") + l->name;
  return s;
}

/// urdfdom accepts a link that is the child of two joints (and so joints that close a loop):
/// kdl_parser would then recurse around the loop until the stack runs out. A URDF is a tree:
/// every link has at most one parent joint and every link hangs from the root. Returns what is
/// wrong, or an empty string.
std::string tree_problem(const urdf::ModelInterface& m) {
  std::map<std::string, std::string> parent_joint_of;  // link -> the first joint naming it as child
  for (const auto& [name, joint] : m.joints_) {
    if (!joint) continue;
    const auto [it, first] = parent_joint_of.emplace(joint->child_link_name, name);
    if (!first)
      return "link '" + joint->child_link_name + "' is the child of both joint '" + it->second + "' and joint '" + name +
             "': a URDF is a tree (a closed loop cannot be described)";
  }
  const auto root = m.getRoot();
  if (!root) return "no root link";
  // Walk down from the root without recursion; a link met twice means a loop.
  std::set<std::string> seen{root->name};
  std::vector<urdf::LinkConstSharedPtr> todo{root};
  while (!todo.empty()) {
    const auto link = todo.back();
    todo.pop_back();
    for (const auto& child : link->child_links) {
      if (!child) continue;
      if (!seen.insert(child->name).second) return "link '" + child->name + "' is reached twice from the root: the joints form a loop";
      todo.push_back(child);
    }
  }
  std::string unreached;
  for (const auto& [name, link] : m.links_)
    if (!seen.count(name)) unreached += (unreached.empty() ? "'" : ", '") + name + "'";
  if (!unreached.empty()) return "links " + unreached + " do not hang from the root '" + root->name + "' (their joints form a loop)";
  return {};
}

/// urdfdom links a parent to its children by shared pointers (Link::child_links): joints that close
/// a loop make a cycle of them, which outlives the model and leaked on every such description the
/// reader refused (LeakSanitizer, UrdfRobot.BadDescriptionsFailByName). Cut before dropping it.
void cut_link_cycles(urdf::ModelInterface& m) {
  for (auto& [name, link] : m.links_)
    if (link) {
      link->child_links.clear();
      link->child_joints.clear();
    }
}

/// A mimic joint's value must be computable from the chain's own joints: its master must be a
/// moving joint between the base and the tip. A mimic of a mimic is resolved to the independent
/// joint at the end (q_a = m_a (m_b q_c + o_b) + o_a), so that hil's kinematics need one pass.
void resolve_mimic_joints(const urdf::ModelInterface& model, const std::string& display_name, const std::string& base_link,
                          const std::string& tip_link, RobotSpec& r) {
  auto index_of = [&](const std::string& name) {
    for (std::size_t i = 0; i < r.joints.size(); ++i)
      if (r.joints[i].name == name) return static_cast<int>(i);
    return -1;
  };
  for (auto& j : r.joints) {
    if (j.mimic_of.empty()) continue;
    const error::Location where{display_name, 0, 0, "joint " + j.name};
    double multiplier = j.mimic_multiplier, offset = j.mimic_offset;
    std::string master = j.mimic_of;
    for (std::size_t hops = 0;; ++hops) {
      const int m = index_of(master);
      if (m < 0) {
        const bool exists = static_cast<bool>(model.getJoint(master));
        throw FormatError(where, "joint '" + j.name + "' mimics '" + master + "', " +
                                     (exists ? "which is not a moving joint between '" + base_link + "' and '" + tip_link +
                                                   "': its value, and so this joint's, is unknown to the chain"
                                             : "which the robot does not have"));
      }
      if (hops > r.joints.size()) throw FormatError(where, "joint '" + j.name + "': its <mimic> joints mimic each other in a cycle");
      const auto& mj = r.joints[static_cast<std::size_t>(m)];
      if (mj.mimic_of.empty()) break;
      offset = multiplier * mj.mimic_offset + offset;
      multiplier *= mj.mimic_multiplier;
      master = mj.mimic_of;
    }
    j.mimic_of = master;
    j.mimic_multiplier = multiplier;
    j.mimic_offset = offset;
  }
}

/// The offset of the first byte that does not belong to a well-formed UTF-8 sequence (RFC 3629:
/// no overlong forms, no surrogates, at most U+10FFFF), or npos when the text is valid UTF-8.
std::size_t first_invalid_utf8(const std::string& s) {
  const auto* b = reinterpret_cast<const unsigned char*>(s.data());
  const std::size_t n = s.size();
  for (std::size_t i = 0; i < n;) {
    const unsigned c = b[i];
    if (c < 0x80) {
      ++i;
      continue;
    }
    std::size_t len = 0;
    unsigned lo = 0x80, hi = 0xBF;  // the range of the second byte
    if (c >= 0xC2 && c <= 0xDF) len = 2;
    else if (c >= 0xE0 && c <= 0xEF) len = 3, lo = c == 0xE0 ? 0xA0 : 0x80, hi = c == 0xED ? 0x9F : 0xBF;
    else if (c >= 0xF0 && c <= 0xF4) len = 4, lo = c == 0xF0 ? 0x90 : 0x80, hi = c == 0xF4 ? 0x8F : 0xBF;
    else return i;
    if (i + len > n) return i;
    if (b[i + 1] < lo || b[i + 1] > hi) return i;
    for (std::size_t k = 2; k < len; ++k)
      if (b[i + k] < 0x80 || b[i + k] > 0xBF) return i;
    i += len;
  }
  return std::string::npos;
}

}  // namespace

RobotSpec parse_urdf_robot(const std::string& xml, const std::string& display_name, const std::string& base_link,
                           const std::string& tip_link) {
  // TinyXML, which urdfdom parses with, trusts a UTF-8 lead byte's length and reads past the end of
  // the text on a broken or truncated sequence (found by fuzz_urdf under ASan): refused here first.
  if (const std::size_t at = first_invalid_utf8(xml); at != std::string::npos) {
    const std::size_t line = 1 + static_cast<std::size_t>(std::count(xml.begin(), xml.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
    const std::size_t nl = at == 0 ? std::string::npos : xml.rfind('\n', at - 1);
    const std::size_t column = at - (nl == std::string::npos ? 0 : nl + 1) + 1;
    char hex[8];
    std::snprintf(hex, sizeof hex, "0x%02X", static_cast<unsigned>(static_cast<unsigned char>(xml[at])));
    throw FormatError({display_name, line, column, "robot"},
                      "not valid UTF-8 at byte " + std::to_string(at) + " (" + hex + "): a URDF is an XML text");
  }
  urdf::ModelInterfaceSharedPtr model;
  KDL::Tree tree;
  {
    std::lock_guard lock(log_mutex());
    CollectLog log;
    console_bridge::useOutputHandler(&log);
    try {
      model = urdf::parseURDF(xml);
    } catch (const std::exception& e) {
      log.lines.push_back(e.what());
      model.reset();
    }
    const std::string problem = model ? tree_problem(*model) : std::string();
    const bool tree_ok = model && problem.empty() && kdl_parser::treeFromUrdfModel(*model, tree);
    console_bridge::restorePreviousOutputHandler();
    if (!model) throw FormatError({display_name, 0, 0, "robot"}, "not a URDF robot description: " + joined(log.lines));
    if (!problem.empty()) {
      cut_link_cycles(*model);
      throw FormatError({display_name, 0, 0, "robot"}, problem);
    }
    if (!tree_ok) throw FormatError({display_name, 0, 0, "robot"}, "KDL could not build the kinematic tree: " + joined(log.lines));
  }
  for (const auto* end : {&base_link, &tip_link})
    if (!model->getLink(*end))
      throw FormatError({display_name, 0, 0, *end == base_link ? "base_link" : "tip_link"},
                        "no link '" + *end + "' in robot '" + model->getName() + "' (links: " + link_list(*model) + ")");
  KDL::Chain chain;
  if (!tree.getChain(base_link, tip_link, chain))
    throw FormatError({display_name, 0, 0, "tip_link"}, "no chain from '" + base_link + "' to '" + tip_link + "'");

  RobotSpec r;
  r.name = model->getName();
  r.convention = DhConvention::urdf;
  r.base_link = base_link;
  r.tip_link = tip_link;
  r.body_links.push_back(base_link);
  // Fixed segments fold into what follows: the next joint's origin, or the tool frame at the end;
  // their inertia into the body they hang from (expressed in that body's frame).
  KDL::Frame T_body_fixed = KDL::Frame::Identity();
  KDL::RigidBodyInertia body_inertia = KDL::RigidBodyInertia::Zero();
  for (const auto& seg : chain.segments) {
    const KDL::Joint& jt = seg.getJoint();
    const KDL::Frame T_parent_child = seg.pose(0.0);
    if (!is_revolute(jt.getType()) && !is_prismatic(jt.getType())) {
      // kdl_parser turns floating and planar joints into fixed ones (with a warning): in the
      // chain that would silently freeze a joint the robot has.
      if (const auto fj = model->getJoint(jt.getName()); fj && (fj->type == urdf::Joint::FLOATING || fj->type == urdf::Joint::PLANAR))
        throw FormatError({display_name, 0, 0, "joint " + fj->name},
                          "joint '" + fj->name + "' is " + (fj->type == urdf::Joint::FLOATING ? "floating" : "planar") +
                              ": a chain for calibration has revolute, continuous, prismatic and fixed joints only");
      T_body_fixed = T_body_fixed * T_parent_child;
      body_inertia = body_inertia + T_body_fixed * seg.getInertia();
      continue;
    }
    const auto uj = model->getJoint(jt.getName());
    r.inertials.push_back(to_inertial(body_inertia));
    DhJointSpec s;
    s.name = jt.getName();
    s.type = is_revolute(jt.getType()) ? JointType::revolute : JointType::prismatic;
    s.T_parent_joint = Pose::from_isometry(to_isometry(T_body_fixed * T_parent_child));
    // KDL gives the axis in the segment's parent frame; the joint frame is the child frame at q = 0.
    const KDL::Vector a = T_parent_child.M.Inverse(jt.JointAxis());
    s.axis = Eigen::Vector3d(a.x(), a.y(), a.z());
    // urdfdom lets an <axis> without a usable xyz through as (0, 0, 0).
    if (!(s.axis.norm() > 1e-9) || !s.axis.allFinite())
      throw FormatError({display_name, 0, 0, "joint " + s.name}, "joint '" + s.name + "' has no axis direction (<axis xyz=\"...\"/>)");
    s.axis.normalize();
    if (uj && uj->limits && uj->type != urdf::Joint::CONTINUOUS) {
      s.lower = uj->limits->lower;
      s.upper = uj->limits->upper;
    }
    if (!(s.lower < s.upper))
      throw FormatError({display_name, 0, 0, "joint " + s.name}, "joint '" + s.name + "': its lower limit is not below its upper limit");
    if (uj && uj->mimic) {
      s.mimic_of = uj->mimic->joint_name;
      s.mimic_multiplier = uj->mimic->multiplier;
      s.mimic_offset = uj->mimic->offset;
      if (!std::isfinite(s.mimic_multiplier) || !std::isfinite(s.mimic_offset))
        throw FormatError({display_name, 0, 0, "joint " + s.name},
                          "joint '" + s.name + "': its <mimic> multiplier or offset is not a number");
    }
    r.joints.push_back(s);
    r.body_links.push_back(seg.getName());
    T_body_fixed = KDL::Frame::Identity();
    body_inertia = seg.getInertia();
  }
  r.inertials.push_back(to_inertial(body_inertia));
  if (r.joints.empty())
    throw FormatError({display_name, 0, 0, "tip_link"}, "the chain from '" + base_link + "' to '" + tip_link + "' has no moving joint");
  r.T_flange_ee = Pose::from_isometry(to_isometry(T_body_fixed));
  resolve_mimic_joints(*model, display_name, base_link, tip_link, r);
  return r;
}

RobotSpec read_urdf_robot(const std::string& path, const std::string& base_link, const std::string& tip_link) {
  std::ifstream in(path);
  if (!in) throw FormatError({path, 0, 0, ""}, "cannot open the URDF file");
  std::stringstream ss;
  ss << in.rdbuf();
  RobotSpec r = parse_urdf_robot(ss.str(), path, base_link, tip_link);
  r.urdf_file = path;
  return r;
}

}  // namespace hil::format
