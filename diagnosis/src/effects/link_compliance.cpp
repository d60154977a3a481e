// link_compliance (stiffness-table family): the links bend too. Its model is StiffnessFamily's
// (stiffness_family.hpp: the link springs' identifiable directions); here its registry entry.
#include <hil/diagnose/effect.hpp>

namespace hil::diagnose {

std::shared_ptr<const Effect> make_link_compliance() {
  return std::make_shared<NamedEffect>("link_compliance", "the links bend too, not only the joints (link springs' identifiable directions)",
                                       FamilyKind::stiffness, 100);
}

}  // namespace hil::diagnose
