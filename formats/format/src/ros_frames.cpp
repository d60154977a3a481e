#include <hil/format/ros_frames.hpp>

#include <set>

namespace hil::format {

std::vector<StaticFrame> static_frames(const RigSpec& rig) {
  // The rig file allows frames in any order; tf consumers do not care, but a reader of the
  // MCAP file's /tf_static is easier on parents first. `world` and `ee` are roots.
  std::vector<StaticFrame> out;
  std::set<std::string> placed{"world", "ee"};
  std::vector<const FrameSpec*> pending;
  for (const auto& f : rig.frames) pending.push_back(&f);
  while (!pending.empty()) {
    std::vector<const FrameSpec*> next;
    for (const auto* f : pending) {
      if (placed.count(f->parent)) {
        out.push_back({f->parent, f->name, f->T_parent_frame});
        placed.insert(f->name);
      } else {
        next.push_back(f);
      }
    }
    if (next.size() == pending.size()) {  // unknown parents: the loader refuses these; keep order
      for (const auto* f : next) out.push_back({f->parent, f->name, f->T_parent_frame});
      break;
    }
    pending.swap(next);
  }
  if (rig.robot) out.push_back({"world", "robot_base", rig.robot->T_world_base});
  return out;
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
