// The stiffness-table family's own effects (stiffness_family.hpp): their registry entries. Its
// sensor_bias and sensor_gain are the contact family's entries (they extend both).
#include <hil/diagnose/effect.hpp>

namespace hil::diagnose {
namespace {

class StiffnessEffect : public Effect {
 public:
  StiffnessEffect(std::string name, std::string description) : name_(std::move(name)), description_(std::move(description)) {}
  std::string name() const override { return name_; }
  std::string description() const override { return description_; }
  bool extends(FamilyKind f) const override { return f == FamilyKind::stiffness; }

 private:
  std::string name_, description_;
};

}  // namespace

std::shared_ptr<const Effect> make_link_compliance() {
  return std::make_shared<StiffnessEffect>("link_compliance",
                                           "the links bend too, not only the joints (link springs' identifiable directions)");
}
std::shared_ptr<const Effect> make_load_offset() {
  return std::make_shared<StiffnessEffect>("load_offset",
                                           "the robot carried a constant load the table does not list (a tool's weight, a cable)");
}

}  // namespace hil::diagnose
