// rest_change (deflection family): the rest pose steps at events located from the data. Its model is
// DeflectionFamily's (deflection_family.hpp); here its registry entry.
#include <hil/diagnose/effect.hpp>

namespace hil::diagnose {
namespace {

class RestChange : public Effect {
 public:
  std::string name() const override { return "rest_change"; }
  int list_order() const override { return 90; }
  std::string description() const override {
    return "the rest pose changes at events located from the data (the body slips on its support and stays where it went)";
  }
  bool extends(FamilyKind f) const override { return f == FamilyKind::deflection; }
  // An event inside a held-out block cannot be predicted from the others: pooled over 8 offsets of
  // the grid the verdict no longer depends on where the block edges cut the events.
  int cv_offsets() const override { return 8; }
  std::string cv_offsets_reason() const override {
    return "rest_change's events make a single grid's verdict depend on where its block edges fall";
  }
  bool locates_events() const override { return true; }
};

}  // namespace

std::shared_ptr<const Effect> make_rest_change() { return std::make_shared<RestChange>(); }

}  // namespace hil::diagnose
