#include <hil/diagnose/effect.hpp>

#include <algorithm>
#include <array>
#include <mutex>
#include <stdexcept>

namespace hil::diagnose {

// The built-in effects, one file each in src/effects/, in the order they are listed and reported.
std::shared_ptr<const Effect> make_geometric_offset();
std::shared_ptr<const Effect> make_robot_compliance();
std::shared_ptr<const Effect> make_time_offset();
std::shared_ptr<const Effect> make_sensor_bias();
std::shared_ptr<const Effect> make_sensor_gain();
std::shared_ptr<const Effect> make_viscous_friction();
std::shared_ptr<const Effect> make_contact_damping();
std::shared_ptr<const Effect> make_nonlinear_stiffness();
std::shared_ptr<const Effect> make_rest_change();
std::shared_ptr<const Effect> make_link_compliance();
std::shared_ptr<const Effect> make_load_offset();

namespace {

struct Registry {
  std::mutex mutex;
  std::vector<std::shared_ptr<const Effect>> effects;
  std::array<std::vector<std::string>, 3> names;  ///< per FamilyKind

  Registry() {
    for (auto& e : {make_geometric_offset(), make_robot_compliance(), make_time_offset(), make_sensor_bias(), make_sensor_gain(),
                    make_viscous_friction(), make_contact_damping(), make_nonlinear_stiffness(), make_rest_change(), make_link_compliance(),
                    make_load_offset()})
      add(e);
  }

  void add(std::shared_ptr<const Effect> e) {
    if (!e) throw std::invalid_argument("register_effect: no effect");
    const std::string n = e->name();
    for (const auto& x : effects)
      if (x->name() == n) throw std::invalid_argument("register_effect: '" + n + "' is registered already");
    for (const FamilyKind f : {FamilyKind::contact, FamilyKind::deflection, FamilyKind::stiffness})
      if (e->extends(f)) names[static_cast<std::size_t>(f)].push_back(n);
    effects.push_back(std::move(e));
  }
};

// Built on first use, so a test fixture's static registration finds the built-in effects first.
Registry& registry() {
  static Registry r;
  return r;
}

}  // namespace

bool register_effect(std::shared_ptr<const Effect> effect) {
  auto& r = registry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  r.add(std::move(effect));
  return true;
}

const Effect* find_effect(const std::string& name) {
  auto& r = registry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  for (const auto& e : r.effects)
    if (e->name() == name) return e.get();
  return nullptr;
}

std::vector<const Effect*> registered_effects() {
  auto& r = registry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  std::vector<const Effect*> out;
  for (const auto& e : r.effects) out.push_back(e.get());
  return out;
}

const std::vector<std::string>& effect_names(FamilyKind family) { return registry().names[static_cast<std::size_t>(family)]; }

int default_cv_offsets(const std::vector<std::string>& candidates) {
  int offsets = 1;
  for (const auto& c : candidates)
    if (const Effect* e = find_effect(c)) offsets = std::max(offsets, e->cv_offsets());
  return offsets;
}

}  // namespace hil::diagnose
