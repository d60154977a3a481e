// load_offset (stiffness-table family): a constant load the table does not list. Its model is
// StiffnessFamily's (stiffness_family.hpp); here its registry entry.
#include <hil/diagnose/effect.hpp>

namespace hil::diagnose {

std::shared_ptr<const Effect> make_load_offset() {
  return std::make_shared<NamedEffect>("load_offset",
                                       "the robot carried a constant load the table does not list (a tool's weight, a cable)",
                                       FamilyKind::stiffness, 110);
}

}  // namespace hil::diagnose
