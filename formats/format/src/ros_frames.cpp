#include <hil/format/ros_frames.hpp>

#include <set>

namespace hil::format {

std::vector<StaticFrame> static_frames(const RigSpec& rig) {
  // The rig file allows frames in any order; tf consumers do not care, but a reader of the
  // MCAP file's /tf_static is easier on parents first. `world` and `ee` are roots.
  std::vector<StaticFrame> out;
  const auto& n = rig.tf;
  std::set<std::string> placed{"world", "ee"};
  std::vector<const FrameSpec*> pending;
  for (const auto& f : rig.frames) pending.push_back(&f);
  while (!pending.empty()) {
    std::vector<const FrameSpec*> next;
    for (const auto* f : pending) {
      if (placed.count(f->parent)) {
        out.push_back({n.ros(f->parent), f->name, f->T_parent_frame});
        placed.insert(f->name);
      } else {
        next.push_back(f);
      }
    }
    if (next.size() == pending.size()) {  // unknown parents: the loader refuses these; keep order
      for (const auto* f : next) out.push_back({n.ros(f->parent), f->name, f->T_parent_frame});
      break;
    }
    pending.swap(next);
  }
  if (rig.robot) out.push_back({n.world, n.base, rig.robot->T_world_base});
  return out;
}

StaticFrame MovingFrame::at(const Pose& T_world_ee) const {
  return {parent, child, Pose::from_isometry(T_parent_world * T_world_ee.isometry())};
}

MovingFrame moving_frame(const RigSpec* rig) {
  MovingFrame m;
  if (!rig) {
    m.parent = "world";
    m.child = "ee";
  } else if (rig->robot) {
    m.parent = rig->tf.base;
    m.child = rig->tf.ee;
    m.T_parent_world = rig->robot->T_world_base.isometry().inverse();
  } else {
    m.parent = rig->tf.world;
    m.child = rig->tf.ee;
  }
  return m;
}

std::vector<std::string> joint_names(const RigSpec* rig, std::size_t count) {
  std::vector<std::string> names;
  names.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    std::string name;
    if (rig && rig->robot && i < rig->robot->joints.size()) name = rig->robot->joints[i].name;
    names.push_back(name.empty() ? "j" + std::to_string(i + 1) : name);
  }
  return names;
}

std::vector<std::string> joint_names(const RigSpec& rig, std::size_t count) { return joint_names(&rig, count); }

}  // namespace hil::format
